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


def done():
    print("%d passed, %d failed" % (_count["passed"], _count["failed"]))
    sys.exit(1 if _count["failed"] else 0)
