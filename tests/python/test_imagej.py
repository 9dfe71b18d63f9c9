#!/usr/bin/python3
"""The ImageJ plugin (imagej/): --help-json for every command, the plugin on
the demo data with no display (call() from a -batch macro) and under Xvfb
(run() and the Recorder), depth.tif calibrated with its lookup table (and its
calibration bar under Xvfb), a selection and a frame range, "other options",
the dialog's remembered values, an unsaved hyperstack, bad inputs (the macro
ends, Java does not; a script catches the failure), Escape, and the
installed jar finding the installed col0rme.

usage: test_imagej.py COL0RME PLUGIN_JAR IJ_JAR SOURCE_DIR BUILD_DIR SCRATCH
Exits 77 (skipped) with the reason, after the --help-json checks, when java,
the jar, ij.jar or Xvfb is missing."""
import glob
import json
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np
import tifffile

exe, jar, ij_jar, src, build, scratch = sys.argv[1:7]
exe, scratch = os.path.abspath(exe), os.path.abspath(scratch)
jar = os.path.abspath(jar) if jar else ""
ANGLES = "62.5,63.5,65,67,70"
STACKS = ",".join("stack_q%02d.tif" % k for k in range(1, 6))
T0 = time.time()


def skip(why):
    print("SKIP: " + why)
    sys.exit(77)


def check(cond, what):
    if not cond:
        print("FAIL: " + what)
        sys.exit(1)
    print("ok: " + what)


# --help-json: every command, every flag of --help, parseable, exit 0
for cmd in ("eval", "info", "simulate", "intensity", "matirf", "run", "support"):
    r = subprocess.run([exe, cmd, "--help-json"], capture_output=True, text=True, timeout=30)
    doc = json.loads(r.stdout)
    flags = [o["flag"] for o in doc["options"]]
    helpflags = re.findall(r"^\s+(?:-\w, )?(--[\w-]+)", subprocess.run([exe, cmd, "--help"], capture_output=True,
                                                                        text=True, timeout=30).stdout, re.M)
    helpflags = [f for f in helpflags if f not in ("--help", "--help-json")]
    check(r.returncode == 0 and doc["command"] == cmd and flags == helpflags
          and all(set(o) == {"flag", "short", "param", "type", "metavar", "help", "default"} for o in doc["options"]),
          "%s --help-json lists the %d options of --help" % (cmd, len(flags)))
run_opts = {o["flag"]: o for o in json.loads(subprocess.run([exe, "run", "--help-json"], capture_output=True,
                                                            text=True).stdout)["options"]}
check(run_opts["--pixel-size"]["param"] == "pixel_nm" and run_opts["--n-glass"]["default"] == "1.518"
      and run_opts["--drift"]["metavar"] == "on|off" and run_opts["--verbose"]["type"] == "flag",
      "run --help-json: parameter names, defaults and choices")

# the plugin needs java, ij.jar and Xvfb (the --help-json checks above do not)
for tool in ("java", "javac", "Xvfb"):
    if not shutil.which(tool):
        skip("%s not found (apt-get install default-jdk-headless xvfb imagej)" % tool)
if not os.path.isfile(jar):
    skip("the plugin jar was not built (no JDK or ij.jar when CMake configured)")
if not os.path.isfile(ij_jar):
    skip("ImageJ's %s not found" % ij_jar)

shutil.rmtree(scratch, ignore_errors=True)
for d in ("bin", "home", "tmp", "ij/plugins", "hooks", "nobin"):
    os.makedirs(os.path.join(scratch, d))
os.symlink(exe, os.path.join(scratch, "bin", "col0rme"))
shutil.copy(jar, os.path.join(scratch, "ij", "plugins", "col0rme_.jar"))
subprocess.run(["javac", "-cp", ij_jar + ":" + jar, "-d", os.path.join(scratch, "hooks"),
                os.path.join(src, "tests", "imagej", "TestHooks.java")], check=True, timeout=120)
TMP = os.path.join(scratch, "tmp")
BASE_PATH = "/usr/bin:/bin"


