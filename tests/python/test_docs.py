"""The docs against the program: docs/params.md is what `col0rme params`
prints (the parameter table of the library), and every option the README
and the guide name is an option of some command.

usage: test_docs.py COL0RME SOURCE_DIR"""
import os
import re
import subprocess
import sys

cli, src = sys.argv[1], sys.argv[2]
fails = []


def run(*args):
    return subprocess.run([cli, *args], capture_output=True, text=True)


r = run("params")
have = open(os.path.join(src, "docs", "params.md")).read()
if r.returncode or r.stdout != have:
    fails.append("docs/params.md differs from `col0rme params` (regenerate: build/col0rme params > docs/params.md)")
rows = [l for l in r.stdout.splitlines() if l.startswith("| `")]
if len(rows) < 40:
    fails.append("col0rme params lists %d parameters" % len(rows))

commands = re.findall(r"^  (\w+) ", run("--help").stdout, re.M)
flags = set()
for c in commands:
    h = run(c, "--help")
    if h.returncode:
        fails.append("col0rme %s --help: exit %d" % (c, h.returncode))
    mine = re.findall(r"^ {2}(?:-\w, )? *--([\w-]+)", h.stdout, re.M)
    dup = sorted({f for f in mine if mine.count(f) > 1})
    if dup:
        fails.append("col0rme %s --help: options listed twice: %s" % (c, dup))
    flags.update(mine)
bench = open(os.path.join(src, "bench", "run.py")).read()   # the README names its options too
for doc in ("README.md", "docs/guide.md", "docs/api.md"):
    text = open(os.path.join(src, doc)).read()
    for f in sorted(set(re.findall(r"`(?:col0rme [^`]*?)?--([a-z][\w-]+)", text))):
        if f not in flags and "--" + f not in bench and f not in ("version", "help", "prefix", "no-index", "no-build-isolation", "system-site-packages"):
            fails.append("%s names --%s, which no command takes" % (doc, f))

for f in fails:
    print("FAIL:", f)
print("%d passed, %d failed" % (3 + len(commands) - len([f for f in fails if "--help" in f]), len(fails)))
sys.exit(1 if fails else 0)
