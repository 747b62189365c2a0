"""artibus sweep (issue 13): cases of a bench as Dask tasks, one Parquet row a
case, resumable by key, failures recorded, bad input refused before any case.

The bench is Bus36m_Circle cut short (roadBefore 2 m, 3 s): the bus is on the
circle after a second. What the sweep computes is checked against plain runs
of the bench made here (runner.run and the bench's KPIs), and against the
behaviour the physics implies (the hinge angle grows with the speed and as the
radius shrinks)."""
import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import artibus
from artibus import ArtibusError, runner
from artibus.bench import script, ssp
from artibus.study import sweep as sw
from artibus.study.sweep import cluster as sw_cluster, worker as sw_worker

sys.path.insert(0, str(Path(__file__).parent))
from held_run import BOUND, HeldRun  # noqa: E402

BENCH = "Bus36m_Circle"
FIXED = {"Driver.roadBefore": 2.0}
STOP = 3.0
KPI = "max |articulation angle| hinge 1 [deg]"
GRID = {"Driver.vSet": "2:6.5:0.5", "Driver.R": "12.5:25:2.5"}       # 10 x 6 = 60 cases
SMALL = {"Driver.vSet": "3,5", "Driver.R": "15,20,25"}


@pytest.fixture(scope="module", autouse=True)
def frozen_bench(tmp_path_factory):
    """The bench packed once into a copy of its own: others rebuilding FMUs or editing
    the .ssd while these tests run would change its content (and rightly rerun every case)."""
    global SSP
    d = tmp_path_factory.mktemp("bench")
    SSP = str(d / f"{BENCH}.ssp")
    Path(SSP).write_bytes(ssp.ssp_path(BENCH).read_bytes())
    yield SSP


@pytest.fixture(scope="module")
def client():
    from dask.distributed import Client, LocalCluster
    import logging
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},   # as artibus.sweep's
                           silence_logs=logging.CRITICAL)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def _run(out, client, **kw):
    args = dict(grid=SMALL, fixed=FIXED, stop_time=STOP, out=out, client=client, progress=None, kpi=KPI)
    args.update(kw)
    return artibus.sweep(SSP, **args)


def same_table(a, b, drop=()):
    """Equal column by column (NaN equal to NaN), in the same order."""
    names = [n for n in a.column_names if n not in drop]
    if names != [n for n in b.column_names if n not in drop]:
        return False
    for n in names:
        x, y = a[n].to_pylist(), b[n].to_pylist()
        if len(x) != len(y):
            return False
        for u, v in zip(x, y):
            if not (u == v or (isinstance(u, float) and isinstance(v, float) and np.isnan(u) and np.isnan(v))):
                return False
    return True


def _plain_kpis(overrides):
    r = runner.run(SSP, overrides={**FIXED, **overrides}, stop_time=STOP)
    return {f"{k.name} [{k.unit}]": k.value for k in script.kpis(BENCH, r)}


def test_grid_of_60_cases_table_plot_and_worst_cases(tmp_path, client):
    res = _run(tmp_path / "s", client, grid=GRID)
    t = res.table
    assert t.num_rows == 60 and res.ran == 60 and res.failed == 0
    rows = t.to_pylist()
    assert [r["case"] for r in rows] == list(range(60))
    assert all(r["status"] == "ok" and r["error"] == "" and r["wall_s"] > 0 for r in rows)
    speeds = sorted({r["Driver.vSet"] for r in rows})
    radii = sorted({r["Driver.R"] for r in rows})
    assert speeds == pytest.approx([2 + 0.5 * k for k in range(10)]) and radii == pytest.approx([12.5, 15, 17.5, 20, 22.5, 25])
    z = {(r["Driver.vSet"], r["Driver.R"]): r[KPI] for r in rows}
    # the physics: faster (further round the circle in 3 s) and tighter -> more articulation
    for R in radii:
        assert all(z[(a, R)] < z[(b, R)] for a, b in zip(speeds, speeds[1:]))
    for v in speeds[4:]:
        assert all(z[(v, a)] > z[(v, b)] for a, b in zip(radii, radii[1:]))
    # a case's row holds the KPIs of a plain run of the bench with its values, exactly
    r0 = rows[37]
    plain = _plain_kpis({"Driver.vSet": r0["Driver.vSet"], "Driver.R": r0["Driver.R"]})
    for name, v in plain.items():
        assert r0[name] == v or (np.isnan(v) and np.isnan(r0[name])), name
    # the table on disk, the study plot, the worst cases with their commands
    assert same_table(pq.read_table(tmp_path / "s" / "results.parquet"), t)
    assert (tmp_path / "s" / "study.png").read_bytes()[:4] == b"\x89PNG"
    worst = (tmp_path / "s" / "worst.txt").read_text().splitlines()
    cmds = [ln for ln in worst if f"artibus run {SSP}" in ln]
    assert len(cmds) == 10
    top = max(rows, key=lambda r: r[KPI])
    assert f"{top[KPI]:.6g}" in cmds[0] and f"Driver.vSet={top['Driver.vSet']!r}" in cmds[0]
    assert "Driver.roadBefore=2.0" in cmds[0] and "--stop-time 3" in cmds[0]


