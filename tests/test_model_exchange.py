"""Model Exchange of the plants (BusKinematics, BusDynamics, MultiAxle3DOF,
ArticulationDamper):
the same FMU, the same right-hand side as its co-simulation interface.

Each plant runs a bench manoeuvre twice: as co-simulation (our loop over
fmi2DoStep, the FMU's own CVODE at rtol 1e-10) and as Model Exchange through
FMPy (its CVode at relative tolerance 1e-10). The inputs are what a bench's
plant gets from a 50 Hz driver: a steering signal sampled every 20 ms and held
(a staircase), set before each co-simulation step and given to FMPy as a
structured array with a step at each sample instant (input events in Model
Exchange). Both integrate the same ODE with the same inputs, so every output
must agree within 1e-6 of its peak. The jack-knife of a reversing bus is an
event in Model Exchange and ends the co-simulation step, at the same time."""
import gc
import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import fmu_file, restore_fmpy_logger
from artibus.fmu import Fmu

TS = 0.02           # the benches' driver samples at 50 Hz
TOL = 1e-10         # both integrators' relative tolerance
REL = 1e-6          # the acceptance: ME equals CS within 1e-6 of each output's peak
PLANTS = ["BusKinematics", "BusDynamics", "MultiAxle3DOF", "ArticulationDamper"]


def staircase(t_end, signals):
    """FMPy's input array for inputs sampled at TS and held: {name: f(t)}
    evaluated at t_k = k TS, a step at every t_k (t_k twice: old, new value)."""
    tk = np.arange(0.0, t_end + 1e-9, TS)
    names = list(signals)
    rows = [(0.0, *[signals[n](0.0) for n in names])]
    for k in range(1, len(tk)):
        old = rows[-1][1:]
        rows.append((tk[k], *old))
        rows.append((tk[k], *[signals[n](tk[k]) for n in names]))
    return np.array(rows, dtype=[("time", np.double)] + [(n, np.double) for n in names])


def run_cs(name, params, signals, t_end):
    tol = {"rtol": TOL, "atol": TOL} if name != "ArticulationDamper" else {}   # its steps are exact
    """Co-simulation: u_k = f(t_k) held over [t_k, t_k + TS); the outputs read at
    t_k after the inputs are set (as FMPy records Model Exchange after the event)."""
    fmu = Fmu(fmu_file(name))
    try:
        # the inputs' first values in initialisation mode, as FMPy gives them to ME
        fmu.initialize({**params, **tol, **{s: f(0.0) for s, f in signals.items()}})
        outs = [v.name for v in fmu.md.modelVariables if v.causality == "output" and v.type == "Real"]
        rows = []
        n = int(round(t_end / TS))
        for k in range(n + 1):
            t = k * TS
            fmu.set_values({s: f(t) for s, f in signals.items()})
            rows.append(fmu.get(*outs))
            if k < n:
                fmu.slave.doStep(t, TS)
        return outs, np.array(rows)
    finally:
        fmu.close()


def run_me(name, params, signals, t_end, outs):
    res = simulate_fmu(str(fmu_file(name)), fmi_type="ModelExchange", start_values=params,
                       input=staircase(t_end, signals), output=outs, stop_time=t_end,
                       output_interval=TS, relative_tolerance=TOL, record_events=False)
    return res


# the bench manoeuvres (stimuli off: the inputs drive)
CASES = {
    # Urbino18_Circle's speed, an S-curve of the front wheel
    "BusKinematics": ({"testSteerAmp": 0.0, "N": 1},
                      {"v": lambda t: 3.0, "gammaF": lambda t: 0.35 * math.sin(2 * math.pi * t / 20.0)},
                      20.0),
    # a lane change at 50 km/h (Bus36m_LaneChange's speed): one sine period of front steering
    "BusDynamics": ({"testSteerAmp": 0.0, "vx_start": 50 / 3.6},
                    {"delta[1]": lambda t: 0.03 * math.sin(2 * math.pi * t / 3.0) if t < 3.0 else 0.0},
                    5.0),
    # MultiAxle_StepSteer's speed, a steering ramp to 0.02 rad then a sine
    "MultiAxle3DOF": ({"testSteerAmp": 0.0},
                      {"u": lambda t: 20.0, "delta[1]": lambda t: 0.02 * min(t, 1.0) + 0.01 * math.sin(2 * t)},
                      6.0),
    # the damper in a sway of the rear section that reaches the 54 deg end stop, the
    # controller's request varying, with a valve lag (tauP = 0.05 s: off by default)
    "ArticulationDamper": ({"tauP": 0.05},
                           {"Lambda": lambda t: 1.0 * math.sin(0.8 * math.pi * t),
                            "LambdaDot": lambda t: 0.8 * math.pi * math.cos(0.8 * math.pi * t),
                            "pct": lambda t: 20.0 + 15.0 * math.sin(3.0 * t)},
                           5.0),
}


