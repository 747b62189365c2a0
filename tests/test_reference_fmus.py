"""The Modelica Reference-FMUs (FMI 2.0 and FMI 3.0 Co-Simulation: BouncingBall, Dahlquist,
Feedthrough, Resource, Stair, VanDerPol), built from their sources by
scripts/build_reference_fmus.sh (docs/developer/tests.md: from which sources, how), run
through `artibus simulate` and in benches of ours against FMPy's simulate_fmu:
a tool we never saw, whose FMUs follow the standard, gives the same table.

Stair ends the simulation itself at t = 9 s (fmi2DoStep returns fmi2Discard and
fmi2GetBooleanStatus(fmi2Terminated) says true): a normal end, exit 0, the
results under the final name; its counter is 1 + floor(t) (it counts the
seconds), up to 10 at t = 9 s. Their FMI 3.0 Stair ends nothing in Co-Simulation
without Event Mode (their fmi3DoStep always says terminateSimulation = false), so
FMI 3.0's terminateSimulation is checked on an FMU of ours whose fmi3DoStep is made to
say it. FMI 3.0 Feedthrough has every variable type: each width is set at its bounds and
read back, a value outside them refused."""
import math
from pathlib import Path

import fmpy
import numpy as np
import pytest

from artibus import cli
from artibus.fmu import simulate
from artibus.runner import Simulation

ROOT = Path(__file__).resolve().parents[1]
REFERENCE_DIR = ROOT / ".tools" / "reference-fmus"
MODELS = ["BouncingBall", "Dahlquist", "Feedthrough", "Resource", "Stair", "VanDerPol"]


def reference_fmu(name, version=2):
    path = REFERENCE_DIR / ("fmi3" if version == 3 else "") / f"{name}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/setup.sh builds it with scripts/build_reference_fmus.sh; needs cargo)")
    return path


def read_csv(path):
    import csv
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def fmpy_table(path, step, stop_time=None, **kw):
    """FMPy's simulate_fmu at our communication step (its default interval is the
    default experiment's step, doubled while over 1000 steps)."""
    r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", output_interval=step, stop_time=stop_time, **kw)
    return list(r.dtype.names), np.column_stack([r[n].astype(float) for n in r.dtype.names])


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_artibus_simulate_equals_fmpy(name, version, tmp_path, capsys):
    fmu = reference_fmu(name, version)
    out = tmp_path / f"{name}.csv"
    assert cli.main(["simulate", str(fmu), "-o", str(out)]) == 0
    names, ours = read_csv(out)
    md = fmpy.read_model_description(str(fmu))
    de = md.defaultExperiment
    step = float(de.stepSize) if de.stepSize else float(de.stopTime) / 500
    theirs_names, theirs = fmpy_table(fmu, step)
    binary = [v.name for v in md.modelVariables if v.causality == "output" and v.type in ("Binary", "Clock")]
    if binary:                         # FMI 3.0 Feedthrough's Binary_output: no number, not in our table
        keep = [i for i, n in enumerate(theirs_names) if n not in binary]
        theirs_names, theirs = [theirs_names[i] for i in keep], theirs[:, keep]
    assert names == theirs_names
    assert ours.shape == theirs.shape
    np.testing.assert_allclose(ours, theirs, rtol=1e-11, atol=1e-300)   # the CSV's 12 digits
    # through the Python API: the same FMU, the same calls, the same numbers, bit for bit
    r = simulate(fmu)
    np.testing.assert_array_equal(r.array(), theirs)
    assert not list(tmp_path.glob("*.partial.csv"))


