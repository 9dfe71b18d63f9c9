#!/usr/bin/python3
"""The PSF width rule (fwhm_rule, docs/defaults.md#fwhm_rule "lambda under model
mismatch"):
- an Airy stack (simulate --psf airy, FWHM 229 nm) given --fwhm 260 reads
  210 nm from its covariance; by default the support uses that width
  (report.json's psf_width, a warning) and its Jaccard index beats the
  stated width's (--fwhm-rule stated) by at least MARGIN (measured below);
- a Gaussian stack reads within 5 %: the stated width is used and the
  support is the same file as with --fwhm-rule stated;
- a bad value is refused naming the parameter.
Seed 5, 48x48, 300 frames, 65 deg, depths 0-200 nm.
usage: test_fwhm_rule.py COL0RME"""
import json
import os
import subprocess
import sys
import tempfile

from checks import check, done, refused

CLI = sys.argv[1]
COMMON = ["--seed", "5", "--width", "48", "--height", "48", "--frames", "300", "--angles", "65", "--z-range", "0,200"]
# measured 0.102 (0.576 -> 0.678); 0.134 (0.486 -> 0.620) before the width's floor on lambda
MARGIN = 0.05


def sh(args):
    return subprocess.run(args, check=True, capture_output=True, text=True)


def support(sim, out, rule, fwhm):
    # lines one fine pixel wide: the lambda rule for them (docs/defaults.md#lambda_rule)
    p = sh([CLI, "support", "-o", out, "--force", "--fwhm", fwhm, "--threads", "1", "--fwhm-rule", rule,
            "--lambda-rule", "peaks", os.path.join(sim, "stack_q01.tif")])
    j = json.loads(sh([CLI, "eval", "--support", os.path.join(out, "support.tif"), "--support-truth",
                       os.path.join(sim, "truth_support.tif"), "--margin", "12"]).stdout)["support"]["jaccard"]
    return json.load(open(os.path.join(out, "report.json")))["psf_width"], j, p.stderr


with tempfile.TemporaryDirectory() as tmp:
    got = {}
    for psf in ("airy", "gaussian"):
        sim = os.path.join(tmp, psf)
        sh([CLI, "simulate", "-o", sim, "--force", *COMMON] + (["--psf", "airy"] if psf == "airy" else []))
        for rule in ("stated", "data"):
            got[psf, rule] = support(sim, os.path.join(tmp, psf + "_" + rule), rule, "260" if psf == "airy" else "229")
        w, ja, err = got[psf, "data"]
        print("%s: FWHM stated %g, data %.1f, used %.1f; Jaccard stated %.3f, data rule %.3f" %
              (psf, w["stated_nm"], w["data_nm"], w["used_nm"], got[psf, "stated"][1], ja))
    w, ja, err = got["airy", "data"]
    check(w["rule"] == "data" and 200 < w["data_nm"] < 0.95 * 229 and w["used_nm"] == w["data_nm"],
          "airy: the data's width (%.1f) used (%.1f)" % (w["data_nm"], w["used_nm"]))
    check("the solves use" in err, "airy: a warning names the width used")
    check(ja >= got["airy", "stated"][1] + MARGIN, "airy: Jaccard %.3f beats the stated width's %.3f by %.2f"
          % (ja, got["airy", "stated"][1], MARGIN))
    ws = got["airy", "stated"][0]
    check(ws["rule"] == "stated" and ws["used_nm"] == 260, "airy, stated: 260 nm used")
    w = got["gaussian", "data"][0]
    check(abs(w["data_nm"] / 229 - 1) < 0.05 and w["used_nm"] == 229, "gaussian: the stated width used (data %.1f)"
          % w["data_nm"])
    same = open(os.path.join(tmp, "gaussian_data", "support.tif"), "rb").read() == \
        open(os.path.join(tmp, "gaussian_stated", "support.tif"), "rb").read()
    check(same, "gaussian: the same support.tif with either rule")
    p = subprocess.run([CLI, "support", "-o", os.path.join(tmp, "bad"), "--fwhm", "229", "--fwhm-rule", "both",
                        os.path.join(tmp, "airy", "stack_q01.tif")], capture_output=True, text=True)
    check(refused(p, "fwhm"), "--fwhm-rule both refused")
done()
