"""report.html (issue 31) through the CLI, on one simulated run: the page
holds every figure, every image decodes, its numbers are report.json's and
the error map's are those of an independent numpy forward model, nothing
is fetched from outside, `col0rme report` writes the same page again,
Chromium renders it without console errors, the error map shows a deleted
part of the true support and invented emitters, and bad directories are
refused with one line and nothing written.

usage: test_report.py COL0RME [full|quick]
(quick, the sanitizer build: a 32x32 x 100-frame run, the same checks and
bars, which hold there too, but no browser, which runs none of col0rme's code)
"""
import base64
import glob
import json
import math
import os
import re
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np
import tifffile

from checks import check, done, refused

CLI = sys.argv[1]
QUICK = sys.argv[2:] == ["quick"]
IDS = ["mean", "render", "depth", "lambda", "drift", "bleach", "frc", "error-map",
       "warnings", "parameters", "timings", "command"]
# the error map's validation margins (docs/guide.md, "Judging a result")
MARGIN_DELETED = 5.0    # residual in the deleted part / same place with the whole true support
MARGIN_INVENTED = 5.0   # residual where emitters were invented / same place without them
MARGIN_LOCAL = 3.0      # the deleted part's rise / the rise elsewhere


def cli(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True)


def png_decode(data):
    """(w, h, pixels) of an 8-bit grey, RGB(A) or indexed PNG, checking signature, CRCs and the
    inflated size; raises ValueError otherwise (an independent decoder)"""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("no PNG signature")
    pos, idat, w, plte = 8, b"", None, None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        crc, = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        if zlib.crc32(kind + body) & 0xffffffff != crc:
            raise ValueError("bad CRC in %s" % kind)
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            if depth != 8 or ctype not in (0, 2, 3, 6):
                raise ValueError("not 8-bit grey, RGB(A) or indexed")
            ch = {0: 1, 2: 3, 3: 1, 6: 4}[ctype]
        elif kind == b"PLTE":
            plte = np.frombuffer(body, np.uint8).reshape(-1, 3)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
        pos += 12 + n
    raw = zlib.decompress(idat)
    if w is None or len(raw) != h * (1 + w * ch):
        raise ValueError("image data of the wrong size")
    # undo the filters for the pixels
    out, prev, stride = [], bytearray(w * ch), w * ch
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f > 4:
            raise ValueError("bad filter %d" % f)
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            b, c = prev[i], prev[i - ch] if i >= ch else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out.append(bytes(line))
        prev = line
    px = np.frombuffer(b"".join(out), np.uint8).reshape(h, w, ch)
    if ctype == 3:
        if px.max() >= len(plte):
            raise ValueError("index beyond the palette")
        px = plte[px[..., 0]]
    return w, h, px


def json_at(rep, path):
    o = rep
    for k in path.split("."):
        o = o[int(k)] if isinstance(o, list) else o[k]
    return o


def psf_factor(n, r, sigma):
    """G[i, a]: integral over coarse pixel i of the unit Gaussian centred on fine pixel a"""
    erf = np.vectorize(math.erf)
    c = (np.arange(n * r) + 0.5) / r
    edges = np.arange(n + 1)[:, None]
    cdf = 0.5 * (1 + erf((edges - c[None, :]) / (sigma * math.sqrt(2))))
    return cdf[1:] - cdf[:-1]


def forward(x, b, pixel, fwhm, r):
    ny, nx = b.shape
    s = fwhm / pixel / (2 * math.sqrt(2 * math.log(2)))
    return psf_factor(ny, r, s) @ x.astype(np.float64) @ psf_factor(nx, r, s).T + b


