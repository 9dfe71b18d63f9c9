"""What a user finds by trying bad data (issue 15), through the CLI:
every refusal is one line naming the file or option and the value, comes
before the heavy work, and leaves OUTDIR as it was; outputs are a
transaction (a failed or killed --force rerun keeps the previous set whole);
multi-channel files are read as one stack per channel; the ImageJ
calibration of the outputs is what Fiji shows; running out of memory is
one line naming the step and the size, and leaves no output (issue 36).

usage: test_robust.py COL0RME [full|quick]   (quick: the sanitizer build, no memory limit)
"""
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import tifffile

from checks import LINES_SIM, check, done, refused

CLI = sys.argv[1]
MODE = sys.argv[2] if len(sys.argv) > 2 else "full"


def cli(*args, **kw):
    return subprocess.run([CLI, *args], capture_output=True, text=True, **kw)


def fade_warning_off(p):
    """p without the bleaching warning: short test stacks never show a fade, and
    the run says so on stderr (bleaching.rate_significant); other lines are kept"""
    err = "".join(l for l in p.stderr.splitlines(True) if "warning: bleaching:" not in l)
    return subprocess.CompletedProcess(p.args, p.returncode, p.stdout, err)


def digest(d):
    """the files of a directory and their contents"""
    return {f: open(os.path.join(d, f), "rb").read() for f in sorted(os.listdir(d))}


def staging_left(parent):
    return [f for f in os.listdir(parent) if ".c0tmp-" in f or ".c0old-" in f or ".tmp" in f]


def simulate(tmp, name, w, h, frames, angles="62,66"):
    """small stacks for the refusals; lines (LINES_SIM): on a 16x16 field of the default's labelled
    tubes the covariance's lags read a PSF of 190 nm, and its warning would be a second line"""
    d = os.path.join(tmp, name)
    p = cli("simulate", "-o", d, "--width", str(w), "--height", str(h), "--frames", str(frames), "--angles", angles,
            *LINES_SIM)
    check(p.returncode == 0, "simulate %s: %s" % (name, p.stderr))
    return [os.path.join(d, "stack_q%02d.tif" % q) for q in range(1, len(angles.split(",")) + 1)]


