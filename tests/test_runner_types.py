"""Every FMI 2.0 type through the runner and `artibus simulate` (issue 15),
with the project's test FMU TypesTest (its outputs plain functions of its
inputs: real_out = factor real_in, int_out = int_in + offset, bool_out =
bool_in xor invert, string_out = prefix + string_in, enum_out = enum_in,
count = the steps taken), one logger per FMU instance, and user mistakes
answered by a message naming the file, element and value, never a traceback."""
import math
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from artibus import ArtibusError, fmu_path
from artibus import testing
from artibus.fmu import DEFAULT_STEPS, simulate
from artibus.runner import Simulation, SimulationError

NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
      'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
      'xmlns:ssm="http://ssp-standard.org/SSP1/SystemStructureParameterMapping"')
TYPES = {"real": "Real", "int": "Integer", "bool": "Boolean", "string": "String", "enum": "Enumeration"}
ARTIBUS = [sys.executable, "-m", "artibus"]


def comp(name, fmu, connectors, extra=""):
    """connectors: (name, kind); the type element left out (optional in SSP 1.0)."""
    conns = "".join(f'<ssd:Connector name="{n}" kind="{k}"/>' for n, k in connectors)
    return (f'<ssd:Component name="{name}" source="resources/{fmu}.fmu" type="application/x-fmu-sharedlibrary">'
            f'<ssd:Connectors>{conns}</ssd:Connectors>{extra}</ssd:Component>')


def conn(a, ca, b, cb, body=""):
    return (f'<ssd:Connection startElement="{a}" startConnector="{ca}" endElement="{b}" endConnector="{cb}">'
            f'{body}</ssd:Connection>')


def make_ssp(tmp_path, elements, connections, stop=1.0, files=None, fmus=("TypesTest",), name="types"):
    return testing.make_ssp(tmp_path, elements, connections or None, stop, ssv=files, name=name, fmu=False,
                            fmus=fmus)


def outs(*names):
    return [(f"{n}_out", "output") for n in names]


def ins(*names):
    return [(f"{n}_in", "input") for n in names]


# T3's parameters from a parameter set of every type, through an SSP parameter
# mapping with each of SSP 1.0's transformations
T3_SSV = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="t3">'
          '<ssv:Parameters>'
          '<ssv:Parameter name="f"><ssv:Real value="1.5"/></ssv:Parameter>'
          '<ssv:Parameter name="n"><ssv:Integer value="7"/></ssv:Parameter>'
          '<ssv:Parameter name="b"><ssv:Boolean value="true"/></ssv:Parameter>'
          '<ssv:Parameter name="s"><ssv:String value="S:"/></ssv:Parameter>'
          '<ssv:Parameter name="e"><ssv:Enumeration value="on"/></ssv:Parameter>'
          '</ssv:Parameters></ssv:ParameterSet>')
T3_MAPPING = ('<ssd:ParameterMapping><ssm:ParameterMapping version="1.0">'
              '<ssm:MappingEntry source="f" target="factor"><ssc:LinearTransformation factor="2"/></ssm:MappingEntry>'
              '<ssm:MappingEntry source="n" target="offset"><ssc:IntegerMappingTransformation>'
              '<ssc:MapEntry source="7" target="8"/></ssc:IntegerMappingTransformation></ssm:MappingEntry>'
              '<ssm:MappingEntry source="b" target="invert"><ssc:BooleanMappingTransformation>'
              '<ssc:MapEntry source="true" target="false"/></ssc:BooleanMappingTransformation></ssm:MappingEntry>'
              '<ssm:MappingEntry source="s" target="prefix"/>'
              '<ssm:MappingEntry source="e" target="enum_in"><ssc:EnumerationMappingTransformation>'
              '<ssc:MapEntry source="on" target="auto"/></ssc:EnumerationMappingTransformation></ssm:MappingEntry>'
              '</ssm:ParameterMapping></ssd:ParameterMapping>')


