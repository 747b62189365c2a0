"""Benchmark (prints, not a test) of artibus sweep's throughput (issue 13).

The same sweep (Bus36m_Circle, roadBefore 2 m, 3 s; a grid of Driver.vSet x
Driver.R) with a local cluster of 1 and of 2 worker processes (one thread
each) and through an external scheduler (`dask scheduler` and two `dask worker
--nthreads 1` started here as separate processes). Each configuration runs the
grid once to warm its workers up (imports, the bench's first instances) and
then a second grid of the same size, timed: cases per minute of the second.
Configurations run in turn, REPEAT rounds; the best and the median are
printed. Target (issue 13): 2 workers at least 1.8 x 1 worker.

usage: .venv/bin/python benchmarks/sweep.py [CASES]     (default 60 cases)
"""
import json
import logging
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import artibus
from artibus import ssp

BENCH = "Bus36m_Circle"
FIXED = {"Driver.roadBefore": 2.0}
STOP = 3.0
REPEAT = 3


def grid(n, shift):
    """n cases (a multiple of 6): speeds x 6 radii; shift gives new values (no case reused)."""
    speeds = [2.0 + shift + 4.0 * k / (n // 6) for k in range(n // 6)]
    return {"Driver.vSet": ",".join(f"{v:.6g}" for v in speeds), "Driver.R": "12.5,15,17.5,20,22.5,25"}


def timed(bench, client, n, out):
    artibus.sweep(bench, grid=grid(n, 0.0), fixed=FIXED, stop_time=STOP, out=out / "warm", client=client,
                  progress=None, plot=False)
    t = time.perf_counter()
    res = artibus.sweep(bench, grid=grid(n, 0.01), fixed=FIXED, stop_time=STOP, out=out / "timed", client=client,
                        progress=None, plot=False)
    wall = time.perf_counter() - t
    assert res.ran == n and res.failed == 0, (res.ran, res.failed)
    return 60 * n / wall


def local(n_workers):
    from dask.distributed import Client, LocalCluster
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.CRITICAL)
    return Client(cluster), [cluster]


def external(tmp):
    from dask.distributed import Client
    f = Path(tmp) / "scheduler.json"
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


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 60
    n -= n % 6
    rates = {"1 worker (local)": [], "2 workers (local)": [], "2 workers (external scheduler)": []}
    with tempfile.TemporaryDirectory(prefix="artibus-bench-sweep-") as tmp:
        bench = str(Path(tmp) / f"{BENCH}.ssp")
        Path(bench).write_bytes(ssp.ssp_path(BENCH).read_bytes())
        for r in range(REPEAT):
            for name in rates:
                client, owned = (local(1) if name.startswith("1") else
                                 local(2) if "local" in name else external(tmp))
                try:
                    out = Path(tmp) / f"{r}-{name.split()[0]}-{'ext' if 'external' in name else 'loc'}"
                    rates[name].append(timed(bench, client, n, out))
                finally:
                    close(client, owned)
                print(f"round {r + 1}: {name}: {rates[name][-1]:.0f} cases/min", flush=True)
    print(f"\nartibus sweep {BENCH} ({n} cases of {STOP:g} s, roadBefore 2 m; {os.cpu_count()} cores), "
          f"cases per minute after a warm-up grid, best / median of {REPEAT}:")
    for name, v in rates.items():
        print(f"  {name:32s} {max(v):7.0f} / {statistics.median(v):7.0f}")
    one = rates["1 worker (local)"]
    two = rates["2 workers (local)"]
    print(f"  2 workers / 1 worker: {max(two) / max(one):.2f} (best), "
          f"{statistics.median(two) / statistics.median(one):.2f} (median); target >= 1.8")


if __name__ == "__main__":
    main()