def max_rel_diff(outs, cs, me):
    """per output: max |ME - CS| over the run / max |CS| (outputs that stay
    below 1e-9 compared absolutely)"""
    worst = {}
    for i, n in enumerate(outs):
        a, b = cs[:, i], me[n]
        peak = np.max(np.abs(a))
        worst[n] = np.max(np.abs(a - b)) / (peak if peak > 1e-9 else 1.0)
    return worst


@pytest.mark.parametrize("name", PLANTS)
def test_model_exchange_equals_co_simulation(name):
    params, signals, t_end = CASES[name]
    outs, cs = run_cs(name, params, signals, t_end)
    me = run_me(name, params, signals, t_end, outs)
    assert len(me) == len(cs)
    np.testing.assert_allclose(me["time"], np.arange(len(cs)) * TS, atol=1e-9)
    worst = max_rel_diff(outs, cs, me)
    top = max(worst, key=worst.get)
    print(f"{name}: max relative difference ME vs CS {worst[top]:.2e} ({top})")
    assert worst[top] < REL, f"{top}: ME and CS differ by {worst[top]:.3g} of its peak"
    # and the manoeuvre did something: the plant moved sideways, the damper took energy
    moved = {"BusKinematics": "y[0]", "BusDynamics": "y[1]", "MultiAxle3DOF": "y", "ArticulationDamper": "Ediss"}[name]
    assert np.max(np.abs(cs[:, outs.index(moved)])) > 0.5


def _cs_jackknife_time(params, signals, t_end):
    fmu = Fmu(fmu_file("BusKinematics"))
    try:
        fmu.initialize({**params, "rtol": TOL, "atol": TOL})
        n = int(round(t_end / TS))
        for k in range(n):
            fmu.set_values({s: f(k * TS) for s, f in signals.items()})
            try:
                fmu.slave.doStep(k * TS, TS)
            except FMICallException:
                msg = " ".join(fmu.log)
                assert "jack-knife at joint 1" in msg, msg
                from fmpy.fmi2 import fmi2LastSuccessfulTime
                return fmu.slave.getRealStatus(fmi2LastSuccessfulTime), k * TS
        return None, None
    finally:
        fmu.close()


def test_jackknife_is_an_event_at_the_co_simulation_time():
    """Reversing with the wagon 0.1 rad off and the front wheel turned: the
    joint angle grows until the virtual steering angle reaches 90 deg. The
    co-simulation step stops there with an error; Model Exchange finds the
    state event (indicator cos(delta_1) - 1e-6) and terminates at that time."""
    params = {"testSteerAmp": 0.0, "N": 1, "beta_start[1]": 0.1}
    signals = {"v": lambda t: -2.0, "gammaF": lambda t: 0.2 * min(t / 2.0, 1.0)}
    t_cs, t_step = _cs_jackknife_time(params, signals, 60.0)
    assert t_cs is not None, "no jack-knife in co-simulation"
    assert t_step <= t_cs < t_step + TS            # inside the step that failed
    messages = []
    res = simulate_fmu(str(fmu_file("BusKinematics")), fmi_type="ModelExchange", start_values=params,
                       input=staircase(60.0, signals), output=["beta[1]", "betaMax[1]"], stop_time=60.0,
                       output_interval=TS, relative_tolerance=TOL, record_events=True,
                       logger=lambda *a: messages.append(a[-1].decode() if isinstance(a[-1], bytes) else str(a[-1])))
    t_me = res["time"][-1]
    print(f"jack-knife: CS t = {t_cs:.9f} s, ME t = {t_me:.9f} s")
    assert t_me < 60.0 - TS                          # the run ended at the event
    assert t_me == pytest.approx(t_cs, abs=1e-6)
    # there the joint angle is at its bound (|delta_1| = 90 deg)
    assert abs(res["beta[1]"][-1]) == pytest.approx(res["betaMax[1]"][-1], rel=1e-3)


