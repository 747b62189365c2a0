"""Benchmark (prints, not a test) of the SSP runner.

1. Every bench: real-time factor, and the runner's own share of the wall time
   (wall time minus the time spent inside the FMUs' doStep and getReal), in the
   one stepping loop, the C core (issues 13, 37: the runner's own share at most
   10 %); a bench with a network (CAN, FMI-LS-BUS) also with its network ticked
   in Python (run(core=False), the network's reference implementation, which the
   core calls back for), the two runs alternately.
   The wall time includes the initialisation (FMUs in initialization mode,
   connected inputs to a fixed point: in C with the core, timed there): "own"
   counts the time inside the FMUs' calls there (getReal, setReal, exitInitialization-
   Mode: a driver builds its road) as the FMUs', "loop" is the share of the
   stepping alone, "init" the initialisation's time.
   Target (issue 5): Bus36m_Circle at 10 ms at least 500 x real time (as the
   bench is: the plant's explicit Runge-Kutta at its default tolerance, 1e-6;
   once more with CVODE's BDF and once at 1e-8 for comparison). Each bench
   runs REPEAT times; the best and the median are printed. The damping bench
   once per damping function (its variants; as it stands it runs option 2).
2. Ours against fmpy.ssp.simulate_ssp on the same two-FMU bench (two
   BusKinematics, one connection, 26 recorded connectors), Jacobi, 60 s at
   10 ms, set-up included; once with both driving straight (the masters'
   own cost) and once with the leader on an S-curve (the FMUs' work, the same
   in both, dominates). Target: ours at least 5 x faster (no network: one run of
   ours, in the C core).

usage: .venv/bin/python benchmarks/runner.py
"""
import statistics
import tempfile
import time
from pathlib import Path

from fmpy.ssp.simulation import simulate_ssp

from artibus import runner
from artibus.bench import ssp

from artibus.testing import component, connection, make_ssp


REPEAT = 5   # runs per bench: this machine is shared, so the best and the median are printed


def _timed_initialization(sim):
    """sim's initialisation, timed: [seconds, of them inside the FMUs' calls] once it ran.
    With the stepping core the rounds to the fixed point and the FMUs' exit from
    initialization mode run in C, which times the FMUs' fmi2GetReal/fmi2SetReal/
    fmi2ExitInitializationMode there itself (sim.settle_wall): counted as the FMUs'."""
    spent, initialize = [0.0, 0.0], sim._initialize

    def inside(f):
        def timed(*args, **kw):
            t0 = time.perf_counter()
            try:
                return f(*args, **kw)
            finally:
                spent[1] += time.perf_counter() - t0
        return timed

    # the wrappers made here, before the run (their making is the benchmark's, not the
    # runner's): timed() only puts them on the instances for the initialisation
    calls = [(u.raw, n) for u in sim.units for n in ("read", "write")] + \
            [(u.fmu.slave, n) for u in sim.units for n in
             ("setupExperiment", "enterInitializationMode", "exitInitializationMode")] + \
            [(u.fmu, "set_values") for u in sim.units]
    wrapped = [(obj, name, inside(getattr(obj, name))) for obj, name in calls]

    def timed(start, stepper):
        for obj, name, f in wrapped:
            setattr(obj, name, f)
        settled = getattr(sim, "settle_wall", 0.0)
        t0 = time.perf_counter()
        try:
            initialize(start, stepper)
        finally:
            spent[0] = time.perf_counter() - t0
            spent[1] += getattr(sim, "settle_wall", 0.0) - settled
            for obj, name, _ in wrapped:
                delattr(obj, name)         # the class's own again
    sim._initialize = timed
    return spent


def bench(name, label=None, **overrides):
    with runner.Simulation(name, overrides=overrides) as sim:
        cores = (None, False) if sim.network is not None else (None,)
    runs = {core: [] for core in cores}   # core: [(wall, own share, own share of the loop, init)]
    stepping = {}
    for _ in range(REPEAT):
        for core in cores:            # alternately: the machine's load drifts
            with runner.Simulation(name, overrides=overrides) as sim:
                init = _timed_initialization(sim)
                r = sim.run(core=core)
                stepping[core] = sim.stepping
                span = r.time[-1] - r.time[0]
                fmu = sum(u.wall for u in sim.units)
                runs[core].append((sim.wall, 1 - (fmu + init[1]) / sim.wall,
                                   1 - fmu / (sim.wall - init[0]), init[0]))
    parts = []
    for core, rows in runs.items():
        walls = [w for w, *_ in rows]
        w, own, loop, init = min(rows)
        parts.append(f"{stepping[core]}: best {span / w:5.0f} x ({w:.3f} s), median "
                     f"{span / statistics.median(walls):5.0f} x, own {100 * own:4.1f} % "
                     f"(loop {100 * loop:4.1f} %, init {1e3 * init:4.1f} ms)")
    print(f"{label or name:32s} {span:5.1f} s at {sim.base_step} s | " + " | ".join(parts))


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
                stepping = sim.stepping
            t_ours.append(time.perf_counter() - t0)
    what = "leader on an S-curve" if steer else "both straight"
    t_fmpy = min(t_fmpy)
    best = min(range(REPEAT), key=t_ours.__getitem__)
    t, lp, fm = t_ours[best], loop[best], fmu[best]
    print(f"two BusKinematics ({what}), 26 connectors, {stop:g} s at {h} s, Jacobi: "
          f"best of {REPEAT}: fmpy.ssp.simulate_ssp {t_fmpy:.3f} s, artibus "
          f"({stepping}) {t:.3f} s with set-up "
          f"({lp:.3f} s stepping, {fm:.3f} s of it inside the FMUs): {t_fmpy / t:.1f} x faster")


if __name__ == "__main__":
    benches()
    against_fmpy(steer=False)
    against_fmpy(steer=True)
