"""Benchmark (prints, not a test) of the SSP runner.

1. Every bench: real-time factor, and the runner's own share of the wall time
   (wall time minus the time spent inside the FMUs' doStep and getReal).
   Target (issue 5): Bus36m_Circle at 10 ms at least 500 x real time.
2. Ours against fmpy.ssp.simulate_ssp on the same two-FMU bench (two
   BusKinematics, one connection, 26 recorded connectors), Jacobi, 60 s at
   10 ms. Target: ours at least 5 x faster.

usage: .venv/bin/python benchmarks/runner.py
"""
import sys
import tempfile
import time
from pathlib import Path

from fmpy.ssp.simulation import simulate_ssp

from artibus import runner, ssp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_runner import component, connection, make_ssp  # noqa: E402


def benches():
    for name in ssp.bench_names():
        with runner.Simulation(name) as sim:
            r = sim.run()
            span = r.time[-1] - r.time[0]
            fmu = sum(u.wall for u in sim.units)
            print(f"{name:24s} {span:6.1f} s simulated in {sim.wall:6.3f} s: {span / sim.wall:7.0f} x real time; "
                  f"base step {sim.base_step} s; runner's own share {100 * (1 - fmu / sim.wall):4.1f} %")


def against_fmpy(stop=60.0, h=0.01):
    outs = [(f"{n}[{i}]", "output") for n in ("theta", "x", "y", "omega", "vel", "kappa", "beta")
            for i in (0, 1) if (n, i) != ("beta", 0)]
    with tempfile.TemporaryDirectory() as d:
        path = make_ssp(Path(d), component("Lead", outs) + component("Follow", [("gammaF", "input")] + outs),
                        connection("Lead", "beta[1]", "Follow", "gammaF"), stop=stop)
        t0 = time.perf_counter()
        simulate_ssp(str(path), stop_time=stop, step_size=h)
        t_fmpy = time.perf_counter() - t0
        t0 = time.perf_counter()
        with runner.Simulation(path, step=h, algorithm="jacobi") as sim:
            sim.run(stop_time=stop)
            loop, fmu = sim.wall, sum(u.wall for u in sim.units)
        t_ours = time.perf_counter() - t0
    print(f"two BusKinematics, 26 connectors, {stop:g} s at {h} s, Jacobi: fmpy.ssp.simulate_ssp {t_fmpy:.3f} s, "
          f"artibus {t_ours:.3f} s with set-up, {loop:.3f} s stepping: {t_fmpy / t_ours:.1f} x faster "
          f"({t_fmpy / loop:.1f} x on the stepping); inside the FMUs {fmu:.3f} s, so the master's own "
          f"time is {t_fmpy - fmu:.3f} s in FMPy's against {t_ours - fmu:.3f} s in ours "
          f"({(t_fmpy - fmu) / (t_ours - fmu):.1f} x)")


if __name__ == "__main__":
    benches()
    against_fmpy()
