"""The library inside a Python program: it leaves the host's signals alone,
reports progress, stops when asked, and speaks Python (keywords, help,
TypeError)."""
import ctypes
import inspect
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pydoc
import pytest

import col0rme

ANGLES = [62.0, 65.0, 68.0]


@pytest.fixture(scope="module")
def sim():
    return col0rme.simulate(width=24, height=24, frames=120, filaments=2, seed=5, angles=ANGLES)


def test_sigint_after_write_raises_keyboardinterrupt(tmp_path):
    """Jupyter's "interrupt kernel" is a SIGINT: after Result.write it must
    still reach Python as KeyboardInterrupt, not end the process."""
    code = textwrap.dedent("""
        import os, signal, sys, time
        import col0rme
        s = col0rme.simulate(width=24, height=24, frames=60, filaments=1, seed=3, angles=[62, 65, 68])
        r = col0rme.run(s.stacks, angles=s.angles, pixel_size_nm=100, fwhm_nm=229)
        r.write(sys.argv[1])
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
            print("no KeyboardInterrupt")
        except KeyboardInterrupt:
            print("KeyboardInterrupt")
    """)
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, (p.returncode, p.stderr)
    assert p.stdout.strip() == "KeyboardInterrupt", p.stdout + p.stderr
    assert os.path.isfile(tmp_path / "out" / "volume.tif")


def run(sim, **kw):
    return col0rme.run(sim.stacks, angles=sim.angles, pixel_size_nm=100, fwhm_nm=229, wavelength_nm=488,
                       n_sample=1.33, **kw)


def test_progress_every_stage(sim):
    heard = []
    r = run(sim, progress=lambda stage, f: heard.append((stage, f)))
    stages = list(dict.fromkeys(s for s, _ in heard))
    assert stages == ["drift", "support", "intensity", "render", "bleaching", "matirf"], stages
    for s in stages:
        fs = [f for t, f in heard if t == s]
        assert fs[0] == 0 and fs[-1] == 1 and fs == sorted(fs), (s, fs)
    assert r.volume is not None
    heard.clear()
    col0rme.support(sim.stacks[0], pixel_size_nm=100, fwhm_nm=229, progress=lambda s, f: heard.append(s))
    assert list(dict.fromkeys(heard)) == ["drift", "support"]


class Stop(Exception):
    pass


@pytest.mark.parametrize("at", ["drift", "support", "matirf"])
def test_callback_exception_ends_the_run(sim, tmp_path, at):
    """the callback's own exception object comes back, the run stops there
    (nothing after it is heard) and nothing is written"""
    heard, err = [], Stop("stop at " + at)

    def fn(stage, f):
        heard.append(stage)
        if stage == at:
            raise err
    os.chdir(tmp_path)
    with pytest.raises(Stop) as e:
        run(sim, progress=fn)
    assert e.value is err
    assert heard[-1] == at and heard.count(at) == 1, heard
    assert os.listdir(tmp_path) == []


def test_keyboardinterrupt_in_callback_propagates(sim):
    def fn(stage, f):
        if stage == "support":
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        run(sim, progress=fn)