@pytest.mark.parametrize("variant", [None, "guidedForceMin"])
def test_reused_instances_give_a_fresh_instances_results(variant, tmp_path):
    """A worker's FMU instances (the plant, the driver, and the controllers with
    their path memories; unsteered and steering), reset and initialised again, give
    what new ones give, bit for bit."""
    p = SSP
    steer = ssp.variant_overrides(SSP, [variant] if variant else [])
    a = {**FIXED, **steer, "Driver.vSet": 6.0, "Driver.R": 12.5}
    b = {**FIXED, **steer, "Driver.vSet": 3.0, "Driver.R": 20.0}
    sw.release()
    sw_worker._simulate(p, a, STOP, None)
    assert [k[1:] for k in sw_worker._SIMS] == [(p, None)]            # kept for the next case
    again = sw_worker._simulate(p, b, STOP, None)
    with pytest.raises(ArtibusError, match="Driver.vSet"):
        sw_worker._simulate(p, {**FIXED, "Driver.vSet": 500.0}, STOP, None)   # out of range: refused
    after_error = sw_worker._simulate(p, b, STOP, None)
    fresh = runner.run(p, overrides=b, stop_time=STOP)
    assert again.names == fresh.names
    assert np.array_equal(again.array(), fresh.array())
    assert np.array_equal(after_error.array(), fresh.array())
    assert sw.release() == 1


def test_a_kept_instance_serves_the_next_sweep_only_with_the_same_bench_content(tmp_path):
    """A worker keeps its instances after a sweep (for the next one on the same
    cluster); a case of an .ssp whose content changed at the same path (here
    its variants) gets new instances, and what a plain run gives."""
    p = tmp_path / f"{BENCH}.ssp"
    p.write_bytes(Path(SSP).read_bytes())
    case = {"Driver.vSet": 5.0, "Driver.R": 15.0}

    def run(data):
        import hashlib
        row, _ = sw.run_case(BENCH, hashlib.sha256(data).hexdigest(), str(p), data, case, FIXED, STOP, None, False)
        assert row["status"] == "ok", row["error"]
        (sim, _), = sw_worker._SIMS.values()
        return row[KPI], sim

    sw.release()
    try:
        k1, sim1 = run(p.read_bytes())
        k2, sim2 = run(p.read_bytes())                  # the next sweep of the same bench
        assert sim2 is sim1 and k2 == k1
        _bench_with_variants(p, 5.0)                    # other content at the same path
        k3, sim3 = run(p.read_bytes())
        assert sim3 is not sim1 and k3 == k1 == _plain_kpis(case)[KPI]
    finally:
        assert sw.release() == 1


