"""One FMU model for FMI 2.0 and 3.0 (issue 37, artibus.fmu.model, artibus.fmu.fmi2/fmi3):
each variable as its modelDescription.xml declares it (its own type, shape and unit, read
here with lxml, not with the code under test), arrays moved whole, Event Mode for any FMI 3.0
FMU that has it, no "FMI 2.0 view" left.

The kinds are the families of SSP's type choice, written here from the standard's text
(SSP 2.0 docs/4___common_content.adoc, "Type Choice"; "Transformation Choice": a
LinearTransformation is valid for Real, Float64 or Float32 connectors, an
IntegerMappingTransformation for the integer types)."""
import math
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from lxml import etree

from artibus.base import fmu_dir

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / ".tools" / "reference-fmus"

SSP_FAMILY = {"Real": "Real", "Float64": "Real", "Float32": "Real", "Boolean": "Boolean", "String": "String",
              "Enumeration": "Enumeration", "Binary": "Binary", "Clock": "Clock",
              **{t: "Integer" for t in ("Integer", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32",
                                        "Int64", "UInt64")}}


def fmus():
    ours = sorted(fmu_dir().glob("*.fmu")) + sorted((fmu_dir() / "fmi3").glob("*.fmu"))
    theirs = sorted(REFERENCE.glob("*.fmu")) + sorted((REFERENCE / "fmi3").glob("*.fmu"))
    return [f for f in ours + theirs if f.name != "Clocks.fmu"]      # (Scheduled Execution only)


def declared(path):
    """[(name, valueReference, type, shape, unit)] as the XML declares each variable"""
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    units = {}
    for t in root.iterfind("TypeDefinitions/*"):
        el = t if root.get("fmiVersion") != "2.0" else next(c for c in t if isinstance(c.tag, str))
        units[t.get("name")] = el.get("unit")
    out, elements = [], list(root.iterfind("ModelVariables/*"))
    starts = {int(e.get("valueReference")): e.get("start") for e in elements}
    for e in elements:
        if root.get("fmiVersion") == "2.0":
            e = next(c for c in e if isinstance(c.tag, str)) if e.tag == "ScalarVariable" else e
            owner = e.getparent()
        else:
            owner = e
        shape = tuple(int(d.get("start")) if d.get("start") is not None else int(starts[int(d.get("valueReference"))])
                      for d in owner.iterfind("Dimension"))
        unit = e.get("unit") or units.get(e.get("declaredType"))
        out.append((owner.get("name"), int(owner.get("valueReference")), e.tag, shape, unit))
    return out


@pytest.mark.parametrize("path", fmus(), ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_each_variable_is_as_the_model_description_declares_it(path):
    from artibus.fmu.model import model_of
    model = model_of(read_model_description(str(path)))
    got = [(v.name, v.valueReference, v.type, v.shape, v.unit) for v in model.modelVariables]
    assert got == declared(path)
    for v in model.modelVariables:
        assert v.kind == SSP_FAMILY[v.type]
        assert v.size == (math.prod(v.shape) if v.shape else 1)
    with zipfile.ZipFile(path) as z:
        version = etree.fromstring(z.read("modelDescription.xml")).get("fmiVersion")
    assert model.fmi == (2 if version == "2.0" else 3)


def test_no_fmi2_view_is_left():
    """an FMI 3.0 FMU is read as itself: no copy of its description under FMI 2.0's type names"""
    import artibus.bench.fmi as fmi
    assert not hasattr(fmi, "fmi2_view") and not hasattr(fmi, "FMI2_TYPE")
    src = ROOT / "src" / "artibus"
    said = [p for p in src.rglob("*.py") if "fmi2_view" in p.read_text() or "FMI2_TYPE" in p.read_text()]
    assert not said


def linear_transform():
    path = REFERENCE / "fmi3" / "LinearTransform.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/build_reference_fmus.sh; needs cargo)")
    return path


