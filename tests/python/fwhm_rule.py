#!/usr/bin/python3
"""The PSF width rule (fwhm_rule, docs/defaults.md#fwhm_rule "lambda under model
mismatch"): the default (data) against --fwhm-rule stated.
    fwhm_rule.py COL0RME WORKDIR [support|depth]
support: single-angle 64x64 stacks of the mismatch panel (Airy members, the
stated-260 one, two Gaussian controls), `support`, Jaccard at 40 nm (3 camera
pixels of margin). depth: 5-angle stacks (--pairs, Airy and Gaussian), `run`,
Jaccard and the median absolute and signed depth error. SEED=5 (default)."""
import json, os, subprocess, sys

BIN, WORK = sys.argv[1], sys.argv[2]
MODE = sys.argv[3] if len(sys.argv) > 3 else "support"
SEED = os.environ.get("SEED", "5")
COMMON = ["--width", "64", "--height", "64", "--angles", "65", "--z-range", "0,200"]
AIRY = ["--psf", "airy"]
MT = ["--filaments", "3", "--persistence", "20000", "--density", "100"]
PANEL = {"airy": (AIRY, []), "airy, stated 260": (AIRY, ["--fwhm", "260"]), "airy, microtubules": (AIRY + MT, []),
         "airy, 200 frames": (AIRY + ["--frames", "200"], []), "base": ([], []), "microtubules": (MT, [])}
DEPTH = {"airy, 5 angles": AIRY, "gaussian, 5 angles": []}


def run(args, **kw):
    return subprocess.run(args, check=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, **kw)


def simulate(name, opts):
    sim = os.path.join(WORK, name.replace(", ", "_").replace(" ", "_"))
    if not os.path.exists(sim + "/sim.json"):
        run([BIN, "simulate", "-o", sim, "--force", "--seed", SEED, "--threads", "1"] + opts)
    return sim


def width(out):
    return json.load(open(out + "/report.json")).get("psf_width", {})


os.makedirs(WORK, exist_ok=True)
if MODE == "support":
    print("| member | stated | data | used | Jaccard, stated | Jaccard, data rule | gain |")
    print("|---|---|---|---|---|---|---|")
    for name, (sopts, ropts) in PANEL.items():
        sim = simulate(name, COMMON + sopts)
        fwhm = str(json.load(open(sim + "/sim.json"))["parameters"]["fwhm_nm"])
        jac = {}
        for rule in ("stated", "data"):
            out = sim + "_" + rule
            run([BIN, "support", "-o", out, "--force", "--fwhm", fwhm, "--threads", "1", *ropts, "--fwhm-rule", rule,
                 sim + "/stack_q01.tif"])
            e = run([BIN, "eval", "--support", out + "/support.tif", "--support-truth", sim + "/truth_support.tif",
                     "--margin", "12"]).stdout
            jac[rule] = json.loads(e)["support"]["jaccard"]
        w = width(sim + "_data")
        print("| %s | %g | %.0f | %.0f | %.3f | %.3f | %+.3f |" % (name, w["stated_nm"], w.get("data_nm", 0), w["used_nm"],
              jac["stated"], jac["data"], jac["data"] - jac["stated"]), flush=True)
else:
    print("| member | rule | used FWHM | Jaccard | median depth err (nm) | median signed (nm) |")
    print("|---|---|---|---|---|---|")
    for name, sopts in DEPTH.items():
        sim = simulate(name, ["--pairs"] + sopts)
        p = json.load(open(sim + "/sim.json"))["parameters"]
        angles = ",".join("%.6g" % a for a in p["angles_deg"])
        stacks = sorted(os.path.join(sim, f) for f in os.listdir(sim) if f.startswith("stack_q"))
        for rule in ("stated", "data"):
            out = sim + "_" + rule
            run([BIN, "run", "-o", out, "--force", "--fwhm", str(p["fwhm_nm"]), "--angles", angles, "--fwhm-rule", rule]
                + stacks)
            run([BIN, "eval", "--run", out, "--truth", sim, "-o", out + "/eval.json"])
            e = json.load(open(out + "/eval.json"))
            d = e["depth"]
            print("| %s | %s | %.0f | %.3f | %.1f | %+.1f |" % (name, rule, width(out)["used_nm"], e["support"]["jaccard"],
                  d["median_abs_error_nm"], d["median_signed_error_nm"]), flush=True)
