"""The runner's stepping core in C (src/runner_core/core.c, issue 13) against
the runner's Python loop: the same result table bit for bit on every bench it
applies to and on the runner's own two-FMU benches (Gauss-Seidel, Jacobi,
multi-rate, transformations), the same error, log and partial results when an
FMU fails midway (in fmi2DoStep, in fmi2SetReal), and today's loop where the
core does not apply; the initialisation's rounds to the fixed point in the
core (the same initialised state on every bench, the same errors when an FMU
fails there or the inputs do not settle). ``Simulation.run(core=False)`` (or ARTIBUS_CORE=0) is the
Python loop, ``core=True`` the core (an error where it does not apply)."""
import zipfile

import numpy as np
import pytest

from artibus import ArtibusError, ROOT, fmu_path
from artibus.bench import ssp
from artibus.runner import Simulation, core_library_path
from artibus.runner.lsbus_bench import read_spec

from test_runner import L0, LEAD_FOLLOW, NS, QUIET, component, connection, make_ssp, nested_bench

pytestmark = pytest.mark.skipif(not core_library_path().is_file(),
                                reason=f"{core_library_path()} not built (cmake target artibus_core)")


def both(ssp_file, run_kw=None, **kw):
    """(result with the core, result with the Python loop); each run checks which stepped."""
    out = []
    for core in (True, False):
        with Simulation(ssp_file, **kw) as sim:
            out.append(sim.run(core=core, **(run_kw or {})))
            assert sim.stepping == ("C core" if core else "Python loop: switched off (core=False)")
            walls = [u.wall for u in sim.units]
            assert all(w > 0 for w in walls) and sum(walls) < sim.wall   # the FMUs' share, measured in C too
            net = sim.can.wall if sim.can is not None else 0.0
            if core:   # the core's own time around them: the FMUs' calls and the network's ticks are within it
                assert sum(walls) + net < sim.core_wall < sim.wall
                assert (net > 0) == (sim.can is not None)
            else:      # the Python loop's network is not timed
                assert net == 0.0
    return out


def assert_bit_for_bit(a, b):
    assert a.names == b.names
    x, y = a.array(), b.array()
    assert x.shape == y.shape and x.dtype == y.dtype == np.float64
    np.testing.assert_array_equal(x, y)
    assert x.tobytes() == y.tobytes()          # also -0.0 against 0.0 and NaN payloads


# --- the benches ---------------------------------------------------------------------

#: the benches compared here, core against Python loop: not those with an FMI-LS-BUS network,
#: whose core run tests/test_lsbus_core.py compares with the Python master
CORE_BENCHES = [b for b in ssp.bench_names() if read_spec(ssp.BENCH_DIR / b / "SystemStructure.ssd") is None]

@pytest.mark.parametrize("bench", CORE_BENCHES)
def test_every_bench_bit_for_bit(bench):
    """The CAN benches too: the core ticks their network (tests/test_can_core.py)."""
    core, python = both(bench)
    assert len(core.time) > 100 and np.all(np.isfinite(core.array()))
    assert_bit_for_bit(core, python)


def test_damping_bench_variant_bit_for_bit():
    """The damping bench with the 100 Hz baseline next to the 50 Hz controller."""
    core, python = both("Scania18m_Damping",
                        overrides=ssp.variant_overrides("Scania18m_Damping", ["baseline", "lc25_50"]))
    assert_bit_for_bit(core, python)


# --- the runner's own benches (tests/test_runner.py) ------------------------------------