def types_bench(tmp_path, ssv=T3_SSV):
    """T1 -> T2 every type (and T1's count into its own int_in), T2.real_out ->
    the Real model Z (ZeroSideslipSteering) -> T3, T3 bound through T3_MAPPING."""
    binding = ('<ssd:ParameterBindings><ssd:ParameterBinding source="resources/t3.ssv">'
               f'{T3_MAPPING}</ssd:ParameterBinding></ssd:ParameterBindings>')
    elements = (comp("T1", "TypesTest", ins("int") + outs(*TYPES) + [("count", "output")])
                + comp("T2", "TypesTest", ins(*TYPES) + outs(*TYPES))
                + comp("Z", "ZeroSideslipSteering", [("delta1", "input"), ("delta[1]", "output")])
                + comp("T3", "TypesTest", ins("real") + outs(*TYPES), binding))
    connections = ("".join(conn("T1", f"{t}_out", "T2", f"{t}_in") for t in TYPES)
                   + conn("T1", "count", "T1", "int_in")
                   + conn("T2", "real_out", "Z", "delta1") + conn("Z", "delta[1]", "T3", "real_in"))
    return make_ssp(tmp_path, elements, connections, files={"t3.ssv": ssv},
                    fmus=("TypesTest", "ZeroSideslipSteering"))


SETS = {"T1.real_in": "0.05", "T1.offset": "5", "T1.bool_in": "1", "T1.string_in": 'a"b c',
        "T1.enum_in": "auto", "T2.prefix": "X,", "T2.invert": "false"}


def test_every_type_through_a_bench_connected_to_itself_and_a_real_model(tmp_path):
    with Simulation(types_bench(tmp_path), step=0.1, overrides=SETS) as sim:
        r = sim.run()
        assert sim.stepping == "C core; in Python: Integer, Boolean, String or Enumeration variables"
    n = len(r.time)
    assert n == 11
    k = np.arange(n)
    # Integer: T1.count -> T1.int_in is the count at the step's start (k - 1 at row k; 0 at
    # the initialisation), plus the --set offset 5; T2 adds its own 1: exact values
    np.testing.assert_array_equal(r["T1.count"], k)
    np.testing.assert_array_equal(r["T1.int_out"], 5 + np.maximum(k - 1, 0))
    np.testing.assert_array_equal(r["T2.int_out"], 6 + np.maximum(k - 1, 0))
    # Boolean as 0/1: T1 inverts the --set true, T2 (invert false) passes it on
    np.testing.assert_array_equal(r["T1.bool_out"], 0.0)
    np.testing.assert_array_equal(r["T2.bool_out"], 0.0)
    # Enumeration by item name: auto = 3
    np.testing.assert_array_equal(r["T1.enum_out"], 3.0)
    np.testing.assert_array_equal(r["T2.enum_out"], 3.0)
    # String: T2's prefix before T1's
    assert list(r["T1.string_out"]) == ['T:a"b c'] * n
    assert list(r["T2.string_out"]) == ['X,T:a"b c'] * n
    # Real: 2 * 2 * 0.05 into Z, whose front axle passes delta1 on (K[1] = 1), into T3
    np.testing.assert_allclose(r["T2.real_out"], 0.2, rtol=1e-15)
    np.testing.assert_allclose(r["Z.delta[1]"][1:], 0.2, rtol=1e-12)
    # T3 through the parameter mapping: factor 2 * 1.5, offset 7 -> 8, invert true -> false,
    # prefix S:, enum_in on -> auto
    np.testing.assert_allclose(r["T3.real_out"], 3.0 * r["Z.delta[1]"], rtol=1e-15)
    np.testing.assert_array_equal(r["T3.int_out"], 8.0)
    np.testing.assert_array_equal(r["T3.bool_out"], 0.0)
    np.testing.assert_array_equal(r["T3.enum_out"], 3.0)
    assert set(r["T3.string_out"]) == {"S:"}


