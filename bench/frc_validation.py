"""Does the support step's FRC track the resolution? Two parallel lines of
emitters a known distance apart (simulate --emitters), one stack each, then
`col0rme support`; for each distance and seed: the FRC figure from report.json's
curve (1 / the frequency where it falls below 1/7, or '<2 fine pixels' when it
never does), the
localisation precision, and whether the two lines come out apart: in the
emitter variance rx.tif (a dip between the lines' peaks, averaged along them,
below DIP of the lower peak) and in support.tif (an empty fine column between
them). Prints one table (and the per-seed rows with --rows).

Run from the repository root after building:
  /usr/bin/python3 bench/frc_validation.py [--seeds 1,2,3,4,5] [--distances 40,60,...]
                                           [--frames 500] [--size 32] [--rows]
About 1 s per run on one core. tests/python/test_frc_validation.py imports
measure() and checks what docs/guide.md states."""
import json
import os
import random
import subprocess
import sys
import tempfile

import numpy as np
import tifffile

BUILD = os.environ.get("BUILD", "build")
CLI = os.path.join(BUILD, "col0rme")
PIXEL, SRF, FWHM = 100.0, 4, 229.0
DIP = 0.8            # a dip below 0.8 of the lower peak: apart (about Rayleigh's 0.735 for two Airy disks)
SPACING = 20.0       # mean distance between emitters along a line, nm


def lines_csv(path, d, size, seed):
    """Two vertical lines d nm apart about the centre (off the fine grid by a
    seed-drawn shift), emitters at uniform random heights over the middle 3/4; the x of the
    centre between them."""
    rng = random.Random(seed)
    side = size * PIXEL
    cx = side / 2 + rng.uniform(0, PIXEL / SRF)
    n = int(0.75 * side / SPACING)
    with open(path, "w") as f:
        for s in (-1, 1):
            for _ in range(n):
                f.write("%.2f,%.2f,0\n" % (cx + s * d / 2, rng.uniform(0.125 * side, 0.875 * side)))
    return cx


