#!/usr/bin/env bash
# The built-in demo: simulate the default 5-angle dataset (64x64, 500 frames
# per angle, fixed seed), estimate the support from the shallowest angle, then
# each angle's intensity and background. It grows with the pipeline: the
# MA-TIRF volume and 'col0rme run'/'eval' are not wired in yet.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-build/demo}
rm -rf "$OUT"
mkdir -p "$OUT"
t0=$(date +%s.%N)
./build/col0rme simulate -o "$OUT/data"
./build/col0rme support --fwhm 229 -o "$OUT/support" "$OUT/data/stack_q01.tif"
./build/col0rme intensity --fwhm 229 --support "$OUT/support/support.tif" -o "$OUT/intensity" "$OUT"/data/stack_q0?.tif
t1=$(date +%s.%N)
/usr/bin/python3 - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
s = json.load(open(out + "/support/report.json"))["support"][0]
i = json.load(open(out + "/intensity/report.json"))["intensity"]
print("support: %d fine pixels, lambda %.3g (%.3g x lambda_max), noise variance %.1f, %d iterations, %.2f s"
      % (s["support_pixels"], s["lambda"], s["lambda_relative"], s["noise_variance"], s["iterations"], s["covariance_s"] + s["solve_s"]))
for q, a in enumerate(i):
    print("intensity q%02d: mu %.3g (discrepancy %s), %.2f s" % (q + 1, a["mu"], a["discrepancy"].split(":")[0], a["seconds"]))
PY
/usr/bin/python3 -c "import sys; print(\"demo: %.1f s; outputs in %s/{data,support,intensity}\" % (float(sys.argv[2]) - float(sys.argv[1]), sys.argv[3]))" "$t0" "$t1" "$OUT"