def test_recording_and_csv_of_every_type(tmp_path):
    record = ["T1.count", "T1.bool_out", "T2.string_out", "T2.enum_out", "T1.real_out", "T1.invert"]
    with Simulation(types_bench(tmp_path), step=0.25, overrides=SETS, record=record) as sim:
        r = sim.run()
    assert r.names == ["time"] + record
    out = tmp_path / "r.csv"
    r.to_csv(out)
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(f'"{n}"' for n in r.names)
    # t, count, bool_out 0/1, the String quoted (CSV's "" for a quote), enum 3, real, invert 1
    assert lines[-1] == '1,4,0,"X,T:a""b c",3,0.1,1'
    assert len(lines) == 1 + 5
    # MAT: a String column as a cell array of its texts, the others as numbers
    from scipy.io import loadmat
    from artibus.runner import save
    m = loadmat(save(r, tmp_path / "r.mat"))
    assert [str(x[0]) for x in m["T2_string_out"][0]] == ['X,T:a"b c'] * 5
    np.testing.assert_array_equal(m["T1_count"][0], [0, 1, 2, 3, 4])


def test_integer_connection_carries_values_beyond_float32_exactly(tmp_path):
    """16777217 = 2^24 + 1 is not a float32; int_out = int_in + offset exactly."""
    path = make_ssp(tmp_path, comp("A", "TypesTest", outs("int")) + comp("B", "TypesTest", ins("int") + outs("int")),
                    conn("A", "int_out", "B", "int_in"))
    with Simulation(path, step=0.5, overrides={"A.int_in": "16777216", "B.offset": "-1000000"}) as sim:
        r = sim.run()
    np.testing.assert_array_equal(r["A.int_out"], 16777217)
    np.testing.assert_array_equal(r["B.int_out"], 16777217 - 1000000)


def test_ssp_mapping_transformations_on_connections(tmp_path):
    body = {"bool": '<ssc:BooleanMappingTransformation><ssc:MapEntry source="false" target="true"/>'
                    '</ssc:BooleanMappingTransformation>',
            "int": '<ssc:IntegerMappingTransformation><ssc:MapEntry source="1" target="42"/>'
                   '</ssc:IntegerMappingTransformation>',
            "enum": '<ssc:EnumerationMappingTransformation><ssc:MapEntry source="off" target="on"/>'
                    '</ssc:EnumerationMappingTransformation>'}
    path = make_ssp(tmp_path, comp("A", "TypesTest", outs("bool", "int", "enum"))
                    + comp("B", "TypesTest", ins("bool", "int", "enum") + outs("bool", "int", "enum")),
                    "".join(conn("A", f"{t}_out", "B", f"{t}_in", b) for t, b in body.items()))
    # A: bool_out = !false = true (not in the map: passes), int_out 0 + 1 = 1 -> 42, enum off -> on
    with Simulation(path, step=0.5, overrides={"B.invert": "false", "B.offset": "0"}) as sim:
        r = sim.run()
    np.testing.assert_array_equal(r["B.bool_out"], 1.0)
    np.testing.assert_array_equal(r["B.int_out"], 42.0)
    np.testing.assert_array_equal(r["B.enum_out"], 2.0)


@pytest.mark.parametrize("a, b, words", [
    ("int_out", "real_in", ["A.int_out -> B.real_in", "A.int_out is Integer", "B.real_in is Real"]),
    ("bool_out", "int_in", ["A.bool_out -> B.int_in", "A.bool_out is Boolean", "B.int_in is Integer"]),
    ("string_out", "enum_in", ["A.string_out -> B.enum_in", "A.string_out is String", "B.enum_in is Enumeration"]),
    ("real_out", "bool_in", ["A.real_out -> B.bool_in", "A.real_out is Real", "B.bool_in is Boolean"]),
])
def test_a_wrong_type_connection_names_both_ends(tmp_path, a, b, words):
    path = make_ssp(tmp_path, comp("A", "TypesTest", [(a, "output")]) + comp("B", "TypesTest", [(b, "input")]),
                    conn("A", a, "B", b))
    with pytest.raises(ArtibusError) as e:
        Simulation(path, step=0.1)
    for w in words + ["SystemStructure.ssd:1: Connection"]:
        assert w in str(e.value)


