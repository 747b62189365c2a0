"""The SSP runner on small benches built here from two BusKinematics FMUs:
Gauss-Seidel and Jacobi semantics checked through the FMUs' own kinematics,
equality with fmpy.ssp.simulate_ssp, nested systems, transformations,
multi-rate, and bad benches reported by file, element and value."""
import math
import subprocess
import sys

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp

from artibus import ArtibusError, fmu_path
from artibus.runner import Simulation, run, save
# the small benches' parts, shared with the benchmarks (the other tests import them from here)
from artibus.testing import NS, component, connection, make_ssp  # noqa: F401


LEAD_FOLLOW = dict(
    elements=component("Lead", [("beta[1]", "output")]) + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")]),
    connections=connection("Lead", "beta[1]", "Follow", "gammaF", 'factor="2.0" offset="0.01"'),
)
L0 = 5.9  # BusKinematics default
# the leader steers by its built-in test stimulus (off by default), the follower only by its input
QUIET = {"Lead.testSteerAmp": 0.2, "Follow.testSteerAmp": 0.0}


def test_gauss_seidel_follower_sees_the_leader_at_the_end_of_the_step(tmp_path):
    """GS: the follower's input over [t, t+h] is the leader's output at t+h;
    BusKinematics' own eq. 19 (kappa0 = tan(gammaF)/L0) shows it at each point."""
    r = run(make_ssp(tmp_path, **LEAD_FOLLOW), step=0.05, overrides=QUIET)
    om, ka = r["Lead.beta[1]"], r["Follow.kappa[0]"]
    assert np.max(np.abs(om)) > 0.05
    np.testing.assert_allclose(ka, np.tan(2.0 * om + 0.01) / L0, rtol=1e-12, atol=1e-15)


def test_jacobi_follower_sees_the_leader_one_step_late(tmp_path):
    r = run(make_ssp(tmp_path, **LEAD_FOLLOW), step=0.05, algorithm="jacobi", overrides=QUIET)
    om, ka = r["Lead.beta[1]"], r["Follow.kappa[0]"]
    np.testing.assert_allclose(ka[1:], np.tan(2.0 * om[:-1] + 0.01) / L0, rtol=1e-12, atol=1e-15)


def test_jacobi_equals_fmpy_simulate_ssp(tmp_path):
    """fmpy.ssp.simulate_ssp: Jacobi, no transformations, row k labelled t_k holds
    the values after the step to t_k+1. Ours: the same numbers one row later."""
    outs = [(f"{n}[{i}]", "output") for n in ("theta", "x", "y", "omega", "vel", "kappa", "beta") for i in (0, 1)
            if (n, i) != ("beta", 0)]
    elements = component("Lead", outs) + component("Follow", [("gammaF", "input")] + outs)
    ssp = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"))
    h, stop = 0.05, 5.0
    ref = simulate_ssp(str(ssp), stop_time=stop, step_size=h)
    with Simulation(ssp, step=h, algorithm="jacobi",
                    record=[f"{c}.{n}" for c in ("Lead", "Follow") for n, _ in outs]) as sim:
        ours = sim.run(stop_time=stop)
    for c in ("Lead", "Follow"):
        for n, _ in outs:
            a = ours[f"{c}.{n}"][1:]
            b = ref[f"{c}.{n}"][: len(a)]
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=f"{c}.{n}")


def nested_bench(tmp_path):
    """Lead -> (x2 +0.01) -> system connector -> (x0.5) -> Follow inside a sub-system."""
    inner = (f'<ssd:System name="Sub"><ssd:Connectors><ssd:Connector name="steer" kind="input"><ssc:Real/>'
             f'</ssd:Connector></ssd:Connectors><ssd:Elements>'
             + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")])
             + '</ssd:Elements><ssd:Connections>'
             + connection(None, "steer", "Follow", "gammaF", 'factor="0.5"')
             + '</ssd:Connections></ssd:System>')
    elements = component("Lead", [("beta[1]", "output")]) + inner
    return make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Sub", "steer", 'factor="2.0" offset="0.01"'))


