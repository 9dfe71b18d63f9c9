"""The Python package against the CLI on the same stacks: same arrays as
the files `col0rme run` / `support` / `matirf` / `simulate` write; bad
input raises col0rme.Error with the library's message.

pytest --cli PATH names the col0rme program (conftest.py); the package finds
its own library."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import tifffile

import col0rme

ANGLES = [62.0, 65.0, 68.0]
SIM = ["--width", "24", "--height", "24", "--frames", "200", "--filaments", "2", "--seed", "5"]


@pytest.fixture(scope="module")
def data(tmp_path_factory, cli):
    d = tmp_path_factory.mktemp("data")
    cli("simulate", *SIM, "--angles", ",".join(map(str, ANGLES)), "-o", d / "sim")
    paths = [d / "sim" / ("stack_q%02d.tif" % (q + 1)) for q in range(len(ANGLES))]
    return d, paths, [tifffile.imread(p).astype(np.float32) for p in paths]


@pytest.fixture(scope="module")
def cli_run(data, cli):
    d, paths, _ = data
    cli("run", "--angles", ",".join(map(str, ANGLES)), "--fwhm", 229, "-o", d / "run", *paths)
    return d / "run"


def same(a, b, what):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, "%s: shape %s vs %s" % (what, a.shape, b.shape)
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6 * max(np.abs(b).max(), 1e-30), err_msg=what)


def test_simulate_equals_cli(data):
    _, _, stacks = data
    sim = col0rme.simulate(width=24, height=24, frames=200, filaments=2, seed=5, angles=ANGLES)
    assert sim.angles == ANGLES and sim.pixel_size == 100 and sim.fwhm == 229
    assert len(sim.stacks) == 3 and sim.emitters.shape[1] == 4 and len(sim.emitters) > 10
    for q in range(3):
        assert np.array_equal(sim.stacks[q], stacks[q])


def test_run_on_arrays_equals_cli(data, cli_run):
    _, _, stacks = data
    r = col0rme.run(stacks, angles=ANGLES, pixel_size=100, fwhm=229)
    # the package's own build of the same sources: the CLI's volume to the bit
    vol = tifffile.imread(cli_run / "volume.tif")
    assert r.volume.dtype == vol.dtype and r.volume.shape == vol.shape
    assert np.array_equal(r.volume, vol), "volume: max |diff| %g" % np.abs(r.volume - vol).max()
    same(r.depth, tifffile.imread(cli_run / "depth.tif"), "depth")
    assert np.array_equal(r.support, tifffile.imread(cli_run / "support.tif") > 0)
    for q in range(3):
        same(r.intensity[q], tifffile.imread(cli_run / ("intensity_q%02d.tif" % (q + 1))), "intensity %d" % q)
        same(r.background[q], tifffile.imread(cli_run / ("background_q%02d.tif" % (q + 1))), "background %d" % q)
    rep = json.load(open(cli_run / "report.json"))
    same(r.z_nm, rep["z_nm"], "z_nm")
    assert r.volume.shape == (len(r.z_nm), 96, 96) and r.support.any()
    assert r.report["parameters"]["fwhm_nm"] == 229 and "timings_s" in r.report


def test_run_on_paths_and_write(data, cli_run, tmp_path):
    _, paths, _ = data
    r = col0rme.run([str(p) for p in paths], angles=ANGLES, fwhm=229)
    same(r.volume, tifffile.imread(cli_run / "volume.tif"), "volume from paths")
    r.write(tmp_path / "out")
    same(tifffile.imread(tmp_path / "out" / "volume.tif"), tifffile.imread(cli_run / "volume.tif"), "written volume")
    with pytest.raises(col0rme.Error):
        r.write(tmp_path / "out")   # not empty, no force


def test_report_page(cli_run, tmp_path):
    """col0rme.report writes report.html again from a run's files; a directory
    that is not a run's output raises and gets nothing"""
    page = (cli_run / "report.html").read_text(encoding="utf-8")
    (tmp_path / "copy").mkdir()
    for f in os.listdir(cli_run):
        if f != "report.html":
            (tmp_path / "copy" / f).write_bytes((cli_run / f).read_bytes())
    path = col0rme.report(str(tmp_path / "copy"))
    assert open(path, encoding="utf-8").read() == page
    (tmp_path / "empty").mkdir()
    with pytest.raises(col0rme.Error, match="not a col0rme output directory"):
        col0rme.report(str(tmp_path / "empty"))
    assert not os.listdir(tmp_path / "empty")


