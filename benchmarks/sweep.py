"""Benchmark (prints, not a test) of artibus sweep's throughput (issue 13).

Sweeps of Bus36m_Circle (a grid of Driver.vSet x Driver.R) with cases of two
lengths:
  long:  the whole manoeuvre (the bench's 70 s: the straight, the circle), a
         chassis engineer's case; most of its time goes into the bench's KPIs;
  short: roadBefore 2 m, 3 s (the bus just on the circle): the per-case and
         per-task overheads show here.
Each runs with a local cluster of 1 and of 2 worker processes (artibus sweep's
own, one thread each) and through an external scheduler (`dask scheduler` and
two `dask worker --nthreads 1` started here as separate processes, Dask's
default settings). Each configuration first runs a small warm-up grid (imports,
the bench's first instances on every worker), then the timed grid (new values:
no case reused): cases per minute, and the CPU time per case of the client
process (with a local cluster's scheduler and nannies), of an external
scheduler and of the workers (psutil, the processes' user + system time): those
do not depend on what else runs on the machine, the wall-clock figures do (the
load average is printed with them). From the CPU times, the ratio 2 workers / 1
worker that 2 idle cores would give (the 1-worker sweep's wall per case is its
worker's CPU per case, the client on the other core; 2 workers share the 2
cores with the client):  bound = max(w1, (w1 + c1) / 2) / ((w2 + c2) / 2),
w: the workers' CPU per case, c: the client's (and an external scheduler's),
1, 2: of the sweep with 1 and with 2 workers. Target (issue 13): 2 workers at least
1.8 x 1 worker.

usage: .venv/bin/python benchmarks/sweep.py [short|long|both] [REPEAT]   (default both, 2)
"""
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import artibus
from artibus.bench import ssp

BENCH = "Bus36m_Circle"
LENGTHS = {
    # name: (stop time (None: the bench's), fixed parameters, speeds, radii, warm-up cases).
    # Grids of a few hundred short and a few dozen long cases: a sweep's fixed costs
    # (its start, the first single-case tasks, the last tasks' tail, results.parquet)
    # spread as in a study, not over a second of work (60 short cases: the client's
    # CPU a case 2.2-3.2 ms, 240: 1.3-1.5 ms, on this machine)
    "long": (None, {}, [2.6, 2.8, 3.0, 3.2], [12.5, 15.0, 17.5, 20.0, 22.5, 25.0], 4),
    "short": (3.0, {"Driver.roadBefore": 2.0}, [2.0 + 0.1 * k for k in range(40)],
              [12.5, 15.0, 17.5, 20.0, 22.5, 25.0], 4),
}
CONFIGS = ("1 worker (local)", "2 workers (local)", "2 workers (external scheduler)")


@dataclass
class Figures:
    rate: float            # cases per minute (wall clock)
    client: float          # s CPU per case: this process (a local cluster's scheduler and nannies too)
    scheduler: float       # s CPU per case: an external scheduler's process (0 for a local cluster)
    workers: float         # s CPU per case: the worker processes together
    load: float            # the 1-minute load average at the end
    cases: int
    span: float            # s simulated per case


