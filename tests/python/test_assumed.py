"""The depth scale's two physical inputs said out loud: an MA-TIRF run that
leaves --wavelength or --n-sample at its default prints one warning line
naming the assumed value; with both given (even at the default's values)
none; a 2D run none. Through `col0rme run` and `col0rme matirf`.

usage: test_assumed.py COL0RME
"""
import os
import subprocess
import sys
import tempfile

from checks import check, done

CLI = sys.argv[1]


def assumed(stderr):
    return [l for l in stderr.splitlines() if "assumed" in l and ("wavelength_nm" in l or "n_sample" in l)]


with tempfile.TemporaryDirectory() as tmp:
    sim = os.path.join(tmp, "sim")
    r = subprocess.run([CLI, "simulate", "-o", sim, "--width", "24", "--height", "24", "--frames", "100",
                        "--angles", "62,65,68", "--seed", "4"], capture_output=True, text=True)
    check(r.returncode == 0, "simulate: " + r.stderr)
    stacks = [os.path.join(sim, "stack_q%02d.tif" % (q + 1)) for q in range(3)]
    cases = [([], ["wavelength_nm 488", "n_sample 1.33"]), (["--wavelength", "488"], ["n_sample 1.33"]),
             (["--n-sample", "1.37"], ["wavelength_nm 488"]), (["--wavelength", "488", "--n-sample", "1.33"], []),
             (["--wavelength", "561", "--n-sample", "1.37"], [])]
    for i, (opts, names) in enumerate(cases):
        out = os.path.join(tmp, "run%d" % i)
        r = subprocess.run([CLI, "run", "--angles", "62,65,68", "--fwhm", "229", *opts, "-o", out, *stacks],
                           capture_output=True, text=True)
        lines = assumed(r.stderr)
        check(r.returncode == 0, "run %s: %s" % (opts, r.stderr))
        if names:
            why = "critical angle" if any("n_sample" in n for n in names) else "penetration depth"
            check(len(lines) == 1 and all(n in lines[0] for n in names) and why in lines[0],
                  "run %s: one line naming %s: %s" % (opts, names, lines))
        else:
            check(not lines, "run %s: no assumed line: %s" % (opts, lines))
    r = subprocess.run([CLI, "run", "--fwhm", "229", "-o", os.path.join(tmp, "2d"), stacks[0]], capture_output=True,
                       text=True)
    check(r.returncode == 0 and not assumed(r.stderr), "2D run: no assumed line: " + r.stderr)
    imgs = [os.path.join(tmp, "run0", "intensity_q%02d.tif" % (q + 1)) for q in range(3)]
    for opts, n in (([], 1), (["--wavelength", "640", "--n-sample", "1.33"], 0)):
        r = subprocess.run([CLI, "matirf", "--angles", "62,65,68", *opts, "-o", os.path.join(tmp, "m%d" % n), *imgs],
                           capture_output=True, text=True)
        check(r.returncode == 0 and len(assumed(r.stderr)) == n, "matirf %s: %d assumed lines: %s" % (opts, n, r.stderr))
done()