def test_fmpy_prints_the_fmus_messages_again_after_a_run_with_a_logger(capsys):
    """After the jack-knife run above gave FMPy a logger of its own, an FMU run
    with FMPy's default callbacks prints its messages through FMPy's own
    printLogMessage (conftest restores FMPy's logger proxy after each test that
    gave it a logger: left pointing at the freed logger, this run crashed in
    SteeringActuator's first warning when test_model_exchange ran before
    test_hardening in one process)."""
    simulate_fmu(str(fmu_file("BusKinematics")), stop_time=0.1,
                 logger=lambda *a: None)                    # as the jack-knife test does
    gc.collect()
    restore_fmpy_logger()                   # what conftest does after every such test (artibus.fmu.claim_logger_proxy)
    capsys.readouterr()
    simulate_fmu(str(fmu_file("SteeringActuator")), stop_time=0.1)   # warns: no command message
    out = capsys.readouterr().out
    assert "[WARNING]" in out and "command message stale" in out, out


@pytest.mark.parametrize("name", PLANTS)
def test_validate_both_interfaces(name):
    """fmpy validate, and the model description declares both interfaces with
    one binary, the states with their derivatives."""
    path = str(fmu_file(name))
    assert validate_fmu(path) == []
    md = read_model_description(path)
    assert md.coSimulation.modelIdentifier == md.modelExchange.modelIdentifier == name
    assert md.numberOfContinuousStates == len(md.derivatives) > 0
    for d in md.derivatives:
        assert d.variable.derivative is not None
        assert d.variable.derivative.variability == "continuous"
    # each interface runs its default experiment with finite results
    for kind in ("CoSimulation", "ModelExchange"):
        res = simulate_fmu(path, fmi_type=kind, stop_time=2.0)
        for n in res.dtype.names:
            assert np.all(np.isfinite(res[n])), (kind, n)


def test_controllers_stay_co_simulation():
    """The sampled controllers and the driver have no Model Exchange interface."""
    for name in ("TrainGuidance", "DampingController", "RoadFollowDriver"):
        assert read_model_description(str(fmu_file(name))).modelExchange is None


def _fmi_sim():
    import shutil
    from conftest import ROOT
    local = ROOT / ".tools" / "bin" / "fmi-sim"
    return str(local) if local.is_file() else shutil.which("fmi-sim")


# start values that make each plant move in its default experiment
FMI_SIM_START = {"BusKinematics": {"testSteerAmp": 0.2}, "BusDynamics": {"testSteerAmp": 0.05},
                 "MultiAxle3DOF": {"testSteerAmp": 0.02},
                 "ArticulationDamper": {"LambdaDot": 0.2, "pct": 20.0, "tauP": 0.05}}


@pytest.mark.skipif(_fmi_sim() is None, reason="fmi-sim (crates.io) not installed: scripts/setup_test.sh builds it when cargo is present")
@pytest.mark.parametrize("name", PLANTS)
def test_model_exchange_in_fmi_sim(name, tmp_path):
    """A second importer (fmi-sim, Rust) runs the Model Exchange interface with
    its forward Euler (1 ms steps) through the default experiment: its end values
    equal FMPy's co-simulation run to Euler's first-order error (5e-3 of each
    output's peak; measured at most 1.2e-3, MultiAxle3DOF's y)."""
    import csv
    import subprocess
    out = tmp_path / "fmi-sim.csv"
    start = FMI_SIM_START[name]
    args = [a for k, v in start.items() for a in ("--init-values", f"{k}={v}")]
    r = subprocess.run([_fmi_sim(), "-q", "--model", str(fmu_file(name)), "-o", str(out),
                        "model-exchange", "--step", "0.001", *args],
                       capture_output=True, text=True, env={"RUST_BACKTRACE": "0", "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr[-2000:]
    with open(out) as f:
        last = list(csv.DictReader(f))[-1]
    ours = simulate_fmu(str(fmu_file(name)), fmi_type="CoSimulation", start_values=start, output_interval=0.05)
    assert float(last["time"]) == pytest.approx(ours["time"][-1])
    for n in ours.dtype.names[1:]:
        scale = float(np.max(np.abs(ours[n].astype(float))))
        assert float(last[n]) == pytest.approx(float(ours[n][-1]), abs=5e-3 * scale + 1e-9), n
