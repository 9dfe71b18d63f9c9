"""Benchmarks: prints one table (size, time, throughput, peak memory, ratio to
a baseline measured in the same run). Run from the repository root after
scripts/setup.sh:  /usr/bin/python3 bench/run.py [--quick]
(--quick skips the 256x256 cases: support, intensity, dense MA-TIRF, and the
350x350 MA-TIRF rows; --matirf350 runs only those, --matirf-psf only their
plain against --psf-fwhm rows; --matirf-example DIR only the authors' public
13-angle example (its images as DIR/img_qNN.tif, its angles in DIR/angles.txt)
with --psf-fwhm against its converged answer;
--large adds whole camera frames: support on 1024x1024x500 and 2048x2048x200,
run on 5 angles of 512x512x500, each against the single-tile path measured in
the same run where it fits, thread scaling and a run next to a busy process;
--large-only runs just those. They take tens of minutes on 2 cores;
--lambda runs only the automatic lambda's rows, one pair per rule (noise, the
default; peaks; cv): at 64x64x500 and 256x256x1000, the command against the
same command with the lambda it chose given.)

Each timed command runs in its own process; peak memory is that process's
maximum resident set size."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

BUILD = os.environ.get("BUILD", "build")
CLI = os.path.join(BUILD, "col0rme")
QUICK = "--quick" in sys.argv
LARGE_ONLY = "--large-only" in sys.argv
LARGE = "--large" in sys.argv or LARGE_ONLY
rows = []
LAST_CPU = [0.0]   # user + system CPU seconds of the last timed() child


def timed(cmd, env=None):
    """(seconds, peak RSS MiB, stdout) of one child process (its own rusage via wait4)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ, **env) if env else None)
    out, err = p.stdout.read(), p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    dt = time.perf_counter() - t0
    LAST_CPU[0] = ru.ru_utime + ru.ru_stime
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode:
        sys.exit("bench: %s failed:\n%s" % (" ".join(cmd), err))
    return dt, ru.ru_maxrss / 1024.0, out