def apart(profile, xa, xb):
    """(dip ratio, resolved) of a profile across the lines: the lowest value
    strictly between the fine columns of the two lines, over the lower of the
    two peaks found within a fine column of each line."""
    fine = PIXEL / SRF
    ca, cb = int(xa // fine), int(xb // fine)
    pa = max(profile[max(ca - 1, 0):ca + 2])
    pb = max(profile[cb - 1:cb + 2])
    if cb - ca < 2 or min(pa, pb) <= 0:
        return 1.0, False
    ia = ca - 1 + int(np.argmax(profile[ca - 1:ca + 2]))
    ib = cb - 1 + int(np.argmax(profile[cb - 1:cb + 2]))
    if ib - ia < 2:
        return 1.0, False
    r = float(min(profile[ia + 1:ib]) / min(pa, pb))
    return r, r < DIP


def crossing(freq, corr, thr=1.0 / 7):
    """The usual FRC resolution: 1 / the first frequency (past the first two
    rings) where the curve falls below 1/7, interpolated; None: it never does
    (finer than 2 fine pixels, the grid's Nyquist)."""
    for k in range(2, len(corr)):
        if corr[k] < thr:
            f0, f1, c0, c1 = freq[k - 1], freq[k], corr[k - 1], corr[k]
            return 1 / (f0 + (c0 - thr) / (c0 - c1) * (f1 - f0) if c0 > c1 else f1)
    return None


def measure(d, seed, size=32, frames=500, cli=CLI, threads=1):
    """One run: a dict with the FRC figure, the precision, and the two
    'resolved' verdicts (emitter variance dip, support gap)."""
    with tempfile.TemporaryDirectory() as tmp:
        csv = os.path.join(tmp, "e.csv")
        cx = lines_csv(csv, d, size, seed)
        sim, sup = os.path.join(tmp, "sim"), os.path.join(tmp, "sup")
        common = ["--threads", str(threads)]
        subprocess.run([cli, "simulate", "-o", sim, "--emitters", csv, "--width", str(size), "--height", str(size),
                        "--frames", str(frames), "--angles", "70", "--brightness-cv", "0", "--seed", str(seed)]
                       + common, check=True, capture_output=True)
        # lines one fine pixel wide: the lambda rule for them (docs/defaults.md#lambda_rule), and no
        # label radius (the support grown across a tube would close the gap between lines 80 nm apart)
        subprocess.run([cli, "support", "--fwhm", str(FWHM), "--srf", str(SRF), "--lambda-rule", "peaks",
                        "--label-radius", "0", "-o", sup,
                        os.path.join(sim, "stack_q01.tif")] + common, check=True, capture_output=True)
        rep = json.load(open(os.path.join(sup, "report.json")))["support"][0]
        rx = tifffile.imread(os.path.join(sup, "rx.tif")).astype(np.float64)
        mask = tifffile.imread(os.path.join(sup, "support.tif")) > 0
    rx = rx.reshape(rx.shape[-2:])
    mask = mask.reshape(mask.shape[-2:])
    rows = slice(int(0.2 * rx.shape[0]), int(0.8 * rx.shape[0]))   # away from the lines' ends
    xa, xb = cx - d / 2, cx + d / 2
    dip, res_rx = apart(rx[rows].mean(axis=0), xa, xb)
    # the support: a fine column between the lines' columns with no support pixel
    # in at least half of the rows
    fine = PIXEL / SRF
    ca, cb = int(xa // fine), int(xb // fine)
    gap = bool(cb - ca >= 2 and any((~mask[rows, c]).mean() >= 0.5 for c in range(ca + 1, cb)))
    frc_nm = crossing(rep["frc"]["frequency_per_nm"], rep["frc"]["correlation"])
    return {"d": d, "seed": seed, "frc_nm": frc_nm, "bound_nm": 2 * fine,
            "precision_nm": rep.get("precision_nm"), "dip": dip, "resolved_rx": res_rx, "resolved_support": gap,
            "support_pixels": rep["support_pixels"]}


def fmt_frc(r):
    return "%.0f" % r["frc_nm"] if r["frc_nm"] is not None else "<%.0f" % r["bound_nm"]


def main():
    args = sys.argv[1:]

    def opt(name, default):
        return args[args.index(name) + 1] if name in args else default
    seeds = [int(s) for s in opt("--seeds", "1,2,3,4,5").split(",")]
    dists = [float(s) for s in opt("--distances", "40,60,80,100,150,200").split(",")]
    frames, size = int(opt("--frames", "500")), int(opt("--size", "32"))
    allr = [measure(d, s, size, frames) for d in dists for s in seeds]
    if "--rows" in args:
        print("d_nm seed frc_nm precision_nm dip resolved_rx resolved_support support_px")
        for r in allr:
            print("%g %d %s %.1f %.2f %s %s %d" % (r["d"], r["seed"], fmt_frc(r), r["precision_nm"], r["dip"],
                                                  r["resolved_rx"], r["resolved_support"], r["support_pixels"]))
        print()
    print("%d seeds, %dx%d px of %g nm, %d frames, FWHM %g nm, fine pixel %g nm" %
          (len(seeds), size, size, PIXEL, frames, FWHM, PIXEL / SRF))
    print("| distance (nm) | FRC figure (nm) | precision (nm) | dip in rx | resolved in rx | gap in support |")
    print("|---|---|---|---|---|---|")
    for d in dists:
        rs = [r for r in allr if r["d"] == d]
        figs = [fmt_frc(r) for r in rs]
        frcs = [f + (" (%d)" % figs.count(f) if figs.count(f) > 1 else "") for f in sorted(set(figs), key=lambda f: (f[0] != "<", float(f.strip("<"))))]
        print("| %g | %s | %.1f | %.2f | %d/%d | %d/%d |" % (
            d, ", ".join(frcs), np.mean([r["precision_nm"] for r in rs]), np.mean([r["dip"] for r in rs]),
            sum(r["resolved_rx"] for r in rs), len(rs), sum(r["resolved_support"] for r in rs), len(rs)))


if __name__ == "__main__":
    main()