def page_checks(out, html, rep):
    for i in IDS:
        check(re.search(r'<section id="%s"' % re.escape(i), html), "page has a section id=%s" % i)
    size = os.path.getsize(os.path.join(out, "report.html"))
    check(size <= 2 << 20, "page of %d bytes <= 2 MB at 64x64 x 5 angles" % size)
    print("report.html: %d bytes" % size)
    # no external resource: no script, no link, no url() and no src/href but data: and #anchors
    check("<script" not in html.lower() and "<link" not in html.lower() and "@import" not in html, "no script, link or import")
    refs = re.findall(r'(?:src|href)\s*=\s*"([^"]*)"', html) + re.findall(r"url\(([^)]*)\)", html)
    bad = [u for u in refs if not (u.startswith("data:image/png;base64,") or u.startswith("#"))]
    check(not bad, "no external reference (%s)" % bad[:3])
    check(not re.search(r"(https?:|ftp:|file:)//", html), "no URL anywhere on the page")
    # every image decodes
    imgs = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]*)", html)
    ok = 0
    for s in imgs:
        try:
            w, h, px = png_decode(base64.b64decode(s, validate=True))
            ok += w > 0 and h > 0 and px.std() > 0
        except (ValueError, zlib.error) as e:
            print("  image: %s" % e, file=sys.stderr)
    nq = len(rep["intensity"])
    check(len(imgs) >= 3 * nq + 2 and ok == len(imgs), "%d of %d inline PNGs decode, not flat" % (ok, len(imgs)))
    # numbers and strings tagged with their report.json path are report.json's
    tagged = re.findall(r'<span class="(num|str)" data-json="([^"]+)">([^<]*)</span>', html)
    wrong = []
    for kind, path, text in tagged:
        v = json_at(rep, path)
        text = text.replace("&amp;", "&").replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", '"')
        if kind == "num":
            if not (isinstance(v, (int, float)) and abs(float(text) - v) <= 5e-4 * abs(v) + 1e-12):
                wrong.append((path, text, v))
        elif text != v:
            wrong.append((path, text, v))
    check(len(tagged) >= 60 and not wrong, "%d tagged values equal report.json's (wrong: %s)" % (len(tagged), wrong[:3]))
    for must in ["parameters.fwhm_nm", "support.0.lambda_relative", "intensity.0.mu", "drift.max_nm",
                 "bleaching.rate_per_frame", "timings_s.support", "matirf.angles_deg.0"]:
        check(any(p == must for _, p, _ in tagged), "the page shows %s" % must)
    # given / chosen / default
    row = lambda label: re.search(r'<tr class="(\w+)"><td>%s' % re.escape(label), html)
    check(row("PSF FWHM (nm)") and row("PSF FWHM (nm)").group(1) == "given", "FWHM marked given")
    m = re.search(r'<tr class="(\w+)"><td>\u03bb / \u03bb_max', html)
    check(m and m.group(1) == "chosen", "lambda marked chosen (automatic)")
    check(row("super-resolution factor") and row("super-resolution factor").group(1) == "default", "srf marked default")
    # the command
    m = re.search(r'<pre class="cmd" data-argv="1">([^<]*)</pre>', html)
    want = "col0rme " + " ".join(shlex.quote(a) for a in rep["argv"])
    check(m and m.group(1).replace("&amp;", "&").replace("&#39;", "'") == want, "command reproduces argv")