def test_stair_ends_the_run_at_9_s_with_exit_0(tmp_path, capsys):
    fmu = reference_fmu("Stair")
    out = tmp_path / "Stair.csv"
    assert cli.main(["simulate", str(fmu), "-o", str(out)]) == 0
    said = capsys.readouterr()
    assert "Stair ended the simulation at t = 9 s" in said.out
    assert "error" not in said.err
    names, table = read_csv(out)
    assert names == ["time", "counter"]
    t, counter = table[:, 0], table[:, 1]
    assert t[-1] == pytest.approx(9.0, abs=1e-12)             # not the stop time (10 s)
    assert len(t) == 46                                        # 0, 0.2, ..., 9
    # it counts the seconds: 1 + floor(t) (an event at each whole second), 10 at 9 s
    expect = [1 + math.floor(x + 1e-9) for x in t]
    assert counter.tolist() == expect
    _, theirs = fmpy_table(fmu, 0.2)
    np.testing.assert_allclose(table, theirs, rtol=1e-11, atol=0)     # the CSV's 12 digits
    r = simulate(fmu)
    np.testing.assert_array_equal(r.array(), theirs)
    assert str(r.terminated) == "Stair ended the simulation at t = 9 s (fmi2Terminated)"
    assert not list(tmp_path.glob("*.partial.csv"))


def test_a_discard_without_terminated_is_still_an_error(tmp_path):
    """fmi2Discard alone (not terminated) is a failure: artibus.fmu.terminated says so."""
    from artibus.fmu import terminated

    class Slave:
        def __init__(self, term):
            self.term = term

        def getBooleanStatus(self, kind):
            assert kind == 3                   # fmi2Terminated
            return self.term

        def getRealStatus(self, kind):
            assert kind == 2                   # fmi2LastSuccessfulTime
            return 4.5

    assert terminated(Slave(False), 2) is None
    assert terminated(Slave(True), 3) is None          # fmi2Error: a failure whatever it says
    assert terminated(Slave(True), 2) == 4.5


NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"')


def _component(name, connectors, folder=""):
    conns = "".join(f'<ssd:Connector name="{n}" kind="{k}"><ssc:{t}/></ssd:Connector>' for n, k, t in connectors)
    return (f'<ssd:Component name="{name}" source="resources/{folder}{name}.fmu" type="application/x-fmu-sharedlibrary">'
            f'<ssd:Connectors>{conns}</ssd:Connectors></ssd:Component>')


def stair_bench(tmp_path, connect_feedthrough):
    """Stair and Dahlquist side by side; with connect_feedthrough, Stair's counter
    into Feedthrough's Integer input too (an Integer connection: the core calls back
    for it, in Python)."""
    elements = _component("Stair", [("counter", "output", "Integer")])
    elements += _component("Dahlquist", [("x", "output", "Real")])
    connections = ""
    models = ["Stair", "Dahlquist"]
    if connect_feedthrough:
        elements += _component("Feedthrough", [("Int32_input", "input", "Integer"),
                                                ("Int32_output", "output", "Integer")])
        connections = ('<ssd:Connections><ssd:Connection startElement="Stair" startConnector="counter" '
                       'endElement="Feedthrough" endConnector="Int32_input"/></ssd:Connections>')
        models.append("Feedthrough")
    return bench_ssp(tmp_path / "Stairs.ssp", elements, connections,
                     {f"resources/{m}.fmu": reference_fmu(m) for m in models})


def bench_ssp(path, elements, connections, files):
    """an .ssp at path: an SSP 1.0 System of the elements and connections (SSD text), stopping
    at 10 s, with files {name in the archive: the file}"""
    from artibus.testing import pack_ssp, ssd_text
    name = path.stem      # (``connections``: the Connections element itself, or "")
    return pack_ssp(path, ssd_text(elements, None, 10, name, system_name=name, after=connections), files)


def test_a_bench_holding_stair_ends_at_9_s(tmp_path):
    """Stair's end ends the bench (the C core's AC_ENDED): the last row at 9 s, Dahlquist's
    x as FMPy computes it alone up to 9 s, the run's end said, not a failure."""
    ssp = stair_bench(tmp_path, connect_feedthrough=False)
    with Simulation(ssp, step=0.2, record=["Dahlquist.x"]) as sim:
        r = sim.run()
        assert sim.stepping == "C core"
    assert r.terminated is not None
    assert r.terminated.component == "Stair" and r.terminated.time == pytest.approx(9.0)
    assert r.time[-1] == pytest.approx(9.0) and len(r.time) == 46
    _, theirs = fmpy_table(reference_fmu("Dahlquist"), 0.2, stop_time=9.0)
    np.testing.assert_allclose(r["Dahlquist.x"], theirs[:, 1], rtol=1e-12, atol=0)


