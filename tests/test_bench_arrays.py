"""FMI 3.0 arrays in a bench (issue 38): an array output connected to an array input of the
same shape reaches it element by element, and both are recorded one column per element.

What the standards say, read for these tests:
- FMI 3.0 2.2.6.2 (getting and setting values): an array variable is set and got whole, its
  values in row-major order; 2.4.7.6 (<Dimension>): a size fixed by ``start`` or given by a
  structural parameter's value (set in Configuration Mode, 2.3).
- SSP 2.0 docs/5___ssd.adoc, Connection: ``startIndices``/``endIndices`` "If not supplied this
  indicates that this connection applies to the whole connector"; Connector: one or more
  <Dimension> "making the connector an array connector". A whole array goes to a whole array;
  two arrays of different shapes cannot be joined element by element: an error naming both.

The FMU: the Reference-FMUs' LinearTransform (y[m] = A[m,n] u[n], m and n structural
parameters, 1..5). The closed forms are computed here with numpy from the A and u given."""
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
LT = ROOT / ".tools" / "reference-fmus" / "fmi3" / "LinearTransform.fmu"
NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
      'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')


@pytest.fixture
def lt():
    if not LT.is_file():
        pytest.skip(f"{LT} not built (scripts/build_reference_fmus.sh; needs cargo)")
    return LT


def ssv(**values):
    """an SSP 1.0 parameter set of Integer values (LinearTransform's UInt64 m and n)"""
    ps = "".join(f'<ssv:Parameter name="{k}"><ssv:Integer value="{v}"/></ssv:Parameter>' for k, v in values.items())
    return (f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {NS} version="1.0" name="p">'
            f'<ssv:Parameters>{ps}</ssv:Parameters></ssv:ParameterSet>')


def component(name, bound=None):
    binding = (f'<ssd:ParameterBindings><ssd:ParameterBinding source="resources/{name}.ssv"/>'
               '</ssd:ParameterBindings>' if bound else "")
    return (f'<ssd:Component name="{name}" source="resources/LinearTransform.fmu">'
            '<ssd:Connectors><ssd:Connector name="u" kind="input"/><ssd:Connector name="y" kind="output"/>'
            f'</ssd:Connectors>{binding}</ssd:Component>')


def bench(tmp_path, lt, bindings):
    """L1.y -> L2.u, each component's structural parameters bound by an .ssv (``bindings``:
    {component: {parameter: value}})"""
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="1.0" name="arr">\n'
           '<ssd:System name="arr"><ssd:Elements>'
           + component("L1", bindings.get("L1")) + component("L2", bindings.get("L2"))
           + '</ssd:Elements><ssd:Connections>\n'
           '<ssd:Connection startElement="L1" startConnector="y" endElement="L2" endConnector="u"/>\n'
           '</ssd:Connections></ssd:System><ssd:DefaultExperiment startTime="0" stopTime="1"/>'
           '</ssd:SystemStructureDescription>')
    path = tmp_path / "arr.ssp"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.write(lt, "resources/LinearTransform.fmu")
        for name, values in bindings.items():
            z.writestr(f"resources/{name}.ssv", ssv(**values))
    return path


def run(path, tmp_path, *sets):
    out = tmp_path / "out.csv"
    args = [a for s in sets for a in ("--set", s)]
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(path), "--step", "0.25", *args, "-o", str(out)],
                       capture_output=True, text=True, cwd=tmp_path)
    return p, out


def test_an_array_output_reaches_an_array_input_element_wise(lt, tmp_path):
    """m = n = 2 for both: L2.y = A2 (A1 u1), each element its own column (row-major, 1-based)"""
    a1, u1, a2 = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([5.0, 6.0]), np.array([[0.0, 1.0], [-1.0, 2.0]])
    p, out = run(bench(tmp_path, lt, {}), tmp_path, "L1.A=1 2 3 4", "L1.u=5 6", "L2.A=0 1 -1 2")
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    y1, y2 = a1 @ u1, a2 @ (a1 @ u1)
    for k in range(2):
        np.testing.assert_array_equal(table[f"L1.y[{k + 1}]"], y1[k])
        np.testing.assert_array_equal(table[f"L2.y[{k + 1}]"][1:], y2[k])    # (from the first step on)


def test_a_structural_parameter_set_in_the_bench_resizes_the_connection(lt, tmp_path):
    """m = 3 on L1 (its y has 3 elements), n = 3 on L2 (its u has 3): the connection carries
    3 values; A1 3x2, A2 2x3"""
    a1 = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    u1 = np.array([1.0, -1.0])
    a2 = np.array([[1.0, 0.0, 2.0], [0.0, -1.0, 1.0]])
    path = bench(tmp_path, lt, {"L1": {"m": 3}, "L2": {"n": 3}})
    p, out = run(path, tmp_path, "L1.A=" + " ".join(map(str, a1.ravel())), "L1.u=1 -1",
                 "L2.A=" + " ".join(map(str, a2.ravel())))
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    assert [n for n in table.dtype.names if n.startswith("L1.y")] == ["L1.y[1]", "L1.y[2]", "L1.y[3]"]
    assert [n for n in table.dtype.names if n.startswith("L2.y")] == ["L2.y[1]", "L2.y[2]"]
    y1 = a1 @ u1
    for k in range(3):
        np.testing.assert_array_equal(table[f"L1.y[{k + 1}]"], y1[k])
    for k in range(2):
        np.testing.assert_array_equal(table[f"L2.y[{k + 1}]"][1:], (a2 @ y1)[k])


