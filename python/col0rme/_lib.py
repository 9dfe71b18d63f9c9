"""Finding libcol0rme.so and declaring the C functions (include/col0rme.h).

pip install ./python builds the library and ships it next to this file
(python/setup.py); COL0RME_LIB=PATH overrides it. A package run from the
source tree, without installing, falls back to an installed library
(pkg-config, then the dynamic loader)."""
import ctypes
import ctypes.util
import os
import pathlib
import shutil
import subprocess

SONAME = "libcol0rme.so.0"
loaded_path = None   # the file load() opened


def _candidates():
    env = os.environ.get("COL0RME_LIB")
    if env:
        yield env
        return
    here = pathlib.Path(__file__).resolve().parent
    for p in sorted(here.glob("libcol0rme.so*")):
        yield str(p)
    if shutil.which("pkg-config"):
        try:
            libdir = subprocess.run(["pkg-config", "--variable=libdir", "col0rme"], capture_output=True,
                                    text=True, check=True).stdout.strip()
            if libdir:
                yield os.path.join(libdir, SONAME)
        except (OSError, subprocess.CalledProcessError):
            pass
    found = ctypes.util.find_library("col0rme")
    if found:
        yield found
    yield SONAME


def load():
    global loaded_path
    tried = []
    for cand in _candidates():
        try:
            lib = ctypes.CDLL(cand)
        except OSError as e:
            tried.append("%s (%s)" % (cand, e))
            continue
        _declare(lib)
        loaded_path = cand
        return lib
    raise OSError("col0rme: cannot load libcol0rme (pip install ./python ships it inside the package; "
                  "COL0RME_LIB=PATH names another). Tried: " + "; ".join(tried))


class Stack(ctypes.Structure):
    _fields_ = [("path", ctypes.c_char_p), ("data", ctypes.POINTER(ctypes.c_float)), ("frames", ctypes.c_int),
                ("height", ctypes.c_int), ("width", ctypes.c_int), ("pixel_nm", ctypes.c_double)]


def _declare(lib):
    P, I, D, S = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_char_p
    IP, FP, DP = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_double)
    sigs = {
        "c0_last_error": (S, []),
        "c0_version": (S, []),
        "c0_run_conf_new": (P, []),
        "c0_run_conf_free": (None, [P]),
        "c0_run_conf_set": (I, [P, S, S]),
        "c0_run_conf_param": (S, [I, ctypes.POINTER(S)]),
        "c0_run_conf_param_info": (S, [I, ctypes.POINTER(S), ctypes.POINTER(S), ctypes.POINTER(S), ctypes.POINTER(S)]),
        "c0_run_conf_set_progress": (None, [P, P, P]),
        "c0_run": (I, [P, ctypes.POINTER(Stack), I, ctypes.POINTER(P)]),
        "c0_run_support": (I, [P, ctypes.POINTER(Stack), I, ctypes.POINTER(P)]),
        "c0_run_matirf": (I, [P, ctypes.POINTER(FP), I, I, I, ctypes.POINTER(P)]),
        "c0_result_write": (I, [P, S, I]),
        "c0_report_html": (I, [S]),
        "c0_result_nstacks": (I, [P]),
        "c0_result_support": (ctypes.POINTER(ctypes.c_uint8), [P, IP, IP]),
        "c0_result_intensity": (FP, [P, I, IP, IP]),
        "c0_result_background": (FP, [P, I, IP, IP]),
        "c0_result_volume": (FP, [P, IP, IP, IP]),
        "c0_result_baseline_volume": (FP, [P, IP, IP, IP]),
        "c0_result_depth": (FP, [P, IP, IP]),
        "c0_result_z_nm": (DP, [P, IP]),
        "c0_result_report_json": (S, [P]),
        "c0_result_free": (None, [P]),
        "c0_simulation_new": (I, [ctypes.POINTER(P)]),
        "c0_simulation_set": (I, [P, S, S]),
        "c0_simulation_get": (D, [P, S]),
        "c0_simulation_run": (I, [P]),
        "c0_simulation_stack": (FP, [P, I, IP, IP, IP]),
        "c0_simulation_angles": (DP, [P, IP]),
        "c0_simulation_emitters": (DP, [P, IP]),
        "c0_simulation_free": (None, [P]),
    }
    for name, (res, args) in sigs.items():
        f = getattr(lib, name)
        f.restype, f.argtypes = res, args