def imagej(macro, name, display=None, headless=True, path=None, plugin_jar=None, timeout=120):
    """Runs macro with ImageJ -batch (its own home and temporary folder);
    returns (exit status, stdout, stderr)."""
    m = os.path.join(scratch, name + ".ijm")
    with open(m, "w") as f:
        f.write(macro)
    env = dict(os.environ, PATH=path or os.path.join(scratch, "bin") + ":" + BASE_PATH, HOME=os.path.join(scratch, "home"))
    env.pop("DISPLAY", None)
    if display:
        env["DISPLAY"] = display
    cp = ij_jar + ":" + os.path.join(scratch, "hooks") + (":" + plugin_jar if plugin_jar else "")
    cmd = ["timeout", str(timeout), "java", "-Xmx1g", "-Duser.home=" + env["HOME"], "-Djava.io.tmpdir=" + TMP,
           "-Dplugins.dir=" + os.path.join(scratch, "ij")]
    if headless:
        cmd.append("-Djava.awt.headless=true")
    r = subprocess.run(cmd + ["-cp", cp, "ij.ImageJ", "-batch", m], capture_output=True, text=True, env=env)
    if r.returncode not in (0, 1):
        print(r.stdout, r.stderr)
    return r.returncode, r.stdout, r.stderr


def volume_bytes(path):
    return tifffile.imread(path).astype(">f4").tobytes()


def same_file_pixels(a, b):
    return np.array_equal(tifffile.imread(a), tifffile.imread(b), equal_nan=True)


# the documented options string (docs/imagej.md), with this test's output folder
doc = open(os.path.join(src, "docs", "imagej.md")).read()
doc_line = re.search(r'^run\("3D-COL0RME\.\.\.", "(.*)"\);$', doc, re.M).group(1)
DOC_OUT = "/data/demo/run"
check(DOC_OUT in doc_line and "stacks=" + STACKS in doc_line, "docs/imagej.md shows the dialog's options string")

# 1. no display: Demo data, then 3D-COL0RME through call(); the opened volume saved raw
demo = os.path.join(scratch, "demo")
out1 = os.path.join(scratch, "run_headless")
raw1 = os.path.join(scratch, "volume_headless.raw")
rc, so, se = imagej(f"""
d = call("col0rme.Col0rme.demo", "{demo}");
print("demo stages: " + call("TestHooks.stagesDone"));
out = call("col0rme.Col0rme.run3d", "angles={ANGLES} pixel=100 fwhm=229 output={out1} other=[--threads 2]");
selectImage("volume.tif");
getVoxelSize(w, h, d, unit);
print("voxel " + w + " " + h + " " + d + " " + unit + " slices " + nSlices);
print("run stages: " + call("TestHooks.stagesDone"));
call("TestHooks.saveRaw", "volume.tif", "{raw1}");
selectImage("depth.tif");
getVoxelSize(w, h, d, unit);
print("depth voxel " + w + " " + unit + ", " + call("TestHooks.depthInfo", "depth.tif"));
""", "headless", plugin_jar=jar)
print(so, se)
cli1 = os.path.join(scratch, "run_cli")
stacks = [os.path.join(demo, "data", s) for s in STACKS.split(",")]
r = subprocess.run([exe, "run", "--progress-json", "--angles", ANGLES, "--pixel-size", "100", "--fwhm", "229", "-o", cli1] + stacks,
                   capture_output=True, text=True, timeout=300)
check(r.returncode == 0, "the CLI on the demo data")
# the stages the CLI's JSON lines finish, in order: the plugin's status line read the same lines
cli_stages = " ".join(json.loads(l)["progress"]["stage"] for l in r.stderr.splitlines()
                      if l.startswith('{"progress":') and json.loads(l)["progress"]["fraction"] == 1)
check(cli_stages.split()[:2] == ["drift", "support"] and "matirf" in cli_stages, "the CLI's --progress-json names its stages: " + cli_stages)
check("run stages: " + cli_stages + "\n" in so, "headless: the plugin's progress came from the JSON lines (the run's stages, in order)")
check("demo stages: simulate\n" in so, "headless: Demo data's progress came from simulate's JSON lines")
check(rc == 0 and os.path.isfile(os.path.join(out1, "volume.tif")), "headless: the plugin ran on the demo data (exit 0)")
check(open(os.path.join(out1, "volume.tif"), "rb").read() == open(os.path.join(cli1, "volume.tif"), "rb").read(),
      "headless: the plugin's volume.tif equals the CLI's, byte for byte")