def test_a_failing_case_is_recorded_and_the_rest_complete(tmp_path, client):
    kw = dict(grid={"Driver.vSet": "3,500,5", "Driver.R": "15,20"}, keep_series=True)
    res = _run(tmp_path / "s", client, **kw)
    rows = res.table.to_pylist()
    assert len(rows) == 6 and res.failed == 2
    for r in rows:
        series = tmp_path / "s" / "series" / f"{r['key']}.parquet"
        if r["Driver.vSet"] == 500:
            assert r["status"] == "failed" and "Driver.vSet" in r["error"] and "500" in r["error"]
            assert r[KPI] is None or np.isnan(r[KPI])
            assert not series.exists()
        else:
            assert r["status"] == "ok" and r[KPI] > 0
            s = pq.read_table(series)       # the case's time series: its KPI again from them
            assert s["time"].to_pylist()[-1] == pytest.approx(STOP)
            assert np.degrees(np.max(np.abs(s["Bus.artAngle[1]"].to_numpy()))) == pytest.approx(r[KPI], rel=1e-12)
    assert _run(tmp_path / "s", client, **kw).ran == 0             # failures recorded are not run again
    retry = _run(tmp_path / "s", client, retry_failed=True, **kw)   # unless asked
    assert retry.ran == 2 and retry.failed == 2 and retry.skipped == 4
    text = (tmp_path / "s" / "worst.txt").read_text()
    assert "Failed cases (2)" in text and "--set Driver.vSet=500.0" in text


def _case_files(out):
    return {f.name: f.stat().st_mtime_ns for f in (Path(out) / "cases").glob("*.parquet")}


def test_an_interrupted_sweep_resumes_without_running_a_finished_case_again(tmp_path, client, external):
    """artibus sweep --scheduler (the command line on the external cluster) killed after some cases, run again.
    Killed while held at its third "case" marker (artibus.runner.markers: the case file written), so
    exactly three cases are on disk, however fast the machine (issue 41: not after polling the folder)."""
    out = tmp_path / "s"
    grid = {"Driver.vSet": "2:6.5:0.5", "Driver.R": "15,20"}       # 20 cases
    args = ["sweep", SSP, "--grid"] + [f"{k}={v}" for k, v in grid.items()] + \
           ["--set", "Driver.roadBefore=2", "--stop-time", "3", "--scheduler", external, "-o", out]
    with HeldRun(args, cwd=tmp_path, new_session=True) as run:
        for _ in range(2):
            run.wait_for(lambda line: line.startswith("case "))
            run.release()
        run.wait_for(lambda line: line.startswith("case "))
        run.kill_group(signal.SIGKILL)
        run.proc.wait()
    before = _case_files(out)
    assert sorted(before) == sorted(f"{line[5:]}.parquet" for line in run.seen if line.startswith("case "))
    assert len(before) == 3
    assert not (out / "results.parquet").exists()
    res = _run(out, client, grid=grid, fixed={"Driver.roadBefore": 2})
    assert res.table.num_rows == 20 and res.failed == 0
    assert res.ran == 20 - len(before) and res.skipped == len(before)
    after = _case_files(out)
    assert all(after[f] == m for f, m in before.items())      # no finished case ran again
    assert len(after) == 20
    again = _run(out, client, grid=grid, fixed={"Driver.roadBefore": 2})
    assert again.ran == 0 and again.skipped == 20 and same_table(again.table, res.table)


def _bench_with_variants(path, vset_b):
    """Bus36m_Circle's .ssp with two variants (their speeds), named after its folder (its KPIs)."""
    variant = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet version="1.0" name="{n}" '
               'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"><ssv:Parameters>'
               '<ssv:Parameter name="Driver.vSet"><ssv:Real value="{v}"/></ssv:Parameter>'
               '</ssv:Parameters></ssv:ParameterSet>')
    src = SSP
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(src) as zi, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zo:
        for n in zi.namelist():
            if not n.startswith("variants/"):
                zo.writestr(n, zi.read(n))
        zo.writestr("variants/slow.ssv", variant.format(n="slow", v=3.0))
        zo.writestr("variants/fast.ssv", variant.format(n="fast", v=vset_b))
    return path


