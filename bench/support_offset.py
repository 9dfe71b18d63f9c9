#!/usr/bin/python3
"""What a support a pixel off costs the depth (docs/history/depth.md, "What the
200-frame runs add above the floor"): the intensity step alone (`col0rme
intensity`, at the run's shared mu) on three supports, the true one, the true
one moved one fine pixel down and the run's, each read out as the run does
(bench/depth_ladder.py: the guided strip and the single-depth fit, true
bleaching factors), every true pixel scored by the depth of its nearest
support pixel (a moved support covers other pixels than the truth).

    /usr/bin/python3 bench/support_offset.py COL0RME SIMDIR RUNDIR WORKDIR

SIMDIR: `col0rme simulate` output; RUNDIR: `col0rme run --angles` on its
stacks; WORKDIR: scratch (created). Prints one markdown row: median / signed
depth error (nm) on each support."""
import json
import os
import subprocess
import sys

import numpy as np
import tifffile as tf

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import depth_ladder as L  # noqa: E402


def nearest(src, dst):
    """for each True pixel of dst, the (y, x) of the nearest True pixel of src"""
    sy, sx = np.nonzero(src)
    dy, dx = np.nonzero(dst)
    best = np.zeros(len(dy), dtype=int)
    for c in np.array_split(np.arange(len(dy)), max(1, len(dy) // 500)):
        best[c] = ((dy[c, None] - sy[None]) ** 2 + (dx[c, None] - sx[None]) ** 2).argmin(1)
    return (dy, dx), (sy[best], sx[best])


def score(d, z, mask):
    (ty, tx), (ny, nx) = nearest(mask, d["zt"] > 0)
    v, t = z[ny, nx], d["zt"][ty, tx]
    e = (v - t)[v > 0]
    return "%.1f / %+.1f" % (np.median(np.abs(e)), np.median(e))


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    cli, sim, run, work = sys.argv[1:]
    os.makedirs(work, exist_ok=True)
    S, R = json.load(open(sim + "/sim.json")), json.load(open(run + "/report.json"))
    mu, fwhm = R["intensity"][0]["mu"], S["parameters"]["fwhm_nm"]
    stacks = sorted(os.path.join(sim, f) for f in os.listdir(sim) if f.startswith("stack_q"))
    d = L.load(sim, run)
    ts = d["ts"]
    moved = np.zeros_like(ts)
    moved[1:] = ts[:-1]
    row = [os.path.basename(os.path.normpath(sim)), "%.3g" % mu]
    for name, m in (("true", ts), ("moved", moved), ("run", d["es"])):
        sup, out = os.path.join(work, "support_%s.tif" % name), os.path.join(work, name)
        tf.imwrite(sup, (m * 255).astype(np.uint8))
        subprocess.run([cli, "intensity", "--support", sup, "--fwhm", str(fwhm), "--mu", repr(mu), "--force",
                        "-o", out] + stacks[:d["nq"]], check=True, capture_output=True)
        x = np.array([tf.imread(out + "/intensity_q%02d.tif" % (q + 1)) for q in range(d["nq"])]).astype(float)
        row.append(score(d, L.depth(d, x, m, d["tb"]), m))
    print("| stack | mu | true support | moved one pixel | the run's support |")
    print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
