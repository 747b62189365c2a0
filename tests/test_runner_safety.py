"""Nothing lost (issue 15): atomic writes, a full disk, SIGINT/SIGTERM while
simulating and while writing, concurrent runs of a stale bench, a bounded
step plan, output paths checked before the run."""
import errno
import os

import pytest

from artibus import ArtibusError
from artibus.files import atomic_path, atomic_write, check_output

#: the unpacked bench and FMUs in a temporary directory of the run's own, removed at its
#: end (the cache of artibus.cache off): what these tests watch
NO_CACHE = {"ARTIBUS_CACHE_MB": "0"}


def test_atomic_write_keeps_old_file_on_interrupt(tmp_path):
    """An interrupted write leaves the previous file, whole, and no temporary file."""
    out = tmp_path / "r.csv"
    with atomic_write(out) as f:
        f.write("old\n")
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(out) as f:
            f.write("half of the new")
            raise KeyboardInterrupt
    assert out.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_atomic_path_keeps_suffix_and_renames(tmp_path):
    out = tmp_path / "plot.png"
    with atomic_path(out) as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path and not out.exists()
        tmp.write_bytes(b"png")
    assert out.read_bytes() == b"png" and len(list(tmp_path.iterdir())) == 1


def test_full_disk_is_one_error_and_no_torn_file(tmp_path, monkeypatch):
    """ENOSPC midway through a write: no file under the final name, an ArtibusError naming it."""
    out = tmp_path / "r.csv"

    class Full:
        def __init__(self, f):
            self.f, self.n = f, 0

        def write(self, s):
            self.n += len(s)
            if self.n > 10:
                raise OSError(errno.ENOSPC, "No space left on device")
            return self.f.write(s)

    with pytest.raises(ArtibusError, match="no space left on device"):
        with atomic_write(out) as f:
            full = Full(f)
            for _ in range(10):
                full.write("0123456789\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where", ["dir", "missing", "readonly"])
def test_check_output_refuses_bad_places(tmp_path, where):
    path = {"dir": tmp_path, "missing": tmp_path / "no" / "r.csv", "readonly": "/proc/r.csv"}[where]
    with pytest.raises(ArtibusError, match="-o"):
        check_output(path)
    check_output(tmp_path / "r.csv")
    assert list(tmp_path.iterdir()) == []


# --- results written whole ---------------------------------------------------------

import shutil
import signal
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np

from artibus import fmu_path, runner
from artibus.fmu import Result
from artibus.runner import core as runner_core, plan as runner_plan, results as runner_results

sys.path.insert(0, str(Path(__file__).parent))
from test_runner import LEAD_FOLLOW, component, connection, make_ssp  # noqa: E402
from held_run import BOUND, HeldRun  # noqa: E402

SLOW = ('<ssd:Annotations><ssc:Annotation type="org.artibus.simulation">'
        '<Simulation xmlns="urn:artibus" stepSize="{}"/></ssc:Annotation></ssd:Annotations>')
STEER = {"Lead.testSteerAmp": 0.2, "Follow.testSteerAmp": 0.0}   # the leader steers, the follower follows


def small_result(n=1000):
    t = np.arange(n) * 0.01
    return Result.from_array(["time", "a", "b"], np.column_stack([t, np.sin(t), np.cos(t)]))


@pytest.mark.parametrize("suffix", [".csv", ".mat"])
def test_save_full_disk_leaves_no_torn_file(tmp_path, monkeypatch, suffix):
    """Issue 15: a full disk left a truncated results file that looked valid. Now
    the final name is absent (or the previous file kept) and the error is one line.
    (A full disk midway through the write: test_full_disk_on_a_real_tiny_file_system.)"""
    out = tmp_path / f"r{suffix}"
    runner.save(small_result(10), out)
    before = out.read_bytes()

    def full(fd):      # a file system with delayed allocation reports a full disk when flushing
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(ArtibusError, match=r"r\.(csv|mat): no space left on device"):
        runner.save(small_result(), out)
    monkeypatch.undo()
    assert out.read_bytes() == before                      # the previous results, whole
    units = [runner.units_path(out).name] if suffix == ".csv" else []      # (the first save's units)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name] + units)


