"""The cross-validated support lambda (--lambda-rule cv, stages/lambda_cv.c).

- on two members of the grid panel (docs/history/lambda-drift.md, *Cross-validated
  lambda*) the chosen lambda's Jaccard index is within 0.02 of the best of
  an 11-point sweep (ratio sqrt 2, 2e-2 ... 6.25e-4), stored here with the
  command that measured it; "fast" is a member where the default rule
  (peaks) is 0.041 short, "62" one where the criterion's least itself (no
  one-standard-error step) is 0.06 short;
- report.json holds the path (falling from its start, least and the
  halves' choice on it, the choice no lower than the least, the solve's
  lambda the choice over sqrt 2) and the report page its plot;
- on 4 tiles (--tile 24) the choice is the one tile's or its path
  neighbour, and does not depend on the thread count (identical files).

The sweep's best (seed 5, 48x48, 500 frames, depths 0-200 nm):
  GRID=1 MEMBERS="ccd 65 500 fast,ccd 62 500" JOBS=2 /usr/bin/python3 \\
      tests/python/lambda_panel.py build/col0rme WORKDIR
usage: test_lambda_cv.py COL0RME [full|quick]
(quick, the sanitizer build: the "fast" member only, without the accuracy bar and the
1-thread run)
"""
import json
import os
import subprocess
import sys
import tempfile

from checks import check, done

CLI = sys.argv[1]
QUICK = sys.argv[2:] == ["quick"]
COMMON = ["--seed", "5", "--width", "48", "--height", "48", "--z-range", "0,200"]
MEMBERS = {   # name: (simulate options, best Jaccard index of the sweep, its lambda)
    "fast": (["--angles", "65", "--tau-on", "10", "--tau-off", "120"], 0.659, 1.41e-2),
    "62": (["--angles", "62"], 0.684, 7.07e-3),
}
if QUICK:
    del MEMBERS["62"]


def sh(args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def support(stack, out, *extra):
    sh([CLI, "support", "-o", out, "--force", "--fwhm", "229", "--lambda-rule", "cv", "--frc", "0", *extra, stack])
    return json.load(open(os.path.join(out, "report.json")))["support"][0]


def jaccard(out, sim):
    r = sh([CLI, "eval", "--support", os.path.join(out, "support.tif"), "--support-truth",
            os.path.join(sim, "truth_support.tif"), "--margin", "12"])
    return json.loads(r)["support"]["jaccard"]


with tempfile.TemporaryDirectory() as tmp:
    for name, (opts, best, lbest) in MEMBERS.items():
        sim = os.path.join(tmp, name)
        sh([CLI, "simulate", "-o", sim, "--force", *COMMON, *opts])
        out = os.path.join(tmp, name + "_cv")
        rep = support(os.path.join(sim, "stack_q01.tif"), out, "--threads", "2")
        j = jaccard(out, sim)
        print("%s: lambda %.4g (best of the sweep %.3g), JI %.3f (best %.3f)" % (name, rep["lambda_relative"], lbest, j,
                                                                                 best))
        if not QUICK:
            check(j >= best - 0.02, "%s: JI %.3f within 0.02 of the sweep's best %.3f" % (name, j, best))
        cv = rep["lambda_auto"]["cross_validation"]
        rel, err = cv["lambda_relative"], cv["error"]
        check(len(rel) == len(err) >= 3 and err[0] >= min(err) and err[0] < 1,
              "%s: the path falls from its start (%d points)" % (name, len(rel)))
        check(cv["least_relative"] in rel and cv["chosen_relative"] in rel
              and cv["chosen_relative"] >= cv["least_relative"]
              and abs(rep["lambda_relative"] * 2 ** 0.5 / cv["chosen_relative"] - 1) < 1e-9,
              "%s: least and chosen on the path, the solve's lambda the chosen over sqrt 2" % name)
        if name == "fast":
            sh([CLI, "report", out])
            page = open(os.path.join(out, "report.html"), encoding="utf-8").read()
            check("cross-validation error" in page, "the report page plots the criterion")
            # tiles: the same path on the 4 tiles' halves (all of them in the subset); 1 and 2 threads
            # give the same files (the sanitizer build runs the 2 threads' path only)
            t2 = os.path.join(tmp, "t2")
            r2 = support(os.path.join(sim, "stack_q01.tif"), t2, "--tile", "24", "--threads", "2")
            ratio = r2["lambda_relative"] / rep["lambda_relative"]
            print("tiles: lambda %.4g (one tile %.4g)" % (r2["lambda_relative"], rep["lambda_relative"]))
            check(0.7 <= ratio <= 1.42, "tiles: lambda %.4g vs one tile %.4g" % (r2["lambda_relative"],
                                                                                  rep["lambda_relative"]))
            if not QUICK:
                t1 = os.path.join(tmp, "t1")
                r1 = support(os.path.join(sim, "stack_q01.tif"), t1, "--tile", "24", "--threads", "1")
                same = all(open(os.path.join(t1, f), "rb").read() == open(os.path.join(t2, f), "rb").read()
                           for f in ("support.tif", "rx.tif"))
                check(same and r1["lambda_relative"] == r2["lambda_relative"], "tiles: 1 and 2 threads give the same files")
done()