def test_a_bench_with_stair_connected_has_fmpys_table_and_exit_0(tmp_path, capsys):
    ssp = stair_bench(tmp_path, connect_feedthrough=True)
    out = tmp_path / "stairs.csv"
    assert cli.main(["run", str(ssp), "--step", "0.2", "-o", str(out)]) == 0
    said = capsys.readouterr()
    assert "Stair ended the simulation at t = 9 s" in said.out
    names, table = read_csv(out)
    _, theirs = fmpy_table(reference_fmu("Stair"), 0.2)
    np.testing.assert_allclose(table[:, [0, names.index("Stair.counter")]], theirs, rtol=1e-11, atol=0)
    # the counter reached Feedthrough, which passes it on (Gauss-Seidel: within the step)
    np.testing.assert_array_equal(table[1:, names.index("Feedthrough.Int32_output")],
                                  table[1:, names.index("Stair.counter")])
    assert not list(tmp_path.glob("*.partial.csv"))


def test_a_sweep_case_that_stair_ends_is_terminated_not_failed(tmp_path):
    from artibus.study.sweep import run_case
    ssp = stair_bench(tmp_path, connect_feedthrough=False)
    row, series = run_case("Stairs", "stairs-test", str(ssp), None, {"Dahlquist.k": 2.0}, {}, None, 0.2, True)
    assert row["status"] == "terminated", row
    assert "Stair ended the simulation at t = 9 s" in row["error"]
    assert series["time"][-1] == pytest.approx(9.0)


# ---- FMI 3.0 --------------------------------------------------------------------------

WIDTHS = {"Int8": (-2**7, 2**7 - 1), "UInt8": (0, 2**8 - 1), "Int16": (-2**15, 2**15 - 1),
          "UInt16": (0, 2**16 - 1), "Int32": (-2**31, 2**31 - 1), "UInt32": (0, 2**32 - 1),
          "Int64": (-2**53, 2**53), "UInt64": (0, 2**53)}     # (64 bits: what a float column holds exactly)


@pytest.mark.parametrize("end", [0, 1], ids=["lowest", "highest"])
def test_feedthrough_fmi3_passes_every_width_at_its_bounds(end, tmp_path):
    """FMI 3.0 Feedthrough's outputs are its inputs (their readme): each integer width at its
    bound comes back exactly, a Float32 as the float32 nearest to what was set, a Boolean."""
    fmu = reference_fmu("Feedthrough", 3)
    out = tmp_path / "f.csv"
    sets = {f"{t}_input": bounds[end] for t, bounds in WIDTHS.items()}
    sets.update({"Float32_continuous_input": 0.1, "Float64_continuous_input": -2.5, "Boolean_input": bool(end)})
    assert cli.main(["simulate", str(fmu), "--stop-time", "0.1", "-o", str(out)]
                    + [f"--set={k}={'true' if v is True else 'false' if v is False else v}" for k, v in sets.items()]) == 0
    names, table = read_csv(out)
    last = dict(zip(names, table[-1]))
    for t, bounds in WIDTHS.items():       # the CSV's 12 digits hold 32 bits exactly
        assert last[f"{t}_output"] == pytest.approx(bounds[end], rel=0 if "32" in t or "8" in t or "16" in t
                                                    else 1e-11), t
    r = simulate(fmu, parameters=sets, stop_time=0.1)      # the table itself: exact, 64 bits up to 2**53
    row = dict(zip(r.names, r.array()[-1]))
    for t, bounds in WIDTHS.items():
        assert row[f"{t}_output"] == bounds[end], t
    assert last["Float32_continuous_output"] == pytest.approx(float(np.float32(0.1)), rel=1e-11)  # the CSV's 12 digits
    assert last["Float32_continuous_output"] != pytest.approx(0.1, rel=1e-11)
    assert last["Float64_continuous_output"] == -2.5
    assert last["Boolean_output"] == float(end)


