"""The runner's one stepping loop, the C core (src/runner_core/core.c, driven by
artibus.runner.core; issues 13, 37), held to references that share no code with it
(issue 37: "the Python step loop goes; it is no oracle"):

- FMPy's simulate_fmu: every FMU of fmus/ and fmus/fmi3/ alone as a one-component bench
  gives FMPy's table bit for bit at the same step;
- closed forms through BusKinematics' eq. 19 (kappa0 = tan(gammaF) / L0), evaluated in
  Python's float arithmetic (each operation rounded once: a fused multiply-add in the
  core's transformations would change last bits) with the C library's tan, bit for bit:
  Gauss-Seidel, Jacobi, linear transformations composed through a nested system, three
  rates (a component takes its input as it stands when its step begins and holds its
  output over the step), stimuli sampled at the start of the step; the initialisation's
  fixed point (every connected input is its transformed source output);
- a CAN bench's network in C against the same network in Python (run(core=False):
  artibus.can.Network, its reference implementation; tests/test_can_core.py in detail),
  in the one loop, over each whole manoeuvre, run and initialisation;
- determinism: every bench run twice in one process (the second run on the first one's
  recycled table) gives the same table bit for bit. That is all a network-free bench is
  compared with here: its values are held by tests/test_masters.py (ecos, libcosim,
  fmpy.ssp) and the benches' and models' own tests;
- a failing FMU midway (fmi2DoStep, fmi2SetReal) and in the initialisation (fmi2SetReal,
  fmi2ExitInitializationMode, rounds that do not settle): the error names the component
  and the time, and the rows kept with it are those of a run stopped just before;
- the parts in Python the core calls back for (stimuli; a network with faults or switched
  off) named in Simulation.stepping; a core library not built an error naming it.
"""
import math

import fmpy
import numpy as np
import pytest

from artibus import ArtibusError, ROOT, fmu_dir
from artibus.bench import ssp
from artibus.fmu import Result
from artibus.runner import Simulation, core_library_path
from artibus.runner.lsbus_bench import read_spec
from artibus.testing import pack_ssp, ssd_text

from test_runner import L0, LEAD_FOLLOW, QUIET, component, connection, make_ssp, nested_bench

pytestmark = pytest.mark.skipif(not core_library_path().is_file(),
                                reason=f"{core_library_path()} not built (cmake target artibus_core)")


def timed_run(ssp_file, core=None, run_kw=None, **kw):
    """(Result, Simulation.stepping, whether the bench has a CAN network) of one run; checks its walls: the FMUs' share (timed
    in C around each call) within the core's own time (inside artibus_core_run), within
    the run's; a CAN network ticked in C timed too (within the core's time), one ticked
    in Python not (its wall 0, its ticks within the core's time)."""
    with Simulation(ssp_file, **kw) as sim:
        result = sim.run(core=core, **(run_kw or {}))
        walls = [u.wall for u in sim.units]
        assert all(w > 0 for w in walls) and sum(walls) < sim.wall
        net = sim.can.wall if sim.can is not None else 0.0
        assert sum(walls) + net < sim.core_wall < sim.wall
        assert (net > 0) == (sim.can is not None and "the network" not in sim.stepping)
        return result, sim.stepping, sim.can is not None


def assert_bit_for_bit(a, b):
    assert a.names == b.names
    x, y = a.array(), b.array()
    assert x.shape == y.shape and x.dtype == y.dtype == np.float64
    np.testing.assert_array_equal(x, y)
    assert x.tobytes() == y.tobytes()          # also -0.0 against 0.0 and NaN payloads


def kappa(gamma_f, l0=L0):
    """BusKinematics' eq. 19 in Python floats: tan(gammaF) / L0, element by element."""
    return np.array([math.tan(float(g)) / l0 for g in gamma_f])


def linear(x, factor, offset):
    """An SSP linear transformation as Python evaluates it: factor x, rounded, + offset, rounded."""
    return [factor * float(v) + offset for v in x]


# --- every FMU alone against FMPy's simulate_fmu ---------------------------------------

