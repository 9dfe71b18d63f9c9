#!/usr/bin/python3
"""What limits a run's depth: the run's depth readout redone outside it with
one input at a time swapped for the simulator's truth (docs/history/depth.md,
"Sparse blinking: what limits the depth").

    /usr/bin/python3 bench/depth_ladder.py SIMDIR RUNDIR [INTENSITY_DIR [--true-support]] [--windows] [--gls]
    /usr/bin/python3 bench/depth_ladder.py SIMDIR [SIMDIR...]     # the truth's rows alone, no run

SIMDIR: `col0rme simulate` output; RUNDIR: `col0rme run --angles` output on its
stacks. The readout: each stack's intensity over its bleaching factor, summed
over the guided strip (17 fine pixels along the structure, 2 either side of
its line, pixels whose 5-pixel guess lies within 50 nm; docs/history/depth.md,
"Depth pooling along the structure"; before it a 7-pixel square, which the
docs' earlier tables used) and fitted with one depth (1 nm grid), as `run`
does before and after its MA-TIRF solve; the solve itself is left out (it reproduces its input's
projections: on the grid's 5-angle CCD sparse-fast 500-frame stack of seed 1
this proxy reads 11.7 / -0.2 nm where the run reads 11.6 / -0.2; with the
square, on the docs' sparse-blinking stack, 17.5 / -3.7 against 17.0 / -3.6).
Rows: median |error|,
median signed error (nm, positive deeper than the truth), coverage, and the
signed error by true depth. Swaps: the true bleaching factors (sim.json), the
true realised intensities (truth_intensity_qNN.tif: each emitter's brightness
times its own on-fraction at that angle) on the run's or the true support, the
model intensities (the emitters' mean on-fraction: no blinking noise), and
with INTENSITY_DIR the intensities of a `col0rme intensity` run (e.g. on the
true support, then --true-support, which also reads them, and the truth, at
the pixels the run covers, to compare with the run's support on the same
pixels; or on stacks with the true background taken out). --windows:
the run's intensities with other windows and ranges. With SIMDIRs alone: the
true realised intensities on the true support (what the simulated blinking and
bleaching leave to any readout), one line a simulation. --gls: also the
readout whose last fit weights the angles by a noise covariance estimated from
the data (docs/history/grid.md, "Why 8 angles read worse than 5")."""
import json
import os
import sys

import numpy as np
import tifffile as tf


def load(sim, run=None):
    S = json.load(open(sim + "/sim.json"))
    R = json.load(open(run + "/report.json")) if run else None
    nq = len(R["matirf"]["angles_deg"]) if run else len(S["estimates"]["angles"])
    A = S["estimates"]["angles"][:nq]
    d = {"nq": nq, "p": 1 / np.array([a["penetration_depth_nm"] for a in A]),
         "i0": np.array([a["i0_relative"] for a in A]),
         "tb": np.array(S["estimates"]["bleaching"]["stack_factors"][:nq]),
         "zt": tf.imread(sim + "/truth_depth.tif"), "ts": tf.imread(sim + "/truth_support.tif") > 0}
    rd = lambda pat: np.array([tf.imread(pat % (q + 1)) for q in range(nq)]).astype(float)
    d["xt"] = rd(sim + "/truth_intensity_q%02d.tif")
    if run:
        d["eb"] = np.array(R["bleaching"]["factors"][:nq])
        d["es"], d["zrun"] = tf.imread(run + "/support.tif") > 0, tf.imread(run + "/depth.tif")
        d["xe"] = rd(run + "/intensity_q%02d.tif")
    fp = S["parameters"]["pixel_size_nm"] / S["parameters"]["srf"]
    em = np.genfromtxt(sim + "/emitters.csv", delimiter=",", names=True)
    pon = S["parameters"]["tau_on_ms"] / (S["parameters"]["tau_on_ms"] + S["parameters"]["tau_off_ms"])
    d["xm"] = np.zeros_like(d["xt"])
    iy, ix = (em["y_nm"] / fp).astype(int), (em["x_nm"] / fp).astype(int)
    for q in range(nq):
        np.add.at(d["xm"][q], (iy, ix), em["brightness"] * d["i0"][q] * np.exp(-d["p"][q] * em["z_nm"]) * pon * d["tb"][q])
    return d


def single(W, z, x, mask):
    """the depth whose exponential best fits each masked pixel's x (one non-negative amplitude)"""
    s = W.T @ x[:, mask]
    g = np.where(s > 0, s * s / (W * W).sum(0)[:, None], 0)
    out = np.zeros(mask.shape)
    out[mask] = np.where(g.max(0) > 0, z[g.argmax(0)], 0)
    return out


