"""The result tables' memory (artibus.tables, issue 13): a table's memory is
recycled only once nothing refers to it (a Result, its array, a column, any
view), never while the user keeps it; recycled memory gives the same results
bit for bit; the pool is bounded and safe from several threads."""
import threading

import numpy as np
import pytest

from artibus.runner import Simulation, core_library_path, tables

BENCH = "MultiAxle_StepSteer"          # 1001 rows x 8 columns, ~1 ms a run
core = pytest.mark.skipif(not core_library_path().is_file(),
                          reason=f"{core_library_path()} not built (cmake target artibus_core)")


def run(**overrides):
    with Simulation(BENCH, overrides=overrides) as sim:
        r = sim.run(core=True)
        assert sim.stepping == "C core"
    return r


def address(a):
    return a.__array_interface__["data"][0]


def overlaps(a, b):
    """Whether two tables' memory overlaps (by address ranges)."""
    x, y = address(a), address(b)
    return x < y + b.nbytes and y < x + a.nbytes


@pytest.fixture(autouse=True)
def empty_pool():
    tables.clear()
    yield
    tables.clear()


# --- through the runner ------------------------------------------------------------

@core
def test_kept_result_is_never_overwritten():
    """Results the user keeps (the Result, or only a column of it) keep their memory
    while later runs of other data go on: each later run gets other memory."""
    first = run()
    kept = first.array().copy()
    column = run(**{"Steering.delta1": 0.03})["Vehicle.beta"]      # the Result dropped, a column kept
    kept_column = column.copy()
    others = [run(**{"Steering.delta1": 0.01 * k}) for k in (4, 5)]
    for r in others:
        assert not np.shares_memory(r.array(), first.array()) and not overlaps(r.array(), first.array())
        assert not np.shares_memory(r.array(), column)
    assert first.array().tobytes() == kept.tobytes()
    assert column.tobytes() == kept_column.tobytes()
    assert not np.array_equal(column, first["Vehicle.beta"])       # (the runs' data differ)


@core
def test_recycled_memory_same_results_bit_for_bit():
    """A dropped result's memory goes to the next run (no page faults), filled with
    garbage in between: the next run's table is the first's, bit for bit."""
    r = run()
    expected, where = r.array().tobytes(), address(r.array())
    del r
    assert tables.held()[1] > 0                                     # its memory is free again
    junk, _ = tables.take(1001, 8)
    assert address(junk) == where
    junk[:] = np.nan
    del junk
    r = run()
    assert address(r.array()) == where                              # recycled
    assert r.array().tobytes() == expected


@core
def test_interrupted_run_partial_result_is_a_copy(monkeypatch):
    """A run interrupted (Ctrl-C between two pieces of the core) hands over a copy of
    its rows: the pooled table goes back to the pool, and a later run taking that
    memory leaves the partial result as it was."""
    from artibus.runner.core import _CoreStepper
    real = _CoreStepper.run

    def interrupted(stepper, *a):
        stepper.lib = _Interrupting(stepper.lib)
        return real(stepper, *a)
    monkeypatch.setattr(_CoreStepper, "run", interrupted)
    with pytest.raises(KeyboardInterrupt) as e:
        run()
    monkeypatch.setattr(_CoreStepper, "run", real)
    part = e.value.result.array()
    saved = part.tobytes()
    assert part.shape == (1, 8) and part.flags.owndata                # the first row, copied
    del e
    later = run(**{"Steering.delta1": 0.05})
    assert not np.shares_memory(later.array(), part) and part.tobytes() == saved


class _Interrupting:
    """The core library, with artibus_core_run raising KeyboardInterrupt (a Ctrl-C
    between two pieces)."""

    def __init__(self, lib):
        self._lib = lib

    def __getattr__(self, name):
        if name == "artibus_core_run":
            def interrupt(*a):
                raise KeyboardInterrupt
            return interrupt
        return getattr(self._lib, name)


# --- the pool itself -------------------------------------------------------------------

def test_take_reuses_only_free_memory():
    a, at = tables.take(100, 7)
    assert a.shape == (100, 7) and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable
    assert at == address(a)
    b, bt = tables.take(100, 7)
    assert not overlaps(a, b)                                       # a is in use
    view = a[10:20, 3]
    del a
    c, _ = tables.take(100, 7)
    assert address(c) != at                                         # a view keeps it
    del view
    d, dt = tables.take(100, 7)
    assert dt == at                                                 # free: recycled
    e, _ = tables.take(99, 7)                                       # smaller: fits a free one
    del e
    f, _ = tables.take(1000, 7)                                     # far larger: new memory
    assert address(f) not in (at, bt)
    fa = address(f)
    del f
    g, _ = tables.take(3, 7)                                        # far smaller: not the big free one
    assert address(g) != fa


def test_pool_is_bounded(monkeypatch):
    monkeypatch.setattr(tables, "POOL_BYTES", 1 << 20)
    kept = [tables.take(100 * k, 10)[0] for k in range(1, 30)]      # 8 kB .. 232 kB each, all kept
    held, free = tables.held()
    assert held <= 1 << 20 and free == 0
    del kept
    for k in range(1, 200):                                         # distinct sizes, each dropped
        tables.take(50 * k + 7, 13)
        assert tables.held()[0] <= 1 << 20
    big, _ = tables.take(1 << 18, 1)                                # 2 MiB: beyond the pool, not pooled
    assert tables.held()[0] <= 1 << 20
    many = [tables.take(10, 10)[0] for _ in range(3 * tables.POOL_COUNT)]   # many small ones kept
    assert len(tables._buffers) <= tables.POOL_COUNT
    del many
    tables.take(10, 10)
    monkeypatch.setattr(tables, "POOL_BYTES", 0)                     # switched off
    tables.clear()
    tables.take(10, 10)
    assert tables.held() == (0, 0)


def test_large_tables_huge_page_aligned():
    a, at = tables.take(7001, 65)                                   # 3.6 MB
    if hasattr(__import__("mmap"), "MADV_HUGEPAGE"):
        assert at % tables.HUGE == 0
    a[:] = 1.5
    assert a.sum() == 1.5 * a.size
    with pytest.raises(ValueError):
        a.base.resize(10)                                            # its memory cannot move


def test_threads_never_share_a_table():
    """Four threads take tables of a few sizes, fill each with their own number,
    keep some and drop others: every kept table still holds its number, and no two
    live tables overlap."""
    kept, errors = [], []
    lock = threading.Lock()
    start = threading.Barrier(4)

    def work(t):
        start.wait()
        rng = np.random.default_rng(t)
        mine = []
        for i in range(300):
            a, at = tables.take(int(rng.integers(50, 60)), 8)
            if at != address(a):
                errors.append("address")
            a[:] = t * 1000 + i
            if rng.random() < 0.1:
                mine.append((a, t * 1000 + i))
            for b, x in mine[-5:]:
                if not np.all(b == x):
                    errors.append(f"thread {t}: a kept table was overwritten")
        with lock:
            kept.extend(mine)

    threads = [threading.Thread(target=work, args=(t,)) for t in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors
    assert all(np.all(a == x) for a, x in kept)
    spans = sorted((address(a), address(a) + a.nbytes) for a, _ in kept)
    assert all(e0 <= s1 for (_, e0), (s1, _) in zip(spans, spans[1:]))