def test_a_changed_ssv_reruns_exactly_the_cases_it_touches(tmp_path, client):
    bench = _bench_with_variants(tmp_path / "b" / f"{BENCH}.ssp", 5.0)
    out = tmp_path / "s"
    kw = dict(grid={"Driver.R": "15,20"}, variants=["slow", "fast"], fixed=FIXED, stop_time=STOP, out=out,
              client=client, progress=None)
    first = artibus.sweep(str(bench), **kw)
    assert first.ran == 4 and first.failed == 0
    assert artibus.sweep(str(bench), **kw).ran == 0
    files = _case_files(out)
    _bench_with_variants(bench, 5.5)                     # the fast variant's .ssv changes
    second = artibus.sweep(str(bench), **kw)
    assert second.ran == 2 and second.skipped == 2
    rows1 = {(r["variant"], r["Driver.R"]): r for r in first.table.to_pylist()}
    rows2 = {(r["variant"], r["Driver.R"]): r for r in second.table.to_pylist()}
    for (v, R), r in rows2.items():
        if v == "slow":
            assert r["key"] == rows1[(v, R)]["key"] and files[f"{r['key']}.parquet"] == _case_files(out)[f"{r['key']}.parquet"]
        else:
            assert r["key"] != rows1[(v, R)]["key"] and r[KPI] > rows1[(v, R)][KPI]   # faster: more articulation
    assert rows2[("fast", 15.0)][KPI] == _plain_kpis({"Driver.vSet": 5.5, "Driver.R": 15.0})[KPI]


def _scheduler_address(sched_file, proc):
    """The address in the scheduler file the dask scheduler writes when it listens: polled
    until it is complete JSON (it is not written atomically); BOUND only bounds a failure."""
    deadline = time.monotonic() + BOUND
    while True:
        try:
            return json.loads(sched_file.read_text())["address"]
        except (OSError, ValueError, KeyError):
            assert proc.poll() is None and time.monotonic() < deadline, "the dask scheduler did not start"
            time.sleep(0.1)


@pytest.fixture(scope="module")
def external(tmp_path_factory):
    """A `dask scheduler` and two `dask worker --nthreads 1` processes on this machine; its address."""
    sched_file = tmp_path_factory.mktemp("dask") / "scheduler.json"
    dask = str(Path(sys.executable).with_name("dask"))
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(sched_file)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)]
    try:
        address = _scheduler_address(sched_file, procs[0])
        for _ in range(2):
            procs.append(subprocess.Popen([dask, "worker", "--scheduler-file", str(sched_file), "--nthreads", "1",
                                           "--nworkers", "1", "--no-dashboard"], stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, start_new_session=True))
        from dask.distributed import Client
        with Client(address, timeout=f"{BOUND:g}s") as c:
            c.wait_for_workers(2, timeout=BOUND)
            assert len(c.scheduler_info()["workers"]) == 2
        yield address
    finally:
        for p in reversed(procs):
            os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def test_an_external_scheduler_with_two_workers_gives_the_same_table(tmp_path, client, external):
    local = _run(tmp_path / "local", client)
    remote = _run(tmp_path / "remote", None, scheduler=external)
    assert local.ran == remote.ran == 6
    assert same_table(remote.table, local.table, drop=["wall_s"])


def _csv(tmp_path, text):
    f = tmp_path / "design.csv"
    f.write_text(text)
    return f


def _yaml(tmp_path, text):
    f = tmp_path / "design.yaml"
    f.write_text(text)
    return f


