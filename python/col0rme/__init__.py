"""3D-COL0RME on numpy arrays: a thin shell over the C library (include/col0rme.h).

    run(stacks, angles=..., pixel_size=..., fwhm=..., **options) -> Result
    support(stacks, pixel_size=..., fwhm=..., **options)         -> Result (support only)
    matirf(images, angles=..., pixel_size=..., **options)        -> Result (volume, depth, z_nm)
    simulate(**parameters)                                       -> Simulation
    report(outdir)                        -> path of outdir/report.html (written again from its files)
    parameters()                                                 -> {name: help}
    library()                                                    -> path of the libcol0rme in use

options are the parameters of c0_run_conf_set (penalty="cel0", kappa=0.05,
lam=1e-3 for "lambda", a Python keyword, ...): numbers, strings, booleans or
sequences. Images are
row-major numpy arrays: stacks T x H x W, volumes Z x H x W. Errors raise
col0rme.Error with the library's message.
"""
import ctypes
import json
import os

import numpy as np

from . import _lib

__all__ = ["Error", "Result", "Simulation", "run", "support", "matirf", "simulate", "report", "parameters", "version",
           "library"]

_c = None


def _L():
    global _c
    if _c is None:
        _c = _lib.load()
    return _c


class Error(Exception):
    """An error reported by libcol0rme (its message names the parameter or file)."""


def _check(status):
    if status:
        raise Error(_L().c0_last_error().decode("utf-8", "replace"))


def version():
    return _L().c0_version().decode()


def library():
    """The path of the libcol0rme the package loaded (its own copy unless COL0RME_LIB says otherwise)."""
    _L()
    return _lib.loaded_path


def parameters():
    """The options run(), support() and matirf() take: {name: help line with the default}."""
    out, i, doc = {}, 0, ctypes.c_char_p()
    while True:
        name = _L().c0_run_conf_param(i, ctypes.byref(doc))
        if not name:
            return out
        out[name.decode()] = doc.value.decode() if doc.value else ""
        i += 1


def _text(name, v):
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return format(float(v), ".17g")
    if isinstance(v, (list, tuple, np.ndarray)):
        return ",".join(_text(name, x) for x in np.asarray(v).ravel().tolist())
    raise Error("%s: cannot pass a %s" % (name, type(v).__name__))


class _Conf:
    """A c0_run_conf with its documented defaults, set by parameter name."""

    def __init__(self, options):
        self._free = _L().c0_run_conf_free   # kept: module globals may be gone at exit
        self.p = _L().c0_run_conf_new()
        if not self.p:
            raise MemoryError("c0_run_conf_new")
        for k, v in options.items():
            if v is not None:
                _check(_L().c0_run_conf_set(self.p, k.encode(), _text(k, v).encode()))

    def __del__(self):
        if getattr(self, "p", None):
            self._free(self.p)
            self.p = None


def _options(angles, pixel_size, fwhm, options):
    o = {("lambda" if k == "lam" else k): v for k, v in options.items()}
    for k, v in (("angles", angles), ("pixel_nm", pixel_size), ("fwhm_nm", fwhm)):
        if v is not None:
            o[k] = v
    return o


def _stacks(stacks):
    if isinstance(stacks, (np.ndarray, str, os.PathLike)):
        stacks = [stacks]
    stacks = list(stacks)
    arr = (_lib.Stack * max(len(stacks), 1))()
    keep = []
    for i, s in enumerate(stacks):
        if isinstance(s, (str, os.PathLike)):
            b = os.fsencode(s)
            keep.append(b)
            arr[i].path = b
            continue
        a = np.ascontiguousarray(s, dtype=np.float32)
        if a.ndim == 2:
            a = a[None]
        if a.ndim != 3:
            raise Error("stack %d: expected a T x H x W array, got shape %s" % (i + 1, a.shape))
        keep.append(a)
        arr[i].data = a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))
        arr[i].frames, arr[i].height, arr[i].width = a.shape
    return arr, len(stacks), keep


def _copy(ptr, shape, dtype):
    if not ptr:
        return None
    n = int(np.prod(shape))
    return np.ctypeslib.as_array(ptr, shape=(n,)).astype(dtype, copy=True).reshape(shape)


