"""3D-COL0RME on numpy arrays: a thin shell over the C library (include/col0rme.h).

    run(stacks, angles=..., pixel_size_nm=..., fwhm_nm=..., ...) -> Result
    support(stacks, pixel_size_nm=..., fwhm_nm=..., ...)         -> Result (support only)
    matirf(images, angles=..., pixel_size_nm=..., ...)           -> Result (volume, depth, z_nm)
    read(outdir)                          -> the Result an earlier run wrote there
    simulate(**parameters)                                       -> Simulation
    report(outdir)                        -> path of outdir/report.html (written again from its files)
    parameters()                                                 -> {name: help}
    library()                                                    -> path of the libcol0rme in use

Every parameter of the library's table is a keyword argument with a type
hint and its documentation (help(col0rme.run)), named with its unit where it
has one (pixel_size_nm, fwhm_nm, wavelength_nm; lambda_ for lambda); the
older pixel_size=, fwhm= and lam= still work. progress=fn calls
fn(stage, fraction) during the run (progress=True: a tqdm bar); an
exception raised in fn, or Ctrl-C, stops the run and propagates. Images are
row-major numpy arrays: stacks T x H x W, volumes Z x H x W. A wrong type
raises TypeError, a bad value ValueError (both also col0rme.Error), other
failures col0rme.Error with the library's message.
"""
import ctypes
import inspect
import os
import re
import typing
import warnings

import numpy as np

from . import _lib, _params, _progress
from ._result import Result, read

__all__ = ["Error", "ParameterError", "ParameterTypeError", "Result", "Simulation", "run", "support", "matirf", "read", "simulate", "report", "parameters",
           "version", "library"]

_c = None


def _L():
    global _c
    if _c is None:
        _c = _lib.load()
    return _c


class Error(Exception):
    """An error reported by libcol0rme (its message names the parameter or file)."""


class ParameterError(Error, ValueError):
    """A value the library refuses (a parameter, an argument's shape): a ValueError, and a col0rme.Error."""


class ParameterTypeError(Error, TypeError):
    """An argument of the wrong type, or an unknown keyword: a TypeError, and a col0rme.Error."""


C0_EINVAL, C0_ECANCELED = 1, 6


def _check(status):
    if status:
        msg = _L().c0_last_error().decode("utf-8", "replace")
        msg = re.sub(r"\b(%s)\b" % "|".join(_params.PY_NAME), lambda m: _params.PY_NAME[m.group(1)], msg)
        raise ParameterError(msg) if status == C0_EINVAL else Error(msg)


def version():
    return _L().c0_version().decode()


def library():
    """The path of the libcol0rme the package loaded (its own copy unless COL0RME_LIB says otherwise)."""
    _L()
    return _lib.loaded_path


def parameters():
    """The library's parameters: {C name: help line with the default}; the
    keyword arguments of run(), support() and matirf() are these (pixel_nm as
    pixel_size_nm, lambda as lambda_)."""
    out, i, doc = {}, 0, ctypes.c_char_p()
    while True:
        name = _L().c0_run_conf_param(i, ctypes.byref(doc))
        if not name:
            return out
        out[name.decode()] = doc.value.decode() if doc.value else ""
        i += 1


class _Conf:
    """A c0_run_conf with its documented defaults, set by parameter name."""

    def __init__(self, values):
        self._free = _L().c0_run_conf_free   # kept: module globals may be gone at exit
        self.p = _L().c0_run_conf_new()
        if not self.p:
            raise MemoryError("c0_run_conf_new")
        for k, v in values.items():
            _check(_L().c0_run_conf_set(self.p, k.encode(), v.encode()))

    def __del__(self):
        if getattr(self, "p", None):
            self._free(self.p)
            self.p = None


def _stacks(stacks):
    if isinstance(stacks, (np.ndarray, str, os.PathLike)):
        stacks = [stacks]
    if not isinstance(stacks, typing.Iterable):
        raise ParameterTypeError("stacks: expected arrays or TIFF paths, got %s" % type(stacks).__name__)
    stacks = list(stacks)
    arr = (_lib.Stack * max(len(stacks), 1))()
    keep = []
    for i, s in enumerate(stacks):
        if isinstance(s, (str, os.PathLike)):
            b = os.fsencode(s)
            keep.append(b)
            arr[i].path = b
            continue
        if not isinstance(s, (np.ndarray, typing.Sequence)):
            raise ParameterTypeError("stack %d: expected a T x H x W array or a TIFF path, got %s" % (i + 1, type(s).__name__))
        a = np.ascontiguousarray(s, dtype=np.float32)
        if a.ndim == 2:
            a = a[None]
        if a.ndim != 3:
            raise ParameterError("stack %d: expected a T x H x W array, got shape %s" % (i + 1, a.shape))
        keep.append(a)
        arr[i].data = a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))
        arr[i].frames, arr[i].height, arr[i].width = a.shape
    return arr, len(stacks), keep


