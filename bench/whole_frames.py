"""Whole camera frames (issue 36): `col0rme run` on 5 angles of simulated
stacks (simulate --seed 3, default angles) at 512x512, 1024x1024 and
2048x2048, one table: frames, wall seconds, peak RSS, each step's seconds
and the peak RSS after it from report.json (the automatic lambda's own seconds, part
of the support step's, on a row of their own), throughput, and the ratio to a baseline measured in the
same run: main's binary on the same stacks when --baseline BIN is given,
else the first row, per pixel and frame.

usage (from the repository root, after the build):
  /usr/bin/python3 bench/whole_frames.py [--sizes 512,1024,2048] [--frames 500]
      [--frames-2048 100] [--baseline OTHER_BUILD/col0rme] [--data DIR]
--data keeps the simulated stacks there and reuses them (5 stacks of
2048x2048x100 are ~4 GB, of 1024x1024x500 ~5 GB); without it they go to a
temporary folder, each size's removed after its rows.
A run that fails (out of memory) gets its row with the last error line.

Each run is its own process; peak RSS is its maximum resident set size
(wait4). Throughput is camera pixels x frames x stacks per wall second.

Then, for the first size's run, the roofline table (issue 55, "count before
you cut"): each step's bytes read from the frames and floating-point work,
counted from the sizes and report.json (a model, stated in roofline_rows),
its seconds, and the fraction of this machine's roofline it reaches,
max(bytes / bandwidth, flops / peak) / seconds. The bandwidth and the peak
are measured first by probe() (numpy: a copy of 512 MB arrays; float64 and
float32 matrix products on all threads, the attainable FMA rate). --roofline-only
prints the probe alone."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

STEPS = ("drift", "support", "intensity", "render", "bleaching", "matirf")


def timed(cmd):
    """(wall s, peak RSS MiB, exit status, last stderr line, CPU s: user + system) of one child process"""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    lines = err.strip().splitlines()
    return (time.perf_counter() - t0, ru.ru_maxrss / 1024.0, os.waitstatus_to_exitcode(status), lines[-1] if lines else "",
            ru.ru_utime + ru.ru_stime)


def stacks(cli, data, w, frames):
    d = os.path.join(data, "s%d_%d" % (w, frames))
    if not os.path.isfile(os.path.join(d, "sim.json")):
        shutil.rmtree(d, ignore_errors=True)
        t = time.perf_counter()
        subprocess.run([cli, "simulate", "-o", d, "--width", str(w), "--height", str(w), "--frames", str(frames),
                        "--seed", "3"], check=True, capture_output=True)
        print("simulated %dx%dx%d in %.0f s" % (w, w, frames, time.perf_counter() - t), file=sys.stderr, flush=True)
    angles = json.load(open(os.path.join(d, "sim.json")))["parameters"]["angles_deg"]
    return d, ",".join("%.6g" % a for a in angles), [os.path.join(d, "stack_q%02d.tif" % q) for q in range(1, len(angles) + 1)]


def run(cli, d, angles, files, tag):
    out = os.path.join(d, "out_" + tag)
    dt, mem, rc, last, cpu = timed([cli, "run", "--fwhm", "229", "--angles", angles, "--force", "-o", out, *files])
    rep = json.load(open(os.path.join(out, "report.json"))) if rc == 0 else {}
    shutil.rmtree(out, ignore_errors=True)
    lam = sum(x.get("lambda_auto", {}).get("seconds", 0) for x in rep.get("support", []))
    return dict(wall=dt, cpu=cpu, mem=mem, rc=rc, last=last, t=rep.get("timings_s", {}), peak=rep.get("peak_rss_mb", {}), lam=lam,
                rep=rep)


def probe():
    """(memory bandwidth GB/s, float64 peak GFLOP/s, float32 peak GFLOP/s): best of a few tries"""
    import numpy as np
    a = np.ones(1 << 26)          # 512 MB
    b = np.empty_like(a)
    bw = 0.0
    for _ in range(5):
        t = time.perf_counter()
        np.copyto(b, a)
        bw = max(bw, 2 * a.nbytes / (time.perf_counter() - t) / 1e9)   # read + write
    del a, b
    peaks = []
    for dt in (np.float64, np.float32):
        n = 2048
        x = np.random.default_rng(1).random((n, n)).astype(dt)
        best = 0.0
        for _ in range(3):
            t = time.perf_counter()
            x @ x
            best = max(best, 2 * n ** 3 / (time.perf_counter() - t) / 1e9)
        peaks.append(best)
    return bw, peaks[0], peaks[1]


def roofline_rows(r, files, w, T, bw, peak):
    """The steps of one run: (step, GB read, GFLOP, seconds, fraction of the roofline, why).
    Counted: every stack's frames are read by drift (block means: 1 add a
    pixel-frame) and by the intensity step's means (a support stack's own
    support pass gives its mean, a pooled one does not; 1 add, plus 1 for the
    block halves of the noise estimate); the support stacks again by the covariance pass (per
    pixel-frame one multiply-add in double for each lag kept, 2 sums for the
    mean and trend, the shift: 2 nlag + 4 flops). Solves (support, lambda
    rule, intensity, MA-TIRF) are iterations on the fine grid's working set,
    not counted here: their rows give time only."""
    t = r["t"]
    rep = r["rep"]
    nbytes = [os.path.getsize(f) for f in files]
    allb = sum(nbytes) / 1e9
    sup = rep.get("support", [])
    # the support stacks (1-based): pooled into one support (each read by the covariance
    # pass, and again by the intensity step for its own noise variance) or each its own
    par = rep.get("parameters", {})
    idx = [q - 1 for q in par.get("support_stacks", [])]
    pooled = bool(par.get("support_pooled"))
    supb = sum(nbytes[q] for q in idx if 0 <= q < len(nbytes)) / 1e9
    px = w * w * T
    nlag = sup[0]["lags"] if sup else 0
    cov_s = sum(s.get("covariance_s", 0) for s in sup)
    lam_s = r["lam"]
    solve_s = t.get("support", 0) - cov_s - lam_s
    nsup = len(idx)
    nint = len(files) if pooled else len(files) - nsup   # the stacks the intensity step reads
    rows = [("drift (block means)", allb, px * len(files) / 1e9, t.get("drift", 0),
             "every stack read; frames decoded one by one, 1 add a pixel: bound by reading"),
            ("support: covariance", supb, (2 * nlag + 4) * px * nsup / 1e9, cov_s,
             "double FMAs (exact float products), a dy's lags at once, strips in L2"),
            ("support: solve (tiles)", None, None, max(solve_s, 0), "FISTA on the tiles' working sets"),
            ("support: lambda rule", None, None, lam_s, "the halves' correlation images (the noise rule: no first solve)"),
            ("intensity (means and solves)", allb if pooled else allb - supb, 2 * px * nint / 1e9, t.get("intensity", 0),
             "the stacks read again (pooled: all, each for its own noise variance), then CG solves for mu"),
            ("bleaching", None, None, t.get("bleaching", 0), ""),
            ("render", None, None, t.get("render", 0), ""),
            ("MA-TIRF", None, None, t.get("matirf", 0), "apg PDHG on the support's columns"),
            ("rest (start, writing)", None, None, r["wall"] - sum(t.values()), "outputs written (compressed TIFF)")]
    out = []
    for name, gb, gf, sec, why in rows:
        att = max(gb / bw if gb else 0, gf / peak if gf else 0)
        out.append((name, "%.3f" % gb if gb is not None else "-", "%.1f" % gf if gf is not None else "-", "%.1f" % sec,
                    "%.0f %%" % (100 * att / sec) if att and sec > 0 else "-", why))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.environ.get("BUILD", "build"))
    ap.add_argument("--sizes", default="512,1024,2048")
    ap.add_argument("--frames", type=int, default=500)
    ap.add_argument("--frames-2048", type=int, default=100, help="frames at 2048x2048 (stacks of 2048x2048x500 are 21 GB)")
    ap.add_argument("--baseline", help="another build's col0rme, run on the same stacks (the ratio column)")
    ap.add_argument("--data", help="keep and reuse the simulated stacks here")
    ap.add_argument("--roofline-only", action="store_true", help="print the probe's bandwidth and peaks and stop")
    ap.add_argument("--probe", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if "--probe" in sys.argv:    # the child below: its arrays stay out of the runs' peak RSS
        print(json.dumps(probe()))
        return
    bw, p64, p32 = json.loads(subprocess.run([sys.executable, os.path.abspath(__file__), "--probe"], check=True,
                                             capture_output=True, text=True).stdout)
    print("probe: memory bandwidth %.1f GB/s (copy, one thread), peak %.1f GFLOP/s float64, %.1f float32 (matrix "
          "products, all threads); load %.1f" % (bw, p64, p32, os.getloadavg()[0]), flush=True)
    if a.roofline_only:
        return
    cli = os.path.join(a.build, "col0rme")
    data = a.data or tempfile.mkdtemp(prefix="c0_whole_")
    os.makedirs(data, exist_ok=True)
    rows, ref, roof = [], None, None
    try:
        for w in (int(s) for s in a.sizes.split(",")):
            T = a.frames_2048 if w >= 2048 else a.frames
            d, angles, files = stacks(cli, data, w, T)
            work = w * w * T * len(files)
            r = run(cli, d, angles, files, "new")
            if r["rc"] == 0 and roof is None:
                roof = ("%dx%d, %d x %d frames" % (w, w, len(files), T), roofline_rows(r, files, w, T, bw, p64))
            b = run(a.baseline, d, angles, files, "base") if a.baseline else None
            if b and b["rc"] == 0 and r["rc"] == 0:
                ratio = "%.2fx faster (CPU s %.0f -> %.0f: %.2fx), %.2fx the memory of the baseline" % (
                    b["wall"] / r["wall"], b["cpu"], r["cpu"], b["cpu"] / r["cpu"], r["mem"] / b["mem"])
            elif b:
                ratio = "baseline: %s" % ("%.0f s, %.0f MiB" % (b["wall"], b["mem"]) if b["rc"] == 0 else "failed: " + b["last"])
            elif r["rc"] == 0 and ref is None:
                ref, ratio = r["wall"] / work, "reference"
            else:
                ratio = "%.2fx the reference's time per pixel-frame" % (r["wall"] / work / ref) if r["rc"] == 0 and ref else ""
            steps = ", ".join("%s %.1f s %s MiB" % (k, r["t"][k], r["peak"].get(k, "?")) for k in STEPS if k in r["t"]) \
                if r["rc"] == 0 else \
                "FAILED (exit %d) after %.0f s: %s" % (r["rc"], r["wall"], r["last"])
            rows.append(("%dx%d" % (w, w), "%d x %d" % (len(files), T), "%.1f (CPU %.0f)" % (r["wall"], r["cpu"]),
                         "%.0f" % r["mem"], steps,
                         "%.1f" % (work / r["wall"] / 1e6), ratio))
            print(" | ".join(rows[-1]), file=sys.stderr, flush=True)
            if r["rc"] == 0 and r["lam"] > 0:   # issue 36: the lambda rule's extra solves on their own row
                rows.append(("  of which lambda rule", "", "%.1f" % r["lam"], "", "inside support: the automatic lambda "
                             "(the halves' correlation images)", "", "wall less it: %.1f s" % (r["wall"] - r["lam"])))
            if not a.data:
                shutil.rmtree(d)
    finally:
        if not a.data:
            shutil.rmtree(data, ignore_errors=True)
    hdr = ("frame", "stacks x frames", "wall s (CPU s)", "peak RSS MiB", "steps: seconds, peak RSS after it", "Mpx-frames/s", "ratio")
    wd = [max(len(str(x[i])) for x in rows + [hdr]) for i in range(len(hdr))]
    print("load %.1f, %d CPUs, %s" % (os.getloadavg()[0], os.cpu_count(), cli))
    print(" | ".join(h.ljust(n) for h, n in zip(hdr, wd)))
    print("-+-".join("-" * n for n in wd))
    for x in rows:
        print(" | ".join(str(c).ljust(n) for c, n in zip(x, wd)))
    if roof:
        hdr = ("step (%s)" % roof[0], "GB read", "GFLOP", "s", "of roofline", "why it is where it is")
        wd = [max(len(str(x[i])) for x in roof[1] + [hdr]) for i in range(len(hdr))]
        print()
        print(" | ".join(h.ljust(n) for h, n in zip(hdr, wd)))
        print("-+-".join("-" * n for n in wd))
        for x in roof[1]:
            print(" | ".join(str(c).ljust(n) for c, n in zip(x, wd)))


if __name__ == "__main__":
    main()