check(open(raw1, "rb").read() == volume_bytes(os.path.join(cli1, "volume.tif")),
      "headless: the volume opened in ImageJ equals the CLI's volume.tif, bit for bit")
check("voxel 25 25 20 nm slices 20" in so, "headless: the opened volume is z-calibrated in nm (25 x 25 x 20 nm)")
argv = json.load(open(os.path.join(out1, "report.json")))["argv"]
check("--progress-json" in argv and "--verbose" not in argv and argv[argv.index("--angles") + 1] == ANGLES,
      "the plugin ran col0rme with --progress-json (not --verbose) and the angles")
check(argv[argv.index("--threads") + 1] == "2", "other=[--threads 2] reached col0rme")
check("depth voxel 25 nm, unit nm colour true range 0.0-400.0" in so,
      "headless: depth.tif opened in nm, values in nm, a depth lookup table over 0-400 nm")

# 2. Xvfb: Demo data, then 3D-COL0RME with only an output folder (the dialog
# prefilled from the demo); the documented run() line, recorded as the menu
# would record it; an unsaved hyperstack (written to a temporary folder,
# big-endian); the documented folder macro on a folder with one acquisition
acqs = os.path.join(scratch, "acquisitions")
os.makedirs(os.path.join(acqs, "a1"))
for p in stacks:
    os.symlink(p, os.path.join(acqs, "a1", os.path.basename(p)))
folder_macro = re.search(r"^```\n(dir = getDirectory.*?)^```", doc, re.M | re.S).group(1)
folder_macro = folder_macro.replace('getDirectory("Folder of acquisitions")', '"%s/"' % acqs)
xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
try:
    display = ":" + xvfb.stdout.readline().decode().strip()
    out0, out2, out3, out5 = (os.path.join(scratch, n) for n in ("run_demo", "run_xvfb", "run_hyper", "run_roi"))
    hyper_copy = os.path.join(scratch, "hyper_as_imagej_writes.tif")
    opts = doc_line.replace(DOC_OUT, out2)
    rc, so, se = imagej(f"""run("Demo data");
run("3D-COL0RME...", "output={out0}");
print("XDEPTH " + call("TestHooks.depthInfo", "depth.tif"));
close("volume.tif"); close("depth.tif"); close("support.tif"); close("render.tif");
line = call("TestHooks.record", "3D-COL0RME...", "{opts}");
print("RECORDED " + line);
close("volume.tif"); close("depth.tif"); close("support.tif"); close("render.tif");
selectImage("stack_q02.tif");
makeRectangle(8, 16, 32, 24);
run("3D-COL0RME...", "stacks={STACKS} angles={ANGLES} pixel=100 fwhm=229 frames=101-400 output={out5} other=[--acquisition-order 1,2,3,4,5]");
selectImage("stack_q02.tif");
print("ROI kept " + selectionType());
run("Select None");
close("volume.tif"); close("depth.tif"); close("support.tif"); close("render.tif");
call("TestHooks.answer", "3D-COL0RME", "Lambda", "0.0021");
run("3D-COL0RME...");
close("volume.tif"); close("depth.tif"); close("support.tif"); close("render.tif");
call("TestHooks.answer", "3D-COL0RME", "Lambda", "");
run("3D-COL0RME...");
print("REMEMBERED lambda=" + call("TestHooks.seen"));
close("volume.tif"); close("depth.tif"); close("support.tif"); close("render.tif");
h = call("TestHooks.hyperstack", "{STACKS}", "angles as channels");
call("TestHooks.saveTiff", "angles as channels", "{hyper_copy}");
for (k = 1; k <= 5; k++) close("stack_q0" + k + ".tif");
run("3D-COL0RME...", "stacks=[angles as channels] angles={ANGLES} pixel=100 fwhm=229 output={out3} drift=on bleaching=estimate");
close("*");
{folder_macro}""", "xvfb", display=display, headless=False)
    print(so, se)
finally:
    xvfb.terminate()
    xvfb.wait()
cli_volume = open(os.path.join(cli1, "volume.tif"), "rb").read()
check(rc == 0, "Xvfb: the macro ran (exit 0)")
check(open(os.path.join(out0, "volume.tif"), "rb").read() == cli_volume,
      "Xvfb: Demo data, then OK in 3D-COL0RME... (only the output given) gives the CLI's volume.tif")