@pytest.mark.parametrize("name, value, words", [
    ("T1.offset", "3.7", ["'T1.offset' = '3.7'", "Integer", "not rounded"]),
    ("T1.bool_in", "yes", ["'T1.bool_in' = 'yes'", "true, false, 1 or 0"]),
    ("T1.enum_in", "sideways", ["'T1.enum_in' = 'sideways'", "off (1), on (2), auto (3)"]),
    ("T1.enum_in", "4", ["'T1.enum_in' = '4'", "4 is not an item of Mode"]),
    ("T1.real_in", "nan", ["'T1.real_in' = 'nan'", "not a finite number"]),
    ("T1.int_out", "1", ["'T1.int_out'", "it is an output"]),
    ("T1.int_inn", "1", ["no variable 'int_inn'", "did you mean 'int_in'"]),
])
def test_a_wrong_value_is_an_error_naming_element_and_value(tmp_path, name, value, words):
    with pytest.raises(ArtibusError) as e:
        Simulation(types_bench(tmp_path), step=0.1, overrides={name: value})
    for w in words:
        assert w in str(e.value)


def test_an_ssv_real_for_an_integer_is_not_truncated(tmp_path):
    ssv = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet ' + NS + ' version="1.0" name="a">'
           '<ssv:Parameters><ssv:Parameter name="offset"><ssv:Real value="3.7"/></ssv:Parameter>'
           '</ssv:Parameters></ssv:ParameterSet>')
    binding = ('<ssd:ParameterBindings><ssd:ParameterBinding source="resources/a.ssv"/>'
               '</ssd:ParameterBindings>')
    path = make_ssp(tmp_path, comp("A", "TypesTest", outs("int"), binding) + comp("B", "TypesTest", ins("int")),
                    conn("A", "int_out", "B", "int_in"), files={"a.ssv": ssv})
    with pytest.raises(ArtibusError) as e:
        Simulation(path, step=0.1)
    assert "types.ssp/resources/a.ssv:1: Parameter 'A.offset' = 3.7" in str(e.value)
    assert "not rounded" in str(e.value)
    # through the mapping of an Integer: the same value refused there, naming the entry
    path = types_bench(tmp_path, T3_SSV.replace('<ssv:Integer value="7"/>', '<ssv:Real value="3.7"/>'))
    with pytest.raises(ArtibusError) as e:
        Simulation(path, step=0.1)
    assert 'MappingEntry source="n" target="offset"' in str(e.value) and "3.7" in str(e.value)


def test_simulate_every_type_alone_with_set_of_each_type(tmp_path):
    r = simulate(fmu_path("TypesTest"), parameters={"real_in": "1.25", "int_in": "-3", "bool_in": "0",
                                                     "string_in": "x", "enum_in": "2", "prefix": "",
                                                     "invert": "true", "offset": "10", "factor": "4"})
    assert r.names == ["time", "real_out", "int_out", "bool_out", "string_out", "enum_out", "count"]
    np.testing.assert_array_equal(r["real_out"], 5.0)
    np.testing.assert_array_equal(r["int_out"], 7.0)
    np.testing.assert_array_equal(r["bool_out"], 1.0)
    np.testing.assert_array_equal(r["enum_out"], 2.0)
    np.testing.assert_array_equal(r["count"], np.arange(11))
    assert set(r["string_out"]) == {"x"}


def fmu_without_step_size(tmp_path):
    """TypesTest with a default experiment that has no stepSize (FMI 2.0 allows it)."""
    src, dst = fmu_path("TypesTest"), tmp_path / "NoStep.fmu"
    with zipfile.ZipFile(src) as zi, zipfile.ZipFile(dst, "w") as zo:
        for item in zi.infolist():
            data = zi.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b' stepSize="0.1"', b"")
                assert b"stepSize" not in data
            zo.writestr(item, data)
    return dst


