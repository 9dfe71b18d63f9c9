"""What a run computed (Result), from the library's result or read back from
an output folder (read)."""
import ctypes
import glob
import json
import os
import shutil

import numpy as np


def _copy(ptr, shape, dtype):
    if not ptr:
        return None
    n = int(np.prod(shape))
    return np.ctypeslib.as_array(ptr, shape=(n,)).astype(dtype, copy=True).reshape(shape)


class Result:
    """What a run computed, as numpy arrays (None where a step did not run),
    with its calibration.

    support : H' x W' bool (fine grid, the union of the supports)
    intensity : list of H' x W' float32, one per stack (fine grid)
    background : list of H x W float32 (camera grid)
    volume : Z x H' x W' float32 (3D mode); baseline_volume with baseline=True
    depth : H' x W' float32, each pixel's single-depth fit (nm; 0 where empty)
    z_nm : Z depth bin centres (nm)
    pixel_size_nm : the camera pixel (background's grid)
    fine_pixel_nm : the fine grid's pixel (support, intensity, volume, depth;
        for matirf() the images' pixel)
    report : the report.json dict (parameters, estimates, timings, warnings)

    write(outdir) writes the files `col0rme run` writes; col0rme.read(outdir)
    gives the same Result back.
    """

    def __init__(self, lib=None, handle=None, pixel_nm=None):
        self._lib, self._h, self._dir, self._vols = lib, handle, None, {}
        self.support = self.depth = self.z_nm = None
        self.intensity, self.background, self.report = [], [], {}
        if handle:
            self._free = lib.c0_result_free
            self._load(lib, handle)
        self._calibrate(pixel_nm)

    def _load(self, L, handle):
        h, w, nz = ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
        ref = ctypes.byref
        s = L.c0_result_support(handle, ref(h), ref(w))
        self.support = _copy(s, (h.value, w.value), np.uint8).astype(bool) if s else None
        for q in range(L.c0_result_nstacks(handle)):
            p = L.c0_result_intensity(handle, q, ref(h), ref(w))
            if p:
                self.intensity.append(_copy(p, (h.value, w.value), np.float32))
            p = L.c0_result_background(handle, q, ref(h), ref(w))
            if p:
                self.background.append(_copy(p, (h.value, w.value), np.float32))
        p = L.c0_result_depth(handle, ref(h), ref(w))
        self.depth = _copy(p, (h.value, w.value), np.float32)
        p = L.c0_result_z_nm(handle, ref(nz))
        self.z_nm = _copy(p, (nz.value,), np.float64)
        j = L.c0_result_report_json(handle)
        self.report = json.loads(j.decode()) if j else {}

    def _calibrate(self, pixel_nm):
        p = self.report.get("parameters") or self.report.get("support_parameters") or {}
        self.pixel_size_nm = p.get("pixel_size_nm", pixel_nm or None)
        self.srf = p.get("srf", 1 if pixel_nm else None)
        fine = self.pixel_size_nm / self.srf if self.pixel_size_nm and self.srf else None
        self.fine_pixel_nm = p.get("fine_pixel_nm", fine)

    def _volume(self, name):
        """The whole volume, copied on first use: the run holds only the
        support's columns, and on a whole camera frame the volume is GBs."""
        if name not in self._vols and self._h:
            nz, h, w = ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
            ref = ctypes.byref
            p = getattr(self._lib, name)(self._h, ref(nz), ref(h), ref(w))
            self._vols[name] = _copy(p, (nz.value, h.value, w.value), np.float32)
        return self._vols.get(name)

    @property
    def volume(self):
        return self._volume("c0_result_volume")

    @property
    def baseline_volume(self):
        return self._volume("c0_result_baseline_volume")

    def write(self, outdir, force=False):
        """Writes the files `col0rme run` writes (volume.tif, report.json,
        report.html, ...) into outdir: created, empty unless force, and on
        failure nothing is left. A Result read from a folder copies its files."""
        from . import _check
        if self._h:
            _check(self._lib.c0_result_write(self._h, os.fsencode(outdir), int(bool(force))))
            return
        if os.path.exists(outdir) and os.listdir(outdir) and not force:
            from . import Error
            raise Error("outdir %s: directory is not empty (force: replace its contents)" % os.fsdecode(outdir))
        tmp = os.fsdecode(outdir).rstrip("/") + ".c0copy-%d" % os.getpid()
        shutil.copytree(self._dir, tmp)
        if os.path.exists(outdir):
            shutil.rmtree(outdir)
        os.rename(tmp, outdir)

    def __repr__(self):
        if self.z_nm is not None and self.depth is not None:
            what = "volume %d x %d x %d" % ((len(self.z_nm),) + self.depth.shape)
        else:
            what = "support %d x %d" % self.support.shape if self.support is not None else "empty"
        return "<col0rme.Result %s, %d stacks, fine pixel %s nm>" % (what, max(len(self.intensity), len(self.background)),
                                                                    self.fine_pixel_nm)

    def __del__(self):
        if getattr(self, "_h", None):
            self._free(self._h)
            self._h = None


def read(outdir):
    """The Result of an earlier run from its output folder (the files
    `col0rme run`, `support` or `matirf`, or Result.write, wrote). Needs
    tifffile (Debian: python3-tifffile)."""
    import tifffile
    from . import Error
    outdir = os.fsdecode(outdir)
    rep = os.path.join(outdir, "report.json")
    if not os.path.isfile(rep):
        raise Error("%s: not a col0rme output directory (no report.json)" % outdir)
    r = Result()
    r._dir = outdir
    with open(rep, encoding="utf-8") as f:
        r.report = json.load(f)

    def tif(name):
        p = os.path.join(outdir, name)
        return tifffile.imread(p) if os.path.isfile(p) else None

    s = tif("support.tif")
    r.support = s > 0 if s is not None else None
    r.intensity = [tifffile.imread(p) for p in sorted(glob.glob(os.path.join(outdir, "intensity_q[0-9]*.tif")))]
    r.background = [tifffile.imread(p) for p in sorted(glob.glob(os.path.join(outdir, "background_q[0-9]*.tif")))]
    r.depth = tif("depth.tif")
    for key, name in (("c0_result_volume", "volume.tif"), ("c0_result_baseline_volume", "baseline_volume.tif")):
        v = tif(name)
        r._vols[key] = v[None] if v is not None and v.ndim == 2 else v
    z = r.report.get("z_nm")
    r.z_nm = np.asarray(z, dtype=np.float64) if z is not None else None
    pixel = None
    if os.path.isfile(os.path.join(outdir, "volume.tif")) and not r.report.get("parameters"):
        with tifffile.TiffFile(os.path.join(outdir, "volume.tif")) as t:   # matirf: the images' pixel, in µm
            x = t.pages[0].tags["XResolution"].value
            pixel = 1000.0 * x[1] / x[0]
    r._calibrate(pixel)
    return r