def sim(out, w, frames, angles="62", extra=()):
    subprocess.run([CLI, "simulate", "-o", out, "--width", str(w), "--height", str(w), "--frames", str(frames),
                    "--angles", angles, "--filaments", str(max(5, w // 12)), *extra], check=True, capture_output=True)


def load():
    return "load %.1f" % os.getloadavg()[0]


def row(what, size, secs, thr, mem, ratio=""):
    rows.append((what, size, "%.3g" % secs, thr, "%.0f" % mem, ratio))
    print(" | ".join(rows[-1]), file=sys.stderr, flush=True)   # as it comes: the table waits for the end


def matirf350(tmp, psf_only=False):
    # MA-TIRF at the size of the public example: a 350x350 dense phantom, the
    # example's 13 angles (equally spaced in NA 1.3478..1.4244), bins 0-300 nm.
    # The solvers against each other; 1 vs 2 threads; Hessian-Schatten;
    # plain against --psf-fwhm (psf_only: just those rows).
    import math
    import numpy as np
    import tifffile
    ang13 = ",".join("%.4f" % math.degrees(math.asin((1.3478 + i * (1.4244 - 1.3478) / 12) / 1.518)) for i in range(13))
    ph = os.path.join(tmp, "phantom350")
    os.mkdir(ph)
    subprocess.run([os.path.join(BUILD, "bench", "matirf_phantom"), ph, "350", "0.03"] + ang13.split(","), check=True)
    imgs = sorted(os.path.join(ph, f) for f in os.listdir(ph) if f.startswith("img_"))
    truth = tifffile.imread(os.path.join(ph, "truth_depth.tif"))

    def mt(tag, extra, env=None):
        o = os.path.join(tmp, "mt350_" + tag)
        dt, mem, _ = timed([CLI, "matirf", "--angles", ang13, "--z-range", "0,300,20", "--force", "-o", o] + extra + imgs, env)
        rep = json.load(open(os.path.join(o, "report.json")))["matirf"]
        rep["mem"], rep["cpu"] = mem, LAST_CPU[0]
        return dt, rep, tifffile.imread(os.path.join(o, "depth.tif"))

    def desc(r, d):
        return "%.1f CPU-s, %d its (+%d coarse), %s, rel. change %.1e, objective %.6g, depth err %.1f nm (signed %+.1f)" % (
            r["cpu"], r["iterations"], r.get("coarse_iterations", 0), "converged" if r["converged"] else "NOT converged",
            r["final_relative_change"], r["objective"], np.median(np.abs(d - truth)), np.median(d - truth))
    if psf_only:
        matirf_psf(tmp, ang13, mt, desc, imgs, truth)
        return

    # apg with the coarse start (the default) against the previous defaults:
    # apg cold (TV), diag (TV before that) and exact (Hessian), measured in
    # the same run, interleaved twice (the faster of each)
    runs = {"diag": ["--matirf-solver", "diag"], "exact": ["--matirf-solver", "exact"],
            "apg cold": ["--matirf-solver", "apg", "--matirf-coarse", "0"], "apg": []}
    best = {}
    for rnd in range(2):
        for tag, extra in runs.items():
            dt, rep, dep = mt(tag.replace(" ", "_"), extra)
            if tag not in best or dt < best[tag][0]:
                best[tag] = (dt, rep, dep)
    tb, rb, db = best["diag"]   # the baseline: the default with TV two steps back
    tc, rc, dc = best["apg cold"]

    for what, tag in (("diag solver (default with TV before apg; baseline)", "diag"),
                      ("exact solver (previous default with the Hessian)", "exact"),
                      ("apg solver, cold start (previous default)", "apg cold"),
                      ("apg solver, 2-level coarse start (default)", "apg")):
        t, r, d = best[tag]
        cmp = "" if tag == "diag" else "%.2fx faster (%.2fx CPU) than diag; depth vs diag: median %.2f nm" % (
            tb / t, rb["cpu"] / r["cpu"], np.median(np.abs(d - db)))
        if tag == "apg":
            cmp += "; %.2fx CPU less than apg cold, depth vs it: median %.2f nm" % (rc["cpu"] / r["cpu"], np.median(np.abs(d - dc)))
        row("matirf, 350x350 phantom, " + what, "350x350x15 x13", t, desc(r, d), r["mem"], cmp)
    t1, t2 = [], []
    for rnd in range(2):   # interleaved
        t1.append(mt("t1", [], {"OMP_NUM_THREADS": "1"})[0])
        t2.append(mt("t2", [], {"OMP_NUM_THREADS": "2"})[0])
    row("matirf apg (default), OMP_NUM_THREADS 1 vs 2", "350x350x15 x13", min(t2), "1 thread %.2f s" % min(t1),
        best["apg"][1]["mem"], "%.2fx speed-up" % (min(t1) / min(t2)))
    base = None
    for solver in ("exact", "apg"):
        t, r, d = mt("hessian_" + solver, ["--reg", "hessian", "--matirf-solver", solver])
        row("matirf Hessian-Schatten, %s solver" % solver, "350x350x15 x13", t, desc(r, d), r["mem"],
            "%.2fx faster (%.2fx CPU) than exact; depth vs exact: median %.2f nm" %
            (base[0] / t, base[1]["cpu"] / r["cpu"], np.median(np.abs(d - base[2]))) if base else "baseline")
        base = base or (t, r, d)
    matirf_psf(tmp, ang13, mt, desc, imgs, truth)


def matirf_psf(tmp, ang13, mt, desc, imgs, truth):
    # deconvolution (issue 33): the phantom blurred by a 240 nm PSF, with a grid
    # of fine lines for the blur to take away; plain apg against apg with
    # --psf-fwhm at its default kappa (1e-3 with --psf-fwhm, issue 33 item 3),
    # at the plain default kappa 0.03 (the same problem's regularisation: the
    # solver's cost) and against diag with it (the solver --psf-fwhm took
    # before), each the faster of two interleaved runs
    import tifffile
    phb = os.path.join(tmp, "phantom350_blur")
    os.mkdir(phb)
    subprocess.run([os.path.join(BUILD, "bench", "matirf_phantom"), "--blur", "240", phb, "350", "0.03"] + ang13.split(","),
                   check=True)
    imgs[:] = sorted(os.path.join(phb, f) for f in os.listdir(phb) if f.startswith("img_"))
    truth[...] = tifffile.imread(os.path.join(phb, "truth_depth.tif"))

    def detail(o):   # fine-detail energy of the sum over depth: its squared Laplacian
        t = tifffile.imread(os.path.join(o, "volume.tif")).sum(axis=0)
        return float(((4 * t[1:-1, 1:-1] - t[:-2, 1:-1] - t[2:, 1:-1] - t[1:-1, :-2] - t[1:-1, 2:]) ** 2).sum())
    psf = ["--psf-fwhm", "240", "--pixel-size", "100"]
    runs = {"plain": [], "psf": psf, "psf k0.03": psf + ["--kappa", "0.03"],
            "psf diag": psf + ["--kappa", "0.03", "--matirf-solver", "diag"]}
    best = {}
    for rnd in range(2):
        for tag, extra in runs.items():
            t = "b_" + tag.replace(" ", "_")
            dt, rep, dep = mt(t, extra)
            rep["detail"] = detail(os.path.join(tmp, "mt350_" + t))
            if tag not in best or rep["cpu"] < best[tag][1]["cpu"]:
                best[tag] = (dt, rep, dep)
    tp, rp, dp = best["plain"]
    for what, tag in (("plain apg (baseline, kappa 0.03)", "plain"), ("apg with --psf-fwhm 240 (default, kappa 1e-3)", "psf"),
                      ("apg with --psf-fwhm 240, kappa 0.03", "psf k0.03"),
                      ("diag with --psf-fwhm 240, kappa 0.03 (before)", "psf diag")):
        t, r, d = best[tag]
        row("matirf, 350x350 phantom blurred by 240 nm, " + what, "350x350x15 x13", t,
            desc(r, d) + ", detail %.3g" % r["detail"], r["mem"],
            "" if tag == "plain" else "%.2fx the plain CPU, %.2fx its fine detail" % (r["cpu"] / rp["cpu"], r["detail"] / rp["detail"]))

def support_row(what, d, w, T, extra=(), env=None, base=None, vs="the baseline"):
    """one 'support' run on d/stack_q01.tif; returns its seconds"""
    o = os.path.join(d, "out_" + "_".join(what.split()))
    cmd = [CLI, "support", "--fwhm", "229", "--pixel-size", "100", "--force", "-o", o, *extra,
           os.path.join(d, "stack_q01.tif")]
    l0 = load()
    dt, mem, _ = timed(cmd, env)
    rep = json.load(open(os.path.join(o, "report.json")))
    s = rep["support"][0]
    row(what, "%dx%dx%d r4" % (w, w, T), dt,
        "%d tiles, %d its max, %s; cov %.0f fr/s; %d thr; %s" % (s["tiles"], s["iterations"],
                                                                "converged" if s["converged"] else "cap",
                                                                s["covariance_frames_per_s"], rep["threads"], l0),
        mem, "%.2fx %s" % (base / dt, vs) if base else "baseline" if base is None else "no baseline (one tile: ~12 GB)")
    return dt


def large(tmp):
    # support on whole frames: tiles (default) against one tile (today's path)
    for w, T, with_base in ((1024, 500, True), (2048, 200, False)):
        d = os.path.join(tmp, "L%d" % w)
        sim(d, w, T)
        base = support_row("support, one tile (baseline)", d, w, T, ("--tile", str(w))) if with_base else 0
        tdef = support_row("support, tiles (default)", d, w, T, base=base)
        support_row("support, tiles, --support-solver pruned", d, w, T, ("--support-solver", "pruned", "--iterations", "8000"),
                    base=tdef, vs="the fista tiles row")
        if w == 1024:
            # thread scaling and a busy neighbour (the passive wait policy vs spinning threads)
            t1 = support_row("support, tiles, 1 thread", d, w, T, ("--threads", "1"))
            support_row("support, tiles, 2 threads", d, w, T, ("--threads", "2"), base=t1)
            busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
            try:
                tb = support_row("support, next to a busy process, spinning (OMP_WAIT_POLICY=ACTIVE)", d, w, T,
                                 env={"OMP_WAIT_POLICY": "ACTIVE"})
                support_row("support, next to a busy process, passive (default)", d, w, T, base=tb)
            finally:
                busy.kill()
                busy.wait()
        shutil.rmtree(d)
    # the whole method on 5 angles of 512x512x500
    d = os.path.join(tmp, "R512")
    sim(d, 512, 500, angles="62,63.5,65,66.5,68")
    stacks = [os.path.join(d, "stack_q%02d.tif" % q) for q in range(1, 6)]
    base = None
    # --tile 512: one tile for the support and the intensity (the whole-frame paths)
    for what, extra in (("run, one tile (baseline)", ("--tile", "512")), ("run, tiles (default)", ())):
        o = os.path.join(tmp, "run_" + what.split(",")[1].split()[0])
        l0 = load()
        dt, mem, _ = timed([CLI, "run", "--fwhm", "229", "--angles", "62,63.5,65,66.5,68", "-o", o, *extra] + stacks)
        ts = json.load(open(os.path.join(o, "report.json")))["timings_s"]
        row(what, "5 x 512x512x500 r4", dt, "drift %.0f s, support %.0f s, intensity %.0f s, bleaching %.1f s, matirf %.0f s; %s"
            % (ts.get("drift", 0), ts["support"], ts["intensity"], ts["bleaching"], ts["matirf"], l0), mem,
            "%.2fx the baseline" % (base / dt) if base else "baseline")
        base = base or dt


def table():
    widths = [max(len(str(r[i])) for r in rows + [("stage", "size", "time s", "throughput", "peak MiB", "ratio")]) for i in range(6)]
    hdr = ("stage", "size", "time s", "throughput", "peak MiB", "ratio")
    print(" | ".join(h.ljust(w) for h, w in zip(hdr, widths)))
    print("-+-".join("-" * w for w in widths))
    for r in rows:
        print(" | ".join(str(c).ljust(w) for c, w in zip(r, widths)))


def matirf_example(tmp, d):
    # the authors' public 13-angle example (esoubies/MA-TIRF_Reconstruction,
    # Example/: not in this repository; DIR holds its 13 images as
    # img_qNN.tif and their angles in degrees, comma-separated, in
    # angles.txt) at their settings: the default tolerance against a tight
    # solve (5e-5), CPU seconds and the median depth difference (issue 55:
    # <= 9 CPU-s, <= 5 nm)
    import numpy as np
    import tifffile
    imgs = sorted(os.path.join(d, f) for f in os.listdir(d) if f.startswith("img_q"))
    ang = open(os.path.join(d, "angles.txt")).read().strip()
    base = [CLI, "matirf", "--angles", ang, "--n-sample", "1.34", "--wavelength", "491", "--pixel-size", "106",
            "--z-range", "0,300,20", "--offset", "200", "--psf-fwhm", "221", "--kappa", "5e-4", "--sparsity", "0", "--force"]
    res = {}
    for tag, extra in (("tight", ["--matirf-tol", "5e-5", "--matirf-iterations", "30000"]), ("default", []),
                       ("plain", None)):
        o = os.path.join(tmp, "ex_" + tag)
        cmd = base + (extra or []) + ["-o", o] + imgs
        if extra is None:   # the same without the PSF
            cmd = [c for c in cmd if c not in ("--psf-fwhm", "221")]
        dt, mem, _ = timed(cmd)
        rep = json.load(open(os.path.join(o, "report.json")))["matirf"]
        res[tag] = (dt, LAST_CPU[0], mem, rep, tifffile.imread(os.path.join(o, "depth.tif")))
    ref = res["tight"][4]
    for tag, what in (("tight", "tolerance 5e-5 (the converged answer)"), ("default", "default tolerance"),
                      ("plain", "no PSF (the plain solve)")):
        dt, cpu, mem, rep, dep = res[tag]
        row("matirf, the authors' example, --psf-fwhm 221, " + what if tag != "plain" else "matirf, the authors' example, " + what,
            "350x350x15 x13", dt, "%.1f CPU-s, %d its (+%d coarse), objective %.6g" % (
                cpu, rep["iterations"], rep.get("coarse_iterations", 0), rep["objective"]), mem,
            "depth vs the converged: median %.2f nm; %.2fx the plain CPU" % (
                np.median(np.abs(dep - ref)), cpu / res["plain"][1]))


if "--matirf-example" in sys.argv:   # the authors' example only: --matirf-example DIR
    with tempfile.TemporaryDirectory() as tmp:
        matirf_example(tmp, sys.argv[sys.argv.index("--matirf-example") + 1])
    table()
    sys.exit(0)

if "--matirf350" in sys.argv or "--matirf-psf" in sys.argv:   # only the MA-TIRF rows at the public example's size
    with tempfile.TemporaryDirectory() as tmp:
        matirf350(tmp, "--matirf350" not in sys.argv)
    table()
    sys.exit(0)

def lambda_rows(tmp):
    # the automatic lambda's cost, per rule (stages/lambda.c, lambda_cv.c): the
    # whole command against the same command with the chosen lambda given
    # (drift and FRC off in both), the faster of two interleaved runs each
    for w, T in ((64, 500), (256, 1000)):
        d = os.path.join(tmp, "l%d" % w)
        sim(d, w, T)
        size = "%dx%dx%d r4" % (w, w, T)
        for rule in ("noise", "peaks", "cv"):
            base = ["--fwhm", "229", "--pixel-size", "100", "--no-drift", "--frc", "0", "--lambda-rule", rule,
                    "--force", os.path.join(d, "stack_q01.tif")]
            best = {}
            for rnd in range(2):
                dt, mem, _ = timed([CLI, "support", *base, "-o", d + "a"])
                la = json.load(open(os.path.join(d + "a", "report.json")))["support"][0]
                if "a" not in best or dt < best["a"][0]:
                    best["a"] = (dt, mem, la)
                dt, mem, _ = timed([CLI, "support", *base, "--lambda", "%.17g" % la["lambda_relative"], "-o", d + "f"])
                lf = json.load(open(os.path.join(d + "f", "report.json")))["support"][0]
                if "f" not in best or dt < best["f"][0]:
                    best["f"] = (dt, mem, lf)
            (ta, ma, la), (tf, mf, lf) = best["a"], best["f"]
            row("support, lambda given (the %s rule's choice)" % rule, size, tf,
                "solve %.2f s, %d its" % (lf["solve_s"], lf["iterations"]), mf)
            cv = la["lambda_auto"].get("cross_validation")
            how = ("path %.2f s: %d points x 2 halves x %d its; " % (cv["seconds"], len(cv["error"]), cv["iterations"])
                   if cv else "rule %.2f s; " % la["lambda_auto"]["seconds"])
            row("support, lambda automatic (%s)" % rule, size, ta, how + "chose %.3g" % la["lambda_relative"], ma,
                "%.2fx given (%.2f fixed-lambda solves)" % (ta / tf, 1 + (ta - tf) / max(lf["solve_s"], 1e-9)))


if "--lambda" in sys.argv:
    with tempfile.TemporaryDirectory() as tmp:
        lambda_rows(tmp)
    table()
    sys.exit(0)

if LARGE_ONLY:   # only the whole-frame rows
    with tempfile.TemporaryDirectory() as tmp:
        large(tmp)
    table()
    sys.exit(0)

with tempfile.TemporaryDirectory() as tmp:
    if LARGE:
        large(tmp)
    # simulate: the default dataset (5 angles x 500 frames x 64x64)
    d = os.path.join(tmp, "sim64")
    dt, mem, _ = timed([CLI, "simulate", "-o", d])
    row("simulate (default)", "5 x 64x64x500", dt, "%.0f frames/s" % (2500 / dt), mem)

    # support: dense reference formulation vs ours on the same 20x20 stack
    d20 = os.path.join(tmp, "s20")
    sim(d20, 20, 500)
    its = 2 if QUICK else 5
    dt, mem, out = timed([os.path.join(BUILD, "bench", "dense_baseline"), os.path.join(d20, "stack_q01.tif"), "100", "229", "4", str(its)])
    dense_it = float(out.split()[0])
    row("support, dense (reference formulation)", "20x20x500 r4", dense_it, "per iteration", mem)
    o = os.path.join(tmp, "o20")
    dt, mem, _ = timed([CLI, "support", "--fwhm", "229", "--pixel-size", "100", "-o", o, os.path.join(d20, "stack_q01.tif")])
    rep = json.load(open(os.path.join(o, "report.json")))["support"][0]
    ours_it = rep["solve_s"] / max(rep["iterations"], 1)
    row("support, banded (col0rme)", "20x20x500 r4", ours_it, "per iteration", mem, "%.0fx faster" % (dense_it / ours_it))

    cases = [(64, 500)] + ([] if QUICK else [(256, 1000)])
    for w, T in cases:
        d = os.path.join(tmp, "s%d" % w)
        sim(d, w, T)
        o = os.path.join(tmp, "o%d" % w)
        dt, mem, _ = timed([CLI, "support", "--fwhm", "229", "--pixel-size", "100", "-o", o, os.path.join(d, "stack_q01.tif")])
        rep = json.load(open(os.path.join(o, "report.json")))["support"][0]
        row("support, whole command", "%dx%dx%d r4" % (w, w, T), dt,
            "%.0f frames/s cov; %d its, %.1f ms/it" % (rep["covariance_frames_per_s"], rep["iterations"],
                                                       1e3 * rep["solve_s"] / max(rep["iterations"], 1)), mem,
            "%.0fx dense per it" % (dense_it / (rep["solve_s"] / max(rep["iterations"], 1))))
        # the automatic lambda against the same command with lambda given
        # (drift and FRC off in both: their own rows below)
        mem_def = mem
        base = ["--fwhm", "229", "--pixel-size", "100", "--no-drift", "--frc", "0"]
        dt_fix, mem, _ = timed([CLI, "support", *base, "--lambda", "1e-2", "-o", o + "f", os.path.join(d, "stack_q01.tif")])
        row("support, lambda 1e-2 given", "%dx%dx%d r4" % (w, w, T), dt_fix, "", mem)
        # the l1 solvers on the same problem: the default (fista, capped) is the baseline
        for what, extra in (("fista (default, baseline)", ["--support-solver", "fista"]),
                            ("pruned, to convergence", ["--support-solver", "pruned", "--iterations", "8000"])):
            dts, mem, _ = timed([CLI, "support", *base, "--lambda", "1e-2", *extra, "--force", "-o", o + "s",
                                 os.path.join(d, "stack_q01.tif")])
            ls = json.load(open(os.path.join(o + "s", "report.json")))["support"][0]
            cpu = LAST_CPU[0]
            if what.startswith("fista"):
                cpu_f = cpu
            row("support solver " + what, "%dx%dx%d r4" % (w, w, T), dts,
                "%.1f CPU-s, %d its, %s, gap %.2g, %d pixels" % (cpu, ls["iterations"], "converged" if ls["converged"]
                                                                  else "cap", ls["duality_gap"], ls["support_pixels"]),
                mem, "%.2fx fista's CPU-s" % (cpu / cpu_f))
        dt_auto, mem, _ = timed([CLI, "support", *base, "-o", o + "a", os.path.join(d, "stack_q01.tif")])
        la = json.load(open(os.path.join(o + "a", "report.json")))["support"][0]
        row("support, lambda automatic", "%dx%dx%d r4" % (w, w, T), dt_auto,
            "chose %.3g in %.2f s" % (la["lambda_relative"], la["lambda_auto"]["seconds"]), mem,
            "%.2fx lambda given" % (dt_auto / dt_fix))
        dt_d, mem, _ = timed([CLI, "support", *base[:-3], "--frc", "0", "-o", o + "d", os.path.join(d, "stack_q01.tif")])
        ld = json.load(open(os.path.join(o + "d", "report.json")))
        row("support, lambda automatic + drift", "%dx%dx%d r4" % (w, w, T), dt_d,
            "drift estimate %.2f s" % ld["drift"]["seconds"], mem, "%.2fx lambda given" % (dt_d / dt_fix))
        row("support, defaults (+ FRC halves)", "%dx%dx%d r4" % (w, w, T), dt,
            "FRC %.2f s" % rep["frc"]["seconds"], mem_def, "%.2fx lambda given" % (dt / dt_fix))

    # the whole method on the default demo data (5 angles, fine grid 256x256)
    d = os.path.join(tmp, "sim64")
    ang = ",".join("%.6g" % a for a in json.load(open(os.path.join(d, "sim.json")))["parameters"]["angles_deg"])
    o = os.path.join(tmp, "run64")
    stacks = [os.path.join(d, "stack_q%02d.tif" % q) for q in range(1, 6)]
    dt, mem, _ = timed([CLI, "run", "--fwhm", "229", "--angles", ang, "-o", o] + stacks)
    ts = json.load(open(os.path.join(o, "report.json")))["timings_s"]
    row("run (3D-COL0RME), whole command", "5 x 64x64x500 r4", dt,
        "support %.1f s, intensity %.1f s, matirf %.1f s" % (ts["support"], ts["intensity"], ts["matirf"]), mem)
    sparse_mt = ts["matirf"]

    # MA-TIRF on 256x256 x 20 bins x 5 angles, every pixel solved for: a
    # dense phantom made with the library's TIRF model (3 % noise; median
    # depth error against its truth), and random images that fit no depth
    # profile (a worst case for the solver), vs the pipeline's sparse case
    if not QUICK:
        import numpy as np
        import tifffile
        ph = os.path.join(tmp, "phantom")
        os.mkdir(ph)
        subprocess.run([os.path.join(BUILD, "bench", "matirf_phantom"), ph, "256", "0.03"] + ang.split(","), check=True)
        rng = np.random.default_rng(1)
        rnd = []
        for q in range(5):
            f = os.path.join(tmp, "random_q%d.tif" % q)
            tifffile.imwrite(f, (rng.random((256, 256)) * np.exp(-0.3 * q) + 0.1).astype(np.float32))
            rnd.append(f)
        for what, imgs in (("dense phantom", sorted(os.path.join(ph, f) for f in os.listdir(ph) if f.startswith("img_"))),
                           ("random images", rnd)):
            o = os.path.join(tmp, "mt_" + what.split()[0])
            dt, mem, _ = timed([CLI, "matirf", "--angles", ang, "-o", o] + imgs)
            rep = json.load(open(os.path.join(o, "report.json")))["matirf"]
            thr = "%d its, %.1f ms/it" % (rep["iterations"], 1e3 * rep["seconds"] / rep["iterations"])
            if what == "dense phantom":
                err = np.abs(tifffile.imread(os.path.join(o, "depth.tif")) - tifffile.imread(os.path.join(ph, "truth_depth.tif")))
                thr += ", depth err %.1f nm" % np.median(err)
            row("matirf, " + what, "256x256x20 x5", dt, thr, mem, "%.1fx the sparse pipeline case" % (rep["seconds"] / sparse_mt))

    if not QUICK:
        matirf350(tmp)

    if not QUICK:
        # intensity of one 256x256 angle on its support
        o = os.path.join(tmp, "int256")
        dt, mem, _ = timed([CLI, "intensity", "--fwhm", "229", "--pixel-size", "100", "--support",
                            os.path.join(tmp, "o256", "support.tif"), "-o", o, os.path.join(tmp, "s256", "stack_q01.tif")])
        rep = json.load(open(os.path.join(o, "report.json")))["intensity"][0]
        row("intensity, noise variance estimated", "256x256x1000 r4", dt,
            "%d solves, %d CG its" % (rep["solves"], rep["cg_iterations"]), mem)
        # as in 'run': the support step has already measured the noise variance
        s2 = json.load(open(os.path.join(tmp, "o256", "report.json")))["support"][0]["noise_variance"]
        o = os.path.join(tmp, "int256b")
        dt, mem, _ = timed([CLI, "intensity", "--fwhm", "229", "--pixel-size", "100", "--noise-variance", repr(s2),
                            "--support", os.path.join(tmp, "o256", "support.tif"), "-o", o,
                            os.path.join(tmp, "s256", "stack_q01.tif")])
        rep = json.load(open(os.path.join(o, "report.json")))["intensity"][0]
        row("intensity, noise variance from support", "256x256x1000 r4", dt,
            "%d solves, %d CG its" % (rep["solves"], rep["cg_iterations"]), mem)

table()
