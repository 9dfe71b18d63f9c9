#!/usr/bin/python3
"""The automatic support lambda against a sweep on a panel of simulated
single-angle stacks (docs/history/lambda-drift.md):
    lambda_panel.py COL0RME WORKDIR [l1|cel0 [SUPPORT OPTIONS...]]
Prints a markdown table: the Jaccard index (40 nm, 3 camera pixels of margin)
for each fixed lambda and for the defaults (automatic lambda, drift correction).
SEEDS=5,6,7 in the environment: each member simulated with each seed, the
Jaccard indices averaged over them (one 48x48 field of a sparse member holds
a few short filaments, and its index jumps between neighbouring lambdas).
SWEEP=... in the environment replaces the sweep's lambdas; MEMBERS=a,b,...
keeps only those members; JOBS=N runs N solves at a time (one thread each).
GRID=1: the grid panel instead (angles x cameras x blinking x frames, issue 29)
with a finer sweep (ratio sqrt 2, 11 points) and a column for the
cross-validated lambda (--lambda-rule cv); the table then gives per member
the Jaccard index and lambda / lambda_max of each automatic rule, its gap to
the sweep's best and its ratio to the best lambda.
RULES=noise,peaks adds a column per named --lambda-rule beside the default's
(gap to the best); LABEL=15 simulates every member with --label-radius 15 (a
labelled tube; its own folders); SOFI=DIR,DIR adds SOFI-tool sets made by
bench/sofi_panel.py (angle01.tif, truth_support.tif; 100 nm pixels, FWHM 229),
each as a member of its own whatever SEEDS says."""
import json, os, subprocess, sys
from concurrent.futures import ThreadPoolExecutor

BIN, WORK = sys.argv[1], sys.argv[2]
PEN = sys.argv[3] if len(sys.argv) > 3 else "l1"
EXTRA = sys.argv[4:]
COMMON = ["--width", "48", "--height", "48", "--angles", "65", "--z-range", "0,200"]
SEEDS = os.environ.get("SEEDS", "5").split(",")
# brightness spread: the simulator's log-normal coefficient of variation
# (0.3 by default); at 1 a few emitters set lambda_max
PANEL = {
    "base": [],
    "sparse": ["--density", "15", "--filaments", "3"],
    "dense": ["--density", "150", "--filaments", "8"],
    "dim": ["--brightness", "100"],
    "200 frames": ["--frames", "200"],
    "bright": ["--brightness", "1000"],
    "drift 100 nm": ["--drift-nm", "100,0"],
    "spread 0.6": ["--brightness-cv", "0.6"],
    "spread 1": ["--brightness-cv", "1.0"],
    "spread 1, dense": ["--brightness-cv", "1.0", "--density", "150", "--filaments", "8"],
    "spread 1, dim": ["--brightness-cv", "1.0", "--brightness", "100"],
    "spread 1, sparse": ["--brightness-cv", "1.0", "--density", "15", "--filaments", "3"],
    "short blinks": ["--tau-on", "10", "--tau-off", "300"],
    "background 200": ["--background", "200"],
    # added after the fcf8527 table (docs/history/lambda-drift.md, *Off the panel*)
    "slow blinks": ["--tau-on", "100", "--tau-off", "1000"],
    "pixel 160, fwhm 300": ["--pixel-size", "160", "--fwhm", "300"],
    "gain 3, offset 500, snr 5": ["--gain", "3", "--offset", "500", "--snr", "5"],
    "depth 0-400": ["--z-range", "0,400"],
    "no bleaching": ["--tau-bleach", "0"],
}
# the grid (issue 29): cameras ccd (the default), "scmos" (hot pixels) and
# "emccd" (gain 10); blinking default (on 20 / off 40 ms), sparse fast
# (10 / 120), dense slow (50 / 50); 500 and 200 frames; angles 62, 65, 70
SCMOS = ["--hot-pixels", "0.01", "--snr", "0", "--read-noise", "3"]
EMCCD = ["--gain", "10", "--snr", "0", "--read-noise", "2"]
FAST = ["--tau-on", "10", "--tau-off", "120"]
SLOW = ["--tau-on", "50", "--tau-off", "50"]
F200 = ["--frames", "200"]
GRID = {
    "ccd 65 500": [],
    "ccd 65 200": F200,
    "ccd 62 500": ["--angles", "62"],
    "ccd 70 500": ["--angles", "70"],
    "scmos 65 500": SCMOS,
    "emccd 65 500": EMCCD,
    "ccd 65 500 fast": FAST,
    "ccd 65 500 slow": SLOW,
    "scmos 65 200": SCMOS + F200,
    "emccd 65 500 fast": EMCCD + FAST,
    "ccd 70 500 slow": ["--angles", "70"] + SLOW,
    "ccd 62 200 fast": ["--angles", "62"] + F200 + FAST,
    "scmos 70 500 slow": ["--angles", "70"] + SCMOS + SLOW,
    "emccd 62 200": ["--angles", "62"] + EMCCD + F200,
    "scmos 62 500 fast": ["--angles", "62"] + SCMOS + FAST,
    "emccd 70 200 slow": ["--angles", "70"] + EMCCD + F200 + SLOW,
}
if os.environ.get("GRID"):
    PANEL = GRID