def _call(call, conf, progress, *args):
    """call(conf, *args, &out) with the progress observer; the Result, or what
    the observer caught raised again unchanged, or Error."""
    obs = _progress.Observer(progress)
    _L().c0_run_conf_set_progress(conf.p, obs.c, None)
    out = ctypes.c_void_p()
    try:
        with obs:   # a Ctrl-C during the run: KeyboardInterrupt from here, once it stopped
            st = call(conf.p, *args, ctypes.byref(out))
            if st == C0_ECANCELED and obs.error is None and obs.sigint is None:
                _check(st)
    except BaseException:
        if out:
            _L().c0_result_free(out)
        raise
    finally:
        _L().c0_run_conf_set_progress(conf.p, None, None)
    if obs.error is not None:
        if out:
            _L().c0_result_free(out)
        raise obs.error
    _check(st)
    return out


def _result(handle, pixel_nm=None):
    r = Result(_L(), handle, pixel_nm)
    for w in r.report.get("warnings", []):
        warnings.warn(w, RuntimeWarning, stacklevel=3)
    return r


def _bind(f, args, kwargs):
    """The call's arguments against f's signature: {C name: text} and the others."""
    if f.__name__ not in _KW:
        _L()   # the library could not be loaded when the package was imported: say why
        _document()
    try:
        return _params.bind(f.__name__, f.__signature__, _KW[f.__name__], args, kwargs)
    except TypeError as e:
        raise ParameterTypeError(str(e)) from None
    except ValueError as e:
        raise ParameterError(str(e)) from None


# ---- the three calls; their keywords and docs are made from the library's table below ----

def _on_stacks(fn, entry, stacks, args, kwargs):
    """run and support: bind the keywords, then one library call on the stacks"""
    values, other = _bind(fn, (stacks,) + args, kwargs)
    conf = _Conf(values)
    arr, n, keep = _stacks(other["stacks"])
    r = _result(_call(getattr(_L(), entry), conf, other.get("progress"), arr, n))
    del keep
    return r


def run(stacks, *args, **kwargs):
    return _on_stacks(run, "c0_run", stacks, args, kwargs)


def support(stacks, *args, **kwargs):
    return _on_stacks(support, "c0_run_support", stacks, args, kwargs)


def matirf(images, *args, **kwargs):
    values, other = _bind(matirf, (images,) + args, kwargs)
    conf = _Conf(values)
    images = other["images"]
    if isinstance(images, np.ndarray) and images.ndim == 3:
        images = list(images)
    if not isinstance(images, typing.Sequence) or not all(isinstance(a, (np.ndarray, typing.Sequence)) for a in images):
        raise ParameterTypeError("images: expected a sequence of H x W arrays, one per angle")
    imgs = [np.ascontiguousarray(a, dtype=np.float32) for a in images]
    if not imgs or any(a.ndim != 2 or a.shape != imgs[0].shape for a in imgs):
        raise ParameterError("images: expected one H x W array per angle, all the same size")
    ptrs = (ctypes.POINTER(ctypes.c_float) * len(imgs))(*[a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)) for a in imgs])
    h, w = imgs[0].shape
    pixel = float(kwargs.get("pixel_size_nm") or kwargs.get("pixel_size") or kwargs.get("pixel_nm") or 0) or None
    return _result(_call(_L().c0_run_matirf, conf, other.get("progress"), ptrs, len(imgs), h, w), pixel)


_SUMMARY = {
    "run": """The whole method on stacks (T x H x W arrays or TIFF paths), one per angle
in the order of angles (deg). Without angles: 2D COL0RME. Returns a Result.""",
    "support": """The support step alone (the union over the support stacks): a Result with
support and report.""",
    "matirf": """MA-TIRF axial reconstruction from one H x W image per angle (the standard
MA-TIRF path): a Result with volume, depth and z_nm. pixel_size_nm: the
images' pixel, for the outputs' calibration and depth pooling.""",
}
_FIRST = {"run": "stacks", "support": "stacks", "matirf": "images"}
_FIRST_DOC = {
    "stacks": "stacks : sequence of array_like or str or path\n    One T x H x W stack per angle (float32 "
              "frames, row-major), or TIFF files.",
    "images": "images : sequence of array_like\n    One H x W image per angle, all the same size.",
}
_PROGRESS_DOC = """progress : callable or bool, optional
    fn(stage, fraction) called during the run with the stage's name and its
    fraction done (0 at its start, 1 at its end); an exception it raises
    stops the run and propagates unchanged, as does Ctrl-C. True: a tqdm bar
    (a line on stderr without tqdm). Default: None."""
