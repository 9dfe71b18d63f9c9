#!/usr/bin/python3
"""The SOFI-tool panel: MA-TIRF sets made by the SOFI Simulation Tool on the
SMLM-2016 MT0 microtubules (the 3D-COL0RME paper's own recipe, code that is
not col0rme's: ../shared/sofisim/), run with col0rme's defaults and scored.

    /usr/bin/python3 bench/sofi_panel.py COL0RME WORKDIR --sofitool DIR --positions CSV
        [--sofisim PATH] [--members a,b] [--sweep] [--jobs N] [-- RUN OPTIONS...]

--sofitool is a checkout of lob-epfl/sofitool and --positions MT0's activations.csv
(nboyd/deep_loco, data/activations.csv); both stay outside the project (the positions
have no licence), and so do the sets (WORKDIR/sets, made once, about 2 minutes each on
one core under GNU Octave: `apt-get install octave octave-image`). Each set's truth.npz
becomes truth_support.tif and truth_depth.tif on the fine grid (a fine pixel is in the
support when it holds a fluorophore; its depth is their mean z), which `col0rme eval`
reads as it reads the simulator's.

Prints a Markdown table, one row per member: the Jaccard index of the support at 40 and
25 nm (one-to-one matching, as COL0RME's code scores it), its fine pixels against the
truth's, depth.tif's median absolute and median signed error (nm; positive = deeper than
the truth), the depth offset one sd of the fitted fade leaves (report.json
bleaching.depth_offset_sd_nm), and with --sweep the best Jaccard (40 nm) of a 16-point
sweep of --lambda (1/70x to 16x the automatic lambda, ratio 1.6; whole runs, so that the
sweep is of the support the run makes, pooled or not) with its multiple of the automatic
lambda and the gap to it."""
import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import tifffile

HERE = os.path.dirname(os.path.abspath(__file__))
ADD = ["--bg-mode", "additive"]
# name: sofisim options. Crops of the 6.4 um MT0 field (a 48-pixel field starts at
# 0-1600 nm), seeds, photon levels, blinking, 3/5/8 angles, 200/500 frames, both
# background modes
MEMBERS = {
    "a1": ["--seed", "11", "--crop-x", "400", "--crop-y", "1200"] + ADD,
    "a2": ["--seed", "12", "--crop-x", "1600", "--crop-y", "400"] + ADD,
    "dim": ["--seed", "13", "--crop-x", "800", "--crop-y", "800", "--photons", "150"] + ADD,
    "sparse": ["--seed", "14", "--crop-x", "1200", "--crop-y", "1600", "--ton-ms", "10", "--toff-ms", "150"] + ADD,
    "ang3": ["--seed", "15", "--crop-x", "0", "--crop-y", "0", "--angles", "62.5,65,70"] + ADD,
    "f200": ["--seed", "17", "--crop-x", "400", "--crop-y", "400", "--frames", "200"] + ADD,
    "ang8": ["--seed", "16", "--crop-x", "1600", "--crop-y", "1600", "--angles", "62.5,63.2,64,65,66,67,68.5,70"] + ADD,
    "sofibg": ["--seed", "18", "--crop-x", "1200", "--crop-y", "400"],
    "bright": ["--seed", "19", "--crop-x", "0", "--crop-y", "1600", "--photons", "800"] + ADD,
}
SWEEP = [16 * 1.6 ** -k for k in range(16)]