def test_nested_system_and_composed_transformations(tmp_path):
    """Lead -> (x2 +0.01) -> system connector -> (x0.5) -> Follow inside a sub-system."""
    ssp = nested_bench(tmp_path)
    r = run(ssp, step=0.05, overrides={"Sub.Follow.testSteerAmp": 0.0})
    np.testing.assert_allclose(r["Sub.Follow.kappa[0]"], np.tan(r["Lead.beta[1]"] + 0.005) / L0, rtol=1e-12)


def test_multi_rate_holds_the_slow_component(tmp_path):
    """Follow at 0.1 s under a 0.05 s base step (GS, Lead first)."""
    ann = ('<ssd:Annotations><ssc:Annotation type="org.artibus.simulation">'
           '<Simulation xmlns="urn:artibus" stepSize="0.1"/></ssc:Annotation></ssd:Annotations>')
    elements = (component("Lead", [("beta[1]", "output")])
                + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], ann))
    ssp = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"))
    r = run(ssp, step=0.05, overrides=QUIET)
    ka, om = r["Follow.kappa[0]"], r["Lead.beta[1]"]
    # it takes its input at the start of its 0.1 s interval and publishes its
    # output at the end: odd rows repeat the row before, even rows show
    # kappa = tan(gammaF)/L0 with gammaF the leader's output 0.1 s earlier
    np.testing.assert_array_equal(ka[1::2], ka[0:-1:2])
    np.testing.assert_allclose(ka[2::2], np.tan(om[1:-1:2]) / L0, rtol=1e-12)


def test_parameters_from_bindings_and_overrides(tmp_path):
    ssv = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="p">'
           '<ssv:Parameters><ssv:Parameter name="L0"><ssv:Real value="4.0"/></ssv:Parameter>'
           '</ssv:Parameters></ssv:ParameterSet>')
    binding = ('<ssd:ParameterBindings><ssd:ParameterBinding source="resources/p.ssv"/>'
               '</ssd:ParameterBindings>')
    elements = (component("Lead", [("beta[1]", "output")])
                + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], binding))
    ssp = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"), ssv={"p.ssv": ssv})
    r = run(ssp, step=0.05, overrides=QUIET)
    np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(r["Lead.beta[1]"]) / 4.0, rtol=1e-12)
    r = run(ssp, step=0.05, overrides={**QUIET, "Follow.L0": 8.0, "Lead.testSteerAmp": 0.0})
    np.testing.assert_allclose(r["Follow.kappa[0]"], 0.0, atol=1e-15)   # no steering at all now


# a vehicle data set written for another component: names BusKinematics does not have
VEHICLE_SSV = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="vehicle">'
               '<ssv:Parameters><ssv:Parameter name="wheelbase_mm"><ssv:Real value="4000.0"/></ssv:Parameter>'
               '<ssv:Parameter name="mass"><ssv:Real value="12000.0"/></ssv:Parameter>'
               '</ssv:Parameters></ssv:ParameterSet>')


def mapping_entries(*entries):
    return "".join(f'<ssm:MappingEntry source="{a}" target="{b}">'
                   + (f'<ssc:LinearTransformation factor="{k}"/>' if k is not None else "")
                   + '</ssm:MappingEntry>' for a, b, k in entries)