def test_full_disk_on_a_real_tiny_file_system(tmp_path):
    """A 64 kB tmpfs (root only): the real ENOSPC, through the CLI's save."""
    mnt = tmp_path / "tiny"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)],
                                           capture_output=True).returncode != 0:
        pytest.skip("mounting a tmpfs needs root")
    try:
        with pytest.raises(ArtibusError, match="no space left on device"):
            runner.save(small_result(20000), mnt / "r.csv")
        assert list(mnt.iterdir()) == []
    finally:
        subprocess.run(["umount", str(mnt)])


def test_partial_path():
    assert runner.partial_path("out/r.csv") == Path("out/r.partial.csv")
    assert runner.partial_path("r.mat") == Path("r.partial.mat")


# --- a bounded step plan -----------------------------------------------------------

class _U:
    def __init__(self, ratio):
        self.ratio = ratio


def test_plan_memory_does_not_grow_with_the_period():
    """Issue 15: --step 1e-8 --stop-time 1e-6 took 886 MB (1.16 GB here) because the
    plan held one entry per base step of the plan's period (10^6 with a 0.01 s
    component). A plan of 10^7 base steps with a period of ~7*10^12 is now built
    without allocating per step, and each step's entry is the definition's."""
    units = [_U(1), _U(1_000_003), _U(7), _U(1_000_033)]
    tracemalloc.start()
    plan = runner_plan._Plan(units, 10_000_000)
    entries = [plan[k] for k in (0, 6, 7, 1_000_002, 1_000_003, 9_999_999)]
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert plan.period > 10 ** 12 and plan.table is None
    assert peak < 100_000, peak
    for k, (starting, ending, gs) in zip((0, 6, 7, 1_000_002, 1_000_003, 9_999_999), entries):
        assert starting == [u for u in units if k % u.ratio == 0]
        assert ending == [u for u in units if (k + 1) % u.ratio == 0]
        assert gs == [(u, u in starting, u in ending) for u in units if u in starting or u in ending]


def test_short_period_plan_is_tabulated_once():
    units = [_U(1), _U(2), _U(3)]
    plan = runner_plan._Plan(units, 1000)
    assert plan.period == 6 and len(plan.table) == 6
    assert plan[13] is plan[1]


@pytest.mark.skipif(not runner.core_library_path().is_file(), reason="the C core is not built")
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_untabulated_plan_bit_for_bit(tmp_path, monkeypatch, algorithm):
    """The plan given to the C core window by window (as for a period too long to
    tabulate) and computed step by step in the Python loop gives the tabulated
    plan's results bit for bit: three rates (0.05, 0.1, 0.15 s), windows of 7 base steps."""
    outs = [("kappa[0]", "output"), ("beta[1]", "output")]
    elements = (component("Lead", outs)
                + component("Follow", [("gammaF", "input")] + outs, SLOW.format(0.1))
                + component("Third", [("gammaF", "input")] + outs, SLOW.format(0.15)))
    connections = (connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="-1.5"')
                   + connection("Follow", "beta[1]", "Third", "gammaF", 'offset="0.02"'))
    path = make_ssp(tmp_path, elements, connections, stop=3.0)
    kw = dict(step=0.05, algorithm=algorithm, overrides={**STEER, "Third.testSteerAmp": 0.0})

    def results():
        out = []
        for core in (True, False):
            with runner.Simulation(path, **kw) as sim:
                out.append(sim.run(core=core).array())
        return out

    tabulated = results()
    monkeypatch.setattr(runner_plan, "PLAN_TABLE", 1)
    monkeypatch.setattr(runner_core, "CORE_PIECE", 7)
    windowed = results()
    assert np.max(np.abs(tabulated[0][:, 1:])) > 1e-3
    for a, b in zip(tabulated + windowed, [tabulated[0]] * 4):
        assert a.tobytes() == b.tobytes()


# --- the CLI: output checked first, interrupts, concurrent runs ---------------------

def artibus(*args, cwd, env=None, **kw):
    return subprocess.run([sys.executable, "-m", "artibus", *args], capture_output=True, text=True,
                          cwd=cwd, env={**os.environ, **(env or {})}, **kw)


@pytest.fixture
def long_bench(tmp_path):
    """Two BusKinematics at 0.05 s: setting up takes a fraction of a second, each
    simulated hour many seconds."""
    return make_ssp(tmp_path, LEAD_FOLLOW["elements"], LEAD_FOLLOW["connections"], stop=10.0)