def test_validation(tmp, s16, s20):
    """(a) sizes, (b) FWHM, (c) pixel size, (d) messages, (i) NA and iterations: all before any work"""
    out = os.path.join(tmp, "v_out")
    base = ["run", "--fwhm", "229", "--angles", "62,66", "-o", out]
    t = time.time()
    # --verbose prints a progress line per stage: the refusal is the only line, so no work began
    check(refused(cli(*base, "--verbose", s16[0], s20[1]), "stack_q02.tif", "20x16", "16x16"),
          "(a) run: stacks of different sizes, before any work")
    check(refused(cli("support", "--verbose", "--fwhm", "229", "-o", out, s16[0], s20[1]), "20x16"),
          "(a) support: sizes checked before the first stack's solve")
    check(refused(cli("intensity", "--verbose", "--fwhm", "229", "--support", s16[0], "-o", out, s16[0], s20[1]), "20x16"),
          "(a) intensity: sizes checked first")
    check(refused(cli("simulate", "--brightness", "inf", "-o", out), "inf", "finite"), "(i) simulate: infinite parameter")
    mask = os.path.join(tmp, "mask.tif")
    tifffile.imwrite(mask, (np.arange(256).reshape(16, 16) % 7 == 0).astype(np.uint8))
    check(refused(cli("eval", "--support", mask, "--support-truth", mask, "--pixel-size", "100", "--radius", "inf"),
                  "radius inf"), "(i) eval: infinite matching radius")
    check(refused(cli("run", "--fwhm", "inf", "--angles", "62,66", "-o", out, *s16), "--fwhm inf"), "(b) --fwhm inf")
    check(refused(cli("run", "--fwhm", "1e12", "--angles", "62,66", "-o", out, *s16), "--fwhm 1e+12"), "(b) --fwhm 1e12")
    for v in ("0", "-1", "inf"):
        check(refused(cli("run", "--pixel-size", v, *base[1:], *s16), "--pixel-size"), "(c) --pixel-size %s refused" % v)
        check(refused(cli("matirf", "--pixel-size", v, "--angles", "62,66", "-o", out, *s16), "--pixel-size"),
              "(c) matirf --pixel-size %s refused" % v)
    # calibrations that disagree, or one missing, without --pixel-size
    other = os.path.join(tmp, "cal80.tif")
    a = tifffile.imread(s16[1])
    tifffile.imwrite(other, a, imagej=True, resolution=(12.5, 12.5), metadata={"unit": "um"})
    check(refused(cli(*base, s16[0], other), "cal80.tif", "80 nm", "100 nm"), "(c) calibrations differ")
    check(cli(*base, "--pixel-size", "100", "--matirf-iterations", "50", s16[0], other).returncode == 0,
          "(c) --pixel-size overrides differing calibrations")
    shutil.rmtree(out, ignore_errors=True)
    p = cli("run", "--fwhm", "229", "--angles", "95,66", "-o", out, *s16)
    check(refused(p, "--angles: angle 95 deg is not between the critical angle"), "(d) message keeps the angle")
    check("--angles: --angles" not in p.stderr, "(d) message not garbled: %r" % p.stderr)
    check(refused(cli("run", "--emission", "510", "--na", "2", "--angles", "62,66", "-o", out, *s16), "--na 2", "--n-glass"),
          "(i) NA above the immersion index")
    check(refused(cli(*base, "--matirf-iterations", "0", *s16), "--matirf-iterations 0"), "(i) --matirf-iterations 0")
    check(refused(cli("support", "--fwhm", "229", "--iterations", "0", "-o", out, *s16), "--iterations 0"), "(i) --iterations 0")
    check(refused(cli(*base, "--kappa", "inf", *s16), "--kappa inf"), "(i) --kappa inf")
    check(refused(cli(*base, "--depth-pool", "inf", *s16), "--depth-pool inf"), "(i) --depth-pool inf")
    few = os.path.join(tmp, "two_frames.tif")
    tifffile.imwrite(few, tifffile.imread(s16[1])[:2])
    check(refused(cli(*base, "--verbose", "--pixel-size", "100", s16[0], few), "two_frames.tif", "2 frames"),
          "(a) too few frames in the second stack, before the first one's work")
    dt = time.time() - t
    check(not os.path.exists(out), "nothing written by refused runs")
    print("refusals: %.2f s for all of them (no solve ran)" % dt, file=sys.stderr)


def test_nonfinite(tmp, s16):
    """(e) NaN/Inf pixels refused naming file, frame and pixel; huge values never become NaN outputs"""
    a = tifffile.imread(s16[0]).astype(np.float32)
    out = os.path.join(tmp, "nf_out")
    base = ["run", "--fwhm", "229", "--pixel-size", "100", "--angles", "62,66", "--no-drift", "-o", out]   # the writer's check, not the drift's
    for what, v in (("NaN", np.nan), ("+infinity", np.inf)):
        b = a.copy()
        b[7, 3, 5] = v
        f = os.path.join(tmp, "bad_%s.tif" % what.strip("+"))
        tifffile.imwrite(f, b)
        check(refused(cli(*base, s16[1], f), os.path.basename(f), "frame 8", "x 5, y 3", what),
              "(e) %s pixel refused naming file, frame and pixel" % what)
    b = a.copy()
    b[7, 3, 5] = 3e38
    f = os.path.join(tmp, "huge.tif")
    tifffile.imwrite(f, b)
    p = cli(*base, f, s16[1])
    # refused when writing a non-finite plane, or earlier when the covariance overflows
    check(refused(p, ".tif: plane", "not written") or refused(p, "huge.tif", "not finite"),
          "(e) 3e38 pixel: no NaN output written silently")
    check(not os.path.exists(out) and not staging_left(tmp), "(e) nothing left by the refused run")
    info = cli("info", "--json", os.path.join(tmp, "bad_NaN.tif"))
    check(info.returncode == 0, "info still describes a file with NaN: %s" % info.stderr)