def sh(args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def truth(d, srf=4):
    """truth.npz -> truth_support.tif (uint8) and truth_depth.tif (float32, nm; 0 off the support)"""
    t = np.load(os.path.join(d, "truth.npz"))
    pos, fine = t["pos_nm"], float(t["pixel"]) / srf
    h, w = tifffile.imread(os.path.join(d, "angle01.tif"), key=0).shape
    iy = np.clip((pos[:, 1] // fine).astype(int), 0, h * srf - 1)
    ix = np.clip((pos[:, 0] // fine).astype(int), 0, w * srf - 1)
    n, zs = np.zeros((h * srf, w * srf)), np.zeros((h * srf, w * srf))
    np.add.at(n, (iy, ix), 1)
    np.add.at(zs, (iy, ix), pos[:, 2])
    # a depth of 0 reads as "no signal": the shallowest fluorophores sit at 0.01 nm
    depth = np.where(n > 0, np.maximum(zs / np.maximum(n, 1), 0.01), 0)
    meta = {"spacing": fine, "unit": "nm"}
    tifffile.imwrite(os.path.join(d, "truth_support.tif"), (n > 0).astype(np.uint8), imagej=True,
                     resolution=(1 / fine, 1 / fine), metadata=meta)
    tifffile.imwrite(os.path.join(d, "truth_depth.tif"), depth.astype(np.float32), imagej=True,
                     resolution=(1 / fine, 1 / fine), metadata=meta)


def make(a, name):
    d = os.path.join(a.work, "sets", name)
    if not os.path.exists(os.path.join(d, "truth.npz")):
        sh(["/usr/bin/python3", a.sofisim, d, "--sofitool", a.sofitool, "--positions", a.positions] + MEMBERS[name])
    if not os.path.exists(os.path.join(d, "truth_depth.tif")):
        truth(d)
    return d


def jaccard(cli, sup, d, radius):
    return json.loads(sh([cli, "eval", "--support", sup, "--support-truth", os.path.join(d, "truth_support.tif"),
                          "--pixel-size", "25", "--radius", str(radius)]))["support"]["jaccard"]


def one(a, name):
    d = make(a, name)
    ang = ",".join("%g" % v for v in np.load(os.path.join(d, "truth.npz"))["angles"])
    stacks = sorted(os.path.join(d, f) for f in os.listdir(d) if f.startswith("angle") and f.endswith(".tif"))
    out = os.path.join(a.work, "run", name)
    optics = ["--pixel-size", "100", "--fwhm", "229", "--n-glass", "1.518", "--n-sample", "1.33", "--wavelength", "488"]
    sh([a.cli, "run", "--angles", ang, "--threads", "1", "--force", "-o", out] + optics + a.run_opts + stacks)
    dep = json.loads(sh([a.cli, "eval", "--depth", out + "/depth.tif", "--depth-truth", d + "/truth_depth.tif"]))["depth"]
    dep = dep[0] if isinstance(dep, list) else dep
    sup = tifffile.imread(out + "/support.tif")
    row = {"member": name, "j40": jaccard(a.cli, out + "/support.tif", d, 40),
           "j25": jaccard(a.cli, out + "/support.tif", d, 25), "pixels": int((sup > 0).sum()),
           "truth_pixels": int((tifffile.imread(d + "/truth_support.tif") > 0).sum()),
           "depth_median": dep["median_abs_error_nm"], "depth_signed": dep["median_signed_error_nm"],
           "fade_sd": json.load(open(out + "/report.json"))["bleaching"].get("depth_offset_sd_nm", float("nan"))}
    if a.sweep:
        rel = json.load(open(out + "/report.json"))["support"][0]["lambda_relative"]
        best = (row["j40"], 1.0)
        for m in SWEEP:
            o = os.path.join(a.work, "sweep", "%s_%.4g" % (name, m))
            # the FRC left on: without it a given lambda's covariance is the whole stack's, not the
            # pooled frame halves' of the automatic run (stages/support.c), and the sweep would be
            # of another estimator; lambda in full, so that 1x is the default's support bit for bit
            sh([a.cli, "run", "--angles", ang, "--threads", "1", "--force", "--lambda", "%.17g" % (rel * m),
                "-o", o] + optics + a.run_opts + stacks)
            best = max(best, (jaccard(a.cli, o + "/support.tif", d, 40), m))
        row["best_j40"], row["best_times_auto"] = best
    return row


def main():
    argv = sys.argv[1:]
    run_opts = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[:argv.index("--")] if "--" in argv else argv
    ap = argparse.ArgumentParser()
    ap.add_argument("cli")
    ap.add_argument("work")
    ap.add_argument("--sofitool", required=True)
    ap.add_argument("--positions", required=True)
    ap.add_argument("--sofisim", default=os.path.join(HERE, "..", "..", "shared", "sofisim", "sofisim.py"))
    ap.add_argument("--members", default=",".join(MEMBERS))
    ap.add_argument("--sweep", action="store_true")
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args(argv)
    a.run_opts = run_opts
    a.cli = os.path.abspath(a.cli)
    names = a.members.split(",")
    for sub in ("sets", "run", "sweep"):
        os.makedirs(os.path.join(a.work, sub), exist_ok=True)
    with ThreadPoolExecutor(a.jobs) as ex:
        rows = list(ex.map(lambda n: one(a, n), names))
    head = ("| member | Jaccard 40 nm | Jaccard 25 nm | pixels (truth) | depth median (nm) | depth signed (nm) |"
            " fade's sd as depth (nm) |")
    print(head + (" best of sweep (x auto) | gap |" if a.sweep else ""))
    print("|---" * (head.count("|") - 1 + (2 if a.sweep else 0)) + "|")
    for r in rows:
        s = "| %s | %.3f | %.3f | %d (%d) | %.1f | %+.1f | %.1f |" % (
            r["member"], r["j40"], r["j25"], r["pixels"], r["truth_pixels"], r["depth_median"], r["depth_signed"],
            r["fade_sd"])
        if a.sweep:
            s += " %.3f (%.3g) | %+.3f |" % (r["best_j40"], r["best_times_auto"], r["j40"] - r["best_j40"])
        print(s, flush=True)


if __name__ == "__main__":
    main()