def test_default_experiment_without_step_size(tmp_path):
    r = simulate(fmu_without_step_size(tmp_path))
    assert len(r.time) == DEFAULT_STEPS + 1
    assert r.time[-1] == pytest.approx(1.0)
    np.testing.assert_array_equal(r["count"], np.arange(DEFAULT_STEPS + 1))


def test_a_bench_component_without_step_size(tmp_path):
    """Alone: the bench's span / DEFAULT_STEPS; beside a component with a step: that step."""
    nostep = fmu_without_step_size(tmp_path).read_bytes()
    alone = make_ssp(tmp_path, comp("A", "NoStep", outs("int")), "", files={"NoStep.fmu": nostep},
                     fmus=(), name="alone")
    with Simulation(alone) as sim:
        r = sim.run()
    assert len(r.time) == DEFAULT_STEPS + 1
    np.testing.assert_array_equal(r["A.int_out"], 1.0)
    both = make_ssp(tmp_path, comp("A", "NoStep", outs("int")) + comp("B", "TypesTest", ins("int") + outs("int")),
                    conn("A", "int_out", "B", "int_in"), files={"NoStep.fmu": nostep}, name="both")
    with Simulation(both) as sim:
        r = sim.run()
    assert [u.step for u in sim.units] == [0.1, 0.1]
    np.testing.assert_array_equal(r["B.int_out"], 2.0)


def run_cli(*args, cwd=None):
    p = subprocess.run(ARTIBUS + [str(a) for a in args], capture_output=True, text=True, cwd=cwd, timeout=300)
    assert "Traceback" not in p.stderr + p.stdout, p.stderr
    return p


def test_cli_simulate_every_type_and_no_step_size(tmp_path):
    out = tmp_path / "t.csv"
    p = run_cli("simulate", fmu_without_step_size(tmp_path), "--set", "string_in=q", "--set", "enum_in=on",
                "--set", "bool_in=true", "--set", "int_in=41", "-o", out)
    assert p.returncode == 0, p.stderr
    lines = out.read_text().splitlines()
    assert lines[0] == '"time","real_out","int_out","bool_out","string_out","enum_out","count"'
    assert len(lines) == 1 + DEFAULT_STEPS + 1
    assert lines[-1] == f'1,0,42,0,"T:q",2,{DEFAULT_STEPS}'


# the mistakes through a subprocess of `artibus`; the others in this process (faster)
@pytest.mark.parametrize("sub, args, words", [
    (True, ["run", "Scania18m_LaneChange", "--set", "Bus.m[1]=abc"], ["'Bus.m[1]' = 'abc'", "not a number"]),
    (True, ["run", "Scania18m_LaneChange", "--set", "Bus.nModules=2.5"], ["'Bus.nModules' = '2.5'", "not rounded"]),
    (True, ["run", "Scania18m_LaneChange", "--stop-time", "inf"], ["inf"]),
    (True, ["simulate", "TypesTest", "--stop-time", "inf"], ["inf"]),
    (True, ["simulate", "missing/Nothing.fmu"], ["missing/Nothing.fmu", "no such FMU file"]),
    (False, ["simulate", "TypesTest", "--set", "int_in=3.7"], ["int_in", "3.7", "not rounded"]),
    (False, ["simulate", "TypesTest", "--set", "bool_in=yes"], ["bool_in", "yes", "true, false, 1 or 0"]),
    (False, ["simulate", "TypesTest", "--step", "nan"], ["nan"]),
    (False, ["simulate", "TypesTst"], ["no such FMU; did you mean TypesTest"]),
    (False, ["run", "Scania18m_LaneChange", "--set", "Bus.FzFromMasses=yes"], ["'Bus.FzFromMasses' = 'yes'"]),
    (False, ["run", "Scania18m_LaneChange", "--set", "Bus.mu[9]=0.5"], ["mu[9]", "mu has indices 1..8"]),
    (False, ["run", "Scania18m_LaneChange", "--set", "Buss.mu[1]=0.5"], ["no component 'Buss'", "did you mean 'Bus'"]),
    (False, ["run", "Scania18m_LaneChange", "--record", "Bus.vx[7]"], ["vx has indices 1..4"]),
    (False, ["run", "Scania18m_LaneChang"], ["did you mean Scania18m_LaneChange"]),
])
def test_cli_user_mistakes_are_messages_not_tracebacks(sub, args, words, capsys, tmp_path):
    if sub:
        p = run_cli(*args)
        code, err = p.returncode, p.stderr
    else:
        from artibus.cli import main
        try:
            code = main(args + (["-o", str(tmp_path / "out.csv")] if "-o" not in args else []))
        except SystemExit as e:      # argparse's usage errors
            code = e.code
        err = capsys.readouterr().err
    assert code not in (0, None)
    for w in words:
        assert w in err, err