def test_an_array_fmu_runs_to_the_closed_form(tmp_path):
    """y = A u (LinearTransform, FMI 3.0, y[m], A[m,n], u[n], m = n = 2): with A = [[1, 2],
    [3, 4]] (row-major) and u = [5, 6], y = [17, 39] at every point, one column per element"""
    from artibus.fmu import simulate
    r = simulate(linear_transform(), parameters={"A": [1.0, 2.0, 3.0, 4.0]},
                 inputs={"u": lambda t: [5.0, 6.0]}, stop_time=1.0, step=0.25)
    assert r.names == ["time", "y[1]", "y[2]"]
    np.testing.assert_array_equal(np.array(r.rows)[:, 1:], [[17.0, 39.0]] * 5)


def test_an_array_fmu_alone_on_the_command_line_equals_fmpy(tmp_path):
    import fmpy
    path = linear_transform()
    out = tmp_path / "lt.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    header = out.read_text().splitlines()[0].replace('"', "").split(",")
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    theirs = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", output_interval=table[1, 0] - table[0, 0])
    assert header == ["time", "y[1]", "y[2]"]
    np.testing.assert_array_equal(table[:, 1:], np.asarray(theirs["y"], dtype=float)[:len(table)])


def test_a_wrong_number_of_values_for_an_array_is_an_error_naming_it():
    from artibus.base import ArtibusError
    from artibus.fmu import Fmu
    with Fmu(linear_transform()) as f:
        f.enter_initialization_mode()
        with pytest.raises(ArtibusError, match=r"A: an array of 4 values \(2x2\), given 3"):
            f.set_values({"A": [1.0, 2.0, 3.0]})


NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"')


def _ssp(path, elements, connections, files):
    from artibus.testing import pack_ssp, ssd_text
    return pack_ssp(path, ssd_text(elements, connections or None, 1, path.stem, system_name=path.stem), files)


def _component(name, fmu, connectors):
    conns = "".join(f'<ssd:Connector name="{n}" kind="{k}"><ssc:{t}/></ssd:Connector>' for n, k, t in connectors)
    return (f'<ssd:Component name="{name}" source="resources/{fmu}.fmu" type="application/x-fmu-sharedlibrary">'
            f'<ssd:Connectors>{conns}</ssd:Connectors></ssd:Component>')


def test_an_array_in_a_bench_is_recorded_element_wise(tmp_path):
    """(issue 38; refused before, when a bench carried scalars only) LinearTransform's y at its
    start values (A the identity, u = [1, 2]: the XML's): y = [1, 2], a column per element;
    connections of arrays: tests/test_bench_arrays.py"""
    ssp = _ssp(tmp_path / "A.ssp", _component("LT", "LinearTransform", [("y", "output", "Real")]), "",
               {"resources/LinearTransform.fmu": linear_transform()})
    out = tmp_path / "a.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(ssp), "--step", "0.5", "-o", str(out)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    header = out.read_text().splitlines()[0].replace('"', "").split(",")
    assert header == ["time", "LT.y[1]", "LT.y[2]"]
    np.testing.assert_array_equal(np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:], [[1.0, 2.0]] * 3)


@pytest.mark.parametrize("value, passes", [(100, True), (300, False)])
def test_an_integer_into_a_narrower_one_is_passed_in_range_and_refused_outside(value, passes, tmp_path):
    """FMI 3.0 Feedthrough's Int32_output into another's Int8_input (both of SSP's Integer
    family): 100 arrives as 100; 300 is outside Int8's [-128, 127] (FMI 3.0 2.4.7.4.2),
    an error naming the connection, never a wrapped 44"""
    feed = REFERENCE / "fmi3" / "Feedthrough.fmu"
    if not feed.is_file():
        pytest.skip(f"{feed} not built")
    elements = (_component("A", "Feedthrough", [("Int32_input", "input", "Integer"),
                                                ("Int32_output", "output", "Integer")])
                + _component("B", "Feedthrough", [("Int8_input", "input", "Integer"),
                                                  ("Int8_output", "output", "Integer")]))
    conn = ('<ssd:Connection startElement="A" startConnector="Int32_output" endElement="B" '
            'endConnector="Int8_input"/>')
    ssp = _ssp(tmp_path / "I.ssp", elements, conn, {"resources/Feedthrough.fmu": feed})
    out = tmp_path / "i.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(ssp), "--step", "0.5", "--set",
                        f"A.Int32_input={value}", "--record", "B.Int8_output", "-o", str(out)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert "Traceback" not in p.stderr
    if passes:
        assert p.returncode == 0, p.stderr
        assert np.loadtxt(out, delimiter=",", skiprows=1)[-1, 1] == value
    else:
        assert p.returncode == 1
        assert "A.Int32_output -> B.Int8_input" in p.stderr and "300 is outside the range" in p.stderr, p.stderr