#: 1/64 s: FMPy's communication points are t_k = k h and its step sizes t_{k+1} - t_k,
#: which are h exactly only when every k h is (a power of two); ours are h. At 0.01 s the
#: integrating FMUs (BusKinematics, BusDynamics, MultiAxle3DOF) differ in the last bits.
H_FMPY = 1 / 64
#: start values that make an FMU move alone (a test stimulus of its own, a constant input
#: it integrates), given to both: as the bench's overrides and as FMPy's start_values
ALONE_START = {"BusKinematics": {"testSteerAmp": 0.2}, "TrainGuidance": {"testSteerAmp": 0.2},
               "ForceMinimization": {"testSteerAmp": 0.2}, "ArticulationDamper": {"LambdaDot": 0.1}}
#: the FMUs whose outputs move alone (the others' outputs are constant with constant inputs)
ALONE_MOVING = {"ArticulationDamper", "BusDynamics", "BusKinematics", "DampingController", "ForceMinimization",
                "MultiAxle3DOF", "SteeringActuator", "SteeringECU", "SwayBaseline", "TrainGuidance", "TypesTest"}
#: FMI-LS-BUS FMUs (Binary and Clock variables): run by their network, tests/test_lsbus_*.py
LSBUS_FMUS = {"CanBus", "SteeringECU_LSBUS", "SteeringActuator_LSBUS", "SteeringSensors_LSBUS"}
ALONE = [(fmi, p.stem) for fmi, d in (("2", fmu_dir()), ("3", fmu_dir() / "fmi3"))
         for p in sorted(d.glob("*.fmu")) if p.stem not in LSBUS_FMUS]


def _connector_type(v):
    """The SSP 1.0 connector type of a model variable (FMI 2.0 or 3.0), None: not one."""
    if v.type in ("Real", "Float64", "Float32"):
        return "<ssc:Real/>"
    if v.type == "Integer" or v.type.startswith(("Int", "UInt")):
        return "<ssc:Integer/>"
    if v.type in ("Boolean", "String"):
        return f"<ssc:{v.type}/>"
    if v.type == "Enumeration":
        return f'<ssc:Enumeration name="{v.declaredType.name}"/>'
    return None


def alone_bench(tmp_path, fmu, stop):
    """(an .ssp holding the FMU as its one component, named by the model, every output
    a connector; nothing connected: the inputs stay at their start values, as in FMPy),
    the component's name, the outputs' names)."""
    md = fmpy.read_model_description(str(fmu))
    outs = [(v.name, _connector_type(v)) for v in md.modelVariables
            if v.causality == "output" and _connector_type(v)]
    conns = "".join(f'<ssd:Connector name="{n}" kind="output">{t}</ssd:Connector>' for n, t in outs)
    name = md.modelName
    component = (f'<ssd:Component name="{name}" source="resources/{fmu.name}" type="application/x-fmu-sharedlibrary">'
                 f'<ssd:Connectors>{conns}</ssd:Connectors></ssd:Component>')
    path = pack_ssp(tmp_path / f"{fmu.stem}.ssp", ssd_text(component, None, stop, "alone"),
                    {f"resources/{fmu.name}": fmu})
    return path, name, [n for n, _ in outs]