@pytest.mark.parametrize("name,value,words", [
    ("Int8_input", 128, "outside the range of an FMI 3.0 Int8 (-128..127)"),
    ("UInt8_input", -1, "outside the range of an FMI 3.0 UInt8 (0..255)"),
    ("UInt64_input", 2**64, "outside the range of an FMI 3.0 UInt64"),
    ("Int64_input", -2**63 - 1, "outside the range of an FMI 3.0 Int64"),
    ("UInt16_input", 1.5, "not an integer"),
    ("Float32_continuous_input", "1e39", "outside the range of an FMI 3.0 Float32"),
    ("Binary_input", "00", "Binary"),
])
def test_feedthrough_fmi3_refuses_a_value_outside_its_type(name, value, words, tmp_path, capsys):
    fmu = reference_fmu("Feedthrough", 3)
    out = tmp_path / "f.csv"
    assert cli.main(["simulate", str(fmu), "--set", f"{name}={value}", "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert words in err and name in err and "Traceback" not in err, err
    assert not out.exists()


def test_fmi3_terminate_simulation_ends_the_run(tmp_path, monkeypatch, capsys):
    """fmi3DoStep saying terminateSimulation (FMI 3.0 4.2.1) at its lastSuccessfulTime ends the
    run there as a normal end: the rows up to that time, exit 0, the end said."""
    from artibus.fmu.result import Termination
    from fmpy.fmi3 import FMU3Slave
    from conftest import fmu3
    real = FMU3Slave.doStep

    def step(self, t, h, *a, **k):
        event, _, early, last = real(self, t, h, *a, **k)
        return (event, True, early, last) if t + h > 0.45 else (event, False, early, last)

    monkeypatch.setattr(FMU3Slave, "doStep", step)
    r = simulate(fmu3("TrainGuidance"), stop_time=2.0, step=0.1)
    assert r.terminated == Termination("TrainGuidance", pytest.approx(0.5), "terminateSimulation")
    assert r.array()[-1, 0] == pytest.approx(0.5) and len(r.rows) == 6    # 0, 0.1, ..., 0.5
    out = tmp_path / "t.csv"
    assert cli.main(["simulate", str(fmu3("TrainGuidance")), "--stop-time", "2", "--step", "0.1", "-o", str(out)]) == 0
    assert "TrainGuidance ended the simulation at t = 0.5 s (terminateSimulation)" in capsys.readouterr().out
    assert len(read_csv(out)[1]) == 6


@pytest.mark.parametrize("folder", ["", "fmi3/"], ids=["resources", "resources-fmi3"])
def test_a_bench_of_fmi3_reference_fmus_equals_fmpy(folder, tmp_path):
    """FMI 3.0 FMUs of others in a bench (their .ssd source resources/<Name>.fmu or
    resources/fmi3/<Name>.fmu), through the core's fmi3 calls: Dahlquist's x as FMPy
    computes it alone"""
    elements = (_component("Stair", [("counter", "output", "Integer")], folder)
                + _component("Dahlquist", [("x", "output", "Real")], folder))
    ssp = bench_ssp(tmp_path / "S.ssp", elements, "",
                    {f"resources/{folder}{m}.fmu": reference_fmu(m, 3) for m in ("Stair", "Dahlquist")})
    with Simulation(ssp, step=0.2, record=["Dahlquist.x"]) as sim:
        r = sim.run()
        assert sim.stepping == "C core"
    _, theirs = fmpy_table(reference_fmu("Dahlquist", 3), 0.2)
    assert len(r.time) == 51
    np.testing.assert_array_equal(r["Dahlquist.x"], theirs[:, 1])