if os.environ.get("MEMBERS"):
    m = os.environ["MEMBERS"]   # names with commas: separate them with ';'
    PANEL = {k: PANEL[k] for k in m.split(";" if ";" in m else ",")}
SWEEP = {"l1": ["4e-2", "2e-2", "1e-2", "5e-3", "2.5e-3", "1.2e-3"],
         "cel0": ["1e-4", "3e-5", "1e-5", "3e-6", "1e-6", "3e-7"]}[PEN]
if os.environ.get("GRID"):
    SWEEP = ["%.3g" % (2e-2 * 2 ** (-k / 2)) for k in range(11)]
if os.environ.get("SWEEP"):      # another sweep, e.g. SWEEP=3e-2,2e-2,1.5e-2,1e-2,7e-3,5e-3
    SWEEP = os.environ["SWEEP"].split(",")


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def ji(sim, out, sofi):
    # the SOFI sets' truth carries no calibration col0rme reads: their fine pixel is 100 nm / 4
    r = subprocess.run([BIN, "eval", "--support", out + "/support.tif", "--support-truth", sim + "/truth_support.tif",
                        "--margin", "12"] + (["--pixel-size", "25"] if sofi else []),
                       check=True, capture_output=True, text=True)
    return json.loads(r.stdout)["support"]["jaccard"]




def solve(job):
    sim, lam = job
    sofi = os.path.exists(sim + "/angle01.tif")
    # outputs in WORK, also for the SOFI sets, which stay as bench/sofi_panel.py made them
    out = os.path.join(WORK, "sofi_" + os.path.basename(sim.rstrip("/")) if sofi else os.path.basename(sim)) \
        + "_out_" + lam.replace(":", "_")
    stack = sim + ("/angle01.tif" if sofi else "/stack_q01.tif")
    fwhm = "229" if sofi else str(json.load(open(sim + "/sim.json"))["parameters"]["fwhm_nm"])
    how = ([] if lam == "auto" else ["--lambda-rule", "cv"] if lam == "cv" else
           ["--lambda-rule", lam[5:]] if lam.startswith("rule:") else ["--lambda", lam])
    run([BIN, "support", "-o", out, "--force", "--fwhm", fwhm, "--penalty", PEN, "--threads", "1", *EXTRA,
         *(["--pixel-size", "100"] if sofi else []), stack] + how)
    rep = json.load(open(out + "/report.json"))["support"][0]
    return ji(sim, out, sofi), rep["lambda_relative"]


os.makedirs(WORK, exist_ok=True)
sims = {}
LABEL = os.environ.get("LABEL")
for name, extra in PANEL.items():
    for seed in SEEDS:
        sim = os.path.join(WORK, name.replace(" ", "_").replace(",", "") + ("" if seed == "5" else "_s" + seed)
                           + ("_label" + LABEL if LABEL else ""))
        if not os.path.exists(sim + "/truth_support.tif"):
            run([BIN, "simulate", "-o", sim, "--force", "--seed", seed] + COMMON + extra
                + (["--label-radius", LABEL] if LABEL else []))
        sims[(name, seed)] = sim
for d in filter(None, os.environ.get("SOFI", "").split(",")):
    PANEL["sofi " + os.path.basename(d.rstrip("/"))] = []
    for seed in SEEDS:
        sims[("sofi " + os.path.basename(d.rstrip("/")), seed)] = d
AUTO = ["auto"] + (["cv"] if os.environ.get("GRID") else []) + [
    "rule:" + r for r in filter(None, os.environ.get("RULES", "").split(","))]
jobs = [(sims[k], lam) for k in sims for lam in SWEEP + AUTO]
with ThreadPoolExecutor(int(os.environ.get("JOBS", "1"))) as ex:
    got = dict(zip(jobs, ex.map(solve, jobs)))
for name in PANEL:
    res = {lam: [sum(got[(sims[(name, s)], lam)][i] for s in SEEDS) / len(SEEDS) for i in (0, 1)]
           for lam in SWEEP + AUTO}
    best = max(res[l][0] for l in SWEEP)
    if os.environ.get("GRID"):
        lbest = max(SWEEP, key=lambda l: res[l][0])
        print("| %s | %s | %.3f (%s) | %s |" % (name, " | ".join("%.3f" % res[l][0] for l in SWEEP), best, lbest, " | ".join(
              "%.3f (%.2g) | %+.3f | %.2f" % (res[a][0], res[a][1], res[a][0] - best, res[a][1] / float(lbest))
              for a in AUTO)), flush=True)
        continue
    print("| %s | %s | %.3f (%.2g) | %.3f | %+.3f |%s" % (name, " | ".join("%.3f" % res[l][0] for l in SWEEP),
          res["auto"][0], res["auto"][1], best, res["auto"][0] - best, "".join(
          " %s %.3f (%.2g) %+.3f |" % (a[5:], res[a][0], res[a][1], res[a][0] - best) for a in AUTO[1:])), flush=True)