@pytest.mark.parametrize("kw, words", [
    (dict(grid={"Drivr.vSet": "1,2"}), ["Drivr.vSet", "no component 'Drivr'"]),
    (dict(grid={"Driver.vSpeed": "1,2"}), ["Driver.vSpeed", "no parameter or input"]),
    (dict(grid={"Driver.vSet": "1,fast"}), ["Driver.vSet", "'fast'", "not a Real"]),
    (dict(grid={"Driver.road": "1,2.5"}), ["Driver.road", "2.5", "not an Enumeration value"]),
    (dict(grid={"Driver.vSet": "1:2"}), ["1:2", "malformed range"]),
    (dict(grid={"Driver.vSet": "5:1:1"}), ["5:1:1", "malformed range"]),
    (dict(grid={"Driver.vSet": "1:5:0"}), ["1:5:0", "malformed range"]),
    (dict(grid={"Driver.vSet": "a:b:1"}), ["a:b:1", "malformed range"]),
    (dict(grid={"Driver.vSet": "1,,2"}), ["1,,2", "empty value"]),
    (dict(grid={"Driver.R": "15"}, variants=["slalom"]), ["variant 'slalom'", "no such variant"]),
    (dict(design="CSV:Driver.vSet,Bus.muu[3]\n3,1\n"), ["design.csv", "Bus.muu[3]"]),
    (dict(design="CSV:Driver.vSet\nthree\n"), ["design.csv", "Driver.vSet", "'three'"]),
    (dict(design="YAML:method: lhs\nn: 4\nseed: 1\nparameters:\n  Driver.vSet: {distribution: gamma}\n"),
     ["design.yaml", "Driver.vSet", "unknown distribution 'gamma'"]),
    (dict(design="YAML:method: montecarlo\nparameters:\n  Driver.vSet: {low: 1, high: 2}\n"),
     ["design.yaml", "needs n", "seed"]),
    (dict(scheduler="tcp://127.0.0.1:9"), ["--scheduler tcp://127.0.0.1:9", "cannot reach"]),
])
def test_bad_input_is_an_error_naming_it_before_any_case(tmp_path, kw, words):
    if isinstance(kw.get("design"), str) and kw["design"][:4] in ("CSV:", "YAML"):
        kind, _, text = kw["design"].partition(":")
        kw = dict(kw, design=_csv(tmp_path, text) if kind == "CSV" else _yaml(tmp_path, text))
    args = dict(grid=SMALL, fixed=FIXED, stop_time=STOP, out=tmp_path / "s", progress=None)
    if "design" in kw:
        args.pop("grid")
    args.update(kw)
    with pytest.raises(ArtibusError) as e:
        artibus.sweep(SSP, **args)
    for w in words:
        assert w in str(e.value), (w, str(e.value))
    assert not list((tmp_path / "s" / "cases").glob("*")) if (tmp_path / "s").exists() else True


def test_the_command_line_prints_the_error_and_runs_nothing(tmp_path):
    p = subprocess.run([sys.executable, "-m", "artibus", "sweep", BENCH, "--grid", "Driver.vSet=1:3",
                        "-o", str(tmp_path / "s")], capture_output=True, text=True)
    assert p.returncode == 1
    assert "artibus: error: --grid Driver.vSet=1:3: malformed range '1:3'" in p.stderr
    assert not (tmp_path / "s").exists()


def test_latin_hypercube_and_monte_carlo_designs(tmp_path, client):
    f = _yaml(tmp_path, "method: lhs\nn: 8\nseed: 7\nparameters:\n"
                        "  Driver.vSet: {distribution: uniform, low: 2, high: 6}\n"
                        "  Driver.R: {distribution: uniform, low: 14, high: 22}\n")
    d = sw.read_design(f)
    v = np.array([[c["Driver.vSet"], c["Driver.R"]] for c in d.cases])
    # Latin hypercube: each of the 8 equal strata of each parameter holds exactly one case
    for j, (lo, hi) in enumerate(((2, 6), (14, 22))):
        assert sorted(np.floor((v[:, j] - lo) / (hi - lo) * 8).astype(int)) == list(range(8))
    assert sw.read_design(f).cases == d.cases                          # the seed fixes it
    mc = _yaml(tmp_path, "method: montecarlo\nn: 8\nseed: 3\nparameters:\n"
                         "  Driver.vSet: {distribution: normal, mean: 4, std: 0.5}\n")
    res = artibus.sweep(SSP, design=mc, fixed=FIXED, stop_time=STOP, out=tmp_path / "mc", client=client,
                        progress=None, kpi="hinge 1")
    speeds = [r["Driver.vSet"] for r in res.table.to_pylist()]
    assert speeds == [c["Driver.vSet"] for c in sw.read_design(mc).cases] and len(set(speeds)) == 8
    assert (tmp_path / "mc" / "study.png").read_bytes()[:4] == b"\x89PNG"