class Result:
    """What a run computed, as numpy arrays (None where a step did not run).

    support: H' x W' bool (fine grid, the union of the supports)
    intensity: list of H' x W' float32, one per stack (fine grid)
    background: list of H x W float32 (camera grid)
    volume: Z x H' x W' float32 (3D mode), depth: H' x W' depth (nm, each pixel's single-depth fit)
    z_nm: Z depth bin centres, baseline_volume (with baseline=True)
    report: the report.json dict (parameters, estimates, timings)
    """

    def __init__(self, handle):
        L, h, w, nz = _L(), ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
        self._h, self._free = handle, L.c0_result_free
        ref = ctypes.byref
        s = L.c0_result_support(handle, ref(h), ref(w))
        self.support = _copy(s, (h.value, w.value), np.uint8).astype(bool) if s else None
        n = L.c0_result_nstacks(handle)
        self.intensity, self.background = [], []
        for q in range(n):
            p = L.c0_result_intensity(handle, q, ref(h), ref(w))
            if p:
                self.intensity.append(_copy(p, (h.value, w.value), np.float32))
            p = L.c0_result_background(handle, q, ref(h), ref(w))
            if p:
                self.background.append(_copy(p, (h.value, w.value), np.float32))
        self._vols = {}
        p = L.c0_result_depth(handle, ref(h), ref(w))
        self.depth = _copy(p, (h.value, w.value), np.float32)
        p = L.c0_result_z_nm(handle, ref(nz))
        self.z_nm = _copy(p, (nz.value,), np.float64)
        j = L.c0_result_report_json(handle)
        self.report = json.loads(j.decode()) if j else {}

    def _volume(self, name):
        """The whole volume, copied on first use: the run holds only the
        support's columns, and on a whole camera frame the volume is GBs."""
        if name not in self._vols:
            nz, h, w = ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
            ref = ctypes.byref
            p = getattr(_L(), name)(self._h, ref(nz), ref(h), ref(w))
            self._vols[name] = _copy(p, (nz.value, h.value, w.value), np.float32)
        return self._vols[name]

    @property
    def volume(self):
        return self._volume("c0_result_volume")

    @property
    def baseline_volume(self):
        return self._volume("c0_result_baseline_volume")

    def write(self, outdir, force=False):
        """Writes the files `col0rme run` writes (volume.tif, report.json, report.html, ...)."""
        _check(_L().c0_result_write(self._h, os.fsencode(outdir), int(bool(force))))

    def __del__(self):
        if getattr(self, "_h", None):
            self._free(self._h)
            self._h = None


def report(outdir):
    """Writes outdir/report.html (and error_qNN.tif) again from the files of
    an earlier run in outdir, as `col0rme report` does; returns its path."""
    _check(_L().c0_report_html(os.fsencode(outdir)))
    return os.path.join(outdir, "report.html")


def _result(call, *args):
    out = ctypes.c_void_p()
    _check(call(*args, ctypes.byref(out)))
    return Result(out)


def run(stacks, angles=None, pixel_size=None, fwhm=None, **options):
    """The whole method on stacks (T x H x W arrays or TIFF paths), one per
    angle in the order of angles (nm, deg). Without angles: 2D COL0RME."""
    conf = _Conf(_options(angles, pixel_size, fwhm, options))
    arr, n, keep = _stacks(stacks)
    r = _result(_L().c0_run, conf.p, arr, n)
    del keep
    return r


def support(stacks, pixel_size=None, fwhm=None, **options):
    """The support step alone (the union over the support stacks): Result with
    support and report."""
    conf = _Conf(_options(None, pixel_size, fwhm, options))
    arr, n, keep = _stacks(stacks)
    r = _result(_L().c0_run_support, conf.p, arr, n)
    del keep
    return r


def matirf(images, angles, pixel_size=None, **options):
    """MA-TIRF axial reconstruction from one H x W image per angle: Result
    with volume, depth and z_nm. pixel_size: the images' pixel (nm), used
    by depth pooling."""
    conf = _Conf(_options(angles, pixel_size, None, options))
    imgs = [np.ascontiguousarray(a, dtype=np.float32) for a in images]
    if not imgs or any(a.ndim != 2 or a.shape != imgs[0].shape for a in imgs):
        raise Error("images: expected one H x W array per angle, all the same size")
    ptrs = (ctypes.POINTER(ctypes.c_float) * len(imgs))(*[a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)) for a in imgs])
    h, w = imgs[0].shape
    return _result(_L().c0_run_matirf, conf.p, ptrs, len(imgs), h, w)


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
        self.pixel_size = self.get("pixel_nm")
        self.fwhm = self.get("fwhm_nm")

    def get(self, name):
        return _L().c0_simulation_get(self._h, name.encode())

    def __del__(self):
        if getattr(self, "_h", None):
            self._free(self._h)
            self._h = None


def simulate(**parameters):
    """The simulator of `col0rme simulate` in memory; parameters by name
    (seed, width, height, frames, pixel_nm or pixel_size, fwhm_nm or fwhm,
    angles or nangles, snr_db, background, ...)."""
    L, h = _L(), ctypes.c_void_p()
    _check(L.c0_simulation_new(ctypes.byref(h)))
    try:
        for k, v in parameters.items():
            k = {"pixel_size": "pixel_nm", "fwhm": "fwhm_nm"}.get(k, k)
            _check(L.c0_simulation_set(h, k.encode(), _text(k, v).encode()))
        _check(L.c0_simulation_run(h))
    except BaseException:
        L.c0_simulation_free(h)
        raise
    return Simulation(h)
