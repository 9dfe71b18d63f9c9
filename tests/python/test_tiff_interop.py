"""TIFF interop against an independent implementation (tifffile, and libtiff's
tiffcp for the LZW/PackBits encoders tifffile lacks without imagecodecs).

usage: test_tiff_interop.py TIFF_TOOL COL0RME DATA_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import tifffile

from checks import check, done

TOOL, CLI, DATA = sys.argv[1:4]


def dump(path):
    raw = path + ".raw"
    p = subprocess.run([TOOL, "dump", path, raw], capture_output=True, text=True)
    if p.returncode:
        return None, None, p.stderr
    info = json.loads(p.stdout)
    a = np.fromfile(raw, dtype="<f8")
    os.remove(raw)
    return info, a.reshape(info["pages"], info["height"], info["width"]), ""


def values(dtype, shape, seed):
    rng = np.random.default_rng(seed)
    dt = np.dtype(dtype)
    if dt.kind == "f":
        return (rng.standard_normal(shape) * 1e3).astype(dt)
    info = np.iinfo(dt)
    return rng.integers(info.min, info.max, size=shape, endpoint=True, dtype=dt)


def read_variants(tmp):
    """Files written by tifffile (and tiffcp) are read back exactly."""
    shape = (3, 37, 29)   # pages, height, width: odd sizes catch stride bugs
    variants = []
    for dt in ["uint8", "uint16", "uint32", "int16", "int32", "float32", "float64"]:
        variants.append((dt, {}, None))
    variants += [
        ("uint16", {"byteorder": ">"}, None),
        ("float32", {"byteorder": ">"}, None),
        ("uint16", {"tile": (16, 16)}, None),
        ("float64", {"tile": (16, 32), "byteorder": ">"}, None),
        ("uint16", {"rowsperstrip": 5}, None),
        ("uint16", {"compression": "zlib"}, None),
        ("uint16", {"compression": "zlib", "predictor": True}, None),
        ("float32", {"compression": "zlib", "byteorder": ">"}, None),
        ("uint16", {"bigtiff": True}, None),
        ("int32", {"bigtiff": True, "byteorder": ">", "tile": (16, 16)}, None),
        ("uint16", {}, "lzw"),
        ("uint8", {}, "packbits"),
        ("float32", {"tile": (16, 16)}, "lzw"),
    ]
    for k, (dt, kw, recompress) in enumerate(variants):
        a = values(dt, shape, k)
        path = os.path.join(tmp, "v%02d.tif" % k)
        tifffile.imwrite(path, a, photometric="minisblack", **kw)
        if recompress:
            src = path + ".src.tif"
            os.rename(path, src)
            subprocess.run(["tiffcp", "-c", recompress, src, path], check=True)
        info, b, err = dump(path)
        label = "%s %s %s" % (dt, kw, recompress or "")
        check(info is not None, "read %s: %s" % (label, err))
        if info is None:
            continue
        check(info["dtype"] == dt, "dtype %s: got %s" % (label, info["dtype"]))
        check(b.shape == a.shape, "shape %s" % label)
        check(np.array_equal(b, a.astype(np.float64)), "values %s" % label)
        if recompress:
            check(info["compression"] == recompress, "compression %s" % label)
        if kw.get("bigtiff"):
            check(info["bigtiff"] == 1, "bigtiff flag %s" % label)
        if kw.get("byteorder") == ">":
            check(info["big_endian"] == 1, "endianness %s" % label)


def read_calibration(tmp):
    # ImageJ hyperstack: 2 channels x 3 slices x 4 frames, 80 nm pixels, 50 nm z
    a = values("uint16", (4, 3, 2, 11, 13), 99)
    p = os.path.join(tmp, "ij.tif")
    tifffile.imwrite(p, a, imagej=True, resolution=(1 / 0.08, 1 / 0.08),
                     metadata={"axes": "TZCYX", "spacing": 0.05, "unit": "um"})
    info, b, err = dump(p)
    check(info is not None, "imagej read: " + err)
    if info:
        check((info["channels"], info["slices"], info["frames"], info["pages"]) == (2, 3, 4, 24), "imagej dims %s" % info)
        check(abs(info["pixel_size_nm"] - 80) < 1e-3, "imagej pixel size %s" % info["pixel_size_nm"])
        check(abs(info["z_spacing_nm"] - 50) < 1e-6, "imagej spacing %s" % info["z_spacing_nm"])
        check(np.array_equal(b, a.reshape(24, 11, 13).astype(float)), "imagej values (XYCZT order)")
    # OME-TIFF pixel size
    p = os.path.join(tmp, "x.ome.tif")
    a = values("uint16", (5, 9, 10), 7)
    tifffile.imwrite(p, a, metadata={"axes": "TYX", "PhysicalSizeX": 0.106, "PhysicalSizeY": 0.106})
    info, b, err = dump(p)
    check(info is not None and abs(info["pixel_size_nm"] - 106) < 1e-6, "ome pixel size %s %s" % (info, err))
    check(b is not None and np.array_equal(b, a.astype(float)), "ome values")


def write_variants(tmp):
    """Files we write are read by tifffile with the right shape, dtype, values, calibration;
    the planes' data lie back to back after the directories, as ImageJ writes them
    (tifffile and ImageJ read a hyperstack from the first plane's offset: 2 planes
    with a directory between them read wrong)."""
    cases = [("uint8", 0, 1, 4, 3), ("uint16", 0, 1, 4, 3), ("float32", 0, 1, 4, 3), ("float32", 1, 1, 4, 3),
             ("float32", 0, 1, 2, 1), ("float32", 0, 2, 1, 1), ("uint16", 0, 1, 1, 2), ("float32", 0, 1, 1, 1)]
    for dt, big, C, Z, T in cases:
        W, H = 7, 5
        p = os.path.join(tmp, "w_%s_%d_%d%d%d.tif" % (dt, big, C, Z, T))
        subprocess.run([TOOL, "write", p, dt, str(W), str(H), str(C), str(Z), str(T), "25", "20", str(big)], check=True)
        with tifffile.TiffFile(p) as tf:
            a = tf.asarray()
            ij = tf.imagej_metadata
            page = tf.pages[0]
            check(tf.is_bigtiff == bool(big), "bigtiff flag %s" % p)
            check(ij is not None and ij.get("slices", 1) == Z and ij.get("frames", 1) == T and ij.get("channels", 1) == C,
                  "ij meta %s" % ij)
            offs = [pg.dataoffsets[0] for pg in tf.pages]
            nb = W * H * np.dtype(dt).itemsize
            check(offs == [offs[0] + k * nb for k in range(len(offs))] and offs[0] > tf.pages[-1].offset,
                  "planes contiguous after the directories %s: %s" % (p, offs))
            check(ij is not None and (Z == 1 or abs(ij.get("spacing", 0) - 0.02) < 1e-9) and ij.get("unit") == "um",
                  "ij calib %s" % ij)
            xr = page.tags["XResolution"].value
            check(abs(xr[0] / xr[1] - 40.0) < 1e-3, "XResolution %s" % (xr,))
            check(a.dtype == np.dtype(dt), "dtype %s" % a.dtype)
            n = W * H * C * Z * T
            i = np.arange(n, dtype=np.int64)
            exp = {"uint8": (i * 7) % 256, "uint16": (i * 7919) % 65536}.get(dt, i * 0.25 - 100.0)
            shape = tuple(k for k in (T, Z, C) if k > 1) + (H, W)
            check(a.shape == shape, "shape %s, expected %s (%s)" % (a.shape, shape, p))
            check(np.array_equal(a.reshape(-1).astype(np.float64), np.asarray(exp, dtype=np.float32).astype(np.float64)), "values %s" % p)


def real_data():
    expect = {  # documented dimensions (SOURCES.md): W, H, T, dtype
        "musij/CardioMyoblast_Mitochondria_100Frames_NA1.4_80nm_1x_510nmemission.tif": (45, 30, 100, "uint16"),
        "musij/014_c00000002-650_775.tif": (70, 70, 50, "uint16"),
        "musij/008_z00000001_c00000001-1.tif": (70, 66, 200, "uint16"),
        "musij/C3-20180719_H9c2_1_dsRed-mito_KDEL_mC1to2000-20m_T23_1516_m_046C_608nm-1.tif": (74, 67, 50, "uint16"),
        "musij/SynEx1.tiff": (7, 7, 49, "uint16"),
        "musij/SynEx2.tiff": (51, 51, 49, "uint8"),
        "deepstorm/ArtificialDataset_demo1.tif": (64, 64, 20, "uint16"),
    }
    for rel, (w, h, t, dt) in expect.items():
        path = os.path.join(DATA, rel)
        p = subprocess.run([CLI, "info", "--json", path], capture_output=True, text=True)
        check(p.returncode == 0, "info %s: %s" % (rel, p.stderr))
        if p.returncode:
            continue
        info = json.loads(p.stdout)
        check((info["width"], info["height"], info["pages"], info["dtype"]) == (w, h, t, dt), "dims %s: %s" % (rel, info))
        ref = tifffile.imread(path).astype(np.float64)
        check(abs(info["mean"] - ref.mean()) < 1e-9 * max(1, ref.mean()) and info["max"] == ref.max() and info["min"] == ref.min(),
              "stats %s" % rel)


def bad_inputs(tmp):
    """One clear error line naming the file, non-zero exit."""
    cases = {}
    cases["missing"] = (os.path.join(tmp, "nope.tif"), "No such file")
    p = os.path.join(tmp, "text.tif")
    open(p, "w").write("hello\n" * 10)
    cases["not a tiff"] = (p, "not a TIFF")
    good = os.path.join(tmp, "good.tif")
    tifffile.imwrite(good, values("uint16", (4, 64, 64), 1), photometric="minisblack")
    p = os.path.join(tmp, "trunc.tif")
    open(p, "wb").write(open(good, "rb").read()[:20000])
    cases["truncated"] = (p, "truncated")
    p = os.path.join(tmp, "sizes.tif")
    with tifffile.TiffWriter(p) as tw:
        tw.write(values("uint16", (8, 8), 2))
        tw.write(values("uint16", (9, 8), 3))
    cases["mixed sizes"] = (p, "different sizes")
    p = os.path.join(tmp, "rgb.tif")
    tifffile.imwrite(p, values("uint8", (8, 8, 3), 4), photometric="rgb")
    cases["rgb"] = (p, "RGB")
    p = os.path.join(tmp, "cplx.tif")
    tifffile.imwrite(p, (values("float32", (8, 8), 5) + 1j).astype(np.complex64))
    cases["complex"] = (p, "complex")
    p = os.path.join(tmp, "zero.tif")
    open(p, "wb").write(b"II*\x00\x00\x00\x00\x00")
    cases["zero pages"] = (p, "no image pages")
    for what, (path, needle) in cases.items():
        r = subprocess.run([CLI, "info", path], capture_output=True, text=True)
        lines = [l for l in r.stderr.splitlines() if l.strip()]
        check(r.returncode != 0, "%s: exit code %d" % (what, r.returncode))
        check(len(lines) == 1 and path in lines[0] and needle in lines[0], "%s: stderr %r" % (what, r.stderr))
        check(r.stdout == "", "%s: printed %r" % (what, r.stdout))


with tempfile.TemporaryDirectory() as tmp:
    read_variants(tmp)
    read_calibration(tmp)
    write_variants(tmp)
    real_data()
    bad_inputs(tmp)
done()
