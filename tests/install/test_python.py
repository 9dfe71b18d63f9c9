"""The Python package as a user installs it: a fresh venv with the system's
numpy (--system-site-packages), pip install of ./python offline, then its
pytest tests against this build's library and CLI.

usage: test_python.py SOURCE_DIR SCRATCH_DIR LIBCOL0RME CLI"""
import os
import shutil
import subprocess
import sys

src, scratch, lib, cli = map(os.path.abspath, sys.argv[1:5])
venv = os.path.join(scratch, "venv")
shutil.rmtree(scratch, ignore_errors=True)
os.makedirs(scratch)


def sh(*cmd, **kw):
    print("$", " ".join(cmd), flush=True)
    return subprocess.run(cmd, **kw).returncode


if sh("/usr/bin/python3", "-m", "venv", "--system-site-packages", venv):
    sys.exit("cannot create a venv (Debian: python3-venv)")
py = os.path.join(venv, "bin", "python")
# from a copy: pip builds in the tree it is given (build/, *.egg-info)
pkg = os.path.join(scratch, "python")
shutil.copytree(os.path.join(src, "python"), pkg, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
# --no-index: nothing from the network; --no-build-isolation: the system's setuptools
if sh(py, "-m", "pip", "install", "-q", "--no-index", "--no-build-isolation", pkg):
    sys.exit("pip install ./python failed")
env = dict(os.environ, COL0RME_LIB=lib, COL0RME_CLI=cli, OMP_WAIT_POLICY="PASSIVE")
# run from the scratch dir so that the installed package is imported, not ./python/col0rme
rc = sh(py, "-m", "pytest", "-q", "-p", "no:cacheprovider", os.path.join(src, "python", "tests"), cwd=scratch, env=env)
# pytest: 0 all passed, 1 some failed, 2 interrupted, 3 internal error, 4 usage error, 5 no tests collected
if rc:
    sys.exit("pytest exit code %d%s" % (rc, " (no tests collected)" if rc == 5 else ""))
