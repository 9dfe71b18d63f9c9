"""The figures of the docs, made from the tree so that they cannot go stale.

    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR]            rewrite the marked block of docs/design.md
    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR] --check    exit 1 if the block differs from the tree
    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR] --screenshot RUN_DIR
        docs/report.png from RUN_DIR/report.html (chromium --headless, then 256
        colours with python3-pil), e.g. after
        `bash scripts/demo.sh` with RUN_DIR build/demo/run

The block of docs/design.md between the markers below holds the house's limits
as measured: the longest .c file and function in src/ and the share of src/ in
src/stages/ (lines of .c and .h files). A function is counted from the first line
of its signature to its closing brace at column 0."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

BEGIN = "<!-- docs_figures.py: begin -->"
END = "<!-- docs_figures.py: end -->"
DESIGN = os.path.join("docs", "design.md")


def sources(root, exts=(".c", ".h")):
    for d, dirs, files in os.walk(root):
        dirs.sort()
        for f in sorted(files):
            if f.endswith(exts):
                yield os.path.join(d, f)


def nlines(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return sum(1 for _ in f)


def functions(path):
    """(name, lines) of each function defined at column 0 in a C file."""
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        l = lines[i]
        if re.match(r"[A-Za-z_]", l) and "(" in l and not l.rstrip().endswith(";") and not l.startswith("#"):
            sig, j = [], i
            while j < len(lines) and len(sig) < 12:
                sig.append(lines[j])
                if lines[j].rstrip().endswith("{") or lines[j] == "{" or lines[j].rstrip().endswith(";"):
                    break
                j += 1
            head = "\n".join(sig).rstrip()
            body_opens = head.endswith("{") and not head.endswith(";")
            if body_opens and re.search(r"\)\s*\{$", head):
                k = j + 1
                while k < len(lines) and lines[k] != "}":
                    k += 1
                name = re.findall(r"(\w+)\s*\(", head)[0]
                out.append((name, k - i + 1))
                i = k
        i += 1
    return out


def measure(src):
    root = os.path.join(src, "src")
    rel = lambda p: os.path.relpath(p, root)
    files = [(nlines(p), rel(p)) for p in sources(root, (".c",))]
    funcs = [(n, name, rel(p)) for p in sources(root, (".c",)) for name, n in functions(p)]
    total = sum(nlines(p) for p in sources(root))
    stages = sum(nlines(p) for p in sources(os.path.join(root, "stages")))
    return {
        "file": max(files),
        "files_over": sum(1 for n, _ in files if n > 700),
        "func": max(funcs),
        "funcs_over": sum(1 for f in funcs if f[0] > 100),
        "total": total,
        "stages": stages,
        "folders": [(f, sum(1 for _ in sources(os.path.join(root, f))), sum(nlines(q) for q in sources(os.path.join(root, f))))
                    for f in sorted(os.listdir(root)) if os.path.isdir(os.path.join(root, f))],
        "cjson": sum(1 for p in sources(os.path.join(root, "stages")) if "cJSON" in open(p, encoding="utf-8", errors="replace").read()),
    }


def block(m):
    fn, fname, ffile = m["func"]
    return "\n".join([
        BEGIN,
        "Measured on the tree by `scripts/docs_figures.py` (its test, `docs_figures`, fails when",
        "this block is stale): longest function %d lines (`%s`, `%s`), longest file %s lines"
        % (fn, fname, ffile, format(m["file"][0], ",")),
        "(`%s`); %d `.c` file%s over 700 lines and %d function%s over 100; `src/stages/` %.1f %% of"
        % (m["file"][1], m["files_over"], "" if m["files_over"] == 1 else "s", m["funcs_over"], "" if m["funcs_over"] == 1 else "s",
           100.0 * m["stages"] / m["total"]),
        "`src/` (%s of %s lines of `.c` and `.h`); `cJSON` in %d file%s of `src/stages/`."
        % (format(m["stages"], ","), format(m["total"], ","), m["cjson"], "" if m["cjson"] == 1 else "s"),
        "",
        "| folder | files (.c, .h) | lines |",
        "|---|---|---|",
    ] + ["| `%s/` | %d | %s |" % (f, n, format(l, ",")) for f, n, l in m["folders"]] + [
        END,
    ])


def screenshot(src, run):
    html = os.path.abspath(os.path.join(run, "report.html"))
    if not os.path.exists(html):
        sys.exit("docs_figures.py: %s: no report.html (run scripts/demo.sh first)" % run)
    browser = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if not browser:
        sys.exit("docs_figures.py: no chromium to take the screenshot with")
    out = os.path.abspath(os.path.join(src, "docs", "report.png"))
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        "--user-data-dir=" + profile, "--window-size=1200,1400",
                        "--screenshot=" + out, "file://" + html],
                       check=True, capture_output=True)
    from PIL import Image   # python3-pil: 256 colours, a third of the size, the same to the eye
    Image.open(out).convert("RGB").quantize(256).save(out, optimize=True)
    print("wrote", out)


def main(argv):
    run = None
    if "--screenshot" in argv:
        k = argv.index("--screenshot")
        if k + 1 >= len(argv):
            sys.exit("docs_figures.py: --screenshot needs the run's directory")
        run = argv[k + 1]
        argv = argv[:k] + argv[k + 2:]
    args = [a for a in argv if not a.startswith("--")]
    src = args[0] if args else "."
    if run:
        return screenshot(src, run)
    path = os.path.join(src, DESIGN)
    text = open(path, encoding="utf-8").read()
    if BEGIN not in text or END not in text:
        sys.exit("docs_figures.py: %s has no block between %s and %s" % (path, BEGIN, END))
    a, b = text.index(BEGIN), text.index(END) + len(END)
    want = block(measure(src))
    if "--check" in argv:
        if text[a:b] != want:
            print("FAIL: %s's figures differ from the tree (run: /usr/bin/python3 scripts/docs_figures.py)" % DESIGN)
            print(want)
            return 1
        print("docs/design.md's figures match the tree")
        return 0
    open(path, "w", encoding="utf-8").write(text[:a] + want + text[b:])
    print(want)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
