"""col0rme simulate through the CLI: determinism, thread independence, ground
truth consistent with the emitter list, and clean refusals of bad parameters.

usage: test_simulate.py COL0RME
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import tifffile

from checks import check, done

CLI = sys.argv[1]


def sim(out, *args, threads=None):
    env = dict(os.environ)
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
    return subprocess.run([CLI, "simulate", "-o", out, "--width", "32", "--height", "24", "--frames", "40",
                           "--angles", "62,64,67", *args], capture_output=True, text=True, env=env)


def files(d):
    return {f: open(os.path.join(d, f), "rb").read() for f in sorted(os.listdir(d)) if f != "sim.json"}


with tempfile.TemporaryDirectory() as tmp:
    a, b, c = (os.path.join(tmp, x) for x in "abc")
    r1 = sim(a, "--seed", "5", threads=1)
    r2 = sim(b, "--seed", "5", threads=2)
    r3 = sim(c, "--seed", "6", threads=2)
    check(r1.returncode == 0 and r2.returncode == 0 and r3.returncode == 0, "runs: %s %s" % (r1.stderr, r2.stderr))
    fa, fb, fc = files(a), files(b), files(c)
    check(fa == fb, "same seed, 1 vs 2 threads: identical bytes")
    check(fa["stack_q01.tif"] != fc["stack_q01.tif"], "another seed differs")

    # calibrated uint16 stacks, one per angle
    with tifffile.TiffFile(os.path.join(a, "stack_q02.tif")) as tf:
        s = tf.asarray()
        check(s.shape == (40, 24, 32) and s.dtype == np.uint16, "stack shape/dtype %s %s" % (s.shape, s.dtype))
        xr = tf.pages[0].tags["XResolution"].value
        check(abs(xr[0] / xr[1] - 10.0) < 1e-4 and tf.imagej_metadata.get("unit") == "um", "stack calibration")

    # ground truth agrees with the emitter list
    rep = json.load(open(os.path.join(a, "sim.json")))
    P = rep["parameters"]
    r, px = P["srf"], P["pixel_size_nm"]
    fp = px / r
    rows = list(csv.DictReader(open(os.path.join(a, "emitters.csv"))))
    check(len(rows) == rep["estimates"]["emitters"] and len(rows) > 50, "emitter count %d" % len(rows))
    E = {k: np.array([float(row[k]) for row in rows]) for k in rows[0]}
    H, W = 24 * r, 32 * r
    fy, fx = (E["y_nm"] // fp).astype(int), (E["x_nm"] // fp).astype(int)
    check(fx.min() >= 0 and fx.max() < W and fy.min() >= 0 and fy.max() < H, "emitters inside the field")
    check(E["z_nm"].min() >= 0 and E["z_nm"].max() <= 400, "depths within the z range")
    ng, ns, lam = P["n_glass"], P["n_sample"], P["wavelength_nm"]
    for q, ang in enumerate(P["angles_deg"]):
        al = np.deg2rad(ang)
        p = 4 * np.pi * ng / lam * np.sqrt(np.sin(al) ** 2 - (ns / ng) ** 2)
        check(abs(1 / p - rep["estimates"]["angles"][q]["penetration_depth_nm"]) < 1e-6, "depth q%d" % q)
        i0r = rep["estimates"]["angles"][q]["i0_relative"]
        exp_img = np.zeros((H, W))
        np.add.at(exp_img, (fy, fx), P["gain_adu_per_photon"] * E["brightness"] * i0r * np.exp(-p * E["z_nm"]) * E["on_q%02d" % (q + 1)])
        got = tifffile.imread(os.path.join(a, "truth_intensity_q%02d.tif" % (q + 1)))
        check(got.shape == (H, W) and np.allclose(got, exp_img, rtol=1e-4, atol=1e-3), "intensity q%d matches emitters" % q)
        bgt = tifffile.imread(os.path.join(a, "truth_background_q%02d.tif" % (q + 1)))
        st = tifffile.imread(os.path.join(a, "stack_q%02d.tif" % (q + 1))).astype(float).mean(0)
        # mean frame = background + blurred intensity: totals agree within noise
        check(abs(st.sum() - bgt.sum() - exp_img.sum()) < 0.05 * exp_img.sum(), "flux q%d" % q)
    seen = sum(E["on_q%02d" % (q + 1)] for q in range(3)) > 0
    wz = np.zeros((H, W)); ww = np.zeros((H, W))
    np.add.at(wz, (fy[seen], fx[seen]), (E["brightness"] * E["z_nm"])[seen])
    np.add.at(ww, (fy[seen], fx[seen]), E["brightness"][seen])
    depth = tifffile.imread(os.path.join(a, "truth_depth.tif"))
    supp = tifffile.imread(os.path.join(a, "truth_support.tif"))
    check(np.array_equal(supp > 0, ww > 0), "support = pixels with a seen emitter")
    check(np.allclose(depth[ww > 0], (wz / np.maximum(ww, 1e-300))[ww > 0], atol=0.01), "depth map = weighted mean z")

    # bad parameters: one error line naming the parameter, non-zero exit, nothing written
    for args, needle in [(["--tau-on", "-5"], "--tau-on"), (["--angles", "95,62"], "incidence angle"),
                         (["--filaments", "0"], "empty structure"), (["--pixel-size", "0"], "--pixel-size"),
                         (["--frames", "abc"], "--frames"), (["--frames", "0"], "--frames 0"),
                         (["--gaps", "1", "--bleach-order", "interleaved"], "--gaps:"),
                         (["--z-range", "300,100"], "--z-range"), (["--psf", "bessel"], "--psf bessel"),
                         (["--psf", "airy", "--drift-nm", "50,0"], "--psf airy")]:
        d = os.path.join(tmp, "bad")
        r = subprocess.run([CLI, "simulate", "-o", d, *args], capture_output=True, text=True)
        lines = r.stderr.strip().splitlines()
        check(r.returncode != 0 and len(lines) == 1 and needle in lines[0], "bad %s: %r" % (args, r.stderr))
        check(not os.path.exists(d), "bad %s: nothing written" % args)
    # a non-empty output directory is refused and left alone
    r = subprocess.run([CLI, "simulate", "-o", a, "--frames", "3"], capture_output=True, text=True)
    check(r.returncode != 0 and "not empty" in r.stderr, "non-empty outdir refused")
    check(files(a) == fa, "non-empty outdir untouched")
    # CSV input, emitters outside the field are dropped
    csvp = os.path.join(tmp, "e.csv")
    open(csvp, "w").write("x_nm,y_nm,z_nm\n100,100,10\n1500,1000,200\n99999,5,5\n")
    d = os.path.join(tmp, "csv")
    r = subprocess.run([CLI, "simulate", "-o", d, "--width", "20", "--height", "20", "--frames", "5",
                        "--emitters", csvp], capture_output=True, text=True)
    check(r.returncode == 0 and json.load(open(os.path.join(d, "sim.json")))["estimates"]["emitters"] == 2, "csv input: %s" % r.stderr)

    # --psf airy: the same scene through another PSF of the same FWHM (its
    # tail beyond 6 FWHM, ~3 % of the light, dropped); the Gaussian's sim.json
    # without the key, as before
    d = os.path.join(tmp, "airy")
    r = sim(d, "--seed", "5", "--psf", "airy", threads=2)
    check(r.returncode == 0, "airy: %s" % r.stderr)
    fd = files(d)
    check(all(fd[f] == fa[f] for f in fa if not f.startswith("stack_")), "airy: the same truth as the Gaussian's")
    check(fd["stack_q01.tif"] != fa["stack_q01.tif"], "airy: other frames")
    check(json.load(open(os.path.join(d, "sim.json")))["parameters"]["psf"] == "airy"
          and "psf" not in P, "sim.json names the Airy PSF only")
    light = lambda x: (tifffile.imread(os.path.join(x, "stack_q01.tif")).astype(float).mean(0)
                       - tifffile.imread(os.path.join(x, "truth_background_q01.tif"))).sum()
    ratio = light(d) / light(a)
    check(0.9 < ratio < 1.0, "airy: %.3f of the Gaussian's light" % ratio)
    # the support's PSF check: the Airy disk reads as a narrower Gaussian and
    # warns, the simulator's Gaussian reads at its FWHM and does not
    for psf in ("gauss", "airy"):
        d = os.path.join(tmp, "check_" + psf)
        r = subprocess.run([CLI, "simulate", "-o", d, "--width", "48", "--height", "48", "--frames", "200", "--angles", "65",
                            "--seed", "5", "--psf", psf], capture_output=True, text=True)
        o = os.path.join(tmp, "check_out_" + psf)
        r2 = subprocess.run([CLI, "support", "--fwhm", "229", "-o", o, os.path.join(d, "stack_q01.tif")],
                            capture_output=True, text=True)
        check(r.returncode == 0 and r2.returncode == 0, "psf check %s: %s %s" % (psf, r.stderr, r2.stderr))
        rep = json.load(open(os.path.join(o, "report.json")))
        fw = rep["support"][0]["lambda_auto"]["fwhm_data_nm"]
        warned = any("covariance's lags" in w for w in rep.get("warnings", []))
        if psf == "gauss":
            check(abs(fw / 229 - 1) < 0.03 and not warned, "Gaussian 229 nm read as %.1f nm, warned %s" % (fw, warned))
        else:
            check(fw < 0.95 * 229 and warned and "covariance's lags" in r2.stderr, "Airy 229 nm read as %.1f nm, warned %s" % (fw, warned))

done()
