"""pip install ./python: builds libcol0rme from the C sources of the checkout
this folder belongs to (its parent: CMakeLists.txt, src/, include/) and ships
the library inside the package, so that `import col0rme` needs neither an
environment variable nor a system-wide install, and keeps working when the
build tree is gone. Offline, with Debian's setuptools and cmake:

    pip install --no-index --no-build-isolation ./python

The CMake build lives in build/cmake beside this file (setuptools' build
folder): installing again only recompiles what changed."""
import os
import pathlib
import shutil
import subprocess

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent


def _cmake(*args):
    print("cmake " + " ".join(map(str, args)), flush=True)
    subprocess.run(["cmake", *map(str, args)], check=True)


def build_library(build):
    """Configures and builds the checkout's libcol0rme in BUILD; returns its SONAME link (libcol0rme.so.0)."""
    if not (ROOT / "CMakeLists.txt").is_file() or not (ROOT / "include" / "col0rme.h").is_file():
        raise SystemExit("col0rme: the C sources (CMakeLists.txt, include/col0rme.h) are not in %s; "
                         "pip install the python/ folder of a col0rme checkout" % ROOT)
    if shutil.which("cmake") is None:
        raise SystemExit("col0rme: cmake not found; it builds libcol0rme (Debian: apt install cmake)")
    cache = build / "CMakeCache.txt"
    if cache.is_file() and "CMAKE_HOME_DIRECTORY:INTERNAL=%s\n" % ROOT not in cache.read_text():
        shutil.rmtree(build)   # configured for a checkout since moved: CMake would refuse it
    # no -Werror: a compiler newer than the one the sources were checked with may warn;
    # no MPI: only the col0rme program starts it, the library alone never does;
    # the install RPATH (none): a build tree's RUNPATH ends in an empty entry, the current directory
    _cmake("-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DBUILD_TESTING=OFF", "-DCOL0RME_WERROR=OFF",
           "-DCOL0RME_MPI=OFF", "-DCOL0RME_IMAGEJ=OFF", "-DCMAKE_BUILD_WITH_INSTALL_RPATH=ON")
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
    _cmake("--build", build, "--target", "c0_shared", "--parallel", jobs)
    sonames = [p for p in build.glob("libcol0rme.so.*") if p.is_symlink() and p.name.count(".") == 2]
    if len(sonames) != 1:
        raise SystemExit("col0rme: no libcol0rme.so.MAJOR in %s after the build" % build)
    return sonames[0]


class BuildWithLibrary(build_py):
    """The Python files, then the library next to them, named by its SONAME."""

    def run(self):
        super().run()
        lib = build_library(pathlib.Path(self.get_finalized_command("build").build_base).resolve() / "cmake")
        # pip install -e imports col0rme/ from this folder: the library goes there
        pkg = HERE if getattr(self, "editable_mode", False) else pathlib.Path(self.build_lib)
        dest = pkg / "col0rme" / lib.name
        shutil.copyfile(lib.resolve(), dest)
        os.chmod(dest, 0o755)


class BinaryDistribution(Distribution):
    """The wheel holds a compiled library: tag it for this platform, not 'any'."""

    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": BuildWithLibrary}, distclass=BinaryDistribution)