def mapped_bench(tmp_path, entries, inline):
    """Follow bound to VEHICLE_SSV through a parameter mapping, inline or a .ssm file."""
    files = {"vehicle.ssv": VEHICLE_SSV}
    if inline:
        mapping = f'<ssd:ParameterMapping><ssm:ParameterMapping version="1.0">{entries}</ssm:ParameterMapping></ssd:ParameterMapping>'
    else:
        files["follow.ssm"] = ('<?xml version="1.0" encoding="UTF-8"?><ssm:ParameterMapping ' + NS
                               + f' version="1.0">{entries}</ssm:ParameterMapping>')
        mapping = '<ssd:ParameterMapping source="resources/follow.ssm"/>'
    binding = (f'<ssd:ParameterBindings><ssd:ParameterBinding source="resources/vehicle.ssv">{mapping}'
               '</ssd:ParameterBinding></ssd:ParameterBindings>')
    elements = (component("Lead", [("beta[1]", "output")])
                + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], binding))
    return make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"), ssv=files)


@pytest.mark.parametrize("inline", [True, False])
def test_parameter_mapping_renames_transforms_and_applies_only_mapped(tmp_path, inline):
    """SSP's parameter mapping: wheelbase_mm -> L0 with factor 0.001 gives
    L0 = 4.0 m, seen through BusKinematics' eq. 19 (kappa0 = tan(gammaF)/L0);
    'mass', which BusKinematics does not have, is not mapped and so not
    applied (bound without a mapping it is an error: the next test). The
    bench validates against the SSP XSDs (FMPy's reader) first."""
    ssp = mapped_bench(tmp_path, mapping_entries(("wheelbase_mm", "L0", 0.001)), inline)
    r = run(ssp, step=0.05, overrides=QUIET)
    assert np.max(np.abs(r["Lead.beta[1]"])) > 0.05
    np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(r["Lead.beta[1]"]) / 4.0, rtol=1e-12)


@pytest.mark.parametrize("entries, words", [
    (None, ["no variable 'wheelbase_mm'"]),                           # no mapping: every name applies
    (mapping_entries(("wheelbase", "L0", None)), ['source="wheelbase"', "has no 'wheelbase'"]),
    (mapping_entries(("wheelbase_mm", "L0", 0.001), ("mass", "L0", None)), ["'L0' is mapped to twice"]),
    (mapping_entries(("mass", "Lzero", None)), ["no variable 'Lzero'"]),
])
def test_bad_parameter_mappings_name_file_entry_value(tmp_path, entries, words):
    if entries is None:
        binding = ('<ssd:ParameterBindings><ssd:ParameterBinding source="resources/vehicle.ssv"/>'
                   '</ssd:ParameterBindings>')
        elements = (component("Lead", [("beta[1]", "output")])
                    + component("Follow", [("gammaF", "input")], binding))
        ssp = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"),
                       ssv={"vehicle.ssv": VEHICLE_SSV})
    else:
        ssp = mapped_bench(tmp_path, entries, inline=False)
    with pytest.raises(ArtibusError) as e:
        run(ssp, step=0.05)
    msg = str(e.value)
    assert str(ssp) in msg and all(w in msg for w in words), msg
    if entries is not None and "Lzero" not in words[0]:
        assert "follow.ssm:1:" in msg      # the file and line of the entry


def test_mat_output(tmp_path):
    from scipy.io import loadmat
    r = run(make_ssp(tmp_path, **LEAD_FOLLOW), step=0.1, stop_time=1.0)
    m = loadmat(str(save(r, tmp_path / "r.mat")))
    np.testing.assert_array_equal(m["Follow_kappa_0"].ravel(), r["Follow.kappa[0]"])