def test_ctrl_c_during_a_run():
    """a SIGINT while the library works (no progress function given) raises
    KeyboardInterrupt from run() at the library's next stage"""
    code = textwrap.dedent("""
        import os, signal, threading, time
        import col0rme
        s = col0rme.simulate(width=32, height=32, frames=400, filaments=3, seed=3, angles=[62, 65, 68])
        t0 = time.time()
        r = col0rme.run(s.stacks, angles=s.angles, pixel_size_nm=100, fwhm_nm=229)
        full = time.time() - t0
        threading.Timer(0.05 * full, os.kill, (os.getpid(), signal.SIGINT)).start()
        t0 = time.time()
        try:
            col0rme.run(s.stacks, angles=s.angles, pixel_size_nm=100, fwhm_nm=229)
            print("finished")
        except KeyboardInterrupt:
            print("KeyboardInterrupt after %.2f of the run" % ((time.time() - t0) / full))
    """)
    p = subprocess.run([sys.executable, "-W", "ignore", "-c", code], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("KeyboardInterrupt"), p.stdout + p.stderr


def test_tqdm_bar_and_without_tqdm():
    code = textwrap.dedent("""
        import sys
        if sys.argv[1] == "without":
            sys.modules["tqdm"] = None   # import tqdm fails
        import col0rme
        s = col0rme.simulate(width=24, height=24, frames=60, filaments=1, seed=3, angles=[62, 65, 68])
        col0rme.run(s.stacks, angles=s.angles, pixel_size_nm=100, fwhm_nm=229, progress=True)
    """)
    for how in ("with", "without"):
        p = subprocess.run([sys.executable, "-W", "ignore", "-c", code, how], capture_output=True, text=True,
                           timeout=300)
        assert p.returncode == 0, p.stderr
        assert "matirf" in p.stderr and "100%" in p.stderr, (how, p.stderr)
        if how == "with":
            assert "|" in p.stderr, p.stderr   # tqdm's bar


def test_help_lists_every_parameter_with_its_default():
    text = pydoc.render_doc(col0rme.run, renderer=pydoc.plaintext)
    flat = " ".join(text.split())
    names = {"pixel_nm": "pixel_size_nm", "lambda": "lambda_"}
    left_out = {"offset", "matirf_background", "estimate_background", "background_smooth", "psf_fwhm_nm",
                "noise_variance"}   # matirf()'s and the single steps'
    kind, choices, hlp, default = (ctypes.c_char_p() for _ in range(4))
    lib = col0rme._L()
    i = 0
    while True:
        name = lib.c0_run_conf_param_info(i, *(ctypes.byref(x) for x in (kind, choices, hlp, default)))
        if not name:
            break
        i += 1
        c = name.decode()
        if c in left_out:
            continue
        py = names.get(c, c)
        d = " ".join(default.value.decode().split())
        assert py + " : " in text and py + ": " in text, py          # the docstring and the signature
        assert ("Default: %s." % d) in flat, (py, d)
    assert i > 60 and "progress : callable" in text
    assert "wavelength_nm : float, optional" in text and "lambda_ : float, optional" in text


def test_wrong_types_and_values(sim):
    ok = dict(angles=sim.angles, fwhm_nm=229)
    for bad in (dict(srf="4"), dict(srf=2.5), dict(penalty=1), dict(angles="62,65,68"), dict(baseline="yes"),
                dict(no_such_parameter=1), dict(pixel_size=100, pixel_size_nm=100)):
        with pytest.raises(TypeError):
            col0rme.run(sim.stacks, **{**ok, **bad})
    for bad in (dict(penalty="l2"), dict(kappa=float("nan")), dict(angles=[62, 65])):
        with pytest.raises(ValueError):
            col0rme.run(sim.stacks, pixel_size_nm=100, **{**ok, **bad})
    with pytest.raises(TypeError):
        col0rme.run(42, **ok)
    with pytest.raises(col0rme.Error, match="pixel_size_nm"):   # the Python name in the library's message
        col0rme.run(sim.stacks, **ok)


def test_old_names_still_work(sim):
    a = col0rme.run(sim.stacks[:1], pixel_size=100, fwhm=229, lam=1e-3, progress=None)
    b = col0rme.run(sim.stacks[:1], pixel_size_nm=100, fwhm_nm=229, lambda_=1e-3)
    c = col0rme.run(sim.stacks[:1], **{"pixel_nm": 100, "fwhm_nm": 229, "lambda": 1e-3})
    assert np.array_equal(a.support, b.support) and np.array_equal(a.support, c.support)
    assert a.report["support"][0]["lambda_relative"] == 1e-3


def test_result_calibration_and_read_round_trip(sim, tmp_path):
    r = run(sim, progress=None)
    assert r.pixel_size_nm == 100 and r.fine_pixel_nm == 25 and r.srf == 4
    assert r.z_nm[0] == 10 and r.z_nm[1] - r.z_nm[0] == 20 and len(r.z_nm) == r.volume.shape[0]
    r.write(tmp_path / "out")
    b = col0rme.read(tmp_path / "out")
    assert (b.pixel_size_nm, b.fine_pixel_nm, b.srf) == (100, 25, 4)
    assert np.array_equal(b.volume, r.volume) and np.array_equal(b.depth, r.depth)
    assert np.array_equal(b.support, r.support) and np.array_equal(b.z_nm, r.z_nm)
    assert len(b.intensity) == 3 and all(np.array_equal(x, y) for x, y in zip(b.intensity, r.intensity))
    assert all(np.array_equal(x, y) for x, y in zip(b.background, r.background))
    assert b.report["parameters"] == r.report["parameters"]
    b.write(tmp_path / "again")
    c = col0rme.read(tmp_path / "again")
    assert np.array_equal(c.volume, r.volume)
    m = col0rme.matirf(r.intensity, angles=sim.angles, pixel_size_nm=25, wavelength_nm=488, n_sample=1.33)
    assert m.fine_pixel_nm == 25
    m.write(tmp_path / "m")
    assert col0rme.read(tmp_path / "m").fine_pixel_nm == pytest.approx(25)
    with pytest.raises(col0rme.Error, match="report.json"):
        col0rme.read(tmp_path)
    s = col0rme.support(sim.stacks[0], pixel_size_nm=100, fwhm_nm=229)
    assert (s.pixel_size_nm, s.fine_pixel_nm, s.srf) == (100, 25, 4)
    s.write(tmp_path / "s")
    b = col0rme.read(tmp_path / "s")
    assert (b.pixel_size_nm, b.fine_pixel_nm, b.srf) == (100, 25, 4) and np.array_equal(b.support, s.support)


def test_keywords_match_the_commands(cli):
    """run(), support() and matirf() take what `col0rme run/support/matirf` take (the CLI-only flags aside)"""
    import json as js
    cli_only = {"outdir", "force", "verbose", "progress_json", "channel", "no_drift", "threads"}
    for name, f in (("run", col0rme.run), ("support", col0rme.support), ("matirf", col0rme.matirf)):
        h = js.loads(cli(name, "--help-json").stdout)
        want = {o["param"] for o in h["options"]} - cli_only
        have = {{"pixel_size_nm": "pixel_nm", "lambda_": "lambda"}.get(k, k) for k in inspect.signature(f).parameters}
        assert want <= have, (name, want - have)
        if name == "matirf":
            assert have - {"images", "progress"} == want, (have ^ want)