def errmap_checks(out, html, rep):
    """RSP, RSE and error_qNN.tif against numpy's forward model"""
    p = rep["parameters"]
    for q in range(len(rep["intensity"])):
        n = "%02d" % (q + 1)
        mean = tifffile.imread(os.path.join(out, "mean_q%s.tif" % n)).astype(np.float64)
        x = tifffile.imread(os.path.join(out, "intensity_q%s.tif" % n))
        b = tifffile.imread(os.path.join(out, "background_q%s.tif" % n)).astype(np.float64)
        model = forward(x, b, p["pixel_size_nm"], p["fwhm_nm"], p["srf"])
        res = mean - model
        rsp, rse = np.corrcoef(mean.ravel(), model.ravel())[0, 1], math.sqrt(np.mean(res ** 2))
        with tifffile.TiffFile(os.path.join(out, "error_q%s.tif" % n)) as t:
            err = t.pages[0].asarray()
            xres = t.pages[0].tags["XResolution"].value
        check(np.max(np.abs(err - res)) < 1e-3 * (np.max(np.abs(res)) + 1), "error_q%s.tif = mean - model" % n)
        check(abs(xres[1] / xres[0] - 0.1) < 1e-6, "error_q%s.tif calibrated at 0.1 um" % n)
        got = {k: float(v) for k, v in re.findall(r'data-err="%d\.(\w+)">([^<]*)<' % q, html)}
        check(abs(got.get("rsp", -9) - rsp) < 1e-3 and abs(got.get("rse", -9) - rse) < 1e-3 * rse,
              "q%d: page RSP %s RSE %s, numpy %.4f %.4g" % (q + 1, got.get("rsp"), got.get("rse"), rsp, rse))
        sd = math.sqrt(rep["intensity"][q]["noise_variance"] / rep["intensity"][q]["frames"])
        check(rsp > 0.99 and rse < 4 * sd, "q%d: the run's model explains its data (RSP %.4f, RSE %.3g, noise sd %.3g)"
              % (q + 1, rsp, rse, sd))


def chromium():
    for c in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(c):
            return c
    return None


def render(browser, html_path, png):
    p = subprocess.run(["timeout", "120", browser, "--headless", "--no-sandbox", "--disable-gpu",
                        "--enable-logging=stderr", "--v=0", "--window-size=1280,3000", "--screenshot=" + png,
                        "file://" + os.path.abspath(html_path)], capture_output=True, text=True)
    console = [l for l in p.stderr.splitlines() if "CONSOLE" in l or "Uncaught" in l]
    return p.returncode, console


def browser_checks(tmp, out):
    b = chromium()
    if not b:
        print("SKIP browser rendering: no chromium installed (scripts/setup.sh installs the Debian package)")
        return
    png = os.path.join(tmp, "shot.png")
    rc, console = render(b, os.path.join(out, "report.html"), png)
    check(rc == 0 and os.path.exists(png), "chromium rendered the page (rc %d)" % rc)
    check(not console, "no console errors: %s" % console[:3])
    if os.path.exists(png):
        w, h, px = png_decode(open(png, "rb").read())
        rgb = px[..., :3].reshape(-1, px.shape[2] if px.shape[2] < 3 else 3)
        colours = len(np.unique(rgb[::7], axis=0))
        dark = np.mean(rgb.sum(1) < 200)
        check(colours > 200 and dark > 0.02, "screenshot %dx%d not blank: %d colours, %.1f %% dark" % (w, h, colours, 100 * dark))
    # the console check can fail: a page with a script error is caught
    bad = os.path.join(tmp, "bad.html")
    open(bad, "w").write("<html><body>x<script>console.error('deliberate');</script></body></html>")
    rc, console = render(b, bad, os.path.join(tmp, "bad.png"))
    check(console, "a console error is seen when there is one")


def region_ratio(a, b, mask):
    return np.mean(np.abs(a[mask])) / max(np.mean(np.abs(b[mask])), 1e-12)


def dilate(m, k):
    out = m.copy()
    for dy in range(-k, k + 1):
        for dx in range(-k, k + 1):
            out |= np.roll(np.roll(m, dy, 0), dx, 1)
    return out


