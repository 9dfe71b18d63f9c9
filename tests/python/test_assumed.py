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
    r = subprocess.run([CLI, "simulate", "-o", sim, "--width", "24", "--height", "24", "--frames", "60",
                        "--angles", "62,65,68", "--seed", "4"], capture_output=True, text=True)
    check(r.returncode == 0, "simulate: " + r.stderr)
    stacks = [os.path.join(sim, "stack_q%02d.tif" % (q + 1)) for q in range(3)]
    cases = [([], ["wavelength_nm 488", "n_sample 1.33"]), (["--wavelength", "488"], ["n_sample 1.33"]),
             (["--n-sample", "1.37"], ["wavelength_nm 488"]), (["--wavelength", "488", "--n-sample", "1.33"], []),
             (["--wavelength", "561", "--n-sample", "1.37"], [])]
    def said(cmd, opts, names, r):
        lines = assumed(r.stderr)
        check(r.returncode == 0, "%s %s: %s" % (cmd, opts, r.stderr))
        if names:
            why = "critical angle" if any("n_sample" in n for n in names) else "penetration depth"
            check(len(lines) == 1 and all(n in lines[0] for n in names) and why in lines[0],
                  "%s %s: one line naming %s: %s" % (cmd, opts, names, lines))
        else:
            check(not lines, "%s %s: no assumed line: %s" % (cmd, opts, lines))

    # two cases through run (the lines come before any work: a short MA-TIRF solve keeps it cheap)
    for i in (0, 3):
        opts, names = cases[i]
        r = subprocess.run([CLI, "run", "--angles", "62,65,68", "--fwhm", "229", "--matirf-iterations", "100", *opts,
                            "-o", os.path.join(tmp, "run%d" % i), *stacks], capture_output=True, text=True)
        said("run", opts, names, r)
    r = subprocess.run([CLI, "run", "--fwhm", "229", "-o", os.path.join(tmp, "2d"), stacks[0]], capture_output=True,
                       text=True)
    check(r.returncode == 0 and not assumed(r.stderr), "2D run: no assumed line: " + r.stderr)
    # all five through matirf, on the first run's intensities (angles above n_sample 1.37's critical 64.5 deg)
    imgs = [os.path.join(tmp, "run0", "intensity_q%02d.tif" % (q + 1)) for q in range(3)]
    for i, (opts, names) in enumerate(cases):
        r = subprocess.run([CLI, "matirf", "--angles", "65,66.5,68", "--matirf-iterations", "100", *opts,
                            "-o", os.path.join(tmp, "m%d" % i), *imgs], capture_output=True, text=True)
        said("matirf", opts, names, r)
done()
