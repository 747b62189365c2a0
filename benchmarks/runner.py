"""Benchmark (prints, not a test) of the SSP runner.

1. Every bench: real-time factor, and the runner's own share of the wall time
   (wall time minus the time spent inside the FMUs' doStep and getReal).
   Target (issue 5): Bus36m_Circle at 10 ms at least 500 x real time (as the
   bench is: the plant's explicit Runge-Kutta at its default tolerance, 1e-6;
   once more with CVODE's BDF and once at 1e-8 for comparison). Each bench
   runs REPEAT times; the best and the median are printed. The damping bench
   once per damping function (its variants; as it stands it runs option 2).
2. Ours against fmpy.ssp.simulate_ssp on the same two-FMU bench (two
   BusKinematics, one connection, 26 recorded connectors), Jacobi, 60 s at
   10 ms, set-up included; once with both driving straight (the masters'
   own cost) and once with the leader on an S-curve (the FMUs' work, the same
   in both, dominates). Target: ours at least 5 x faster.

usage: .venv/bin/python benchmarks/runner.py
"""
import statistics
import sys
import tempfile
import time
from pathlib import Path

from fmpy.ssp.simulation import simulate_ssp

from artibus import runner, ssp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_runner import component, connection, make_ssp  # noqa: E402


REPEAT = 5   # runs per bench: this machine is shared, so the best and the median are printed


def bench(name, label=None, **overrides):
    walls, own = [], []
    for _ in range(REPEAT):
        with runner.Simulation(name, overrides=overrides) as sim:
            r = sim.run()
            span = r.time[-1] - r.time[0]
            walls.append(sim.wall)
            own.append(1 - sum(u.wall for u in sim.units) / sim.wall)
    best = min(range(REPEAT), key=walls.__getitem__)
    print(f"{label or name:32s} {span:6.1f} s simulated: best {span / walls[best]:5.0f} x real time "
          f"({walls[best]:.3f} s), median {span / statistics.median(walls):5.0f} x; base step "
          f"{sim.base_step} s; runner's own share {100 * own[best]:4.1f} %")


def benches():
    for name in ssp.bench_names():
        bench(name)
    # the plant's integrator: the benches' explicit Runge-Kutta against CVODE's
    # BDF (the FMU's default), and the tolerance: 1e-6 (default) against 1e-8
    bench("Bus36m_Circle", "Bus36m_Circle, BDF", **{"Bus.solver": 0})
    bench("Bus36m_Circle", "Bus36m_Circle, rtol 1e-8", **{"Bus.rtol": 1e-8, "Bus.atol": 1e-8})
    # the damping bench's functions (issue 11: at least 500 x real time, as the other benches)
    for f in ("none", "floor", "baseline", "option1", "option3", "revised"):
        bench("Scania18m_Damping", f"Scania18m_Damping, {f}", **ssp.variant_overrides("Scania18m_Damping", [f]))


def against_fmpy(stop=60.0, h=0.01, steer=True):
    """steer: the leader drives its built-in S-curve, so the follower's input
    changes every step and both FMUs integrate (the FMUs' work dominates);
    without it both drive straight and the FMUs do almost nothing: the time is
    the masters' own."""
    from types import SimpleNamespace
    outs = [(f"{n}[{i}]", "output") for n in ("theta", "x", "y", "omega", "vel", "kappa", "beta")
            for i in (0, 1) if (n, i) != ("beta", 0)]
    params = {"Follow.testSteerAmp": 0.0}
    if not steer:
        params["Lead.testSteerAmp"] = 0.0
    pset = SimpleNamespace(parameters=[SimpleNamespace(name=k, value=v) for k, v in params.items()])
    with tempfile.TemporaryDirectory() as d:
        path = make_ssp(Path(d), component("Lead", outs) + component("Follow", [("gammaF", "input")] + outs),
                        connection("Lead", "beta[1]", "Follow", "gammaF"), stop=stop)
        t_fmpy, t_ours, loop, fmu = [], [], [], []
        for _ in range(REPEAT):       # alternately, each with its set-up (reading, unpacking, loading)
            t0 = time.perf_counter()
            simulate_ssp(str(path), stop_time=stop, step_size=h, parameter_set=pset)
            t_fmpy.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            with runner.Simulation(path, step=h, algorithm="jacobi", overrides=params) as sim:
                sim.run(stop_time=stop)
                loop.append(sim.wall)
                fmu.append(sum(u.wall for u in sim.units))
            t_ours.append(time.perf_counter() - t0)
        best = min(range(REPEAT), key=t_ours.__getitem__)
        t_fmpy, t_ours, loop, fmu = min(t_fmpy), t_ours[best], loop[best], fmu[best]
    what = "leader on an S-curve" if steer else "both straight"
    print(f"two BusKinematics ({what}), 26 connectors, {stop:g} s at {h} s, Jacobi: "
          f"best of {REPEAT}: fmpy.ssp.simulate_ssp {t_fmpy:.3f} s, artibus {t_ours:.3f} s with set-up "
          f"({loop:.3f} s stepping, {fmu:.3f} s of it inside the FMUs): {t_fmpy / t_ours:.1f} x faster")


if __name__ == "__main__":
    benches()
    against_fmpy(steer=False)
    against_fmpy(steer=True)