@pytest.mark.parametrize("fmi, name", ALONE, ids=[f"{n}-fmi{f}" for f, n in ALONE])
def test_every_fmu_alone_is_fmpys_simulate_fmu_bit_for_bit(tmp_path, fmi, name):
    """The reference: FMPy's simulate_fmu (Co-Simulation) of the same FMU at the same
    step, its default experiment's stop time (at most 10 s): the same time column and
    every output FMPy records (FMPy records no String), bit for bit. Through the core's
    FMI 2.0 or 3.0 calls, Integer/Boolean/Enumeration outputs through its callback."""
    fmu = (fmu_dir() / "fmi3" if fmi == "3" else fmu_dir()) / f"{name}.fmu"
    de = fmpy.read_model_description(str(fmu)).defaultExperiment
    stop = min(float(de.stopTime) if de is not None and de.stopTime else 10.0, 10.0)
    path, comp, outs = alone_bench(tmp_path, fmu, stop)
    start = ALONE_START.get(name, {})
    ours, stepping, _ = timed_run(path, step=H_FMPY, record=[f"{comp}.{n}" for n in outs],
                               overrides={f"{comp}.{k}": v for k, v in start.items()})
    assert stepping.startswith("C core")
    theirs = fmpy.simulate_fmu(str(fmu), fmi_type="CoSimulation", step_size=H_FMPY, output_interval=H_FMPY,
                               stop_time=stop, start_values=start)
    assert len(ours.time) == len(theirs) == round(stop / H_FMPY) + 1
    assert ours.time.tobytes() == np.asarray(theirs["time"], float).tobytes()
    cols = theirs.dtype.names[1:]
    assert {f"{comp}.{n}" for n in cols} == set(ours.names[1:]) - set(ours.strings)
    for n in cols:
        assert ours[f"{comp}.{n}"].tobytes() == np.asarray(theirs[n], float).tobytes(), n
    moving = [n for n in cols if np.ptp(np.asarray(theirs[n], float)) > 0]
    assert bool(moving) == (name in ALONE_MOVING), moving       # the comparison means something


# --- the benches -------------------------------------------------------------------------

#: every bench but those with an FMI-LS-BUS network (tests/test_lsbus_core.py holds their
#: network in C to the one in Python)
CORE_BENCHES = [b for b in ssp.bench_names() if read_spec(ssp.BENCH_DIR / b / "SystemStructure.ssd") is None]


def twice(bench, **kw):
    """(first run, second run) of a bench in one process: the first in the C core with its
    network (if any) in C; the second with its network in Python (run(core=False)), on the
    first run's recycled table (artibus.runner.tables) and new structs."""
    first, stepping, network = timed_run(bench, **kw)
    assert stepping == "C core"
    kept = Result.from_array(list(first.names), first.array().copy())
    kept.terminated = first.terminated
    del first                                     # its table free for the second run to take
    second, stepping, _ = timed_run(bench, core=False, **kw)
    assert stepping == ("C core; in Python: the network, switched off (core=False)" if network else "C core")
    return kept, second


@pytest.mark.parametrize("bench", CORE_BENCHES)
def test_every_bench_twice_the_same_and_its_can_network_in_python(bench):
    """A CAN bench: its network in C (artibus.runner.can_core) equals the network in Python
    (artibus.can.Network, the reference) bit for bit over the whole default experiment.
    Every other bench: the two runs are the same loop, so this is determinism (no state
    kept between runs, a recycled table written whole); its values' references are above
    (each FMU against FMPy) and in tests/test_masters.py (the benches in other masters)."""
    first, second = twice(bench)
    assert len(first.time) > 100 and np.all(np.isfinite(first.array()))
    assert first.terminated is None and second.terminated is None
    assert_bit_for_bit(first, second)


def test_damping_bench_variant_twice_the_same():
    """The damping bench with the 100 Hz baseline next to the 50 Hz controller (determinism)."""
    first, second = twice("Scania18m_Damping",
                             overrides=ssp.variant_overrides("Scania18m_Damping", ["baseline", "lc25_50"]))
    assert_bit_for_bit(first, second)


# --- the runner's own benches (tests/test_runner.py): closed forms ------------------------

SLOW = ('<ssd:Annotations><ssc:Annotation type="org.artibus.simulation">'
        '<Simulation xmlns="urn:artibus" stepSize="{}"/></ssc:Annotation></ssd:Annotations>')


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("factor, offset", [(2.0, 0.01), (0.7, 0.013)])
def test_two_fmu_bench_with_a_transformation(tmp_path, algorithm, factor, offset):
    """gammaF = factor beta + offset, through BusKinematics' eq. 19 (kappa0 = tan(gammaF) /
    L0) bit for bit: 0.7 beta + 0.013 rounds twice, so a fused multiply-add in the core (its
    code compiled with contraction on an FMA machine) would change last bits."""
    path = make_ssp(tmp_path, LEAD_FOLLOW["elements"],
                    connection("Lead", "beta[1]", "Follow", "gammaF", f'factor="{factor}" offset="{offset}"'))
    r, stepping, _ = timed_run(path, step=0.05, overrides=QUIET, algorithm=algorithm)
    assert stepping == "C core"
    om, ka = r["Lead.beta[1]"], r["Follow.kappa[0]"]
    assert np.max(np.abs(om)) > 0.05
    if algorithm == "gauss-seidel":     # the follower sees the leader at the end of the step
        np.testing.assert_array_equal(ka, kappa(linear(om, factor, offset)))
    else:                               # one step late; at the start the leader's initial output
        np.testing.assert_array_equal(ka[1:], kappa(linear(om[:-1], factor, offset)))
        np.testing.assert_array_equal(ka[:1], kappa(linear(om[:1], factor, offset)))