@pytest.mark.parametrize("where", ["dir", "missing", "readonly"])
def test_bad_output_is_refused_before_the_run(tmp_path, long_bench, where):
    """Issue 15: -o to a directory or a read-only place ended in a traceback after
    the whole run, its results lost. Now: one line, before simulating (a run of
    10^6 s would take hours): the run reports no step (artibus.runner.markers;
    the same bench reports its steps in the tests below)."""
    o = {"dir": tmp_path, "missing": tmp_path / "no" / "r.csv", "readonly": "/proc/r.csv"}[where]
    with HeldRun(["run", long_bench, "--stop-time", "1e6", "-o", o], cwd=tmp_path, hold=False) as run:
        err = run.finish()
    assert run.proc.returncode == 1 and "Traceback" not in err
    assert err.startswith(f"artibus: error: -o {o}:") and len(err.strip().splitlines()) == 1
    assert run.seen == []                                     # not one piece of steps taken


def _held_run(tmp_path, bench, out, stop, env=None):
    """artibus run BENCH -o OUT in the background, held at each marker (held_run),
    its temporary files in a directory of the test's own."""
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    return HeldRun(["run", bench, "--stop-time", stop, "-o", out], cwd=tmp_path,
                   env={"TMPDIR": str(tmpdir), **NO_CACHE, **(env or {})}), tmpdir


def _check_partial(run, err, sig, out, t_held, h):
    """The run signalled while held after the step loop reached t_held: exit
    128 + signal, one line, OUT absent, OUT.partial.csv with every base step
    from 0 to t_held (whole rows: the run stood between two pieces) and its units."""
    assert run.proc.returncode == 128 + sig, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    partial = runner.partial_path(out)
    assert err.strip() == (f"artibus: stopped by {signal.Signals(sig).name}; partial results up to "
                           f"t = {t_held:g} s in {partial}")
    assert not out.exists() and sorted(p.name for p in out.parent.iterdir()) == [partial.name,
                                                                            runner.units_path(partial).name]
    table = np.loadtxt(partial, delimiter=",", skiprows=1)
    assert table.shape[0] == round(t_held / h) + 1 and table[0, 0] == 0.0
    assert table[-1, 0] == pytest.approx(t_held, rel=1e-12)
    np.testing.assert_allclose(np.diff(table[:, 0]), h, rtol=1e-6)   # whole rows, every base step


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_while_simulating_keeps_partial_results(tmp_path, long_bench, sig):
    """Issue 15: SIGINT while simulating kept nothing, SIGTERM left the unpacked
    bench behind. Now: OUT.partial.csv with the rows up to then, OUT absent,
    one line, exit code 128 + signal, no temporary directory left. Issue 41: the
    signal comes while the run is held at its first marker of the step loop
    (after the C core's first piece, t = 250 s of 1000 s): it cannot have ended,
    however fast or loaded the machine (a sleep of 2 s was after its end)."""
    out = tmp_path / "out" / "r.csv"
    out.parent.mkdir()
    run, tmpdir = _held_run(tmp_path, long_bench, out, 1000)
    with run:
        t_held = float(run.wait_for(lambda line: line.startswith("t="))[2:])
        assert 0 < t_held < 1000
        run.signal(sig)
        err = run.finish()
    _check_partial(run, err, sig, out, t_held, 0.05)
    assert list(tmpdir.iterdir()) == []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_while_writing_finishes_the_write(tmp_path, long_bench, sig):
    """Issue 15: a signal while the CSV was written left a truncated CSV under the
    final name; issue 28: then the finished run was discarded ("nothing written").
    Now: the write finishes, the complete results under the final name (whole
    rows, every base step) with their units, the message says so; no temporary
    file, no temporary directory. Issue 41: the signal comes while the run is
    held where the write has begun (its "saving" marker), not when a temporary
    file was seen (a fast write could be over before the test looked)."""
    out = tmp_path / "out" / "r.csv"
    out.parent.mkdir()
    run, tmpdir = _held_run(tmp_path, long_bench, out, 1000)
    with run:
        run.wait_for(lambda line: line == f"saving {out}")     # held inside the write: signal it there
        run.signal(sig)
        err = run.finish()
    assert run.proc.returncode == 128 + sig, err
    assert err.strip() == (f"artibus: stopped by {signal.Signals(sig).name}; the finished run's results "
                           f"are complete in {out}")
    assert sorted(p.name for p in out.parent.iterdir()) == [out.name, runner.units_path(out).name]
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert table.shape[0] == 20001 and table[0, 0] == 0.0 and table[-1, 0] == pytest.approx(1000)
    np.testing.assert_allclose(np.diff(table[:, 0]), 0.05, rtol=1e-6)
    assert list(tmpdir.iterdir()) == []


