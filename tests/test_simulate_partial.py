"""artibus simulate keeps partial results on SIGINT and SIGTERM as artibus run does
(issue 15): OUT.partial.csv with whole rows up to then (and its units), OUT absent,
one line, exit 128 + signal, the unpacked FMU removed."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from artibus import runner

#: the unpacked bench and FMUs in a temporary directory of the run's own, removed at its
#: end (the cache of artibus.cache off): what these tests watch
NO_CACHE = {"ARTIBUS_CACHE_MB": "0"}


def _wait_for(predicate, timeout=60.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    return False


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_simulate_interrupted_keeps_partial_results(tmp_path, sig):
    out = tmp_path / "out" / "r.csv"
    out.parent.mkdir()
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "artibus", "simulate", "BusKinematics", "--stop-time", "1e5",
                             "--step", "0.01", "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=tmp_path, env={**os.environ, "TMPDIR": str(tmpdir), **NO_CACHE})
    assert _wait_for(lambda: any(tmpdir.iterdir()))        # the FMU unpacked
    time.sleep(2.0)                                           # instantiated, initialised, stepping
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    partial = runner.partial_path(out)
    assert err.startswith(f"artibus: stopped by {signal.Signals(sig).name}; partial results up to t = "), err
    assert str(partial) in err
    assert not out.exists()
    assert sorted(p.name for p in out.parent.iterdir()) == [partial.name, runner.units_path(partial).name]
    table = np.loadtxt(partial, delimiter=",", skiprows=1)
    assert table.shape[0] > 10 and table[0, 0] == 0.0 and table[-1, 0] < 1e5
    np.testing.assert_allclose(np.diff(table[:, 0]), 0.01, rtol=1e-6)   # whole rows, every step
    t_end = float(err.split("up to t = ")[1].split(" s")[0])
    assert t_end == pytest.approx(table[-1, 0], rel=1e-5)
    header = partial.read_text().splitlines()[0].replace('"', "").split(",")
    assert list(runner.read_units(partial)) == header and runner.read_units(partial)["time"] == "s"
    assert list(tmpdir.iterdir()) == []                      # the unpacked FMU removed
