#!/usr/bin/python3
"""Defaults across a grid of acquisitions (docs/history/grid.md):
angle sets x cameras x blinking regimes x frame counts, every cell a 5- (or 3-,
or 8-) angle simulation with close filament pairs and bleaching accumulated
over the acquisition, run with the defaults and scored against its truth.

    /usr/bin/python3 bench/grid.py COL0RME WORKDIR [--sweep] [--cells a,b,...]
        [--seeds 1,2] [--jobs N] [--json FILE] [--label-radius NM] [-- RUN OPTIONS...]

Prints a Markdown table, one row per cell (the median over the seeds):
Jaccard of the support (40 nm), median absolute and median SIGNED depth error
(nm; positive = deeper than the truth), depth coverage, and with --sweep the
best Jaccard of a 14-point sweep of --lambda on the support stacks (`support` on
every stack: pooled, as the run's support is by default; 0.1x to 8x
the automatic lambda, ratio about 1.4) and its gap to the automatic choice.
With a camera "scmos" and a col0rme that accepts --offset-map/--variance-map,
a "scmos+maps" row runs the same stacks with the simulator's calibration maps.
Simulations are cached in WORKDIR (same cell, same seed: not simulated again).
--cells keeps the cells whose name contains any of the given words. --label-radius puts
the emitters on a tube of that radius around each filament (simulate --label-radius; the
cells are then simulated in WORKDIR/sim_labelNM)."""
import json
import math
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

N_GLASS, N_SAMPLE = 1.518, 1.33
SWEEP = [0.1, 0.14, 0.2, 0.28, 0.4, 0.56, 0.8, 1.0, 1.4, 2.0, 2.8, 4.0, 5.6, 8.0]


def angles(k):
    """k angles equally spaced in NA from 0.3 deg above critical to 70 deg, as the simulator's default."""
    lo = math.asin(N_SAMPLE / N_GLASS) + math.radians(0.3)
    na = [N_GLASS * math.sin(lo) + i * (N_GLASS * math.sin(math.radians(70)) - N_GLASS * math.sin(lo)) / (k - 1)
          for i in range(k)]
    return ",".join("%.4f" % math.degrees(math.asin(v / N_GLASS)) for v in na)


def cameras(helptext):
    """camera name -> simulate options; the simulator's own camera models when it has them."""
    if "--camera" in helptext:
        return {"ccd": [], "emccd": ["--camera", "emccd"], "scmos": ["--camera", "scmos"]}
    return {"ccd": [], "emccd": ["--gain", "10", "--snr", "0", "--read-noise", "2"],
            "scmos": ["--hot-pixels", "0.01", "--snr", "0", "--read-noise", "3"]}


BLINKING = {"standard": [], "sparse-fast": ["--tau-on", "10", "--tau-off", "120"],
            "dense-slow": ["--tau-on", "50", "--tau-off", "50"]}
ANGLES = {"3ang": 3, "5ang": 5, "8ang": 8}
FRAMES = [200, 500]