def test_nested_system_composed_transformations(tmp_path):
    """Lead -> (x2 +0.01) -> system connector -> (x0.5) -> Follow: one transformation,
    factor 1, offset 0.005, bit for bit."""
    path = nested_bench(tmp_path)
    r, _, _ = timed_run(path, step=0.05, overrides={"Lead.testSteerAmp": 0.2, "Sub.Follow.testSteerAmp": 0.0})
    np.testing.assert_array_equal(r["Sub.Follow.kappa[0]"], kappa(linear(r["Lead.beta[1]"], 1.0, 0.005)))
    assert np.max(np.abs(r["Lead.beta[1]"])) > 1e-3


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_multi_rate_three_rates(tmp_path, algorithm):
    """Lead at the base step 0.05 s, Follow at 0.1 s, Third at 0.15 s (the plan's
    period is 6 base steps), chained Lead -> Follow -> Third, many outputs recorded.
    A component whose step begins at base step k takes its input from its source's
    output as it stands then: recorded in row k + 1 (Gauss-Seidel: the source, earlier
    in the order, has done base step k) or row k (Jacobi); it holds its output over its
    step, shown at the step's end (row k + its ratio)."""
    outs = [(f"{n}[{i}]", "output") for n in ("theta", "x", "y", "kappa", "beta") for i in (0, 1)
            if (n, i) != ("beta", 0)]
    elements = (component("Lead", outs)
                + component("Follow", [("gammaF", "input")] + outs, SLOW.format(0.1))
                + component("Third", [("gammaF", "input")] + outs, SLOW.format(0.15)))
    connections = (connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="-1.5"')
                   + connection("Follow", "beta[1]", "Third", "gammaF", 'offset="0.02"'))
    path = make_ssp(tmp_path, elements, connections, stop=12.0)
    r, stepping, _ = timed_run(path, step=0.05, algorithm=algorithm,
                            overrides={"Lead.testSteerAmp": 0.2, "Follow.testSteerAmp": 0.0,
                                       "Third.testSteerAmp": 0.0})
    assert stepping == "C core" and len(r.time) == 241
    ka = r["Follow.kappa[0]"]
    np.testing.assert_array_equal(ka[1::2], ka[0:-1:2])          # held over its 0.1 s
    k3 = r["Third.kappa[0]"]
    assert np.all(k3[1::3] == k3[0:-1:3]) and np.all(k3[2::3] == k3[0:-2:3])   # held over 0.15 s
    assert np.max(np.abs(k3)) > 1e-3
    late = 0 if algorithm == "gauss-seidel" else 1
    starts2, starts3 = np.arange(0, 240, 2), np.arange(0, 240, 3)
    np.testing.assert_array_equal(ka[starts2 + 2], kappa(linear(r["Lead.beta[1]"][starts2 + 1 - late], -1.5, 0.0)))
    np.testing.assert_array_equal(k3[starts3 + 3], kappa(linear(r["Follow.beta[1]"][starts3 + 1 - late], 1.0, 0.02)))


def test_progress_bar_runs_in_pieces_the_same(tmp_path, capsys):
    """With the progress bar the core runs in 50 pieces between the bar's updates; without
    it in one: the same table bit for bit, the bar drawn 50 times."""
    results, bars = [], []
    for progress in (True, False):
        with Simulation(make_ssp(tmp_path, **LEAD_FOLLOW), step=0.05, overrides=QUIET) as sim:
            results.append(sim.run(progress=progress))
        bars.append(capsys.readouterr().err)
    assert_bit_for_bit(*results)
    assert bars[0].count("\r") == 50 and bars[0].endswith("]\n") and bars[1] == ""