SLOW = ('<ssd:Annotations><ssc:Annotation type="org.artibus.simulation">'
        '<Simulation xmlns="urn:artibus" stepSize="{}"/></ssc:Annotation></ssd:Annotations>')


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("factor, offset", [(2.0, 0.01), (0.7, 0.013)])
def test_two_fmu_bench_with_a_transformation(tmp_path, algorithm, factor, offset):
    """0.7 beta + 0.013 rounds twice: a fused multiply-add (the core compiled
    with contraction on an FMA machine) would change last bits."""
    path = make_ssp(tmp_path, LEAD_FOLLOW["elements"],
                    connection("Lead", "beta[1]", "Follow", "gammaF", f'factor="{factor}" offset="{offset}"'))
    core, python = both(path, step=0.05, overrides=QUIET, algorithm=algorithm)
    assert_bit_for_bit(core, python)
    om, ka = core["Lead.beta[1]"], core["Follow.kappa[0]"]
    assert np.max(np.abs(om)) > 0.05
    # the semantics, through BusKinematics' eq. 19 (kappa0 = tan(gammaF) / L0), gammaF = factor beta + offset
    if algorithm == "gauss-seidel":     # the follower sees the leader at the end of the step
        np.testing.assert_allclose(ka, np.tan(factor * om + offset) / L0, rtol=1e-12, atol=1e-15)
    else:                               # one step late
        np.testing.assert_allclose(ka[1:], np.tan(factor * om[:-1] + offset) / L0, rtol=1e-12, atol=1e-15)


def test_nested_system_composed_transformations(tmp_path):
    path = nested_bench(tmp_path)
    core, python = both(path, step=0.05, overrides={"Sub.Follow.testSteerAmp": 0.0})
    assert_bit_for_bit(core, python)
    np.testing.assert_allclose(core["Sub.Follow.kappa[0]"], np.tan(core["Lead.beta[1]"] + 0.005) / L0, rtol=1e-12)


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_multi_rate_three_rates(tmp_path, algorithm):
    """Lead at the base step 0.05 s, Follow at 0.1 s, Third at 0.15 s (the plan's
    period is 6 base steps), chained Lead -> Follow -> Third, many outputs recorded."""
    outs = [(f"{n}[{i}]", "output") for n in ("theta", "x", "y", "kappa", "beta") for i in (0, 1)
            if (n, i) != ("beta", 0)]
    elements = (component("Lead", outs)
                + component("Follow", [("gammaF", "input")] + outs, SLOW.format(0.1))
                + component("Third", [("gammaF", "input")] + outs, SLOW.format(0.15)))
    connections = (connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="-1.5"')
                   + connection("Follow", "beta[1]", "Third", "gammaF", 'offset="0.02"'))
    path = make_ssp(tmp_path, elements, connections, stop=12.0)
    core, python = both(path, step=0.05, algorithm=algorithm,
                        overrides={"Lead.testSteerAmp": 0.2, "Follow.testSteerAmp": 0.0, "Third.testSteerAmp": 0.0})
    assert_bit_for_bit(core, python)
    ka = core["Follow.kappa[0]"]
    np.testing.assert_array_equal(ka[1::2], ka[0:-1:2])          # held over its 0.1 s
    k3 = core["Third.kappa[0]"]
    assert np.all(k3[1::3] == k3[0:-1:3]) and np.all(k3[2::3] == k3[0:-2:3])   # held over 0.15 s
    assert np.max(np.abs(k3)) > 1e-3


def test_progress_bar_is_the_same(tmp_path, capsys):
    """With the progress bar the core runs in pieces between the bar's updates."""
    results, bars = [], []
    for core in (True, False):
        with Simulation(make_ssp(tmp_path, **LEAD_FOLLOW), step=0.05, overrides=QUIET) as sim:
            results.append(sim.run(core=core, progress=True))
        bars.append(capsys.readouterr().err)
    assert_bit_for_bit(*results)
    assert bars[0] == bars[1] and bars[0].count("\r") == 50 and bars[0].endswith("]\n")


# --- a failing FMU midway ------------------------------------------------------------

def bench_with(tmp_path, elements, connections, fmus, stop=10.0):
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="1.0" name="fail">'
           f'<ssd:System name="root"><ssd:Elements>{elements}</ssd:Elements>'
           f'<ssd:Connections>{connections}</ssd:Connections></ssd:System>'
           f'<ssd:DefaultExperiment startTime="0" stopTime="{stop}"/></ssd:SystemStructureDescription>')
    path = tmp_path / "fail.ssp"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for name in fmus:
            z.write(fmu_path(name), f"resources/{name}.fmu")
    return path