check(re.search(r"^XDEPTH unit nm colour true range 0.0-400.0 overlay true$", so, re.M) is not None,
      "Xvfb: depth.tif with its depth lookup table and calibration bar")
sup5 = tifffile.imread(os.path.join(out5, "support.tif"))
rep5 = json.load(open(os.path.join(out5, "report.json")))
# the support pools the 5 stacks' frames 101-400
check(sup5.shape == (96, 128) and all(s["frames"] == 5 * 300 for s in rep5["support"]) and "ROI kept 0" in so
      and rep5["argv"][rep5["argv"].index("--acquisition-order") + 1] == "1,2,3,4,5",
      "Xvfb: a rectangular selection (32x24) and frames=101-400 honoured, other options passed, the selection kept")
asked = sorted(glob.glob(os.path.join(TMP, "col0rme-demo*", "data", "col0rme_run*", "report.json")))
argv_asked = [json.load(open(p))["argv"] for p in asked]
check("REMEMBERED lambda=0.0021" in so and len(argv_asked) == 2
      and all(a[a.index("--lambda") + 1] == "0.0021" for a in argv_asked if "--lambda" in a) and "--lambda" in argv_asked[0]
      and "--lambda" in argv_asked[1],
      "Xvfb: the dialog remembers its last values (lambda typed once, offered again: %s)"
      % [a[a.index("--lambda") + 1] if "--lambda" in a else None for a in argv_asked])
rec = re.search(r'^RECORDED (.*)$', so, re.M).group(1).strip()
check(rec == 'run("3D-COL0RME...", "%s");' % opts, "Xvfb: the Recorder's line is the documented options string")
check(open(os.path.join(out2, "volume.tif"), "rb").read() == cli_volume,
      "Xvfb: run(\"3D-COL0RME...\") gives the CLI's volume.tif, byte for byte")
check(open(hyper_copy, "rb").read(2) == b"MM", "ImageJ writes the hyperstack big-endian (MM)")
check(same_file_pixels(os.path.join(out3, "volume.tif"), os.path.join(cli1, "volume.tif")),
      "Xvfb: an unsaved hyperstack (angles as channels, written big-endian by ImageJ) gives the same volume")
check(open(os.path.join(acqs, "a1_col0rme", "volume.tif"), "rb").read() == cli_volume,
      "Xvfb: the documented folder macro gives the CLI's volume.tif for the acquisition")
hyper_argv = json.load(open(os.path.join(out3, "report.json")))["argv"]
check(re.fullmatch(re.escape(TMP) + r"/col0rme-in\d*/stack_01\.tif", hyper_argv[-1]) is not None,
      "the unsaved hyperstack went to col0rme as a temporary file")
check(not [f for f in os.listdir(TMP) if f.startswith("col0rme-in")], "the temporary copy of the hyperstack was removed")
shutil.rmtree(TMP)
os.makedirs(TMP)

# 3. bad input: one line, the macro ends there (a macro error) but Java does
# not (ImageJ -batch then exits 0 as after any macro), nothing written
def refused(name, macro, want, path=None):
    out = os.path.join(scratch, "bad_" + name)
    before = set(os.listdir(scratch))
    rc, so, se = imagej(macro.replace("output=OUT", "output=" + out) + '\nprint("MACRO WENT ON");', "bad_" + name,
                        path=path, plugin_jar=jar)
    lines = [l for l in se.splitlines() if l.strip()]
    print("  " + name + ": " + " | ".join(lines))
    check(rc == 0 and len(lines) == 1 and want in lines[0] and lines[0].startswith("col0rme")
          and "MACRO WENT ON" not in so and "Exception" not in so,
          "bad input, %s: one line with '%s', the macro ended, Java did not exit 1" % (name, want))
    check(not os.path.exists(out) and set(os.listdir(scratch)) - before == {"bad_" + name + ".ijm"}
          and not os.listdir(TMP), "bad input, %s: nothing written" % name)