# --- a failing FMU midway ------------------------------------------------------------

def bench_with(tmp_path, elements, connections, fmus, stop=10.0):
    return make_ssp(tmp_path, elements, connections, stop, name="fail", fmu=False, fmus=fmus)


def failure(path, algorithm, component, **kw):
    """The SimulationError of a run that fails: it names the component, the time (the last
    row kept's) and the FMU's last error message, carries the FMU's log, and the rows kept
    are those of the same run stopped at that time (its last row's), bit for bit."""
    with Simulation(path, step=0.05, algorithm=algorithm, **kw) as sim:
        with pytest.raises(Exception) as e:
            sim.run()
        assert sim.stepping == "C core"
        log = [m for u in sim.units if u.path == component for m in u.fmu.log]
    e = e.value
    assert type(e).__name__ == "SimulationError"
    errors = [m for m in log if m.startswith(("[Error]", "[Fatal]"))]
    assert e.log == log and errors and str(e).endswith(errors[-1])
    if len(e.result.time):
        t = e.result.time[-1]
        assert f"component '{component}' failed at t = {t:g} s: " in str(e)
        with Simulation(path, step=0.05, algorithm=algorithm, **kw) as sim:
            before = sim.run(stop_time=t)
        assert_bit_for_bit(e.result, before)
    return e


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_do_step_error_and_partial_results(tmp_path, algorithm):
    """gammaF = 40 beta[1] reaches pi/2 midway: Follow's fmi2DoStep refuses it."""
    elements = component("Lead", [("beta[1]", "output")]) + component(
        "Follow", [("gammaF", "input"), ("kappa[0]", "output")], SLOW.format(0.1))
    path = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="40"'))
    e = failure(path, algorithm, "Follow", overrides=QUIET)
    assert "component 'Follow' failed at t = " in str(e) and "beyond pi/2" in str(e)
    beta = e.result["Lead.beta[1]"]
    assert 1.0 < e.result.time[-1] < 10.0
    # the failing input is 40 beta[1] of one of the last rows (GS and Jacobi take it at different ones)
    assert np.max(np.abs(40 * beta[:-4])) < np.pi / 2 <= np.max(np.abs(40 * beta))


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_set_real_error_and_partial_results(tmp_path, algorithm):
    """pct = 1000 beta[1] + 25 leaves the damper's 0..50 % midway: its fmi2SetReal refuses
    it, and the error names the damper (the unit whose call failed, not the one that
    stepped last)."""
    e = failure(damper_bench(tmp_path, 25), algorithm, "Damper", overrides={"Lead.testSteerAmp": 0.2})
    assert "component 'Damper' failed at t = " in str(e) and "pct" in str(e)
    assert 0.5 < e.result.time[-1] < 10.0
    beta = e.result["Lead.beta[1]"]
    # Gauss-Seidel: the leader's output that fails is the step's, not recorded; Jacobi: the last row's
    assert np.max(np.abs(1000 * beta[:-1])) <= 25 and abs(1000 * beta[-1]) > 23


# --- the parts in Python, and where the core is found -----------------------------------

@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_stimuli_run_in_the_core_called_back(tmp_path, algorithm):
    """A stimulus (a Python function of time) is added to its input's connection value
    at the start of each of the component's steps (the core calls back for it): with
    GS gammaF(row k + 1) = (2 beta(row k + 1) + 0.01) + f(t_k), bit for bit."""
    path = make_ssp(tmp_path, **LEAD_FOLLOW)
    with Simulation(path, step=0.05, overrides=QUIET, algorithm=algorithm,
                    stimuli={"Follow.gammaF": lambda t: 0.01 * math.sin(t)}) as sim:
        r = sim.run()
        assert sim.stepping == "C core; in Python: stimuli (Python functions of time)"
    t, om, ka = r.time, r["Lead.beta[1]"], r["Follow.kappa[0]"]
    src = om[1:] if algorithm == "gauss-seidel" else om[:-1]
    np.testing.assert_array_equal(ka[1:], kappa([g + 0.01 * math.sin(tk) for g, tk in zip(linear(src, 2.0, 0.01),
                                                                                        t[:-1])]))
    assert np.max(np.abs(0.01 * np.sin(t))) > 0.009


