"""The figures of the docs, made from the tree so that they cannot go stale.

    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR]            rewrite the marked block of docs/design.md
    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR] --check    exit 1 if the block differs from the tree
    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR] --screenshot RUN_DIR
        docs/report.png from RUN_DIR/report.html (chromium --headless, then 256
        colours with python3-pil), e.g. after
        `bash scripts/demo.sh` with RUN_DIR build/demo/run
    /usr/bin/python3 scripts/docs_figures.py [SOURCE_DIR] --imagej BUILD_DIR
        docs/imagej_dialog.png and docs/imagej_result.png: ImageJ (ij.jar) with the
        built plugin (BUILD_DIR/imagej/col0rme_.jar) and BUILD_DIR/col0rme under Xvfb,
        Demo data, the 3D-COL0RME dialog, then its run's windows tiled

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


SHOT_JAVA = r"""
import java.awt.*;
import java.awt.event.KeyEvent;
import java.awt.image.BufferedImage;
import java.io.File;
import javax.imageio.ImageIO;

/** Screenshots for the docs, called from an ImageJ macro with call("DocShot...."). */
public class DocShot {
	static void shoot(Rectangle r, String path) throws Exception {
		BufferedImage img = new Robot().createScreenCapture(r);
		ImageIO.write(img, "png", new File(path));
	}

	/** Once a dialog shows: its picture into path, then Enter (OK, as filled in). */
	public static String dialogLater(final String path) {
		Thread t = new Thread(() -> {
			try {
				for (int i = 0; i < 1200; i++) {
					Thread.sleep(100);
					for (Window w : Window.getWindows())
						if (w instanceof ij.gui.GenericDialog && w.isShowing()) {
							Thread.sleep(2000);
							shoot(w.getBounds(), path);
							((java.awt.event.KeyListener) w).keyPressed(new KeyEvent(w, KeyEvent.KEY_PRESSED,
								System.currentTimeMillis(), 0, KeyEvent.VK_ENTER, (char) 10));
							return;
						}
				}
			} catch (Exception e) {
				e.printStackTrace();
			}
		});
		t.setDaemon(true);
		t.start();
		return "";
	}

	/** The image windows of the titles given (comma-separated), in a row of
	 *  columns two high from the screen's top left, as one picture; the
	 *  other windows are hidden. */
	public static String windows(String titles, String path) throws Exception {
		java.util.List<String> want = java.util.Arrays.asList(titles.split(","));
		Window[] shown = new Window[want.size()];
		StringBuilder seen = new StringBuilder();
		for (int t = 0; t < 100 && java.util.Arrays.asList(shown).contains(null); t++) {
			Thread.sleep(200);
			seen.setLength(0);
			for (Window w : Window.getWindows())
				if (w instanceof ij.gui.ImageWindow && w.isShowing()) {
					String title = ((ij.gui.ImageWindow) w).getImagePlus().getTitle();
					seen.append(title).append(' ');
					int k = want.indexOf(title);
					if (k >= 0)
						shown[k] = w;
				}
		}
		for (Window w : Window.getWindows())
			if (w.isShowing() && !java.util.Arrays.asList(shown).contains(w))
				w.setVisible(false);   /* ImageJ's own window, the stacks, the Log */
		for (int k = 0; k < shown.length; k++)
			if (shown[k] == null)
				throw new IllegalStateException("no window " + want.get(k) + " among: " + seen);
		int x = 0, y = 0, colw = 0;
		Rectangle all = null;
		for (int k = 0; k < shown.length; k++) {
			if (k % 2 == 0 && k > 0) {
				x += colw;
				y = 0;
				colw = 0;
			}
			shown[k].setLocation(x, y);
			Rectangle r = shown[k].getBounds();
			y += r.height;
			colw = Math.max(colw, r.width);
			all = all == null ? r : all.union(r);
		}
		Thread.sleep(3000);
		shoot(all, path);
		return path;
	}

	public static String quit() {
		System.exit(0);
		return "";
	}
}
"""


def imagej_shots(src, build):
    """docs/imagej_dialog.png and docs/imagej_result.png, made under Xvfb."""
    jar = os.path.abspath(os.path.join(build, "imagej", "col0rme_.jar"))
    exe = os.path.abspath(os.path.join(build, "col0rme"))
    ij_jar = next((j for j in ("/usr/share/java/ij.jar",) if os.path.exists(j)), None)
    for what, ok in (("the plugin jar " + jar, os.path.exists(jar)), ("ImageJ's ij.jar (Debian imagej)", ij_jar),
                     ("java", shutil.which("java")), ("javac", shutil.which("javac")), ("Xvfb", shutil.which("Xvfb"))):
        if not ok:
            sys.exit("docs_figures.py: %s not found" % what)
    docs = os.path.abspath(os.path.join(src, "docs"))
    with tempfile.TemporaryDirectory() as tmp:
        for d in ("bin", "home", "ij/plugins", "shot"):
            os.makedirs(os.path.join(tmp, d))
        os.symlink(exe, os.path.join(tmp, "bin", "col0rme"))
        shutil.copy(jar, os.path.join(tmp, "ij", "plugins"))
        open(os.path.join(tmp, "shot", "DocShot.java"), "w").write(SHOT_JAVA)
        subprocess.run(["javac", "-cp", ij_jar, "-d", os.path.join(tmp, "shot"), os.path.join(tmp, "shot", "DocShot.java")],
                       check=True)
        dialog, result = os.path.join(tmp, "dialog.png"), os.path.join(tmp, "result.png")
        macro = os.path.join(tmp, "shots.ijm")
        open(macro, "w").write("""run("Demo data");
call("DocShot.dialogLater", "%s");
run("3D-COL0RME...");
selectImage("volume.tif");
setSlice(6);
call("DocShot.windows", "volume.tif,render.tif,depth.png,support.tif", "%s");
call("DocShot.quit");
""" % (dialog, result))
        xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        try:
            env = dict(os.environ, DISPLAY=":" + xvfb.stdout.readline().decode().strip(), HOME=os.path.join(tmp, "home"),
                       PATH=os.path.join(tmp, "bin") + ":/usr/bin:/bin")
            r = subprocess.run(["timeout", "180", "java", "-Xmx1g", "-Duser.home=" + env["HOME"],
                                "-Dplugins.dir=" + os.path.join(tmp, "ij"), "-Djava.io.tmpdir=" + tmp, "-cp", ij_jar + ":" + os.path.join(tmp, "shot"),
                                "ij.ImageJ", "-macro", macro], env=env, capture_output=True, text=True)
        finally:
            xvfb.terminate()
            xvfb.wait()
        if not (os.path.exists(dialog) and os.path.exists(result)):
            sys.exit("docs_figures.py: ImageJ made no screenshot (exit %d)\n%s%s" % (r.returncode, r.stdout, r.stderr))
        from PIL import Image
        for f, name in ((dialog, "imagej_dialog.png"), (result, "imagej_result.png")):
            Image.open(f).convert("RGB").quantize(256).save(os.path.join(docs, name), optimize=True)
            print("wrote", os.path.join(docs, name))


def main(argv):
    if "--imagej" in argv:
        k = argv.index("--imagej")
        rest = argv[:k] + argv[k + 2:]
        return imagej_shots(rest[0] if rest else ".", argv[k + 1])
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