def validation(tmp, data, stack):
    """deleting 20 % of the true support, or inventing emitters in empty
    areas, raises the residual there"""
    truth = tifffile.imread(os.path.join(data, "truth_support.tif")) > 0
    L = truth.shape[0]
    r = 4
    # a band of columns holding 20 % of the true support
    cols = np.cumsum(truth.sum(0)) / truth.sum()
    c0 = int(np.searchsorted(cols, 0.4))
    c1 = int(np.searchsorted(cols, 0.6))
    cut = truth.copy()
    cut[:, c0:c1] = False
    print("deleted %.1f %% of the true support (fine columns %d-%d)" % (100 * (1 - cut.sum() / truth.sum()), c0, c1))
    outs = {}
    for name, m in (("whole", truth), ("cut", cut)):
        sup = os.path.join(tmp, "support_%s.tif" % name)
        tifffile.imwrite(sup, m.astype(np.uint8), imagej=True, resolution=(1 / 0.025, 1 / 0.025), metadata={"unit": "um"})
        outs[name] = os.path.join(tmp, "int_" + name)
        p = cli("intensity", "--support", sup, "--fwhm", "229", "-o", outs[name], stack)
        check(p.returncode == 0 and os.path.exists(os.path.join(outs[name], "report.html")),
              "intensity on the %s support writes a page: %s" % (name, p.stderr.strip()))
    if not all(os.path.exists(os.path.join(o, "error_q01.tif")) for o in outs.values()):
        check(False, "error maps written")
        return
    err = {k: tifffile.imread(os.path.join(o, "error_q01.tif")) for k, o in outs.items()}
    # the camera pixels the deleted part lights: its coarse footprint, one pixel around
    deleted = (truth & ~cut).reshape(L // r, r, L // r, r).any(axis=(1, 3))
    there, elsewhere = dilate(deleted, 1), ~dilate(deleted, 3)
    k_del = region_ratio(err["cut"], err["whole"], there)
    k_else = region_ratio(err["cut"], err["whole"], elsewhere)
    print("deleted 20 %%: mean |residual| there x %.2f, elsewhere x %.2f (margin %g)" % (k_del, k_else, MARGIN_DELETED))
    check(k_del >= MARGIN_DELETED, "deleted support raises the residual there by >= %g (x %.2f)" % (MARGIN_DELETED, k_del))
    check(np.mean(err["cut"][there]) > 0, "missing structure reads positive (data brighter)")
    check(k_del >= MARGIN_LOCAL * k_else, "the rise is local: x %.2f there, x %.2f elsewhere" % (k_del, k_else))
    # invented emitters: short segments in empty areas of the estimate, as bright as its bright pixels
    inv = os.path.join(tmp, "int_invented")
    shutil.copytree(outs["whole"], inv)
    for f in glob.glob(os.path.join(inv, "report.html")) + glob.glob(os.path.join(inv, "error_*.tif")):
        os.remove(f)
    x = tifffile.imread(os.path.join(inv, "intensity_q01.tif"))
    level = np.percentile(x[x > 0], 90)
    empty = ~dilate(truth.reshape(L // r, r, L // r, r).any(axis=(1, 3)), 3)
    ys, xs = np.nonzero(empty[2:-2, 2:-2])
    rng = np.random.default_rng(5)
    placed = np.zeros_like(empty)
    for i in rng.choice(len(ys), size=min(8, len(ys)), replace=False):
        cy, cx = (ys[i] + 2) * r + 1, (xs[i] + 2) * r
        x[cy, cx:cx + 3] += level
        placed[ys[i] + 2, xs[i] + 2] = True
    with tifffile.TiffFile(os.path.join(outs["whole"], "intensity_q01.tif")) as t:
        res = t.pages[0].tags["XResolution"].value
    tifffile.imwrite(os.path.join(inv, "intensity_q01.tif"), x, imagej=True, resolution=(res[0] / res[1],) * 2,
                     metadata={"unit": "um"})
    p = cli("report", inv)
    check(p.returncode == 0, "report on the edited estimate: %s" % p.stderr.strip())
    if p.returncode:
        return
    e_inv = tifffile.imread(os.path.join(inv, "error_q01.tif"))
    there = dilate(placed, 1)
    k_inv = region_ratio(e_inv, err["whole"], there)
    print("invented emitters (%d): mean |residual| there x %.2f (margin %g)" % (placed.sum(), k_inv, MARGIN_INVENTED))
    check(k_inv >= MARGIN_INVENTED, "invented emitters raise the residual there by >= %g (x %.2f)" % (MARGIN_INVENTED, k_inv))
    check(np.mean(e_inv[there]) < 0, "invented structure reads negative (model brighter)")


def bad_input(tmp, out):
    def untouched(d, before):
        return sorted(os.listdir(d)) == before

    empty = os.path.join(tmp, "empty")
    os.mkdir(empty)
    check(refused(cli("report", empty), empty, "not a col0rme output directory") and not os.listdir(empty),
          "report on an empty directory: one line, nothing written")
    check(refused(cli("report", os.path.join(tmp, "nowhere")), "nowhere"), "report on a missing directory")
    for victim, needle in (("intensity_q02.tif", "intensity_q02.tif"), ("mean_q03.tif", "mean_q03.tif"),
                           ("volume.tif", "volume.tif"), ("render.tif", "render.tif")):
        d = os.path.join(tmp, "miss_" + victim)
        shutil.copytree(out, d)
        for f in glob.glob(os.path.join(d, "report.html")) + glob.glob(os.path.join(d, "error_*.tif")):
            os.remove(f)
        os.remove(os.path.join(d, victim))
        before = sorted(os.listdir(d))
        check(refused(cli("report", d), needle, "missing") and untouched(d, before),
              "report without %s: one line naming it, nothing written" % victim)
    d = os.path.join(tmp, "badjson")
    shutil.copytree(out, d)
    os.remove(os.path.join(d, "report.html"))
    open(os.path.join(d, "report.json"), "w").write('{"argv": [')
    before = sorted(os.listdir(d))
    check(refused(cli("report", d), "report.json") and untouched(d, before), "report with a broken report.json")
    d = os.path.join(tmp, "badsize")
    shutil.copytree(out, d)
    os.remove(os.path.join(d, "report.html"))
    tifffile.imwrite(os.path.join(d, "background_q01.tif"), np.zeros((8, 8), np.float32))
    before = sorted(os.listdir(d))
    check(refused(cli("report", d), "background_q01.tif") and untouched(d, before), "report with a background of the wrong size")


def main():
    tmp = tempfile.mkdtemp(prefix="c0report")
    try:
        data, out = os.path.join(tmp, "data"), os.path.join(tmp, "run")
        small = ["--width", "32", "--height", "32", "--frames", "100"] if QUICK else []
        p = cli("simulate", "--seed", "3", "--pairs", "-o", data, *small)
        check(p.returncode == 0, "simulate: %s" % p.stderr)
        ang = ",".join("%.6g" % a for a in json.load(open(os.path.join(data, "sim.json")))["parameters"]["angles_deg"])
        stacks = sorted(glob.glob(os.path.join(data, "stack_q*.tif")))
        p = cli("run", "--fwhm", "229", "--angles", ang, "--baseline", "-o", out, *stacks)
        check(p.returncode == 0, "run: %s" % p.stderr)
        if p.returncode:
            return
        html = open(os.path.join(out, "report.html"), encoding="utf-8").read()
        rep = json.load(open(os.path.join(out, "report.json")))
        page_checks(out, html, rep)
        errmap_checks(out, html, rep)
        # col0rme report writes the same page again
        os.rename(os.path.join(out, "report.html"), os.path.join(tmp, "first.html"))
        p = cli("report", out)
        check(p.returncode == 0 and open(os.path.join(out, "report.html"), encoding="utf-8").read() == html,
              "col0rme report writes the run's page again, byte for byte: %s" % p.stderr.strip())
        # support writes its part: the mean, the lambda curve and the FRC
        sup = os.path.join(tmp, "support")
        p = cli("support", "--fwhm", "229", "-o", sup, stacks[0])
        page = open(os.path.join(sup, "report.html"), encoding="utf-8").read() if p.returncode == 0 else ""
        check(all('<section id="%s"' % i in page for i in IDS) and "<polyline" in page
              and len(re.findall(r"data:image/png", page)) == 1, "support writes a page with its part: %s" % p.stderr.strip())
        if not QUICK:
            browser_checks(tmp, out)
        bad_input(tmp, out)
        validation(tmp, data, stacks[0])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    done()


main()
