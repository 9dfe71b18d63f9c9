#!/usr/bin/env bash
# compare_builds.sh OLD_COL0RME NEW_COL0RME [WORKDIR]
#
# Refactors must not change results: runs `simulate`, `run`, `support`,
# `intensity` and `matirf` on the demo data with two builds of the program
# and compares every file they write, byte for byte. report.json is compared
# without what changes from one run to the next (timings, creation time,
# argv, the binary's versions and the progress-free wall clocks); report.html,
# made from the other files with the timings and paths, is left out.
# Exits 1 and names each differing file when the builds disagree, with how
# far apart a differing TIFF is (max and median |new - old| over the pixels
# either sets, relative L2; with numpy and tifffile).
set -euo pipefail
OLD=$(readlink -f "$1"); NEW=$(readlink -f "$2")
W=${3:-$(mktemp -d)}
rm -rf "$W"; mkdir -p "$W"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}

outputs() {   # outputs BIN DIR: every command's files under DIR
	local b=$1 d=$2
	mkdir -p "$d"
	"$b" simulate --seed 1 --pairs -o "$d/data" >/dev/null
	local angles
	angles=$(/usr/bin/python3 -c "import json,sys; print(','.join('%.6g' % a for a in json.load(open(sys.argv[1]))['parameters']['angles_deg']))" "$d/data/sim.json")
	"$b" run --fwhm 229 --angles "$angles" --baseline -o "$d/run" "$d"/data/stack_q0?.tif 2>/dev/null
	"$b" run --fwhm 229 --angles "$angles" --penalty cel0 --bleach off --no-drift -o "$d/run_cel0" "$d"/data/stack_q0?.tif 2>/dev/null
	"$b" support --fwhm 229 -o "$d/support" "$d/data/stack_q01.tif" 2>/dev/null
	"$b" intensity --fwhm 229 --support "$d/support/support.tif" -o "$d/intensity" "$d"/data/stack_q0?.tif 2>/dev/null
	"$b" matirf --angles "$angles" -o "$d/matirf" "$d"/intensity/intensity_q0?.tif 2>/dev/null
	"$b" matirf --angles "$angles" --psf-fwhm 229 --matirf-iterations 300 -o "$d/matirf_psf" "$d"/intensity/intensity_q0?.tif 2>/dev/null
}

outputs "$OLD" "$W/old"
outputs "$NEW" "$W/new"

/usr/bin/python3 - "$W/old" "$W/new" <<'PY'
import json, os, sys
old, new = sys.argv[1:]
VOLATILE = {"timings_s", "peak_rss_mb", "rss_rise_mb", "created", "argv", "versions", "omp_wait_policy", "threads", "wall_s", "cpu_s", "seconds"}
def strip(x, root):   # the two builds wrote under different folders
    if isinstance(x, dict):
        return {k: strip(v, root) for k, v in x.items() if k not in VOLATILE and not k.endswith("_s")}
    if isinstance(x, list):
        return [strip(v, root) for v in x]
    return x.replace(root, "DIR") if isinstance(x, str) else x
def tiff_numbers(a, b):   # how far apart: max and median |new - old| where either is set, relative L2
    try:
        import numpy as np, tifffile
        x, y = tifffile.imread(a).astype(float), tifffile.imread(b).astype(float)
    except Exception:
        return ""
    if x.shape != y.shape:
        return f" (shapes {x.shape} and {y.shape})"
    m = np.isfinite(x) & np.isfinite(y) & ((x != 0) | (y != 0))
    d = np.abs(y - x)[m]
    if not d.size:
        return ""
    return f" (max {d.max():.4g}, median {np.median(d):.4g}, relative L2 {np.linalg.norm(d) / max(np.linalg.norm(x[m]), 1e-300):.3g})"
files = sorted(os.path.relpath(os.path.join(r, f), old) for r, _, fs in os.walk(old) for f in fs)
newfiles = sorted(os.path.relpath(os.path.join(r, f), new) for r, _, fs in os.walk(new) for f in fs)
bad = [f"only in one build: {f}" for f in sorted(set(files) ^ set(newfiles))]
for f in sorted(set(files) & set(newfiles)):
    if f.endswith("report.html"):   # made from the files compared here, with their timings and paths
        continue
    a, b = os.path.join(old, f), os.path.join(new, f)
    if f.endswith(".json"):
        same = strip(json.load(open(a)), old) == strip(json.load(open(b)), new)
    else:
        same = open(a, "rb").read() == open(b, "rb").read()
    if not same:
        bad.append(f"differs: {f}" + (tiff_numbers(a, b) if f.endswith(".tif") else ""))
print("\n".join(bad) if bad else f"identical: {len(files)} files")
sys.exit(1 if bad else 0)
PY
