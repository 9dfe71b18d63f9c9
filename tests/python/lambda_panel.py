#!/usr/bin/python3
"""The automatic support lambda against a sweep on a panel of simulated
single-angle stacks (docs/parameters.md):
    lambda_panel.py COL0RME WORKDIR [l1|cel0 [SUPPORT OPTIONS...]]
Prints a markdown table: the Jaccard index (40 nm, 3 camera pixels of margin)
for each fixed lambda and for the defaults (automatic lambda, drift correction).
SEEDS=5,6,7 in the environment: each member simulated with each seed, the
Jaccard indices averaged over them (one 48x48 field of a sparse member holds
a few short filaments, and its index jumps between neighbouring lambdas).
SWEEP=... in the environment replaces the sweep's lambdas."""
import json, os, subprocess, sys

BIN, WORK = sys.argv[1], sys.argv[2]
PEN = sys.argv[3] if len(sys.argv) > 3 else "l1"
EXTRA = sys.argv[4:]
COMMON = ["--width", "48", "--height", "48", "--angles", "65", "--z-range", "0,200"]
SEEDS = os.environ.get("SEEDS", "5").split(",")
PANEL = {
    "base": [],
    "sparse": ["--density", "15", "--filaments", "3"],
    "dense": ["--density", "150", "--filaments", "8"],
    "dim": ["--brightness", "100"],
    "200 frames": ["--frames", "200"],
    "bright": ["--brightness", "1000"],
    "drift 100 nm": ["--drift-nm", "100,0"],
}
SWEEP = {"l1": ["4e-2", "2e-2", "1e-2", "5e-3", "2.5e-3", "1.2e-3"],
         "cel0": ["1e-4", "3e-5", "1e-5", "3e-6", "1e-6", "3e-7"]}[PEN]
if os.environ.get("SWEEP"):      # another sweep, e.g. SWEEP=3e-2,2e-2,1.5e-2,1e-2,7e-3,5e-3
    SWEEP = os.environ["SWEEP"].split(",")


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def ji(sim, out):
    r = subprocess.run([BIN, "eval", "--support", out + "/support.tif", "--support-truth", sim + "/truth_support.tif",
                        "--margin", "12"], check=True, capture_output=True, text=True)
    return json.loads(r.stdout)["support"]["jaccard"]


os.makedirs(WORK, exist_ok=True)
rows = []
for name, extra in PANEL.items():
    res = {}
    for seed in SEEDS:
        sim = os.path.join(WORK, name.replace(" ", "_") + ("" if seed == "5" else "_s" + seed))
        if not os.path.exists(sim + "/truth_support.tif"):
            run([BIN, "simulate", "-o", sim, "--force", "--seed", seed] + COMMON + extra)
        for lam in SWEEP + ["auto"]:
            out = sim + "_out"
            run([BIN, "support", "-o", out, "--force", "--fwhm", "229", "--penalty", PEN, *EXTRA, sim + "/stack_q01.tif"] +
                ([] if lam == "auto" else ["--lambda", lam]))
            rep = json.load(open(out + "/report.json"))["support"][0]
            j, lr = res.get(lam, (0, 0))
            res[lam] = (j + ji(sim, out) / len(SEEDS), lr + rep["lambda_relative"] / len(SEEDS))
    best = max(res[l][0] for l in SWEEP)
    rows.append((name, res, best))
    print("| %s | %s | %.3f (%.2g) | %.3f | %+.3f |" % (name, " | ".join("%.3f" % res[l][0] for l in SWEEP),
          res["auto"][0], res["auto"][1], best, res["auto"][0] - best), flush=True)
