"""The support on real MusiJ mitochondria stacks (tests/data/musij) with the
defaults: few support pixels far from the structure.

Measure (numpy only): the structure is where the temporal mean, smoothed by a
Gaussian of the PSF's sd and less its 5th percentile, exceeds 25 % of its
99.9th percentile; a support pixel is far when its camera pixel lies more
than 3 camera pixels from that mask. The share of far support pixels must be
below 10 % with the defaults (automatic lambda, drift correction); the old
fixed lambda 1e-2 is printed for comparison.

usage: test_musij.py COL0RME DATA_DIR"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import tifffile

from checks import check, done

CLI, DATA = sys.argv[1], sys.argv[2]
# file, emission (nm), pixel (nm), NA: from the .txt beside each file, or the name
STACKS = [("CardioMyoblast_Mitochondria_100Frames_NA1.4_80nm_1x_510nmemission.tif", 510, 80, 1.4),
          ("014_c00000002-650_775.tif", 525, 80, 1.4),
          ("C3-20180719_H9c2_1_dsRed-mito_KDEL_mC1to2000-20m_T23_1516_m_046C_608nm-1.tif", 608, 80, 1.4)]


def smooth(img, sig):
    r = int(np.ceil(3 * sig))
    k = np.exp(-np.arange(-r, r + 1) ** 2 / (2 * sig * sig))
    k /= k.sum()
    p = np.pad(img, r, mode="edge")
    p = np.apply_along_axis(lambda v: np.convolve(v, k, "valid"), 0, p)
    return np.apply_along_axis(lambda v: np.convolve(v, k, "valid"), 1, p)


def far_share(stack, support, srf, sig_px, dist=3):
    m = smooth(tifffile.imread(stack).astype(float).mean(0), sig_px)
    m -= np.percentile(m, 5)
    s = m > 0.25 * np.percentile(m, 99.9)
    H, W = s.shape
    near = np.zeros_like(s)
    for dy in range(-dist, dist + 1):
        for dx in range(-dist, dist + 1):
            if dy * dy + dx * dx <= dist * dist:
                near[max(dy, 0):H + min(dy, 0), max(dx, 0):W + min(dx, 0)] |= \
                    s[max(-dy, 0):H + min(-dy, 0), max(-dx, 0):W + min(-dx, 0)]
    ys, xs = np.nonzero(support)
    return float((~near[ys // srf, xs // srf]).mean()) if len(ys) else 0.0, len(ys)


with tempfile.TemporaryDirectory() as tmp:
    for name, em, px, na in STACKS:
        fwhm = 0.51 * em / na
        path = os.path.join(DATA, "musij", name)
        res = {}
        for label, extra in (("defaults", []), ("lambda 1e-2", ["--lambda", "1e-2"])):
            out = os.path.join(tmp, "o")
            p = subprocess.run([CLI, "support", "-o", out, "--force", "--pixel-size", str(px), "--fwhm", str(fwhm), path]
                               + extra, capture_output=True, text=True)
            check(p.returncode == 0, "%s: support failed: %s" % (name, p.stderr.strip()))
            if p.returncode:
                continue
            sup = tifffile.imread(os.path.join(out, "support.tif")) > 0
            rep = json.load(open(os.path.join(out, "report.json")))["support"][0]
            res[label] = far_share(path, sup, 4, fwhm / 2.3548 / px) + (rep["lambda_relative"],)
        print("%s: far share %s" % (name[:24], ", ".join("%s %.3f of %d pixels (lambda %.3g)" % ((k,) + v)
                                                        for k, v in res.items())))
        if "defaults" in res:
            check(res["defaults"][0] < 0.10, "%s: %.1f %% of the support far from the structure" % (name, 100 * res["defaults"][0]))
            check(res["defaults"][1] > 50, "%s: only %d support pixels" % (name, res["defaults"][1]))
done()