# with no display ImageJ opens no images: these name the files in stacks=
paths = ",".join(stacks)
small = os.path.join(scratch, "small.tif")
plain = os.path.join(scratch, "plain.tif")
noise = np.random.default_rng(1).integers(90, 200, (100, 32, 32)).astype(np.uint16)
tifffile.imwrite(small, noise, imagej=True, resolution=(10, 10), metadata={"unit": "um"})
tifffile.imwrite(plain, noise)
RUN = 'call("col0rme.Col0rme.run3d", "stacks=[%s] angles=%s fwhm=229 output=OUT");'
refused("sizes", RUN % (",".join(stacks[:4] + [small]), ANGLES), "the stacks must have the same size")
refused("count", RUN % (",".join(stacks[:4]), ANGLES), "5 angles but 4 stacks")
refused("uncalibrated", 'call("col0rme.Col0rme.support", "stack=%s fwhm=229 output=OUT");' % plain, "has no pixel size")
refused("no_executable", RUN % (paths, ANGLES), "the col0rme executable was not found",
        path=os.path.join(scratch, "nobin") + ":" + BASE_PATH)
refused("prefs_executable", 'call("ij.Prefs.set", "col0rme.executable", "%s/nobin/col0rme");\n' % scratch + RUN % (paths, ANGLES),
        "set in ImageJ's preferences")
# the CLI refuses a single stack below the critical angle only when fewer than
# two are above it (the others join the support): the CLI's own line comes back
refused("below_critical", RUN % (paths, "50,55,58,60,61"),
        "col0rme run: error: --angles: MA-TIRF needs at least 2 angles above the critical angle")
refused("escape", 'call("TestHooks.escapeWhileRunning", "run");\n' + RUN % (paths, ANGLES), "cancelled; nothing was written")
RUN_OTHER = 'call("col0rme.Col0rme.run3d", "stacks=[%s] angles=%s fwhm=229 output=OUT other=[%s]");'
refused("other_unknown", RUN_OTHER % (paths, ANGLES, "--no-such-flag 1"), "--no-such-flag is not an option of col0rme run")
refused("other_field", RUN_OTHER % (paths, ANGLES, "--fwhm 200"), "--fwhm is the dialog's field fwhm=")
refused("other_value", RUN_OTHER % (paths, ANGLES, "--acquisition"), "--acquisition needs a value")
refused("frames", 'call("col0rme.Col0rme.run3d", "stacks=[%s] angles=%s fwhm=229 frames=400-900 output=OUT");'
        % (paths, ANGLES), "has frames 1-500")

# a script outside any macro catches the failure as a RuntimeException; Java goes on
r = subprocess.run(["java", "-Djava.awt.headless=true", "-Duser.home=" + os.path.join(scratch, "home"),
                    "-cp", ij_jar + ":" + os.path.join(scratch, "hooks") + ":" + jar, "TestHooks",
                    "stacks=[%s] angles=%s fwhm=229 output=%s" % (",".join(stacks[:4]), ANGLES,
                                                                  os.path.join(scratch, "bad_script"))],
                   capture_output=True, text=True, timeout=120, env=dict(os.environ, PATH=os.path.join(scratch, "bin") + ":" + BASE_PATH))
check(r.returncode == 0 and "caught: col0rme: 5 angles but 4 stacks" in r.stdout and "java goes on" in r.stdout
      and not os.path.exists(os.path.join(scratch, "bad_script")),
      "a script's call that fails raises a RuntimeException it catches; Java goes on (%r)" % (r.stdout + r.stderr)[-300:])

# 4. the installed jar finds the installed col0rme (no col0rme on PATH): Support only
prefix = os.path.join(scratch, "prefix")
subprocess.run(["cmake", "--install", build, "--prefix", prefix], check=True, capture_output=True, timeout=120)
ijar = os.path.join(prefix, "share", "col0rme", "imagej", "col0rme_.jar")
check(os.path.isfile(ijar), "cmake --install puts the plugin at share/col0rme/imagej/col0rme_.jar")
out4 = os.path.join(scratch, "support_installed")
rc, so, se = imagej(f"""call("col0rme.Col0rme.support", "stack={stacks[0]} fwhm=229 output={out4}");
print("images " + nImages);""", "installed", path=os.path.join(scratch, "nobin") + ":" + BASE_PATH, plugin_jar=ijar)
print(so, se)
check(rc == 0 and "col0rme: " + os.path.join(prefix, "bin", "col0rme") + " support" in so
      and os.path.isfile(os.path.join(out4, "support.tif")), "the installed plugin runs PREFIX/bin/col0rme: Support only")
print("test_imagej: all passed in %.1f s" % (time.time() - T0))