def test_arrays_of_different_shapes_are_an_error_naming_both(lt, tmp_path):
    """L1.y has 3 elements (m = 3), L2.u 2 (n = 2): refused before the run, naming the file,
    the connection's line, both connectors and both shapes"""
    p, _ = run(bench(tmp_path, lt, {"L1": {"m": 3}}), tmp_path)
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    err = p.stderr
    assert "arr.ssp" in err and ":3:" in err, err          # the Connection is on the .ssd's line 3
    assert "L1.y -> L2.u" in err and "L1.y is Float64[3]" in err and "L2.u is Float64[2]" in err, err


FT = ROOT / ".tools" / "reference-fmus" / "fmi3" / "Feedthrough.fmu"


def element_bench(tmp_path, lt, indices):
    """SSP 2.0 (startIndices is SSP 2.0's): L.y[indices[0]] -> F.Float64_continuous_input and
    L.A[indices[1]] -> F.Float64_discrete_input (Feedthrough: each output its input)"""
    if not FT.is_file():
        pytest.skip(f"{FT} not built")
    f = ('<ssd:Component name="F" source="resources/Feedthrough.fmu"><ssd:Connectors>'
         '<ssd:Connector name="Float64_continuous_input" kind="input"/>'
         '<ssd:Connector name="Float64_discrete_input" kind="input"/>'
         '<ssd:Connector name="Float64_continuous_output" kind="output"/>'
         '<ssd:Connector name="Float64_discrete_output" kind="output"/></ssd:Connectors></ssd:Component>')
    lc = ('<ssd:Component name="L" source="resources/LinearTransform.fmu"><ssd:Connectors>'
          '<ssd:Connector name="y" kind="output"/><ssd:Connector name="A" kind="parameter"/>'
          '</ssd:Connectors></ssd:Component>')
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="2.0" name="el">\n'
           f'<ssd:System name="el"><ssd:Elements>{lc}{f}</ssd:Elements><ssd:Connections>\n'
           f'<ssd:Connection startElement="L" startConnector="y" {indices[0]} endElement="F" '
           'endConnector="Float64_continuous_input"/>\n'
           f'<ssd:Connection startElement="L" startConnector="A" {indices[1]} endElement="F" '
           'endConnector="Float64_discrete_input"/>\n'
           '</ssd:Connections></ssd:System><ssd:DefaultExperiment startTime="0" stopTime="1"/>'
           '</ssd:SystemStructureDescription>')
    path = tmp_path / "el.ssp"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.write(lt, "resources/LinearTransform.fmu")
        z.write(FT, "resources/Feedthrough.fmu")
    return path


def test_one_element_of_an_array_reaches_a_scalar_input(lt, tmp_path):
    """SSP 2.0's startIndices name one element (1-based, an index per dimension, row-major as
    FMI 3.0 orders an array): y[2] = (A u)[2] = 3*5 + 4*6 = 39 and A[2,1] = 3 reach Feedthrough's
    scalar inputs, whose outputs give them back"""
    path = element_bench(tmp_path, lt, ('startIndices="2"', 'startIndices="2 1"'))
    p, out = run(path, tmp_path, "L.A=1 2 3 4", "L.u=5 6")
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    assert "Indices" not in p.stderr, p.stderr               # (applied, not "not applied")
    import csv
    with open(out, newline="") as f:
        header, *rows = list(csv.reader(f))                # (L.A[1,2]: a quoted name with a comma)
    table = np.array(rows, dtype=float)
    assert header[3:7] == ["L.A[1,1]", "L.A[1,2]", "L.A[2,1]", "L.A[2,2]"]
    np.testing.assert_array_equal(table[:, 3:7], [[1.0, 2.0, 3.0, 4.0]] * len(table))
    np.testing.assert_array_equal(table[1:, header.index("F.Float64_continuous_output")], 39.0)
    np.testing.assert_array_equal(table[1:, header.index("F.Float64_discrete_output")], 3.0)


@pytest.mark.parametrize("indices, words", [
    (('startIndices="3"', 'startIndices="1 1"'), 'startIndices="3" do not name an element of L.y, Float64[2]'),
    (('startIndices="1"', 'startIndices="2"'), 'startIndices="2" do not name an element of L.A, Float64[2,2]'),
    (('', 'startIndices="1 1"'), "the shapes differ (L.y is Float64[2], F.Float64_continuous_input is Float64)"),
    (('startIndices="1" endIndices="1"', ''), 'endIndices="1": the runner connects into a whole array or a scalar'),
])
def test_indices_that_do_not_fit_are_an_error_naming_them(lt, tmp_path, indices, words):
    p, _ = run(element_bench(tmp_path, lt, indices), tmp_path)
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert "el.ssp" in p.stderr and words in p.stderr, p.stderr