def test_cli_a_corrupt_fmu_inside_an_ssp_is_named(tmp_path):
    path = make_ssp(tmp_path, comp("A", "Broken", outs("int")) + comp("B", "TypesTest", ins("int")),
                    conn("A", "int_out", "B", "int_in"), files={"Broken.fmu": b"not a zip file"})
    p = run_cli("run", path, "-o", tmp_path / "r.csv")
    assert p.returncode == 1
    assert "Component 'A'" in p.stderr and 'resources/Broken.fmu' in p.stderr and "not a readable" in p.stderr


def test_each_message_reaches_the_instance_that_sent_it(tmp_path):
    """Three FMUs; the first instantiated fails (a NaN fed by a stimulus): its own
    message is in the error, naming it, and in its log only."""
    path = make_ssp(tmp_path, comp("First", "TypesTest", ins("real") + outs("real"))
                    + comp("Z", "ZeroSideslipSteering", [("delta1", "input"), ("delta[1]", "output")])
                    + comp("Last", "TypesTest", ins("real") + outs("real")),
                    conn("First", "real_out", "Z", "delta1") + conn("Z", "delta[1]", "Last", "real_in"),
                    fmus=("TypesTest", "ZeroSideslipSteering"))
    with Simulation(path, step=0.1, stimuli={"First.real_in": lambda t: math.nan if t >= 0.45 else 0.0}) as sim:
        with pytest.raises(SimulationError) as e:
            sim.run()
        logs = {u.path: list(u.fmu.log) for u in sim.units}
    msg = str(e.value)
    assert "component 'First' failed at t = 0.5 s" in msg and "real_in = nan" in msg
    assert any("real_in = nan" in m for m in logs["First"])
    assert not any("real_in" in m for m in logs["Last"] + logs["Z"])
    assert len(e.value.result.time) == 6           # rows 0 .. 0.5 s kept


def test_an_initialisation_failure_names_the_component(tmp_path):
    """The middle FMU's check fails at the initialisation (its prefix and input
    together too long for its String output): its message, its name."""
    path = make_ssp(tmp_path, comp("A", "TypesTest", outs("real")) + comp("B", "TypesTest", ins("real") + outs("real"))
                    + comp("C", "TypesTest", ins("real")),
                    conn("A", "real_out", "B", "real_in") + conn("B", "real_out", "C", "real_in"))
    long = "x" * 600
    with Simulation(path, step=0.1, overrides={"B.prefix": long, "B.string_in": long}) as sim:
        with pytest.raises(SimulationError) as e:
            sim.run()
    assert "component 'B' failed at t = 0 s" in str(e.value) and "prefix + string_in is 1200 bytes" in str(e.value)


def test_messages_reach_their_instance_after_fmpy_ran_an_fmu_of_its_own():
    """fmpy.simulate_fmu takes the logger proxy's one pointer for its own
    logger (and frees it): ours takes it back before it calls the FMU again."""
    import gc
    from fmpy import simulate_fmu
    from fmpy.fmi1 import FMICallException
    from artibus.fmu import Fmu
    with Fmu(fmu_path("TypesTest"), instance_name="Mine") as f:
        simulate_fmu(str(fmu_path("TypesTest")))
        gc.collect()
        f.initialize({})
        with pytest.raises(FMICallException):
            f.set_values({"real_in": math.nan})
        assert any("real_in = nan" in m for m in f.log), f.log