def test_concurrent_runs_of_a_stale_bench(tmp_path):
    """Issue 15: runs of a stale bench by name raced on one <bench>.ssp.part (5 of
    24 died). Four at once with the bench's .ssp missing (stale: each packs it):
    all succeed with identical results, no temporary pack left."""
    fmus = tmp_path / "fmus"
    fmus.mkdir()
    shutil.copy(fmu_path("BusDynamics"), fmus / "BusDynamics.fmu")     # the bench's one FMU
    env = {"ARTIBUS_FMU_DIR": str(fmus)}
    for round_ in range(1):
        (fmus / "Scania18m_OpenLoop.ssp").unlink(missing_ok=True)
        procs = [subprocess.Popen([sys.executable, "-m", "artibus", "run", "Scania18m_OpenLoop",
                                   "--stop-time", "0.5", "-o", str(tmp_path / f"r{round_}{i}.csv")],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                                  env={**os.environ, **env}) for i in range(4)]
        for p in procs:
            _, err = p.communicate(timeout=300)
            assert p.returncode == 0, err
        texts = {(tmp_path / f"r{round_}{i}.csv").read_text() for i in range(4)}
        assert len(texts) == 1 and len(next(iter(texts)).splitlines()) > 10
    assert sorted(p.name for p in fmus.iterdir() if p.suffix not in (".fmu",)) == ["Scania18m_OpenLoop.ssp"]


def test_results_too_large_for_memory_refused_before_the_run(tmp_path, long_bench):
    """A run whose result table cannot fit (10^11 base steps) is one line before
    it starts, not a MemoryError or the OOM killer later."""
    with pytest.raises(ArtibusError, match=r"3 columns of results would take 2\.4 GB, more than half"):
        runner_results.check_room(100_000_000, 3, "b.ssd", available=4_000_000_000)
    runner_results.check_room(100_000_000, 3, "b.ssd", available=8_000_000_000)
    with HeldRun(["run", long_bench, "--step", "1e-9", "--stop-time", "100", "-o", tmp_path / "r.csv"],
                 cwd=tmp_path, hold=False) as run:
        err = run.finish()
    assert run.proc.returncode == 1 and "Traceback" not in err and "--record" in err
    assert run.seen == [] and not (tmp_path / "r.csv").exists()     # refused before a step


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_ctrl_c_inside_a_python_callback_keeps_the_rows_done(long_bench, algorithm):
    """Issue 37: the one stepping loop calls back into Python (here a stimulus, a Python
    function of time) in the middle of a base step. Ctrl-C there (the stimulus raises
    KeyboardInterrupt when called at t = 1 s, base step 20 of 0.05 s) unwinds through no C
    frame: the core stops, and the KeyboardInterrupt comes out with the rows of the base
    steps done before it (0 .. 1 s, 21 whole rows), as between two pieces of steps."""
    calls = []

    def stimulus(t):
        calls.append(t)
        if t >= 1.0 - 1e-9:
            raise KeyboardInterrupt
        return 0.0
    with runner.Simulation(long_bench, step=0.05, algorithm=algorithm,
                           stimuli={"Follow.gammaF": stimulus}) as sim:
        with pytest.raises(KeyboardInterrupt) as e:
            sim.run(stop_time=1000.0)
        assert "in Python: stimuli" in sim.stepping
    table = e.value.result.array()
    assert table.shape[0] == 21 and table[-1, 0] == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(np.diff(table[:, 0]), 0.05, rtol=1e-9)
    assert np.all(np.isfinite(table))
    assert calls[-1] == pytest.approx(1.0, rel=1e-12)          # called at each step's start until then