@pytest.mark.parametrize("case, words", [
    ("missing_fmu", ["Component 'Lead'", "resources/BusKinematics.fmu", "not in the .ssp"]),
    ("dangling", ["Connection Lead.omega[9] -> Follow.gammaF", "'Lead' declares no connector 'omega[9]'"]),
    ("undeclared", ["Connection Lead.omega[9] -> Follow.gammaF", "no variable 'Lead.omega[9]'"]),
    ("type", ["Lead.x[0] -> Follow.N", "Real -> Integer"]),
    ("units", ["Lead.omega[0] -> Follow.v", "'rad/s' to 'm/s'"]),
    ("loop", ["algebraic loop", "Lead.omega[0]", "Follow.omega[0]"]),
    ("ssv", ["'Follow.Lzero' = 4.0", "no variable 'Lzero'"]),
    ("step", ["--step 0", "must be > 0"]),
])
def test_bad_benches_name_file_element_value(tmp_path, case, words):
    kw = dict(LEAD_FOLLOW)
    step = 0.05
    if case == "missing_fmu":
        kw["fmu"] = False
    elif case == "dangling":
        kw["connections"] = connection("Lead", "omega[9]", "Follow", "gammaF")
    elif case == "undeclared":
        kw["elements"] = (component("Lead", [("omega[9]", "output")])
                          + component("Follow", [("gammaF", "input")]))
        kw["connections"] = connection("Lead", "omega[9]", "Follow", "gammaF")
    elif case == "type":
        kw["elements"] = component("Lead", [("x[0]", "output")]) + component("Follow", [("N", "input")])
        kw["connections"] = connection("Lead", "x[0]", "Follow", "N")
    elif case == "units":
        kw["elements"] = component("Lead", [("omega[0]", "output")]) + component("Follow", [("v", "input")])
        kw["connections"] = connection("Lead", "omega[0]", "Follow", "v")
    elif case == "loop":
        kw["elements"] = (component("Lead", [("omega[0]", "output"), ("gammaF", "input")])
                          + component("Follow", [("gammaF", "input"), ("omega[0]", "output")]))
        kw["connections"] = (connection("Lead", "omega[0]", "Follow", "gammaF", 'factor="0.5"')
                             + connection("Follow", "omega[0]", "Lead", "gammaF", 'factor="0.5"'))
    elif case == "ssv":
        ssv = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="p">'
               '<ssv:Parameters><ssv:Parameter name="Lzero"><ssv:Real value="4.0"/></ssv:Parameter>'
               '</ssv:Parameters></ssv:ParameterSet>')
        kw["ssv"] = {"p.ssv": ssv}
        kw["elements"] = (component("Lead", [("beta[1]", "output")])
                          + component("Follow", [("gammaF", "input")],
                                      '<ssd:ParameterBindings><ssd:ParameterBinding source="resources/p.ssv"/>'
                                      '</ssd:ParameterBindings>'))
    elif case == "step":
        step = 0.0
    ssp = make_ssp(tmp_path, **kw)
    with pytest.raises(ArtibusError) as e:
        run(ssp, step=step)
    msg = str(e.value)
    for w in words:
        assert w in msg, (w, msg)
    if case not in ("step",):
        assert str(ssp) in msg


def road_bench(tmp_path, road_file):
    """A RoadFollowDriver, its bench's parameter set giving it road = 0 and
    roadFile = road_file, fed a BusKinematics' x[0]; the .ssp packs the road
    resources/road.csv (a straight line, 'x,y' per line)."""
    ssv = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="p">'
           '<ssv:Parameters><ssv:Parameter name="road"><ssv:Integer value="0"/></ssv:Parameter>'
           f'<ssv:Parameter name="roadFile"><ssv:String value="{road_file}"/></ssv:Parameter>'
           '</ssv:Parameters></ssv:ParameterSet>')
    driver = ('<ssd:Component name="Driver" source="resources/RoadFollowDriver.fmu" '
              'type="application/x-fmu-sharedlibrary"><ssd:Connectors><ssd:Connector name="x" kind="input">'
              '<ssc:Real/></ssd:Connector></ssd:Connectors><ssd:ParameterBindings>'
              '<ssd:ParameterBinding source="resources/p.ssv"/></ssd:ParameterBindings></ssd:Component>')
    files = {"p.ssv": ssv, "road.csv": "".join(f"{10.0 * i},0\n" for i in range(11)),
             "RoadFollowDriver.fmu": fmu_path("RoadFollowDriver").read_bytes()}
    return make_ssp(tmp_path, component("Car", [("x[0]", "output")]) + driver,
                    connection("Car", "x[0]", "Driver", "x"), stop=1.0, ssv=files)


