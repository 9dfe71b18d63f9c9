"""The col0rme program the tests compare the package with: --cli PATH
(default: col0rme on PATH). An option, not an environment variable, so that
the package under test runs in an environment with no col0rme variable."""
import subprocess

import pytest


def pytest_addoption(parser):
    parser.addoption("--cli", default="col0rme", help="the col0rme program (default: col0rme on PATH)")


@pytest.fixture(scope="session")
def cli(request):
    exe = request.config.getoption("--cli")

    def call(*args):
        r = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r
    return call