def test_switched_off_or_not_built(tmp_path, monkeypatch):
    """ARTIBUS_CORE=0 ticks the networks in Python (a bench without one: the same run);
    a core library that is not there is an error naming it, at the run."""
    path = make_ssp(tmp_path, **LEAD_FOLLOW)
    with Simulation(path, step=0.1) as sim:
        sim.run(stop_time=1.0)
        assert sim.stepping == "C core"
    monkeypatch.setenv("ARTIBUS_CORE", "0")
    with Simulation(path, step=0.1) as sim:
        sim.run(stop_time=1.0)
        assert sim.stepping == "C core"
    with Simulation("Bus36m_Circle_CAN") as sim:
        sim.run(stop_time=0.5)
        assert sim.stepping == "C core; in Python: the network, switched off (ARTIBUS_CORE=0)"
    monkeypatch.delenv("ARTIBUS_CORE")
    monkeypatch.setenv("ARTIBUS_CORE_LIB", str(tmp_path / "nowhere.so"))
    with Simulation(path, step=0.1) as sim:
        with pytest.raises(ArtibusError) as e:
            sim.run(stop_time=1.0)
    assert str(e.value) == (f"{sim.bench.file}: the C stepping core: {tmp_path / 'nowhere.so'} is not built "
                            "(scripts/setup.sh builds it)")


def test_library_next_to_the_fmus_in_use(tmp_path, monkeypatch):
    """With ARTIBUS_FMU_DIR = <build>/fmus (the sanitizer build's FMUs) the core
    is <build>/lib's when that is built, else build/lib's."""
    monkeypatch.delenv("ARTIBUS_CORE_LIB", raising=False)
    monkeypatch.delenv("ARTIBUS_FMU_DIR", raising=False)
    default = core_library_path()
    assert default == ROOT / "build" / "lib" / "libartibus_core.so"
    (tmp_path / "fmus").mkdir()
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(tmp_path / "fmus"))
    assert core_library_path() == default
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "libartibus_core.so").write_bytes(b"")
    assert core_library_path() == tmp_path / "lib" / "libartibus_core.so"


# --- the initialisation's rounds to the fixed point in the core (artibus_core_settle) ---------

def initialised(sim, core=None):
    """Every unit's inputs, outputs and inputs last set, and the CAN network's E2E state,
    right after Simulation._initialize (the run stops after a few steps); checks there that
    the state is the fixed point: every connected input is its source's output through
    the connection's transformation (in Python floats), bit for bit, and the inputs last
    set are the inputs."""
    state, initialize = [], sim._initialize

    def snapshot(start, stepper):
        initialize(start, stepper)
        for u in sim.units:
            raw = u.raw
            for i, out, j, factor, offset in u.sources:
                assert raw.inp[i].hex() == (factor * out[j] + offset).hex(), (u.path, u.in_names[i])
            assert raw.written == (bytes(raw.inp)[:8 * raw.n_in] if raw.n_in else None), u.path
        state.extend((bytes(u.raw.inp), bytes(u.raw.out), u.raw.written) for u in sim.units)
        if sim.can is not None:
            state.extend((m.counter, m.last_counter, m.good_tick) for m in sim.can.messages)
    sim._initialize = snapshot
    sim.run(stop_time=sim.bench.start_time + 5 * sim.base_step, core=core)
    return state


@pytest.mark.parametrize("bench", CORE_BENCHES)
def test_initialisation_of_every_bench_is_the_fixed_point(bench):
    """After the rounds to the fixed point in the core (artibus_core_settle, which times the
    FMUs' calls there): every connected input its transformed source output (initialised's
    checks); a CAN bench's network settled in Python (its reference) gives the same state,
    bit for bit, every unit's inputs and outputs and the messages' E2E state."""
    with Simulation(bench) as sim:
        state = initialised(sim)
        assert sim.settle_wall > 0 and sim.stepping == "C core"
        network = sim.can is not None
    if network:
        with Simulation(bench) as sim:
            assert initialised(sim, core=False) == state
            assert sim.stepping == "C core; in Python: the network, switched off (core=False)"