def test_event_mode_of_any_fmi3_fmu_that_has_it():
    """eventModeUsed: after fmi3ExitInitializationMode the instance is in Event Mode (FMI 3.0
    4.2.1), leaves it after the discrete states settle; a clock set in Step Mode, an Event Mode
    asked of an FMU without hasEventMode or of an FMI 2.0 FMU: errors naming them"""
    from artibus.base import ArtibusError
    from artibus.fmu import Fmu
    with Fmu(linear_transform(), event_mode=True) as f:
        f.initialize({})
        assert f.calls.mode == "event"
        f.calls.leave_event_mode()
        assert f.calls.mode == "step" and f.do_step(0.0, 0.5) is None
        with pytest.raises(ArtibusError, match="fmi3SetClock in Step Mode"):
            f.calls.set_clocks([1])
    dahlquist = REFERENCE / "fmi3" / "Dahlquist.fmu"
    if dahlquist.is_file() and not read_model_description(str(dahlquist)).coSimulation.hasEventMode:
        with pytest.raises(ArtibusError, match="has no Event Mode"):
            Fmu(dahlquist, event_mode=True)
    with pytest.raises(ArtibusError, match="FMI 2.0 FMU: no Event Mode"):
        Fmu(fmu_dir() / "CanBus.fmu" if (fmu_dir() / "CanBus.fmu").is_file() else fmu_dir() / "SteeringECU.fmu",
            event_mode=True)


def test_the_lsbus_network_runs_on_the_one_fmu_model():
    """the FMI-LS-BUS master's node and bus instances are artibus.fmu.Fmu instances, their
    Event Mode artibus.fmu.fmi3's (no wrapper of its own)"""
    from artibus.fmu import Fmu
    from artibus.fmu.fmi3 import Calls
    from artibus.runner.lsbus import Network
    f3 = fmu_dir() / "fmi3"
    nodes = {"sensors": (f3 / "SteeringSensors_LSBUS.fmu", {}), "ecu": (f3 / "SteeringECU_LSBUS.fmu", {})}
    with Network(nodes) as net:
        for f in net.nodes:
            assert isinstance(f.instance, Fmu) and isinstance(f.calls, Calls) and f.calls.event_mode_used
        net.run(0.05)
        assert all(f.n_events > 0 for f in net.nodes)


def test_structural_parameters_resize_the_arrays(tmp_path):
    """m = 3, n = 2 set in Configuration Mode (FMI 3.0 2.3): A is 3x2, u 2, y 3; with
    A = [[1, 2], [3, 4], [5, 6]] and u = [1, 1], y = [3, 7, 11], in three columns"""
    out = tmp_path / "lt.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(linear_transform()), "--set", "m=3",
                        "--set", "n=2", "--set", "A=1 2 3 4 5 6", "--set", "u=1 1", "--stop-time", "1",
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    header = out.read_text().splitlines()[0].replace('"', "").split(",")
    assert header == ["time", "y[1]", "y[2]", "y[3]"]
    np.testing.assert_array_equal(np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:], [[3.0, 7.0, 11.0]] * 501)


@pytest.mark.parametrize("sets, words", [
    (["m=3", "A=1 2 3 4"], "LinearTransform.A is an array of 6 values (3x2), given 4"),
    (["m=6"], "is outside [1, 5] of LinearTransform"),
    (["u=1 x"], "not a valid Float64 for LinearTransform.u"),
])
def test_a_wrong_structural_or_array_value_is_an_error_naming_it(sets, words, tmp_path):
    args = [a for s in sets for a in ("--set", s)]
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(linear_transform()), *args,
                        "-o", str(tmp_path / "x.csv")], capture_output=True, text=True)
    assert p.returncode == 1 and "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert words in p.stderr, p.stderr