def test_options_reach_the_library(data):
    _, _, stacks = data
    r = col0rme.run(stacks[:1], pixel_size=100, fwhm=229, penalty="cel0", srf=2, lam=1e-4)
    assert r.volume is None and r.support.shape == (48, 48) and len(r.intensity) == 1
    assert r.report["parameters"]["mode"] == "2D"
    assert json.dumps(r.report).count("cel0") >= 1 and "0.0001" in json.dumps(r.report)


def test_support_equals_cli(data, cli, tmp_path):
    _, paths, stacks = data
    cli("support", "--fwhm", 229, "-o", tmp_path / "s", paths[0])
    r = col0rme.support(stacks[0], pixel_size=100, fwhm=229)
    assert np.array_equal(r.support, tifffile.imread(tmp_path / "s" / "support.tif") > 0)
    assert r.volume is None


def test_matirf_equals_cli(cli_run, cli, tmp_path):
    imgs = [cli_run / ("intensity_q%02d.tif" % (q + 1)) for q in range(3)]
    cli("matirf", "--angles", ",".join(map(str, ANGLES)), "-o", tmp_path / "m", *imgs)
    r = col0rme.matirf([tifffile.imread(p) for p in imgs], angles=ANGLES)
    same(r.volume, tifffile.imread(tmp_path / "m" / "volume.tif"), "matirf volume")
    same(r.depth, tifffile.imread(tmp_path / "m" / "depth.tif"), "matirf depth")


def test_library_is_the_packages_own():
    """pip install ./python ships libcol0rme inside the package; COL0RME_LIB overrides it."""
    lib = col0rme.library()
    if os.environ.get("COL0RME_LIB"):
        assert lib == os.environ["COL0RME_LIB"]
    else:
        assert os.path.dirname(lib) == os.path.dirname(os.path.abspath(col0rme.__file__)), lib
        assert os.path.basename(lib).startswith("libcol0rme.so."), lib


def test_parameters_listed():
    p = col0rme.parameters()
    assert {"lambda", "angles", "pixel_nm", "fwhm_nm", "kappa", "baseline"} <= set(p) and all(p.values())


def test_bad_input_raises(data):
    _, _, stacks = data
    with pytest.raises(TypeError, match="no_such_parameter"):
        col0rme.run(stacks, angles=ANGLES, fwhm=229, no_such_parameter=1)
    with pytest.raises(TypeError, match="lambda"):
        col0rme.run(stacks, angles=ANGLES, fwhm=229, **{"lambda": "abc"})
    with pytest.raises(col0rme.Error, match="lambda_"):   # a TypeError is a col0rme.Error too
        col0rme.run(stacks, angles=ANGLES, fwhm=229, lambda_="abc")
    with pytest.raises(col0rme.Error, match="angles"):
        col0rme.run(stacks[:2], angles=ANGLES, pixel_size=100, fwhm=229)
    with pytest.raises(col0rme.Error, match="T x H x W"):
        col0rme.run([np.zeros(10, np.float32)], fwhm=229, pixel_size=100)
    with pytest.raises(col0rme.Error):
        col0rme.run(["/nonexistent/stack.tif"], fwhm=229)
    with pytest.raises(col0rme.Error):
        col0rme.simulate(width=4)
    with pytest.raises(col0rme.Error, match="bogus"):
        col0rme.simulate(bogus=1)


def test_documented_example_runs():
    """examples/run_arrays.py, the example of docs/api.md, as a user runs it."""
    ex = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "run_arrays.py")
    r = subprocess.run([sys.executable, ex], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "volume (20, 96, 96)" in r.stdout and "refused: angles" in r.stdout, r.stdout