_TAKES = {
    "run": lambda c: c not in _params.RAW_MATIRF and c != "noise_variance",
    "support": lambda c: c in _params.SUPPORT,
    "matirf": lambda c: c in _params.MATIRF,
}
_KW = {}


def _document():
    """Signatures and docstrings of run, support and matirf from the table
    (left plain when the library cannot be loaded: the call then says why)."""
    try:
        table = _params.table(_L())
    except (OSError, AttributeError):
        return
    P = inspect.Parameter
    for name, f in (("run", run), ("support", support), ("matirf", matirf)):
        kw = _params.keywords(table, _TAKES[name])
        _KW[name] = kw
        arrays = typing.Union[typing.Sequence[typing.Any], np.ndarray]
        first = P(_FIRST[name], P.POSITIONAL_OR_KEYWORD,
                  annotation=arrays if name == "matirf" else typing.Union[arrays, str, os.PathLike])
        prog = P("progress", P.KEYWORD_ONLY, default=None,
                 annotation=typing.Union[typing.Callable[[str, float], typing.Any], bool, None])
        f.__signature__ = _params.signature([first], kw, [prog])
        f.__annotations__ = {p.name: p.annotation for p in f.__signature__.parameters.values()}
        f.__annotations__["return"] = Result
        f.__doc__ = _params.docstring(_SUMMARY[name], kw, _FIRST_DOC[_FIRST[name]] + "\n" + _PROGRESS_DOC)


def report(outdir):
    """Writes outdir/report.html (and error_qNN.tif) again from the files of
    an earlier run in outdir, as `col0rme report` does; returns its path."""
    _check(_L().c0_report_html(os.fsencode(outdir)))
    return os.path.join(outdir, "report.html")


class Simulation:
    """Simulated acquisitions: stacks (list of T x H x W float32 ADU, one per
    angle), angles (deg), emitters (N x 4: x, y, z in nm, brightness),
    pixel_size and fwhm (nm), and get(name) for any other parameter."""

    def __init__(self, handle):
        L, t, h, w, n = _L(), ctypes.c_int(), ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
        self._h, self._free = handle, L.c0_simulation_free
        ref = ctypes.byref
        a = L.c0_simulation_angles(handle, ref(n))
        self.angles = [a[i] for i in range(n.value)]
        self.stacks = [_copy(L.c0_simulation_stack(handle, q, ref(t), ref(h), ref(w)), (t.value, h.value, w.value),
                             np.float32) for q in range(n.value)]
        e = L.c0_simulation_emitters(handle, ref(n))
        self.emitters = _copy(e, (n.value, 4), np.float64) if n.value else np.zeros((0, 4))
        self.pixel_size = self.pixel_size_nm = self.get("pixel_nm")
        self.fwhm = self.fwhm_nm = self.get("fwhm_nm")

    def get(self, name):
        return _L().c0_simulation_get(self._h, name.encode())

    def __del__(self):
        if getattr(self, "_h", None):
            self._free(self._h)
            self._h = None


def _copy(ptr, shape, dtype):
    if not ptr:
        return None
    n = int(np.prod(shape))
    return np.ctypeslib.as_array(ptr, shape=(n,)).astype(dtype, copy=True).reshape(shape)


def _sim_text(name, v):
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return format(float(v), ".17g")
    if isinstance(v, (list, tuple, np.ndarray)):
        return ",".join(_sim_text(name, x) for x in np.asarray(v).ravel().tolist())
    raise ParameterTypeError("%s: cannot pass a %s" % (name, type(v).__name__))


def simulate(**parameters):
    """The simulator of `col0rme simulate` in memory; parameters by name
    (seed, width, height, frames, pixel_nm or pixel_size(_nm), fwhm_nm or fwhm,
    angles or nangles, snr_db, background, ...)."""
    L, h = _L(), ctypes.c_void_p()
    _check(L.c0_simulation_new(ctypes.byref(h)))
    try:
        for k, v in parameters.items():
            k = {"pixel_size": "pixel_nm", "pixel_size_nm": "pixel_nm", "fwhm": "fwhm_nm"}.get(k, k)
            _check(L.c0_simulation_set(h, k.encode(), _sim_text(k, v).encode()))
        _check(L.c0_simulation_run(h))
    except BaseException:
        L.c0_simulation_free(h)
        raise
    return Simulation(h)


_document()
