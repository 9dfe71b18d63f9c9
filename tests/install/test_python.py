"""The Python package as a user installs it, with no environment variable:
from a copy of the checkout (as a fresh clone; pip builds in the tree it is
given), `pip install --no-index --no-build-isolation ./python` in a fresh
venv with the system's numpy, which builds libcol0rme and ships it in the
package; then its pytest tests, which compare it with this build's CLI.
Then the route of an installed prefix: `cmake --install BUILD --prefix P`,
the same pip install in a second venv, and col0rme.run there equal to P's
col0rme run; COL0RME_LIB still overrides.

usage: test_python.py SOURCE_DIR BUILD_DIR SCRATCH_DIR CLI"""
import glob
import os
import shutil
import subprocess
import sys
import time

src, build, scratch, cli = map(os.path.abspath, sys.argv[1:5])
shutil.rmtree(scratch, ignore_errors=True)
os.makedirs(scratch)
# what the library's CMake build reads (tests/ is off in the package's build)
checkout = os.path.join(scratch, "checkout")
os.makedirs(checkout)
shutil.copy(os.path.join(src, "CMakeLists.txt"), checkout)
for name in ("cmake", "include", "src", "bench", "python"):
    shutil.copytree(os.path.join(src, name), os.path.join(checkout, name),
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
shutil.rmtree(os.path.join(checkout, "python", "build"), ignore_errors=True)   # a pip install's, in-tree

# nothing that could point the package at a library: what a new user's shell has
env = {k: v for k, v in os.environ.items()
       if not k.startswith("COL0RME") and k not in ("LD_LIBRARY_PATH", "PYTHONPATH", "PKG_CONFIG_PATH")}
env.update(OMP_WAIT_POLICY="PASSIVE", PYTHONDONTWRITEBYTECODE="1")


def sh(*cmd, **kw):
    print("$", " ".join(cmd), flush=True)
    t = time.time()
    rc = subprocess.run(cmd, env=kw.pop("env", env), **kw).returncode
    print("  (%.0f s)" % (time.time() - t), flush=True)
    return rc


def venv_with_package(name):
    venv = os.path.join(scratch, name)
    if sh("/usr/bin/python3", "-m", "venv", "--system-site-packages", venv):
        sys.exit("cannot create a venv (Debian: python3-venv)")
    py = os.path.join(venv, "bin", "python")
    # --no-index: nothing from the network; --no-build-isolation: the system's setuptools
    if sh(py, "-m", "pip", "install", "-q", "--no-index", "--no-build-isolation", "./python", cwd=checkout):
        sys.exit("pip install ./python failed")
    return py


py = venv_with_package("venv")
# from the scratch dir, so that the installed package is imported, not ./python/col0rme
rc = sh(py, "-m", "pytest", "-q", "-p", "no:cacheprovider", os.path.join(src, "python", "tests"), "--cli", cli,
        cwd=scratch)
# pytest: 0 all passed, 1 some failed, 2 interrupted, 3 internal error, 4 usage error, 5 no tests collected
if rc:
    sys.exit("pytest exit code %d%s" % (rc, " (no tests collected)" if rc == 5 else ""))

# the installed prefix, then pip install in another venv (the checkout's CMake build is reused)
prefix = os.path.join(scratch, "prefix")
if sh("cmake", "--install", build, "--prefix", prefix, stdout=subprocess.DEVNULL):
    sys.exit("cmake --install failed")
py2 = venv_with_package("venv_prefix")
prefix_lib = glob.glob(os.path.join(prefix, "lib*", "libcol0rme.so.0"))
# in the venv: the library loaded, and col0rme.run on the stacks of P's col0rme simulate = P's col0rme run
check = r"""
import os, subprocess, sys
import numpy as np, tifffile
import col0rme


def run_cli(*args):
    r = subprocess.run([cli, *args], capture_output=True, text=True)
    assert r.returncode == 0, "col0rme %s: %s" % (args[0], r.stderr)


cli, d = sys.argv[1:3]
os.makedirs(d)
lib = col0rme.library()
own = os.path.join(os.path.dirname(col0rme.__file__), "libcol0rme.so.0")
assert lib == os.environ.get("COL0RME_LIB", own), lib
run_cli("simulate", "--width", "20", "--height", "20", "--frames", "150", "--filaments", "2", "--angles", "62,66",
        "-o", d + "/sim")
paths = [d + "/sim/stack_q%02d.tif" % (q + 1) for q in range(2)]
run_cli("run", "--angles", "62,66", "--fwhm", "229", "-o", d + "/run", *paths)
r = col0rme.run([tifffile.imread(p).astype(np.float32) for p in paths], angles=[62, 66], pixel_size=100, fwhm=229)
vol = tifffile.imread(d + "/run/volume.tif")
assert r.volume.shape == vol.shape and np.array_equal(r.volume, vol), "volume differs from the CLI's"
print("col0rme.run == %s run: volume %s, library %s" % (cli, vol.shape, lib))
"""
prefix_cli = os.path.join(prefix, "bin", "col0rme")
if len(prefix_lib) != 1:
    sys.exit("no lib*/libcol0rme.so.0 in the installed prefix")
script = os.path.join(scratch, "run_in_venv.py")
open(script, "w").write(check)
if sh(py2, script, prefix_cli, os.path.join(scratch, "own"), cwd=scratch):
    sys.exit("the package in a second venv, after cmake --install: FAILED")
# COL0RME_LIB overrides the package's own copy: here with the prefix's library
if sh(py2, script, prefix_cli, os.path.join(scratch, "override"), cwd=scratch,
      env=dict(env, COL0RME_LIB=prefix_lib[0])):
    sys.exit("COL0RME_LIB=the prefix's library: FAILED")
print("ok")