def test_transaction(tmp, s16, big):
    """(f) a failing or killed --force rerun leaves the previous set whole; stale staging is cleaned"""
    out = os.path.join(tmp, "tx_out")
    fast = ["--matirf-iterations", "100"]
    p = cli("run", "--fwhm", "229", "--angles", "62,66", *fast, "-o", out, *s16)
    check(p.returncode == 0, "first run: %s" % p.stderr)
    before = digest(out)
    bad = os.path.join(tmp, "bad_NaN.tif")
    p = cli("run", "--fwhm", "229", "--pixel-size", "100", "--angles", "62,66", "--force", "-o", out, s16[0], bad)
    check(p.returncode != 0 and digest(out) == before, "(f) failed --force rerun: previous result intact")
    huge = os.path.join(tmp, "huge.tif")
    p = cli("run", "--fwhm", "229", "--pixel-size", "100", "--angles", "62,66", "--force", "-o", out, huge, s16[1])
    check(p.returncode != 0 and digest(out) == before, "(f) --force rerun failing while writing: previous result intact")
    check(not staging_left(tmp), "(f) no staging left: %s" % staging_left(tmp))
    # killed in the middle of the work
    proc = subprocess.Popen([CLI, "run", "--fwhm", "229", "--angles", "62,66", "--force", "-o", out, *big],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 30
    while time.time() < deadline and not any(".c0tmp-" in f for f in os.listdir(tmp)):
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    proc.wait()
    check(proc.returncode != 0 and digest(out) == before, "(f) SIGTERM: previous result intact")
    check(not staging_left(tmp), "(f) SIGTERM: staging removed: %s" % staging_left(tmp))
    proc = subprocess.Popen([CLI, "run", "--fwhm", "229", "--angles", "62,66", "--force", "-o", out, *big],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 30
    while time.time() < deadline and not any(".c0tmp-" in f for f in os.listdir(tmp)):
        time.sleep(0.05)
    proc.kill()   # SIGKILL: nothing can clean up, the next run does
    proc.wait()
    check(any(".c0tmp-" in f for f in os.listdir(tmp)), "(f) SIGKILL leaves a staging directory")
    with open(os.path.join(out, "mine.txt"), "w") as f:
        f.write("old\n")
    p = cli("run", "--fwhm", "229", "--angles", "62,66", *fast, "--force", "-o", out, *s16)
    check(p.returncode == 0, "rerun: %s" % p.stderr)
    check(not staging_left(tmp), "(f) the next run removed the dead run's staging: %s" % staging_left(tmp))
    check(sorted(digest(out)) == sorted(before), "(f) --force replaced the old set as a whole (extra file gone)")
    # killed between moving the old result aside and the new one in: the next run puts it back
    dead = subprocess.Popen(["true"])
    dead.wait()
    lost = os.path.join(tmp, "lost_out")
    os.makedirs(lost + ".c0old-%d" % dead.pid)
    with open(os.path.join(lost + ".c0old-%d" % dead.pid, "report.json"), "w") as f:
        f.write("{}\n")
    p = cli("run", "--fwhm", "229", "--angles", "62,66", "-o", lost, *s16)
    check(refused(p, "not empty") and os.listdir(lost) == ["report.json"] and not staging_left(tmp),
          "(f) a result moved aside by a killed swap is restored, not deleted")
    os.makedirs(os.path.join(out, "sub"))
    check(refused(cli("run", "--fwhm", "229", "--angles", "62,66", "--force", "-o", out, *s16), "sub"),
          "(f) --force refuses a directory holding a directory")


def test_channels(tmp, s16):
    """(g) a 2-channel ImageJ hyperstack and an OME file give the same result as the separate stacks"""
    a, b = (tifffile.imread(s).astype(np.uint16) for s in s16)
    hyper = os.path.join(tmp, "hyper.tif")
    tifffile.imwrite(hyper, np.stack([a, b], axis=1), imagej=True, resolution=(10, 10),
                     metadata={"axes": "TCYX", "unit": "um"})
    ome = os.path.join(tmp, "multi.ome.tif")
    tifffile.imwrite(ome, np.stack([a, b], axis=0), ome=True,
                     metadata={"axes": "CTYX", "PhysicalSizeX": 0.1, "PhysicalSizeY": 0.1})
    series = os.path.join(tmp, "series.ome.tif")   # one OME image series per angle
    with tifffile.TiffWriter(series, ome=True) as tw:
        for x in (a, b):
            tw.write(x, metadata={"axes": "TYX", "PhysicalSizeX": 0.1, "PhysicalSizeY": 0.1})
    fast = ["--fwhm", "229", "--angles", "62,66", "--matirf-iterations", "200"]
    ref = os.path.join(tmp, "ch_ref")
    check(cli("run", *fast, "-o", ref, *s16).returncode == 0, "separate stacks run")
    for name, f in (("ImageJ", hyper), ("OME", ome), ("OME-series", series)):
        o = os.path.join(tmp, "ch_" + name)
        p = cli("run", *fast, "-o", o, f)
        check(p.returncode == 0, "(g) %s 2-channel file runs: %s" % (name, p.stderr))
        if p.returncode:
            continue
        same = all(np.array_equal(tifffile.imread(os.path.join(o, n)), tifffile.imread(os.path.join(ref, n)))
                   for n in ("support.tif", "intensity_q01.tif", "intensity_q02.tif", "volume.tif"))
        check(same, "(g) %s channels read as the angles, in order (outputs identical)" % name)
        info = json.loads(cli("info", "--json", f).stdout)
        check(info["channels"] == 2 and info["pages"] == 2 * a.shape[0], "(g) info shows 2 channels: %s" % info)
        text = cli("info", f).stdout
        check("read as 2 stacks" in text, "(g) info says how the channels are read")
    # one channel by --channel and by FILE:cK
    p = cli("support", "--fwhm", "229", "--channel", "2", "-o", os.path.join(tmp, "ch_sel"), hyper)
    check(p.returncode == 0, "(g) --channel 2: %s" % p.stderr)
    p = cli("support", "--fwhm", "229", "-o", os.path.join(tmp, "ch_spec"), hyper + ":c2")
    check(p.returncode == 0, "(g) FILE:c2: %s" % p.stderr)
    if p.returncode == 0:
        check(np.array_equal(tifffile.imread(os.path.join(tmp, "ch_sel", "rx.tif")),
                             tifffile.imread(os.path.join(tmp, "ch_spec", "rx.tif"))), "(g) --channel 2 = FILE:c2")
    check(refused(cli("support", "--fwhm", "229", "--channel", "3", "-o", os.path.join(tmp, "ch_bad"), hyper),
                  "--channel 3", "2 channels"), "(g) --channel beyond the file refused")


def test_outdir_messages(tmp, s16):
    """(i) an unreadable OUTDIR is 'not readable'; a full disk says 'No space left on device'"""
    locked = os.path.join(tmp, "locked")
    os.makedirs(locked)
    os.chmod(locked, 0)
    args = ["run", "--fwhm", "229", "--angles", "62,66", "-o", locked, *s16]
    if os.geteuid() == 0:   # root reads anything: ask as nobody (it needs to reach the program and the stacks)
        os.chmod(tmp, 0o777)
        p = subprocess.run(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", CLI, *args],
                           capture_output=True, text=True)
    else:
        p = cli(*args)
    if "Permission denied" in p.stderr and "stack" in p.stderr:
        print("skipped: the unprivileged user cannot read the test files", file=sys.stderr)
    else:
        check(refused(p, "not readable", "Permission denied"), "(i) mode-000 OUTDIR is 'not readable'")
    os.chmod(locked, 0o700)
    full = os.path.join(tmp, "full")
    os.makedirs(full)
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=48k", "tmpfs", full], capture_output=True).returncode:
        print("skipped: cannot mount a small tmpfs to fill (needs root)", file=sys.stderr)
        return
    try:
        p = fade_warning_off(cli("run", "--fwhm", "229", "--angles", "62,66", "--wavelength", "488", "--n-sample", "1.33",
                                 "-o", os.path.join(full, "out"), *s16))
        check(refused(p, "No space left on device"), "(i) disk full says 'No space left on device'")
        check(os.listdir(full) == [], "(i) nothing left on the full disk: %s" % os.listdir(full))
    finally:
        subprocess.run(["umount", full])


def test_calibration(tmp, s16):
    """the guide: outputs calibrated in µm (Fiji's unit), z spacing the bin width, slice 1 at 10 nm"""
    out = os.path.join(tmp, "cal_out")
    p = cli("run", "--fwhm", "229", "--angles", "62,66", "--matirf-iterations", "100", "-o", out, *s16)
    check(p.returncode == 0, "calibration run: %s" % p.stderr)
    if p.returncode:
        return
    vf = tifffile.TiffFile(os.path.join(out, "volume.tif"))
    md = vf.imagej_metadata
    x = vf.pages[0].tags["XResolution"].value
    check(md.get("unit") == "um", "volume.tif unit is um (Fiji shows µm): %s" % md)
    check(abs(x[1] / x[0] - 0.025) < 1e-6, "fine pixel 0.025 um = 25 nm: %s" % (x,))
    check(abs(md.get("spacing", 0) - 0.02) < 1e-9, "z spacing 0.02 um = the 20 nm bin width")
    z0 = -md.get("zorigin", 0) * md.get("spacing", 0) * 1000   # Fiji: z of slice k = (k - zorigin) * spacing
    check(abs(z0 - 10) < 1e-6, "first slice at its bin centre, 10 nm (zorigin %s)" % md.get("zorigin"))
    z = json.load(open(os.path.join(out, "report.json")))["z_nm"]
    check(abs(z[0] - z0) < 1e-6, "report z_nm[0] %s = Fiji's first slice %s" % (z[0], z0))
    s = tifffile.TiffFile(os.path.join(out, "support.tif"))
    check(s.imagej_metadata.get("unit") == "um", "support.tif in um")
    guide = open(os.path.join(os.path.dirname(__file__), "..", "..", "docs", "guide.md")).read()
    check("show them in nm" not in guide and "µm" in guide, "the guide says the calibration unit is µm")


def test_subcritical(tmp):
    """issue 30: a stack at or below the critical angle gets one warning line; a typo far below is refused"""
    s3 = simulate(tmp, "d3", 16, 16, 40, "62,66,70")
    out = os.path.join(tmp, "sub_out")
    fast = ["--fwhm", "229", "--matirf-iterations", "100", "--no-drift", "--wavelength", "488", "--n-sample", "1.33"]
    p = fade_warning_off(cli("run", *fast, "--angles", "60.5,66,70", "-o", out, *s3))   # critical angle 61.2 at 1.518/1.33
    warns = [l for l in p.stderr.splitlines() if "warning" in l]
    check(p.returncode == 0 and len(warns) == 1 and "60.5 deg" in warns[0] and "61.18 deg" in warns[0]
          and "support only" in warns[0], "sub-critical angle: one warning line (%r)" % p.stderr)
    rep = json.load(open(os.path.join(out, "report.json"))) if p.returncode == 0 else {}
    check([w for w in rep.get("warnings", []) if not w.startswith("bleaching:")] == [w.split("warning: ", 1)[1] for w in warns],
          "the warning is in report.json")
    p0 = cli("run", *fast, "--angles", "62,66,70", "-o", os.path.join(tmp, "sub_ok"), *s3)
    b = json.load(open(os.path.join(tmp, "sub_ok", "report.json")))["bleaching"] if p0.returncode == 0 else {}
    fw = [l for l in p0.stderr.splitlines() if "warning: bleaching:" in l]
    quiet = b.get("rate_significant", True) and b.get("rate_fit_per_frame", 0) >= 0   # a negative fit is clamped, and said
    check(len(fw) == (0 if quiet else 1) and (not fw or "bleach repeat" in fw[0]),
          "a fade the stacks do not show: one warning line on stderr, naming the remedy (%r)" % p0.stderr)
    p = fade_warning_off(p0)
    check(p.returncode == 0 and "warning" not in p.stderr, "TIRF angles: no warning (%r)" % p.stderr)
    bad = os.path.join(tmp, "sub_bad")
    check(refused(cli("run", *fast, "--angles", "45,66,70", "-o", bad, *s3), "--angles: 45 deg", "critical angle 61.18 deg"),
          "an angle under 0.8 of the critical one is refused")
    check(not os.path.exists(bad), "nothing written for the refused angle")
def matirf_images(tmp, stacks):
    """one 2D image per angle: each stack's mean less the camera offset"""
    imgs = []
    for q, s in enumerate(stacks):
        f = os.path.join(tmp, "mean_q%02d.tif" % (q + 1))
        tifffile.imwrite(f, tifffile.imread(s).astype(np.float32).mean(axis=0) - 100)
        imgs.append(f)
    return imgs


def solver_of(out):
    return json.load(open(os.path.join(out, "report.json")))["matirf"]["solver"]


def test_matirf_psf(tmp, big):
    """issue 33: with --psf-fwhm an explicit --matirf-solver is obeyed (all three model the blur) and auto
    stays its documented apg, quietly"""
    imgs = matirf_images(tmp, big)
    out = os.path.join(tmp, "psf_out")
    base = ["matirf", "--angles", "62,66", "--pixel-size", "100", "--matirf-iterations", "200", "-o", out]
    for s in ("apg", "exact", "diag"):
        p = cli(*base, "--force", "--psf-fwhm", "240", "--matirf-solver", s, *imgs)
        check(p.returncode == 0 and solver_of(out) == s and "auto" not in p.stderr,
              "matirf --matirf-solver %s --psf-fwhm runs %s: %r" % (s, s, p.stderr))
    for extra in ([], ["--psf-fwhm", "240"]):
        p = cli(*base, "--force", *extra, *imgs)
        check(p.returncode == 0 and solver_of(out) == "apg" and "auto" not in p.stderr,
              "auto %s: apg, quietly" % " ".join(extra))
    # bad FWHMs: one line naming --psf-fwhm before the solve (1200 nm = 12 px, over a quarter of 40 px)
    bad = os.path.join(tmp, "psf_bad")
    for v, why in (("-5", "positive"), ("nan", "number"), ("inf", "finite"), ("1200", "quarter of the 40x40 field")):
        check(refused(cli(*base[:-1], bad, "--matirf-solver", "diag", "--psf-fwhm", v, *imgs), "--psf-fwhm", why),
              "--psf-fwhm %s refused naming it" % v)
    check(not os.path.exists(bad), "nothing written by the refused FWHMs")


def test_out_of_memory(tmp, big):
    """issue 36: run under address-space limits rising from below what the program needs to load to above
    what the run needs; each run either completes or fails with one line naming the step and the size it
    asked for, a non-zero exit and no output folder (nor a staging one). One thread and one malloc arena
    keep the need small and about the same on any machine (~35 MB on 40x40x200)."""
    parent = os.path.join(tmp, "oom")
    os.mkdir(parent)
    out = os.path.join(parent, "out")
    env = dict(os.environ, OMP_NUM_THREADS="1", MALLOC_ARENA_MAX="1")
    said, ran = [], False
    for mb in range(16, 132, 4):
        lim = mb << 20
        p = subprocess.run([CLI, "run", "--fwhm", "229", "--angles", "62,66", "-o", out, *big], capture_output=True,
                           text=True, env=env, preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (lim, lim)))
        if p.returncode == 0:
            ran = os.path.isfile(os.path.join(out, "volume.tif"))
            break
        m = re.search(r"out of memory in the (\w+) step allocating [0-9.]+ MB \(peak resident so far [0-9]+ MB\)", p.stderr)
        if m:
            check(refused(p, "col0rme run: error: out of memory in the"), "%d MB: one line %r" % (mb, p.stderr.strip()))
            said.append(m.group(1))
        # below what loading needs, the loader or a library's own allocator fails (no line of ours): no output either way
        check(not os.path.exists(out) and not staging_left(parent), "%d MB: no output folder left" % mb)
    check(said and ran, "some limits fail naming a step (%s), a larger one completes" % ", ".join(sorted(set(said))))


with tempfile.TemporaryDirectory() as tmp:
    s16 = simulate(tmp, "d16", 16, 16, 40)
    s20 = simulate(tmp, "d20", 20, 16, 40)
    big = simulate(tmp, "dbig", 40, 40, 200)
    test_validation(tmp, s16, s20)
    test_nonfinite(tmp, s16)
    test_transaction(tmp, s16, big)
    test_channels(tmp, s16)
    test_calibration(tmp, s16)
    test_outdir_messages(tmp, s16)
    test_subcritical(tmp)
    test_matirf_psf(tmp, big)
    if MODE == "full":
        test_out_of_memory(tmp, big)
done()