def _grid(length, shift=0.0, n=None):
    _, _, speeds, radii, warm = LENGTHS[length]
    if n is not None:              # the warm-up: the first n of other speeds
        speeds = speeds[:max(1, n // len(radii))]
    return {"Driver.vSet": ",".join(f"{v + shift:.6g}" for v in speeds),
            "Driver.R": ",".join(f"{r:g}" for r in radii)}


def _cpu(procs):
    import psutil
    total = 0.0
    for p in procs:
        try:
            t = p.cpu_times()
            total += t.user + t.system
        except psutil.Error:
            pass
    return total


def timed(bench, client, length, out, owned=()):
    """Figures of a timed grid after a warm-up grid on the client's cluster."""
    import psutil
    stop, fixed, speeds, radii, warm = LENGTHS[length]
    artibus.sweep(bench, grid=_grid(length, 0.05, warm), fixed=fixed, stop_time=stop, out=out / "warm",
                  client=client, progress=None, plot=False)
    me = psutil.Process()
    external = [psutil.Process(p.pid) for p in owned if isinstance(p, subprocess.Popen)]
    sched = external[:1]
    workers = [c for p in external[1:] for c in [p] + p.children(recursive=True)] if external else \
        me.children(recursive=True)
    c0, s0, w0 = _cpu([me]), _cpu(sched), _cpu(workers)
    t = time.perf_counter()
    res = artibus.sweep(bench, grid=_grid(length), fixed=fixed, stop_time=stop, out=out / "timed", client=client,
                        progress=None, plot=False)
    wall = time.perf_counter() - t
    n = len(speeds) * len(radii)
    assert res.ran == n and res.failed == 0, (res.ran, res.failed)
    span = stop if stop is not None else ssp.read(bench).stop_time
    return Figures(60 * n / wall, (_cpu([me]) - c0) / n, (_cpu(sched) - s0) / n, (_cpu(workers) - w0) / n,
                   os.getloadavg()[0], n, span)


def local(n_workers):
    """A local cluster as artibus sweep makes it (sweep._client)."""
    from artibus.study.sweep import cluster as sw_cluster
    client, cluster = sw_cluster._client(None, n_workers)
    return client, [cluster]


def external(tmp):
    from dask.distributed import Client
    f = Path(tmp) / "scheduler.json"
    f.unlink(missing_ok=True)
    dask = str(Path(sys.executable).with_name("dask"))
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(f)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)]
    while not f.is_file():
        time.sleep(0.1)
    for _ in range(2):
        procs.append(subprocess.Popen([dask, "worker", "--scheduler-file", str(f), "--nthreads", "1", "--nworkers",
                                       "1", "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
    c = Client(json.loads(f.read_text())["address"], timeout="30s")
    c.wait_for_workers(2, timeout=120)
    return c, procs


def close(client, owned):
    client.close()
    for o in reversed(owned):
        if isinstance(o, subprocess.Popen):
            os.killpg(o.pid, signal.SIGTERM)
            o.wait()
        else:
            o.close()


def run(tmp, lengths=("long", "short"), repeat=2, configs=CONFIGS):
    """{length: {config: [Figures of each round]}}; configurations in turn, `repeat` rounds."""
    bench = str(Path(tmp) / f"{BENCH}.ssp")
    Path(bench).write_bytes(ssp.ssp_path(BENCH).read_bytes())
    out = {length: {c: [] for c in configs} for length in lengths}
    for r in range(repeat):
        for length in lengths:
            for name in configs:
                client, owned = (local(1) if name.startswith("1") else
                                 local(2) if "local" in name else external(tmp))
                try:
                    d = Path(tmp) / f"{length}-{r}-{name.split()[0]}-{'ext' if 'external' in name else 'loc'}"
                    out[length][name].append(timed(bench, client, length, d, owned))
                finally:
                    close(client, owned)
    return out


def bound(one, two):
    """The ratio 2 workers / 1 worker 2 idle cores give, from the CPU per case (see the docstring)."""
    t1 = max(one.workers, (one.workers + one.client + one.scheduler) / 2)     # s a case, 1 worker
    t2 = (two.workers + two.client + two.scheduler) / 2                       # 2 workers on 2 cores
    return t1 / t2


def report(results, line=print):
    """Lines per length: each configuration's best round (cases/min) with its CPU per case; the ratios.
    Returns {length: (wall ratio of the best rounds, CPU bound)}."""
    ratios = {}
    for length, by_config in results.items():
        stop, *_ = LENGTHS[length]
        any_fig = next(iter(by_config.values()))[0]
        line(f"   {length}: {any_fig.cases} cases of {any_fig.span:g} s simulated"
             + (" (roadBefore 2 m)" if length == "short" else " (the whole manoeuvre)"))
        line(f"     {'':32s} {'cases/min':>9s} {'median':>7s} {'load':>5s}   CPU ms a case: {'workers':>8s} "
             f"{'client':>7s} {'ext. sched.':>11s}")
        best = {}
        for name, figs in by_config.items():
            b = max(figs, key=lambda f: f.rate)
            best[name] = b
            line(f"     {name:32s} {b.rate:9.0f} {statistics.median(f.rate for f in figs):7.0f} {b.load:5.1f}   "
                 f"{'':14s} {1e3 * b.workers:8.1f} {1e3 * b.client:7.1f} {1e3 * b.scheduler:11.1f}")
        one, two = best["1 worker (local)"], best["2 workers (local)"]
        wall = two.rate / one.rate
        cpu = bound(one, two)
        line(f"     2 workers / 1 worker: {wall:.2f} (wall clock, best rounds), {cpu:.2f} (from the CPU per case, "
             f"what 2 idle cores give)")
        ratios[length] = (wall, cpu)
    return ratios


def main():
    which = sys.argv[1] if len(sys.argv) > 1 else "both"
    repeat = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    lengths = ("long", "short") if which == "both" else (which,)
    with tempfile.TemporaryDirectory(prefix="artibus-bench-sweep-") as tmp:
        results = run(tmp, lengths, repeat)
    print(f"artibus sweep {BENCH}, {os.cpu_count()} cores, best of {repeat} rounds:")
    report(results)


if __name__ == "__main__":
    main()
