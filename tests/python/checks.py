"""Shared by the Python tests: count checks, name each failure on stderr,
and finish with one summary line and the exit status."""
import sys

_count = {"passed": 0, "failed": 0}


def check(cond, what):
    if cond:
        _count["passed"] += 1
    else:
        _count["failed"] += 1
        print("FAIL:", what, file=sys.stderr)


def refused(p, *needles):
    """a CLI refusal: one error line naming the culprit (every needle), a non-zero exit,
    nothing on stdout; the exit and stderr are printed when it is not"""
    lines = p.stderr.strip().splitlines()
    ok = p.returncode != 0 and len(lines) == 1 and all(n in lines[0] for n in needles) and not p.stdout
    if not ok:
        print("  rc %d, stderr %r" % (p.returncode, p.stderr.strip()), file=sys.stderr)
    return ok


def done():
    print("%d passed, %d failed" % (_count["passed"], _count["failed"]))
    sys.exit(1 if _count["failed"] else 0)


# The simulator's structure before issue 52 (emitters on each filament's axis, 60 a um) and the
# run's model for it (no label radius). For tests whose subject is not the structure but
# whose bars were set where the signal is that weak: the camera's pattern, the fade's fit.
LINES_SIM = ["--density", "60", "--label-radius", "0"]
LINES_RUN = ["--label-radius", "0"]