def box(x, mask, h):
    xm = np.where(mask, x, 0)
    c = np.pad(xm, ((h + 1, h), (h + 1, h))).cumsum(0).cumsum(1)
    o = c[2 * h + 1:, 2 * h + 1:] - c[:-2 * h - 1, 2 * h + 1:] - c[2 * h + 1:, :-2 * h - 1] + c[:-2 * h - 1, :-2 * h - 1]
    return np.where(mask, o, 0)


def offset(dy, dx, H, W):
    """the slices of the centres c and of their neighbours o at (dy, dx), inside an H x W image"""
    return ((slice(max(0, -dy), H - max(0, dy)), slice(max(0, -dx), W - max(0, dx))),
            (slice(max(0, dy), H - max(0, -dy)), slice(max(0, dx), W - max(0, -dx))))


def normals(mask, r=3):
    """each pixel's unit normal (x, y) to its structure: the minor axis of the
    second moments of the mask's pixels within r (a disc), as c0_pixlist_normals"""
    H, W = mask.shape
    sxx, syy, sxy = np.zeros((H, W)), np.zeros((H, W)), np.zeros((H, W))
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dx * dx + dy * dy <= r * r:
                c, o = offset(dy, dx, H, W)
                n = mask[o]
                sxx[c] += n * dx * dx; syy[c] += n * dy * dy; sxy[c] += n * dx * dy
    along = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    return -np.sin(along), np.cos(along)


def strip(x, mask, guide, rng, h, width):
    """each masked pixel's sum over the (2h+1)^2 window's masked pixels whose
    guide lies within rng of the centre's and, unless width is None, within
    width of the line along the centre's structure, as the run's
    c0_pool_guided_at (width None: the guided square of before the strip)"""
    H, W = mask.shape
    nx, ny = normals(mask) if width is not None else (None, None)
    xm, out = np.where(mask[None], x, 0), np.zeros_like(x)
    for dy in range(-h, h + 1):
        for dx in range(-h, h + 1):
            c, o = offset(dy, dx, H, W)
            ok = mask[o] & (np.abs(guide[o] - guide[c]) <= rng)
            if width is not None:
                ok &= np.abs(nx[c] * dx + ny[c] * dy) <= width
            out[(slice(None),) + c] += np.where(ok[None], xm[(slice(None),) + o], 0)
    return np.where(mask[None], out, 0)