@pytest.mark.parametrize("where", ["ssv", "override"])
def test_a_resources_parameter_naming_a_file_not_in_the_ssp(tmp_path, where):
    """A String parameter "resources/<file>" names a file inside the .ssp
    (runner.resolve_resources): one the .ssp does not hold, given by the bench's
    parameter set or by an override, is refused when the bench is set up, before
    any step, naming the bench, the parameter, the value and where the value is
    from (the .ssv inside the .ssp, or --set); not passed on to
    the FMU, whose own error would be about a path in a temporary directory.
    The same bench with the file it packs is set up, the value the path of the
    unpacked file."""
    missing = "resources/raod.csv"
    ssp = road_bench(tmp_path, missing if where == "ssv" else "resources/road.csv")
    overrides = {"Driver.roadFile": missing} if where == "override" else {}
    with pytest.raises(ArtibusError) as e:
        Simulation(ssp, step=0.1, overrides=overrides)   # set up only: no step taken
    msg = str(e.value)
    assert msg.startswith(f"{ssp}/SystemStructure.ssd: ") and "parameter 'roadFile'" in msg, msg
    assert f"= '{missing}'" in msg and "no such file in the .ssp" in msg, msg
    # and where the value is from: the parameter set inside the .ssp, or the override
    assert (f"(from {ssp}/resources/p.ssv" if where == "ssv" else "(from --set") in msg, msg

    # the CLI: the same text, exit status 1, no traceback, no result file
    args = ["--set", f"Driver.roadFile={missing}"] if where == "override" else []
    out = tmp_path / "r.csv"
    r = subprocess.run([sys.executable, "-m", "artibus", "run", str(ssp), "--step", "0.1", *args,
                        "-o", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert msg in r.stderr and not out.exists(), r.stderr

    # control: the file the .ssp holds is found and handed over as its unpacked path
    with Simulation(road_bench(tmp_path, "resources/road.csv"), step=0.1) as sim:
        given = sim.parameters["Driver"]["roadFile"]
        assert given != "resources/road.csv" and given.endswith("/resources/road.csv")
        with open(given) as f:
            assert f.readline() == "0.0,0\n"


def test_cli_run_errors_exit_nonzero_without_traceback(tmp_path):
    ssp = make_ssp(tmp_path, LEAD_FOLLOW["elements"], connection("Lead", "omega[9]", "Follow", "gammaF"))
    r = subprocess.run([sys.executable, "-m", "artibus", "run", str(ssp), "--step", "0.1"],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 1 and "Traceback" not in r.stderr and "omega[9]" in r.stderr


def test_cli_run_writes_results(tmp_path):
    ssp = make_ssp(tmp_path, **LEAD_FOLLOW)
    out = tmp_path / "r.csv"
    r = subprocess.run([sys.executable, "-m", "artibus", "run", str(ssp), "--step", "0.1",
                        "--set", "Lead.testSteerAmp=0.3", "-o", str(out)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    header = out.read_text().splitlines()[0]
    assert '"Follow.kappa[0]"' in header and len(out.read_text().splitlines()) == 102


def test_a_bench_by_name_is_packed_again_when_a_file_it_packs_is_newer(tmp_path, monkeypatch):
    """A bench run by name is what ssp/benches, fmus/ and ssp/parameters hold
    now: a missing .ssp is packed, an edited parameter set or a rebuilt FMU is
    packed again (the run sees it), an unchanged bench is left as it is."""
    import os
    import shutil
    from artibus.bench import ssp as ssp_mod
    benches, fmus = tmp_path / "benches", tmp_path / "fmus"
    (benches / "Tiny").mkdir(parents=True)
    fmus.mkdir()
    shutil.copy(fmu_path("BusKinematics"), fmus / "BusKinematics.fmu")
    ssv = benches / "Tiny" / "resources" / "Tiny.ssv"
    ssv.parent.mkdir()

    def write_ssv(L0):
        ssv.write_text(f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {NS} version="1.0" '
                       f'name="Tiny"><ssv:Parameters><ssv:Parameter name="L0"><ssv:Real value="{L0}"/>'
                       f'</ssv:Parameter></ssv:Parameters></ssv:ParameterSet>')

    write_ssv(5.0)
    binding = ('<ssd:ParameterBindings><ssd:ParameterBinding source="resources/Tiny.ssv"/>'
               '</ssd:ParameterBindings>')
    (benches / "Tiny" / "SystemStructure.ssd").write_text(
        f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="1.0" name="Tiny">'
        f'<ssd:System name="root"><ssd:Elements>{component("Car", [("kappa[0]", "output")], binding)}'
        f'</ssd:Elements></ssd:System><ssd:DefaultExperiment startTime="0" stopTime="1"/>'
        f'</ssd:SystemStructureDescription>')
    monkeypatch.setattr(ssp_mod, "BENCH_DIR", benches)
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(fmus))

    def kappa_times_L0(L0):   # BusKinematics eq. 19: kappa0 = tan(gammaF) / L0, gammaF its test steering
        r = run("Tiny", step=0.1, overrides={"Car.testSteerAmp": 0.2})
        k = r["Car.kappa[0]"]
        assert np.max(np.abs(k)) > 1e-3
        return k * L0

    path = ssp_mod.ssp_path("Tiny")                    # missing: packed
    assert path == fmus / "Tiny.ssp"
    first = kappa_times_L0(5.0)
    stamp = path.stat().st_mtime_ns
    assert ssp_mod.ssp_path("Tiny").stat().st_mtime_ns == stamp     # unchanged: not packed again

    later = stamp + 10 ** 9
    write_ssv(8.0)
    os.utime(ssv, ns=(later, later))
    np.testing.assert_allclose(kappa_times_L0(8.0), first, rtol=1e-12)   # the run saw L0 = 8
    stamp = path.stat().st_mtime_ns

    later = stamp + 10 ** 9
    os.utime(fmus / "BusKinematics.fmu", ns=(later, later))      # "rebuilt"
    assert ssp_mod.ssp_path("Tiny").stat().st_mtime_ns > stamp

    (fmus / "BusKinematics.fmu").unlink()              # not built: a clear error, not a stale run
    with pytest.raises(ArtibusError, match=r"SystemStructure.ssd:1: <Component source=\"resources/"
                                           r"BusKinematics.fmu\">: no such file .*set-up command"):
        ssp_mod.ssp_path("Tiny")


def test_a_pack_left_in_fmus_of_no_bench_is_refused_by_name(tmp_path, monkeypatch):
    """A bench removed from ssp/benches (Bus36m_Circle_GuidedForceMin became a
    variant) leaves its old pack in an existing checkout's fmus/: its name must
    not run that stale pack silently but name it, and the bench and variant meant."""
    import shutil
    from artibus import ArtibusError
    from artibus.bench import ssp as ssp_mod
    real = ssp_mod.ssp_path("Bus36m_Circle")
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(tmp_path))
    shutil.copy(real, tmp_path / "Bus36m_Circle_GuidedForceMin.ssp")
    with pytest.raises(ArtibusError) as e:
        ssp_mod.ssp_path("Bus36m_Circle_GuidedForceMin")
    msg = str(e.value)
    assert "Bus36m_Circle --variant guidedForceMin" in msg
    assert str(tmp_path / "Bus36m_Circle_GuidedForceMin.ssp") in msg and "earlier build" in msg
    assert ssp_mod.ssp_path(str(tmp_path / "Bus36m_Circle_GuidedForceMin.ssp")).is_file()   # by path: runs