def sh(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(" ".join(args) + ": " + r.stderr.strip()[-300:])
    return r.stdout


def cells(cli):
    cams = cameras(sh([cli, "simulate", "--help"]))
    for a in ANGLES:
        for c in cams:
            for b in BLINKING:
                for f in FRAMES:
                    yield "%s %s %s %d" % (a, c, b, f), ANGLES[a], cams[c] + BLINKING[b] + ["--frames", str(f)]


def one(cli, work, name, k, sim_opts, seed, sweep, run_opts, maps, label=0):
    key = name.replace(" ", "_") + "_s%d" % seed
    sim, res = os.path.join(work, "sim_label%g" % label if label else "sim", key), []
    sim_opts = sim_opts + (["--label-radius", "%g" % label] if label else [])
    ang = angles(k)
    if not os.path.exists(os.path.join(sim, "sim.json")):
        sh([cli, "simulate", "--seed", str(seed), "--pairs", "--angles", ang, "--threads", "1", "--force",
            "-o", sim] + sim_opts)
    stacks = sorted(os.path.join(sim, f) for f in os.listdir(sim) if f.startswith("stack_q"))
    variants = [("", [])]
    if maps and os.path.exists(os.path.join(sim, "calib_offset.tif")):
        variants.append(("+maps", ["--offset-map", sim + "/calib_offset.tif",
                                   "--variance-map", sim + "/calib_variance.tif"]))
    for tag, extra in variants:
        out = os.path.join(work, "run", key + tag)
        sh([cli, "run", "--fwhm", "229", "--angles", ang, "--threads", "1", "--force", "-o", out]
           + run_opts + extra + stacks)
        ev = json.loads(sh([cli, "eval", "--run", out, "--truth", sim]))
        d = ev["depth"]
        row = {"cell": name + tag, "seed": seed, "jaccard": ev["support"]["jaccard"],
               "depth_median": d["median_abs_error_nm"], "depth_signed": d["median_signed_error_nm"],
               "coverage": d["coverage"]}
        if sweep and not tag:
            rel = json.load(open(out + "/report.json"))["support"][0]["lambda_relative"]
            best = (row["jaccard"], 1.0)
            for m in SWEEP:
                if m == 1.0:
                    continue
                o = os.path.join(work, "sweep", "%s_%g" % (key, m))
                sh([cli, "support", "--fwhm", "229", "--threads", "1", "--force", "--lambda", "%.17g" % (rel * m),
                    "-o", o] + run_opts + stacks)
                j = json.loads(sh([cli, "eval", "--support", o + "/support.tif", "--support-truth",
                                   sim + "/truth_support.tif"]))["support"]["jaccard"]
                best = max(best, (j, m))
            row["best_jaccard"], row["best_times_auto"] = best
        res.append(row)
    return res


def table(rows, sweep):
    by = {}
    for r in rows:
        by.setdefault(r["cell"], []).append(r)
    head = "| cell | seeds | Jaccard | median depth err (nm) | median signed (nm) | coverage |"
    rule = "|---|---|---|---|---|---|"
    if sweep:
        head += " best-λ Jaccard | gap | best λ / auto |"
        rule += "---|---|---|"
    lines = [head, rule]
    med = lambda rs, k: statistics.median(r[k] for r in rs)
    for cell, rs in by.items():
        s = "| %s | %d | %.3f | %.1f | %+.1f | %.2f |" % (cell, len(rs), med(rs, "jaccard"), med(rs, "depth_median"),
                                                       med(rs, "depth_signed"), med(rs, "coverage"))
        if sweep and "best_jaccard" in rs[0]:
            s += " %.3f | %.3f | %.2g |" % (med(rs, "best_jaccard"),
                                           statistics.median(r["best_jaccard"] - r["jaccard"] for r in rs),
                                           med(rs, "best_times_auto"))
        lines.append(s)
    allr = rows
    lines.append("")
    lines.append("over all %d runs: median depth error %.1f nm (worst cell %.1f), median signed %+.1f nm "
                 "(range %+.1f to %+.1f), Jaccard %.3f" % (
                     len(allr), statistics.median(r["depth_median"] for r in allr),
                     max(med(rs, "depth_median") for rs in by.values()),
                     statistics.median(r["depth_signed"] for r in allr),
                     min(med(rs, "depth_signed") for rs in by.values()),
                     max(med(rs, "depth_signed") for rs in by.values()),
                     statistics.median(r["jaccard"] for r in allr)))
    if sweep:
        gaps = [r["best_jaccard"] - r["jaccard"] for r in allr if "best_jaccard" in r]
        if gaps:
            lines.append("λ: gap to the sweep's best Jaccard: median %.3f, max %.3f; %d of %d runs within 0.02" % (
                statistics.median(gaps), max(gaps), sum(g <= 0.02 for g in gaps), len(gaps)))
    return "\n".join(lines)


def main():
    argv = sys.argv[1:]
    run_opts = []
    if "--" in argv:
        i = argv.index("--")
        argv, run_opts = argv[:i], argv[i + 1:]
    cli, work = os.path.abspath(argv[0]), argv[1]
    opt = lambda name, default: argv[argv.index(name) + 1] if name in argv else default
    sweep = "--sweep" in argv
    seeds = [int(s) for s in opt("--seeds", "1").split(",")]
    words = opt("--cells", "").split(",") if "--cells" in argv else None
    maps = "--offset-map" in sh([cli, "run", "--help"])
    todo = [(n, k, o, s) for n, k, o in cells(cli) for s in seeds
            if not words or any(w in n for w in words)]
    label = float(opt("--label-radius", "0"))
    for d in ("sim", "run", "sweep") + (("sim_label%g" % label,) if label else ()):
        os.makedirs(os.path.join(work, d), exist_ok=True)
    with ThreadPoolExecutor(int(opt("--jobs", "2"))) as pool:
        futs = [pool.submit(one, cli, work, n, k, o, s, sweep, run_opts, maps, label) for n, k, o, s in todo]
        rows = []
        for f in futs:
            rows += f.result()
            print("done: %s seed %d" % (rows[-1]["cell"], rows[-1]["seed"]), file=sys.stderr, flush=True)
    if "--json" in argv:
        json.dump(rows, open(opt("--json", ""), "w"), indent=1)
    print(table(rows, sweep))


if __name__ == "__main__":
    main()