def gls(W, z, x, mask, f):
    """single() whose fit weights the angles by C = D Sigma D: D the first fit's
    projections, Sigma = s I + b B the relative noise (s: independent per angle,
    blinking and camera; B_qr = 1/f_earlier - 1: each emitter's own bleaching,
    carried to every later stack of a sequential acquisition), s and b fitted to
    the first fit's relative residuals (their expectation P Sigma P^T, P the
    projector of the fit's two parameters), no constant from a simulator"""
    xm = x[:, mask]
    s = W.T @ xm
    g = np.where(s > 0, s * s / (W * W).sum(0)[:, None], 0)
    ok = g.max(0) > 0
    w0, K = W[:, g.argmax(0)][:, ok], len(f)
    y = xm[:, ok]
    r = y / ((w0 * y).sum(0) / (w0 * w0).sum(0) * w0) - 1
    B = 1 / f[np.minimum.outer(np.arange(K), np.arange(K))] - 1
    A = np.array([np.ones(K), np.log(W[:, 1] / W[:, 0]) / (z[1] - z[0])]).T      # d log w / dz = -p
    S, M1, M2 = np.zeros((K, K)), np.zeros((K, K)), np.zeros((K, K))
    for k in range(y.shape[1]):
        D = w0[:, k] ** 2
        P = np.eye(K) - A @ np.linalg.solve(A.T @ (D[:, None] * A), (A * D[:, None]).T)
        S += np.outer(r[:, k], r[:, k]); M1 += P @ P.T; M2 += P @ B @ P.T
    (sb, be), *_ = np.linalg.lstsq(np.array([M1.ravel(), M2.ravel()]).T, S.ravel(), rcond=None)
    Si = np.linalg.inv(max(sb, 1e-12) * np.eye(K) + max(be, 0) * B)
    Siy = Si @ (y / w0)
    zo = np.zeros(y.shape[1])
    for c in np.array_split(np.arange(y.shape[1]), max(1, y.shape[1] // 1000)):
        wt = W[:, :, None] / w0[:, None, c]
        num = np.einsum("kzn,kn->zn", wt, Siy[:, c])
        gg = np.where(num > 0, num * num / np.einsum("kzn,kl,lzn->zn", wt, Si, wt), 0)
        zo[c] = np.where(gg.max(0) > 0, z[gg.argmax(0)], 0)
    out, v = np.zeros(mask.shape), np.zeros(mask.sum())
    v[ok] = zo
    out[mask] = v
    return out


def depth(d, x, mask, f, h=8, hg=2, rng=50.0, fit=None, width=2.0):
    p, i0 = d["p"][:, None], d["i0"][:, None]
    zb, zc = np.arange(10, 400, 20.0), np.arange(0, 400.01, 1.0)
    Wb = i0 * np.exp(-p * (zb[None] - 10)) * -np.expm1(-p * 20) / (p * 20)   # 20 nm bins, as the run's guess
    Wc = i0 * np.exp(-p * zc[None])
    x = x / f[:, None, None]
    if h == 0:
        return single(Wc, zc, x, mask)
    g = single(Wb, zb, np.array([box(v, mask, hg) for v in x]), mask)
    if rng <= 0:
        xp = np.array([box(v, mask, h) for v in x])
    else:
        xp = strip(x, mask, g, rng, h, width)
    return gls(Wc, zc, xp, mask, f) if fit == "gls" else single(Wc, zc, xp, mask)


def row(d, z, label, at=None):
    """at: only the true pixels where this mask is set (e.g. the run's depth > 0)"""
    m = (d["zt"] > 0) & (True if at is None else at)
    v, t = z[m], d["zt"][m]
    ok = v > 0
    e, t = v[ok] - t[ok], t[ok]
    by = ["%+5.1f" % np.median(e[(t >= a) & (t < a + 100)]) if ((t >= a) & (t < a + 100)).any() else "  -  "
          for a in (0, 100, 200, 300)]
    print("| %s | %.1f | %+.1f | %.2f | %s |" % (label, np.median(np.abs(e)), np.median(e), ok.mean(), " | ".join(by)), flush=True)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) == 1 or not os.path.exists(args[1] + "/report.json"):
        for sim in args:      # the truth alone
            d = load(sim)
            print("%s: true realised intensities, true support:" % sim, end=" ")
            row(d, depth(d, d["xt"], d["ts"], d["tb"]), "readout")
            if "--gls" in sys.argv:
                print("%s: the same, GLS:" % sim, end=" ")
                row(d, depth(d, d["xt"], d["ts"], d["tb"], fit="gls"), "readout")
        return
    d = load(args[0], args[1])
    print("| input | median (nm) | signed (nm) | coverage | signed, true z 0-100 | 100-200 | 200-300 | 300-400 |")
    print("|---|---|---|---|---|---|---|---|")
    row(d, d["zrun"], "the run (depth.tif)")
    row(d, depth(d, d["xe"], d["es"], d["eb"]), "readout redone, the run's inputs")
    if "--gls" in sys.argv:
        row(d, depth(d, d["xe"], d["es"], d["eb"], fit="gls"), "readout redone, the run's inputs, GLS fit")
    row(d, depth(d, d["xe"], d["es"], d["tb"]), "true bleaching factors")
    row(d, depth(d, d["xt"], d["es"], d["tb"]), "true realised intensities, the run's support")
    zt = depth(d, d["xt"], d["ts"], d["tb"])
    row(d, zt, "true realised intensities, true support")
    row(d, zt, "the same, at the pixels the run covers", d["zrun"] > 0)
    if "--gls" in sys.argv:
        row(d, depth(d, d["xt"], d["ts"], d["tb"], fit="gls"), "true realised intensities, true support, GLS fit")
    row(d, depth(d, d["xm"], d["ts"], d["tb"]), "model intensities (no blinking noise), true support")
    if len(args) > 2:
        xi = np.array([tf.imread(args[2] + "/intensity_q%02d.tif" % (q + 1)) for q in range(d["nq"])]).astype(float)
        mask = d["ts"] if "--true-support" in sys.argv else d["es"]
        zi = depth(d, xi, mask, d["tb"])
        row(d, zi, "intensities of %s, true bleaching" % args[2])
        if "--true-support" in sys.argv:
            row(d, zi, "the same, at the pixels the run covers", d["zrun"] > 0)
    if "--windows" in sys.argv:
        for h in (2, 3, 4, 5, 6, 8):
            for rng in (50, 100, 0):
                row(d, depth(d, d["xe"], d["es"], d["eb"], h=h, rng=rng, width=None),
                    "square window %d px, range %d nm" % (2 * h + 1, rng))
            row(d, depth(d, d["xe"], d["es"], d["eb"], h=h), "strip %d px long, range 50 nm" % (2 * h + 1))


if __name__ == "__main__":
    main()