def failures(path, algorithm, **kw):
    errors = []
    for core in (True, False):
        with Simulation(path, step=0.05, algorithm=algorithm, **kw) as sim:
            with pytest.raises(Exception) as e:
                sim.run(core=core)
            assert sim.stepping.startswith("C core" if core else "Python loop")
        errors.append(e.value)
    a, b = errors
    assert type(a) is type(b) and type(a).__name__ == "SimulationError"
    assert str(a) == str(b) and a.log == b.log
    assert_bit_for_bit(a.result, b.result)
    return a


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_do_step_same_error_and_partial_results(tmp_path, algorithm):
    """gammaF = 40 beta[1] reaches pi/2 midway: Follow's fmi2DoStep refuses it."""
    elements = component("Lead", [("beta[1]", "output")]) + component(
        "Follow", [("gammaF", "input"), ("kappa[0]", "output")], SLOW.format(0.1))
    path = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="40"'))
    e = failures(path, algorithm, overrides=QUIET)
    assert "component 'Follow' failed at t = " in str(e) and "beyond pi/2" in str(e)
    beta = e.result["Lead.beta[1]"]
    assert 1.0 < e.result.time[-1] < 10.0
    # the failing input is 40 beta[1] of one of the last rows (GS and Jacobi take it at different ones)
    assert np.max(np.abs(40 * beta[:-4])) < np.pi / 2 <= np.max(np.abs(40 * beta))


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_set_real_same_error_and_partial_results(tmp_path, algorithm):
    """pct = 1000 beta[1] + 25 leaves the damper's 0..50 % midway: its
    fmi2SetReal refuses it, and the error names the damper (the Python loop
    named the unit that stepped last before this change)."""
    e = failures(damper_bench(tmp_path, 25), algorithm, overrides={"Lead.testSteerAmp": 0.2})
    assert "component 'Damper' failed at t = " in str(e) and "pct" in str(e)
    assert 0.5 < e.result.time[-1] < 10.0
    beta = e.result["Lead.beta[1]"]
    # Gauss-Seidel: the leader's output that fails is the step's, not recorded; Jacobi: the last row's
    assert np.max(np.abs(1000 * beta[:-1])) <= 25 and abs(1000 * beta[-1]) > 23


# --- where the core does not apply, and where it is found ---------------------------------

def test_stimuli_take_the_python_loop(tmp_path):
    path = make_ssp(tmp_path, **LEAD_FOLLOW)
    with Simulation(path, step=0.05, overrides=QUIET, stimuli={"Follow.gammaF": lambda t: 0.01}) as sim:
        r = sim.run()
        assert sim.stepping == "Python loop: stimuli (Python functions of time)"
    np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(2.0 * r["Lead.beta[1]"] + 0.02) / L0, rtol=1e-12)
    with Simulation(path, step=0.05, stimuli={"Follow.gammaF": lambda t: 0.01}) as sim:
        with pytest.raises(ArtibusError, match="does not apply: stimuli"):
            sim.run(core=True)


def test_switched_off_or_not_built(tmp_path, monkeypatch):
    path = make_ssp(tmp_path, **LEAD_FOLLOW)
    with Simulation(path, step=0.1) as sim:
        sim.run(stop_time=1.0)
        assert sim.stepping == "C core"
    monkeypatch.setenv("ARTIBUS_CORE", "0")
    with Simulation(path, step=0.1) as sim:
        sim.run(stop_time=1.0)
        assert sim.stepping == "Python loop: switched off (ARTIBUS_CORE=0)"
    monkeypatch.delenv("ARTIBUS_CORE")
    monkeypatch.setenv("ARTIBUS_CORE_LIB", str(tmp_path / "nowhere.so"))
    with Simulation(path, step=0.1) as sim:
        sim.run(stop_time=1.0)
        assert sim.stepping == f"Python loop: {tmp_path / 'nowhere.so'} is not built"


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

