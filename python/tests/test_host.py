"""The library inside a Python program: it leaves the host's signals alone,
reports progress, stops when asked, and speaks Python (keywords, help,
TypeError)."""
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
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
        r = col0rme.run(s.stacks, angles=s.angles, pixel_size=100, fwhm=229)
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
