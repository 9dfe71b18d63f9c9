#!/usr/bin/python3
"""The depth readout weighted by the intensities' own noise, measured from
frame halves (docs/parameters.md, "Weighting the angles by the noise of frame
halves"). Not what `run` does: a measurement of what it would gain.

    /usr/bin/python3 bench/depth_weights.py BIN SIMDIR RUNDIR [--block N] [--keep DIR]

BIN: the col0rme binary; SIMDIR: `col0rme simulate` output; RUNDIR: `col0rme
run --angles` output on its stacks (no drift: `col0rme intensity` corrects
none). Each stack is cut into blocks of N frames (default 20, longer than a
blink), the even blocks and the odd blocks made two stacks, and `col0rme
intensity` solves each on the run's support at the run's shared mu (and its
calibration maps). The intensity step is linear in the mean, so half the
halves' difference is a draw of the full stack's estimation noise. Summed over
the run's strips (bench/depth_ladder.py) it gives each angle's random noise,
modelled as s_q m_q^2 + c_q (m the fitted model); the residuals of the fit
beyond that noise give one more absolute variance, the systematic misfit
(leverage taken into account), so that a stack whose residuals are not noise
keeps the plain fit's equal weights. Rows: median |error| and median signed
error (nm) of the run, of the plain readout (what the run computes) and of
the weighted one, then the noise model."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import tifffile as tf

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import depth_ladder as L   # noqa: E402


def fit(W, y, v):
    """each column of y's best single depth index, amplitude and validity,
    the angles weighted by 1/v (K x n variances)"""
    num, den = W.T @ (y / v), (W * W).T @ (1 / v)
    g = np.where(num > 0, num * num / den, 0)
    k, i = g.argmax(0), np.arange(y.shape[1])
    return k, num[k, i] / den[k, i], g.max(0) > 0


def resid_proj(W, p, k, a, v):
    """I - H of the weighted two-parameter fit (amplitude, depth) at each
    column, (n, K, K), and the model"""
    m = W[:, k] * a
    J = np.stack([m, -p[:, None] * m], 1)
    JtVJ = np.einsum('kan,kn,kbn->nab', J, 1 / v, J)
    H = np.einsum('kan,nab,lbn,ln->nkl', J, np.linalg.inv(JtVJ), J, 1 / v)
    return np.eye(len(p))[None] - H, m


def weighted(W, p, y, D):
    """the noise-weighted fit of y (K x n) given D, a draw of its noise"""
    k, a, ok = fit(W, y, np.ones_like(y))
    m = W[:, k] * a
    vr, model = np.zeros_like(y), []
    for q in range(len(p)):
        A = np.array([m[q, ok] ** 2, np.ones(ok.sum())]).T
        (s, c), *_ = np.linalg.lstsq(A, D[q, ok] ** 2, rcond=None)
        s, c = max(s, 0), max(c, 0)
        vr[q] = s * m[q] ** 2 + c + 1e-12
        model.append((s, c, c / max(s * (m[q, ok] ** 2).mean(), 1e-30)))
    v, csys, ratio = vr, 0.0, 0.0
    for _ in range(3):
        k, a, ok = fit(W, y, v)
        R, mm = resid_proj(W, p, k[ok], a[ok], v[:, ok])
        r2, R2 = ((y[:, ok] - mm) ** 2).T, R ** 2
        pred = np.einsum('nkl,ln->nk', R2, vr[:, ok])
        X = R2.sum(2)
        csys = max(0.0, float(((r2 - pred) * X).sum() / (X * X).sum()))
        ratio = r2.sum() / pred.sum()
        v = vr + csys
    k, a, ok = fit(W, y, v)
    return k, ok, model, csys, ratio


def halves(bin_, run, block, work):
    """the two block halves' intensities on the run's support and mu"""
    R = json.load(open(run + "/report.json"))
    stacks = [i["stack"] for i in R["intensity"]]
    argv, extra = R["argv"], []
    for flag in ("--offset-map", "--variance-map", "--gain-map"):
        if flag in argv:
            extra += [flag, argv[argv.index(flag) + 1]]
    P = R["parameters"]
    out = []
    for h in (0, 1):
        names = []
        for s in stacks:
            x = tf.imread(s)
            n = "%s/h%d_%s" % (work, h, os.path.basename(s))
            tf.imwrite(n, x[(np.arange(len(x)) // block) % 2 == h])
            names.append(n)
        o = "%s/half%d" % (work, h)
        subprocess.run([bin_, "intensity", "--support", run + "/support.tif", "--fwhm", str(P["fwhm_nm"]),
                        "--pixel-size", str(P["pixel_size_nm"]), "--srf", str(P["srf"]),
                        "--mu", repr(R["intensity"][0]["mu"]), "--force", "-o", o] + extra + names,
                       check=True, stdout=subprocess.DEVNULL)
        out.append(np.array([tf.imread(o + "/intensity_q%02d.tif" % (q + 1)) for q in range(len(stacks))]).astype(float))
    return out


def main():
    opt = {"--block": "20", "--keep": None}
    args, it = [], iter(sys.argv[1:])
    for a in it:
        if a in opt:
            opt[a] = next(it)
        else:
            args.append(a)
    bin_, sim, run = args
    block, keep = int(opt["--block"]), opt["--keep"]
    d = L.load(sim, run)
    with tempfile.TemporaryDirectory() as tmp:
        work = keep or tmp
        os.makedirs(work, exist_ok=True)
        xa, xb = halves(bin_, run, block, work)
    p, mask, f = d["p"], d["es"], d["eb"]
    zb, zc = np.arange(10, 400, 20.0), np.arange(0, 400.01, 1.0)
    Wb = d["i0"][:, None] * np.exp(-p[:, None] * (zb[None] - 10)) * -np.expm1(-p[:, None] * 20) / (p[:, None] * 20)
    Wc = d["i0"][:, None] * np.exp(-p[:, None] * zc[None])
    x = d["xe"] / f[:, None, None]
    guide = L.single(Wb, zb, np.array([L.box(v, mask, 2) for v in x]), mask)
    y = L.strip(x, mask, guide, 50.0, 8, 2.0)[:, mask]
    D = L.strip((xa - xb) / 2 / f[:, None, None], mask, guide, 50.0, 8, 2.0)[:, mask]
    k0, _, ok0 = fit(Wc, y, np.ones_like(y))
    k1, ok1, model, csys, ratio = weighted(Wc, p, y, D)
    print("| readout | median (nm) | signed (nm) | coverage | signed, true z 0-100 | 100-200 | 200-300 | 300-400 |")
    print("|---|---|---|---|---|---|---|---|")
    L.row(d, d["zrun"], "the run (depth.tif)")
    for lab, k, ok in (("plain (equal weights)", k0, ok0), ("weighted by the halves' noise", k1, ok1)):
        z = np.zeros(mask.shape)
        z[mask] = np.where(ok, zc[k], 0)
        L.row(d, z, lab)
    print("noise per angle: relative sd %s; absolute share c/(s m^2) %s; systematic variance %.3g; "
          "residuals / noise %.2f" % (" ".join("%.3f" % np.sqrt(s) for s, _, _ in model),
                                      " ".join("%.2f" % sh for _, _, sh in model), csys, ratio))


if __name__ == "__main__":
    main()