def damper_bench(tmp_path, offset):
    """pct = 1000 beta[1] + offset: beta[1] is 0 at the start."""
    damper = ('<ssd:Component name="Damper" source="resources/ArticulationDamper.fmu" '
              'type="application/x-fmu-sharedlibrary"><ssd:Connectors>'
              '<ssd:Connector name="pct" kind="input"><ssc:Real/></ssd:Connector>'
              '<ssd:Connector name="Mmax" kind="output"><ssc:Real/></ssd:Connector>'
              '</ssd:Connectors></ssd:Component>')
    elements = component("Lead", [("beta[1]", "output"), ("kappa[0]", "output")]) + damper
    connections = connection("Lead", "beta[1]", "Damper", "pct", f'factor="1000" offset="{offset}"')
    return bench_with(tmp_path, elements, connections, ["BusKinematics", "ArticulationDamper"])


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_set_real_in_the_initialisation(tmp_path, algorithm):
    """pct = 75 % at the start, outside the damper's 0..50 %: its fmi2SetReal in the
    initialisation's first round refuses it; the error names the damper, no rows."""
    e = failure(damper_bench(tmp_path, 75), algorithm, "Damper")
    assert "component 'Damper' failed at t = 0 s" in str(e) and "pct" in str(e)
    assert len(e.result.time) == 0


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_not_settled(tmp_path, monkeypatch, algorithm):
    """One round allowed: pct goes 0 -> 25 in it, so the inputs have not settled; two are
    enough."""
    import artibus.runner.simulation
    monkeypatch.setattr(artibus.runner.simulation, "MAX_INIT_ITERATIONS", 1)
    path = damper_bench(tmp_path, 25)
    with Simulation(path, step=0.05, algorithm=algorithm) as sim:
        with pytest.raises(ArtibusError) as e:
            sim.run()
        assert sim.stepping == "C core"
    assert str(e.value) == f"{sim.bench.file}: initialisation did not settle in 1 iterations of the connected inputs"
    monkeypatch.setattr(artibus.runner.simulation, "MAX_INIT_ITERATIONS", 2)      # two are enough
    with Simulation(path, step=0.05, algorithm=algorithm) as sim:
        assert sim.run(stop_time=0.2)["Damper.Mmax"].size == 5


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_exit_initialization(tmp_path, algorithm):
    """A damper whose geometry its model_init refuses (R = Xrear = Yrear = 5 cm:
    a cylinder 2 cm long), no output read: its fmi2ExitInitializationMode fails,
    after the rounds; the error names the damper, no rows."""
    import artibus.runner
    damper = ('<ssd:Component name="Damper" source="resources/ArticulationDamper.fmu" '
              'type="application/x-fmu-sharedlibrary"><ssd:Connectors>'
              '<ssd:Connector name="pct" kind="input"><ssc:Real/></ssd:Connector>'
              '</ssd:Connectors></ssd:Component>')
    elements = component("Lead", [("beta[1]", "output"), ("kappa[0]", "output")]) + damper
    path = bench_with(tmp_path, elements, connection("Lead", "beta[1]", "Damper", "pct", 'factor="1000" offset="25"'),
                      ["BusKinematics", "ArticulationDamper"])
    functions = []
    initialize = artibus.runner.Simulation._initialize

    def spy(self, start, stepper):
        try:
            initialize(self, start, stepper)
        except Exception as e:
            functions.append(getattr(e, "function", None))
            raise
    artibus.runner.Simulation._initialize = spy
    try:
        e = failure(path, algorithm, "Damper", overrides={"Damper.R": 0.05, "Damper.Xrear": 0.05, "Damper.Yrear": 0.05})
    finally:
        artibus.runner.Simulation._initialize = initialize
    assert functions == ["fmi2ExitInitializationMode"]
    assert "component 'Damper' failed at t = 0 s" in str(e) and "geometry R = 0.05 m" in str(e)
    assert len(e.result.time) == 0
