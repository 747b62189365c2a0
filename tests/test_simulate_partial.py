"""artibus simulate keeps partial results on SIGINT and SIGTERM as artibus run does
(issue 15): OUT.partial.csv with whole rows up to then (and its units), OUT absent,
one line, exit 128 + signal, the unpacked FMU removed. The signal comes while the
run is held at a marker of its step loop (artibus.runner.markers, tests/held_run.py),
never after a sleep (issue 41)."""
import signal
import sys
from pathlib import Path

import numpy as np
import pytest

from artibus import runner

sys.path.insert(0, str(Path(__file__).parent))
from held_run import HeldRun  # noqa: E402

#: the unpacked bench and FMUs in a temporary directory of the run's own, removed at its
#: end (the cache of artibus.cache off): what these tests watch
NO_CACHE = {"ARTIBUS_CACHE_MB": "0"}


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_simulate_interrupted_keeps_partial_results(tmp_path, sig):
    out = tmp_path / "out" / "r.csv"
    out.parent.mkdir()
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    with HeldRun(["simulate", "BusKinematics", "--stop-time", "200", "--step", "0.01", "-o", out],
                 cwd=tmp_path, env={"TMPDIR": str(tmpdir), **NO_CACHE}) as run:
        line = run.wait_for(lambda line: line.startswith("t="))    # held after 5000 steps: it cannot have ended
        assert line == "t=50.0"
        run.signal(sig)
        err = run.finish()
    assert run.proc.returncode == 128 + sig, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    partial = runner.partial_path(out)
    assert err.strip() == f"artibus: stopped by {signal.Signals(sig).name}; partial results up to t = 50 s in {partial}"
    assert not out.exists()
    assert sorted(p.name for p in out.parent.iterdir()) == [partial.name, runner.units_path(partial).name]
    table = np.loadtxt(partial, delimiter=",", skiprows=1)
    assert table.shape[0] == 5001 and table[0, 0] == 0.0 and table[-1, 0] == pytest.approx(50.0, rel=1e-12)
    np.testing.assert_allclose(np.diff(table[:, 0]), 0.01, rtol=1e-6)   # whole rows, every step
    header = partial.read_text().splitlines()[0].replace('"', "").split(",")
    assert list(runner.read_units(partial)) == header and runner.read_units(partial)["time"] == "s"
    assert list(tmpdir.iterdir()) == []                      # the unpacked FMU removed
