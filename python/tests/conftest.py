"""The col0rme program the tests compare the package with: --cli PATH
(default: col0rme on PATH). An option, not an environment variable, so that
the package under test runs in an environment with no col0rme variable."""


def pytest_addoption(parser):
    parser.addoption("--cli", default="col0rme", help="the col0rme program (default: col0rme on PATH)")
