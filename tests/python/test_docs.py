"""The docs against the program: docs/params.md is what `col0rme params`
prints (the parameter table of the library), every row links to a section of
docs/defaults.md that exists, every docs/*.md#anchor that src/ cites and every
link between the docs resolves, and every option the README and the guide
name is an option of some command.

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
rows = [l for l in r.stdout.splitlines() if l.startswith("| [`")]
if len(rows) < 40:
    fails.append("col0rme params lists %d parameters" % len(rows))


def anchors(path):
    """The anchors of a Markdown file: GitHub's slugs of its headings and its
    explicit <a id> / <a name> tags."""
    text = re.sub(r"^```.*?^```", "", open(path, encoding="utf-8").read(), flags=re.M | re.S)
    have = set(re.findall(r"<a (?:id|name)=\"([^\"]+)\"", text))
    seen = {}
    for h in re.findall(r"^#{1,6} +(.+?) *#*$", text, re.M):
        slug = re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        have.add(slug if n == 0 else "%s-%d" % (slug, n))
    return have


docs = os.path.join(src, "docs")
defaults = anchors(os.path.join(docs, "defaults.md"))
for row in rows:
    m = re.match(r"\| \[`(\w+)`\]\(defaults\.md#([^)]+)\)", row)
    if not m:
        fails.append("docs/params.md row without a link to docs/defaults.md: " + row[:60])
    elif m.group(2) not in defaults:
        fails.append("docs/params.md: %s links to defaults.md#%s, which has no such section" % m.groups())

# docs/X.md#anchor cited in the code
for d, _, files in os.walk(os.path.join(src, "src")):
    for f in files:
        text = open(os.path.join(d, f), encoding="utf-8", errors="replace").read()
        for doc, a in sorted(set(re.findall(r"docs/([\w/.-]+\.md)(?:#([^\s,;:)\"'`]+))?", text))):
            p = os.path.join(docs, doc)
            if not os.path.exists(p):
                fails.append("%s cites docs/%s, which does not exist" % (f, doc))
            elif a and a not in anchors(p):
                fails.append("%s cites docs/%s#%s, which has no such anchor" % (f, doc, a))
        if "docs/" + "parameters.md" in text:   # split so that the citation script leaves it alone
            fails.append("%s cites docs/" "parameters.md, which is now docs/defaults.md and docs/history/" % f)

# links between the docs: [text](path#anchor) relative to the linking file
for doc in ["README.md"] + ["docs/" + f for f in sorted(os.listdir(docs)) if f.endswith(".md")]:
    here = os.path.dirname(os.path.join(src, doc))
    text = re.sub(r"^```.*?^```", "", open(os.path.join(src, doc), encoding="utf-8").read(), flags=re.M | re.S)
    for target in sorted(set(re.findall(r"\]\(([^)\s]+)\)", text))):
        if re.match(r"[a-z]+:", target):
            continue
        path, _, a = target.partition("#")
        p = os.path.normpath(os.path.join(here, path)) if path else os.path.join(src, doc)
        if not os.path.exists(p):
            fails.append("%s links to %s, which does not exist" % (doc, target))
        elif a and p.endswith(".md") and a not in anchors(p):
            fails.append("%s links to %s, which has no such anchor" % (doc, target))

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