def initialised(sim, core):
    """Every unit's inputs, outputs and inputs last set, and the CAN network's
    E2E state, right after Simulation._initialize (the run stops after a few steps)."""
    state, initialize = [], sim._initialize

    def snapshot(start):
        initialize(start)
        state.extend((bytes(u.raw.inp), bytes(u.raw.out), u.raw.written) for u in sim.units)
        if sim.can is not None:
            state.extend((m.counter, m.last_counter, m.good_tick) for m in sim.can.messages)
    sim._initialize = snapshot
    sim.run(stop_time=sim.bench.start_time + 5 * sim.base_step, core=core)
    assert sim.stepping.startswith("C core" if core else "Python loop")
    return state


@pytest.mark.parametrize("bench", CORE_BENCHES)
def test_initialisation_of_every_bench_bit_for_bit(bench):
    """Every unit's inputs, outputs and inputs last set after the rounds to the fixed
    point in the core (artibus_core_settle), the Python loop's, bit for bit."""
    states = []
    for core in (True, False):
        with Simulation(bench) as sim:
            states.append(initialised(sim, core))
            settled = getattr(sim, "settle_wall", 0.0)
            assert (settled > 0) if core else settled == 0.0     # the core's rounds ran (and timed the FMUs)
    assert states[0] == states[1]


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
def test_failing_set_real_in_the_initialisation_same_error(tmp_path, algorithm):
    """pct = 75 % at the start, outside the damper's 0..50 %: its fmi2SetReal in the
    initialisation's first round refuses it; the same error names the damper."""
    e = failures(damper_bench(tmp_path, 75), algorithm)
    assert "component 'Damper' failed at t = 0 s" in str(e) and "pct" in str(e)
    assert len(e.result.time) == 0


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_not_settled_same_error(tmp_path, monkeypatch, algorithm):
    """One round allowed: pct goes 0 -> 25 in it, so the inputs have not settled."""
    import artibus.runner.simulation
    monkeypatch.setattr(artibus.runner.simulation, "MAX_INIT_ITERATIONS", 1)
    path = damper_bench(tmp_path, 25)
    errors = []
    for core in (True, False):
        with Simulation(path, step=0.05, algorithm=algorithm) as sim:
            with pytest.raises(ArtibusError) as e:
                sim.run(core=core)
            assert sim.stepping.startswith("C core" if core else "Python loop")
            errors.append(str(e.value))
    assert errors[0] == errors[1] and errors[0].endswith("initialisation did not settle in 1 iterations "
                                                         "of the connected inputs")
    monkeypatch.setattr(artibus.runner.simulation, "MAX_INIT_ITERATIONS", 2)      # two are enough
    for core in (True, False):
        with Simulation(path, step=0.05, algorithm=algorithm) as sim:
            assert sim.run(stop_time=0.2, core=core)["Damper.Mmax"].size == 5


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_failing_exit_initialization_same_error(tmp_path, algorithm):
    """A damper whose geometry its model_init refuses (R = Xrear = Yrear = 5 cm:
    a cylinder 2 cm long), no output read: its fmi2ExitInitializationMode fails,
    after the rounds; the same error names the damper."""
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

    def spy(self, start):
        try:
            initialize(self, start)
        except Exception as e:
            functions.append(getattr(e, "function", None))
            raise
    artibus.runner.Simulation._initialize = spy
    try:
        e = failures(path, algorithm, overrides={"Damper.R": 0.05, "Damper.Xrear": 0.05, "Damper.Yrear": 0.05})
    finally:
        artibus.runner.Simulation._initialize = initialize
    assert functions == ["fmi2ExitInitializationMode"] * 2
    assert "component 'Damper' failed at t = 0 s" in str(e) and "geometry R = 0.05 m" in str(e)
    assert len(e.result.time) == 0
