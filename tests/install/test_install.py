"""Install to a temporary prefix and use the library as a third party would:
the header alone, every examples/*.c built with pkg-config alone, one run of
each, and a CMake project with find_package(col0rme). The Python package
after such an install: test_python.py.

usage: test_install.py BUILD_DIR SOURCE_DIR SCRATCH_DIR"""
import glob
import os
import re
import shutil
import subprocess
import sys

build, src, scratch = map(os.path.abspath, sys.argv[1:4])
fails = []


def check(ok, what):
    print("%-60s %s" % (what, "ok" if ok else "FAILED"))
    if not ok:
        fails.append(what)
    return ok


def sh(cmd, env=None, cwd=None):
    r = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    if r.returncode:
        print("$ %s\n%s%s" % (" ".join(cmd), r.stdout, r.stderr))
    return r


shutil.rmtree(scratch, ignore_errors=True)
os.makedirs(scratch)
prefix = os.path.join(scratch, "prefix")
check(sh(["cmake", "--install", build, "--prefix", prefix]).returncode == 0, "cmake --install")

header = os.path.join(prefix, "include", "col0rme.h")
libs = glob.glob(os.path.join(prefix, "lib*", "libcol0rme.so*"))
pcs = glob.glob(os.path.join(prefix, "lib*", "pkgconfig", "col0rme.pc"))
cfgs = glob.glob(os.path.join(prefix, "lib*", "cmake", "col0rme", "col0rmeConfig.cmake"))
check(os.path.isfile(header), "include/col0rme.h installed")
check(len(libs) >= 3, "libcol0rme.so, .so.MAJOR and the real file installed (%d)" % len(libs))
check(len(pcs) == 1 and len(cfgs) == 1, "col0rme.pc and col0rmeConfig.cmake installed")
if fails:
    sys.exit(1)
libdir = os.path.dirname(pcs[0]).rsplit(os.sep, 1)[0]
so = os.path.join(libdir, "libcol0rme.so")

# SONAME, and the exported symbols are exactly the functions of the header
dyn = sh(["readelf", "-d", so]).stdout
check(re.search(r"SONAME.*\[libcol0rme\.so\.\d+\]", dyn) is not None, "SONAME libcol0rme.so.MAJOR")
syms = set(re.findall(r"\b(c0_\w+)$", sh(["nm", "-D", "--defined-only", so]).stdout, re.M))
hdr = open(header).read()
decl = set(re.findall(r"\b(c0_\w+)\s*\(", re.sub(r"/\*.*?\*/", "", hdr, flags=re.S)))
others = sorted(s for s in re.findall(r"^\S+ [TDBR] (\S+)$", sh(["nm", "-D", "--defined-only", so]).stdout, re.M)
                if not s.startswith("c0_"))
check(syms == decl, "exported c0_ symbols = the header's functions"
      + ("" if syms == decl else " (only exported: %s; only declared: %s)" % (sorted(syms - decl), sorted(decl - syms))))
check(not others, "no other symbols exported %s" % (others[:5] if others else ""))

env = dict(os.environ, PKG_CONFIG_PATH=os.path.dirname(pcs[0]), LD_LIBRARY_PATH=libdir, OMP_WAIT_POLICY="PASSIVE")
flags = sh(["pkg-config", "--cflags", "--libs", "col0rme"], env=env).stdout.split()
check(any(f.startswith("-L") for f in flags), "pkg-config --cflags --libs col0rme: %s" % " ".join(flags))

# the header alone compiles, strict C11
t = os.path.join(scratch, "header.c")
open(t, "w").write("#include <col0rme.h>\nint main(void) { return c0_last_error() == 0; }\n")
check(sh(["cc", "-std=c11", "-Wall", "-Wextra", "-pedantic", "-Werror", t, "-o", t[:-2]] + flags,
         env=env).returncode == 0, "col0rme.h alone, -std=c11 -pedantic")

# the examples of docs/api.md are these files, verbatim
doc = open(os.path.join(src, "docs", "api.md")).read()
for ex, lang in (("run_arrays.c", "c"), ("run_arrays.py", "python")):
    text = open(os.path.join(src, "examples", ex)).read()
    check("```%s\n%s```" % (lang, text) in doc, "docs/api.md shows examples/%s as it is" % ex)

exes = {}
for ex in sorted(glob.glob(os.path.join(src, "examples", "*.c"))):
    name = os.path.basename(ex)[:-2]
    exe = os.path.join(scratch, name)
    if check(sh(["cc", "-std=c11", "-Wall", "-Werror", ex, "-o", exe] + flags, env=env).returncode == 0,
             "examples/%s.c builds with pkg-config alone" % name):
        exes[name] = exe

if "run_arrays" in exes:
    r = sh([exes["run_arrays"]], env=env)
    print(r.stdout.strip())
    check(r.returncode == 0 and "volume" in r.stdout, "run_arrays runs the method on arrays")
if "run_files" in exes:
    data, out = os.path.join(scratch, "data"), os.path.join(scratch, "out")
    col0rme = os.path.join(prefix, "bin", "col0rme")
    r = sh([col0rme, "simulate", "--width", "20", "--height", "20", "--frames", "150", "--angles", "62,66",
            "--filaments", "2", "-o", data], env=env)
    if check(r.returncode == 0, "installed col0rme simulate"):
        r = sh([exes["run_files"], out, "62,66", os.path.join(data, "stack_q01.tif"),
                os.path.join(data, "stack_q02.tif")], env=env)
        check(r.returncode == 0 and os.path.isfile(os.path.join(out, "volume.tif"))
              and os.path.isfile(os.path.join(out, "report.json")), "run_files writes volume.tif and report.json")
        r = sh([exes["run_files"], out, "62,66", os.path.join(data, "stack_q01.tif")], env=env)
        check(r.returncode != 0 and "angles" in r.stderr, "run_files: one stack for two angles is refused")

# a CMake project that finds the installed package
proj = os.path.join(scratch, "cmake_project")
os.makedirs(proj)
shutil.copy(os.path.join(src, "examples", "run_arrays.c"), proj)
open(os.path.join(proj, "CMakeLists.txt"), "w").write(
    "cmake_minimum_required(VERSION 3.18)\nproject(use_col0rme C)\nfind_package(col0rme 0.1 REQUIRED)\n"
    "add_executable(run_arrays run_arrays.c)\ntarget_link_libraries(run_arrays PRIVATE col0rme::col0rme)\n")
ok = sh(["cmake", "-S", proj, "-B", os.path.join(proj, "build"), "-DCMAKE_PREFIX_PATH=" + prefix], env=env).returncode == 0
ok = ok and sh(["cmake", "--build", os.path.join(proj, "build")], env=env).returncode == 0
check(ok, "find_package(col0rme) + col0rme::col0rme in a CMake project")
if ok:
    check(sh([os.path.join(proj, "build", "run_arrays")], env=env).returncode == 0, "its run_arrays runs")

print("%d failed" % len(fails))
sys.exit(1 if fails else 0)