def test_cases_are_handed_out_once_in_tasks_sized_by_their_time():
    """_Chunks: every case once, in order; single cases until 1 per worker has
    come back; then tasks of a 1 / (2 workers) share of what is left, at least
    MIN_S and at most MAX_S seconds of work (by the cases' CPU time so far)."""
    class Client:
        def nthreads(self):
            return {"a": 1, "b": 1}
    chunks = sw_cluster._Chunks(range(1000), Client())
    assert chunks.in_flight() == 2 * sw_cluster._Chunks.IN_FLIGHT           # two workers
    tasks = [chunks.next() for _ in range(4)]
    assert tasks == [[0], [1], [2], [3]]
    chunks.took(0.01)
    tasks.append(chunks.next())
    assert tasks[-1] == [4]                   # one result for two workers: still one case a task
    for _ in range(3):
        chunks.took(0.01)                     # 10 ms a case: MAX_S 2 s -> 200 cases, MIN_S 0.1 s -> 10
    while chunks.pending:
        tasks.append(chunks.next())
    flat = [i for t in tasks for i in t]
    assert flat == list(range(1000))
    sizes = [len(t) for t in tasks[5:]]
    assert sizes[0] == 200                    # 995 left: a quarter is 249, MAX_S caps it
    assert all(10 <= n <= 200 for n in sizes[:-1]) and sizes[-1] <= 10
    assert sizes == sorted(sizes, reverse=True)     # shorter towards the end
    long = sw_cluster._Chunks(range(10), Client())
    for _ in range(4):
        long.took(3.0)                        # a case longer than MAX_S: one a task
    assert [len(long.next()) for _ in range(10)] == [1] * 10


def test_a_case_that_kills_its_worker_fails_alone(tmp_path):
    """Another's FMU may crash the process it runs in. The case that kills its
    worker (here Driver.vSet = 4, R = 20: os._exit in the worker, a WorkerPlugin)
    is recorded failed; the cases that shared its task (or waited on the worker
    it killed) run again one a task and complete: every other case is ok."""
    import logging

    import dask
    from dask.distributed import Client, LocalCluster, WorkerPlugin

    class Killer(WorkerPlugin):
        def setup(self, worker):
            from artibus.study.sweep import worker as s
            run_case = s.run_case

            def killing(*a, **k):
                if a[4].get("Driver.vSet") == 4.0 and a[4].get("Driver.R") == 20.0:
                    os._exit(3)
                return run_case(*a, **k)
            s.run_case = killing

    # Dask gives up on a task at the first worker death (allowed-failures 0: the sweep's own
    # retries are what is tested) and hands a worker one task at a time (worker-saturation 1:
    # no case waits on the worker the killer takes down with it, so only the killer fails)
    with dask.config.set({"distributed.scheduler.allowed-failures": 0,
                          "distributed.scheduler.worker-saturation": 1.0}):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                               silence_logs=logging.CRITICAL)
        c = Client(cluster)
        try:
            c.register_plugin(Killer())
            res = _run(tmp_path / "s", c, grid={"Driver.vSet": "2:5.5:0.5", "Driver.R": "15,20,25"})
        finally:
            c.close()
            cluster.close()
    rows = res.table.to_pylist()
    assert len(rows) == 24
    dead = sorted(r["Driver.R"] for r in rows if r["status"] != "ok")
    assert dead == [20.0]
    assert all(r["Driver.vSet"] == 4.0 and "worker" in r["error"] for r in rows if r["status"] != "ok")
    assert all(r[KPI] > 0 for r in rows if r["status"] == "ok")


def test_own_cluster_leaves_dask_port_8787_alone():
    """The sweep's own local cluster opens no dashboard and does not take Dask's
    8787: with 8787 taken (a user's own dashboard), no warning about it."""
    import socket
    import warnings
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", 8787))
        s.listen()
    except OSError:
        pass                                    # taken already: the same situation
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            c, cluster = sw_cluster._client(None, 1)
            try:
                port = c.scheduler_info()["services"].get("dashboard")
                assert port != 8787
            finally:
                c.close()
                cluster.close()
    finally:
        s.close()
