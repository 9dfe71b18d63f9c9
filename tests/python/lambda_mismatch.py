#!/usr/bin/python3
"""The automatic support lambda under model mismatch (docs/history/lambda-drift.md,
"lambda under model mismatch"): single-angle stacks whose PSF, stated FWHM,
pixel size, photon budget or structure differ from what the default rule's
constants were measured on, each swept over a fixed lambda / lambda_max grid.
    lambda_mismatch.py COL0RME WORKDIR [MEMBER ...]
Prints a markdown table: per member the sweep's best Jaccard (40 nm, 3 camera
pixels of margin) and its lambda, then the default rule (peaks) and the
cross-validated lambda (--lambda-rule cv): Jaccard (lambda / lambda_max),
signed gap to the best, chosen lambda over the best lambda.
SEED=5 (default), JOBS=N solves at a time (one thread each), SWEEP=a,b,...
replaces the sweep, JSON=FILE writes every solve's result."""
import json, os, subprocess, sys
from concurrent.futures import ThreadPoolExecutor

BIN, WORK = sys.argv[1], sys.argv[2]
SEED = os.environ.get("SEED", "5")
COMMON = ["--width", "64", "--height", "64", "--angles", "65", "--z-range", "0,200"]
AIRY = ["--psf", "airy"]
# name: (simulate options, support options[, the member whose stack it
# reads]); the support's --fwhm is the simulated one unless given
PANEL = {
    "base": ([], []),
    "airy": (AIRY, []),
    "fwhm stated 200": ([], ["--fwhm", "200"]),
    "fwhm stated 260": ([], ["--fwhm", "260"]),
    "airy, stated 200": (AIRY, ["--fwhm", "200"]),
    "airy, stated 260": (AIRY, ["--fwhm", "260"]),
    "pixel 108": (["--pixel-size", "108"], []),
    "pixel 160": (["--pixel-size", "160"], []),
    "airy, pixel 160": (AIRY + ["--pixel-size", "160"], []),
    "dim, background 200": (["--brightness", "100", "--background", "200"], []),
    "bright": (["--brightness", "1000"], []),
    "microtubules": (["--filaments", "3", "--persistence", "20000", "--density", "100"], []),
    "airy, 200 frames": (AIRY + ["--frames", "200"], []),
    "airy, microtubules": (AIRY + ["--filaments", "3", "--persistence", "20000", "--density", "100"], []),
    # the Airy stacks run with the FWHM of the Gaussian their covariance's
    # lags fit (lag 2 over lag 1: 212-214 nm)
    "airy, stated 213": (AIRY, ["--fwhm", "213"], "airy"),
    "airy, microtubules, stated 213": (AIRY, ["--fwhm", "213"], "airy, microtubules"),
    "airy, 200 frames, stated 213": (AIRY, ["--fwhm", "213"], "airy, 200 frames"),
}
ALL = dict(PANEL)
if len(sys.argv) > 3:
    PANEL = {k: PANEL[k] for k in sys.argv[3:]}
    for k in list(PANEL):   # a member's stack from another member (its simulation)
        if len(PANEL[k]) > 2:
            PANEL.setdefault(PANEL[k][2], ALL[PANEL[k][2]])
SWEEP = ["%.3g" % (2e-2 * 2 ** (-k / 2)) for k in range(-3, 16)]   # 5.66e-2 ... 1.1e-4
if os.environ.get("SWEEP"):
    SWEEP = os.environ["SWEEP"].split(",")


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def simdir(name):
    own = PANEL[name][2] if len(PANEL[name]) > 2 else name
    return os.path.join(WORK, own.replace(", ", "_").replace(" ", "_"))


def solve(job):
    name, lam = job
    sim = simdir(name)
    out = os.path.join(WORK, name.replace(", ", "_").replace(" ", "_")) + "_out_" + lam
    if not os.path.exists(out + "/report.json"):
        fwhm = str(json.load(open(sim + "/sim.json"))["parameters"]["fwhm_nm"])
        run([BIN, "support", "-o", out, "--force", "--fwhm", fwhm, "--threads", "1", *PANEL[name][1], sim + "/stack_q01.tif"]
            + ([] if lam == "auto" else ["--lambda-rule", "cv"] if lam == "cv" else ["--lambda", lam]))
    r = subprocess.run([BIN, "eval", "--support", out + "/support.tif", "--support-truth", sim + "/truth_support.tif",
                        "--margin", "12"], check=True, capture_output=True, text=True)
    rep = json.load(open(out + "/report.json"))["support"][0]
    return {"jaccard": json.loads(r.stdout)["support"]["jaccard"], "lambda_relative": rep["lambda_relative"],
            "lambda_auto": rep.get("lambda_auto"), "support_pixels": rep.get("support_pixels")}


os.makedirs(WORK, exist_ok=True)
for name in PANEL:
    sim, sim_opts = simdir(name), PANEL[name][0]
    if not os.path.exists(sim + "/truth_support.tif"):
        run([BIN, "simulate", "-o", sim, "--force", "--seed", SEED, "--threads", "1"] + COMMON + sim_opts)
jobs = [(n, lam) for n in PANEL for lam in ["auto", "cv"] + SWEEP]
with ThreadPoolExecutor(int(os.environ.get("JOBS", "1"))) as ex:
    got = dict(zip(jobs, ex.map(solve, jobs)))
if os.environ.get("JSON"):
    json.dump({"%s|%s" % k: v for k, v in got.items()}, open(os.environ["JSON"], "w"), indent=1)
print("| member | best (λ/λ_max) | peaks (default) | gap | ratio | cv | gap | ratio |")
print("|---|---|---|---|---|---|---|---|")
for name in PANEL:
    lbest = max(SWEEP, key=lambda l: got[(name, l)]["jaccard"])
    best = got[(name, lbest)]["jaccard"]
    print("| %s | %.3f (%s) | %s |" % (name, best, lbest, " | ".join(
        "%.3f (%.2g) | %+.3f | %.2f" % (got[(name, a)]["jaccard"], got[(name, a)]["lambda_relative"],
                                        got[(name, a)]["jaccard"] - best, got[(name, a)]["lambda_relative"] / float(lbest))
        for a in ("auto", "cv"))), flush=True)
