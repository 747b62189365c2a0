"""A crashing FMU ends only the process it runs in (issue 38, artibus.fmu.isolated): `artibus
simulate` says which FMU, the signal and the last recorded time in one line, exits 1, and keeps
the rows recorded before the crash as OUT.partial.csv.

The FMU: made here with pythonfmu3 (the test extra), an FMI 3.0 Co-Simulation FMU whose doStep
reads address 0 (a segmentation fault of the process that loaded it) on its step past 0.45 s;
before that its output x is the time its step ended (x(t_k) = t_k, x(0) = 0)."""
import signal
import subprocess
import sys

import numpy as np
import pytest

CRASH_FMU = '''
import ctypes
from pythonfmu3 import Fmi3Causality, Fmi3Slave, Fmi3Variability, Float64


class Crash(Fmi3Slave):
    """x = the time its step ended; a read of address 0 on the step past 0.45 s"""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.time, self.x = 0.0, 0.0
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous))
        self.register_variable(Float64("x", causality=Fmi3Causality.output, variability=Fmi3Variability.continuous))

    def do_step(self, current_time, step_size):
        if current_time + step_size > 0.45:
            ctypes.string_at(0)
        self.x = current_time + step_size
        return True
'''


@pytest.fixture(scope="module")
def crash_fmu(tmp_path_factory):
    pytest.importorskip("pythonfmu3", reason="pythonfmu3 (pyproject's test extra) is not installed")
    d = tmp_path_factory.mktemp("crash")
    (d / "Crash.py").write_text(CRASH_FMU)
    p = subprocess.run([sys.executable, "-m", "pythonfmu3", "build", "-f", str(d / "Crash.py"), "-d", str(d)],
                       capture_output=True, text=True, cwd=d)
    assert p.returncode == 0 and (d / "Crash.fmu").is_file(), p.stderr
    return d / "Crash.fmu"


def test_a_crashing_fmu_ends_only_its_process_and_its_rows_are_kept(crash_fmu, tmp_path):
    out = tmp_path / "c.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(crash_fmu), "--stop-time", "1",
                        "--step", "0.1", "-o", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 1, (p.returncode, p.stderr)     # (not -SIGSEGV: artibus itself went on)
    lines = p.stderr.strip().splitlines()
    assert "Traceback" not in p.stderr and len(lines) == 2, p.stderr
    assert lines[0].startswith(f"artibus: error: {crash_fmu}: the process running Crash was killed by "
                               f"{signal.SIGSEGV.name} after t = 0.4 s"), p.stderr
    partial = tmp_path / "c.partial.csv"
    assert lines[1] == f"artibus: partial results up to the failure: {partial}"
    assert not out.exists()
    table = np.genfromtxt(partial, delimiter=",", names=True, deletechars="")
    np.testing.assert_allclose(table["time"], [0.0, 0.1, 0.2, 0.3, 0.4], rtol=1e-12)
    np.testing.assert_allclose(table["x"], table["time"], rtol=1e-12)
