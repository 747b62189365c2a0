"""One typing rule for SSP 1.0 and 2.0 benches, and units a parameter file may not redefine
(issue 41, classes 4, 5 and 10).

Each bad binding is written into an SSP 1.0 bench (Urbino18_Circle: the driver's inline
values) and into an SSP 2.0 bench (Bus36m_Circle_LSBUS: an FMI-LS-BUS node's or the bus
simulation FMU's inline values); `artibus run` and `artibus check` of each refuse it with the
same message, built here from the FMUs' modelDescription.xml (the variable's type, min and
max) and the line lxml reads the value at: "<file>:<line>: Parameter '<Comp.var>' = <value>:
<reason>". The same for an input connected twice. A unit defined twice in one file, or an SI
unit's name given another factor, is an error naming the file and the line; `artibus check`
of a parameter file lists the units it uses with their factors."""
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from lxml import etree

from artibus.bench import ssp as ssp_mod
from artibus.bench.ssd import NS

ARTIBUS = Path(sys.executable).parent / "artibus"
SSV_NS = ('xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
          'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')
BENCH = {"1.0": "Urbino18_Circle", "2.0": "Bus36m_Circle_LSBUS"}


def artibus(*args):
    """(exit code, stderr) of the artibus command"""
    r = subprocess.run([str(ARTIBUS), *map(str, args)], capture_output=True, text=True, timeout=600)
    return r.returncode, r.stderr.strip()


def edited(tmp_path, version, edit, name="bad"):
    """a copy of the bench's .ssp whose .ssd ``edit(root)`` changed; edit returns the element
    the message is to name: (the .ssp, the .ssd's name in messages, that element's line)"""
    src = ssp_mod.ssp_path(BENCH[version])
    with zipfile.ZipFile(src) as z:
        members = {n: z.read(n) for n in z.namelist()}
    tree = etree.ElementTree(etree.fromstring(members["SystemStructure.ssd"]))
    path = tree.getelementpath(edit(tree.getroot()))
    text = etree.tostring(tree, xml_declaration=True, encoding="UTF-8")
    line = etree.fromstring(text).getroottree().find(path).sourceline    # the line as written
    out = tmp_path / f"{name}.ssp"
    with zipfile.ZipFile(out, "w") as z:
        for n, data in members.items():
            z.writestr(n, text if n == "SystemStructure.ssd" else data)
    return out, f"{out}/SystemStructure.ssd", line


def component(root, name):
    return next(c for c in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS) if c.get("name") == name)


def bind(comp, var, kind, value, unit=None):
    """comp's inline value of var set to <ssv:kind value=...> (replacing its own): the Parameter"""
    params = comp.find("ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/ssv:ParameterSet/"
                       "ssv:Parameters", NS)
    old = next((p for p in params.iterfind("ssv:Parameter", NS) if p.get("name") == var), None)
    p = etree.SubElement(params, f"{{{NS['ssv']}}}Parameter", name=var)
    if old is not None:
        old.addprevious(p)
        params.remove(old)
    v = etree.SubElement(p, f"{{{NS['ssv']}}}{kind}", value=value)
    if unit:
        v.set("unit", unit)
    return p


def variable(fmu, name):
    """(type, min, max, unit) of an FMU's variable, from its modelDescription.xml"""
    with zipfile.ZipFile(fmu) as z:
        md = etree.fromstring(z.read("modelDescription.xml"))
    v = next(v for v in md.iter() if v.get("name") == name and v.get("valueReference") is not None)
    t = v if v.tag not in ("ScalarVariable",) else next(c for c in v if isinstance(c.tag, str))
    return t.tag, t.get("min"), t.get("max"), t.get("unit")      # (the type as the FMU names it)


def fmu_of(version, comp):
    from artibus import fmu_path
    model = {"Driver": "RoadFollowDriver", "ECU1": "SteeringECU_LSBUS", "CanBus": "CanBus"}[comp]
    return model, fmu_path(f"fmi3/{model}" if version == "2.0" and comp != "Driver" else model)


# (case) -> {version: (component, variable, ssv element, value, unit)}; the reason's template
CASES = {
    "Real 2.7 -> Integer": ({"1.0": ("Driver", "nSpeed", "Real", "2.7", None),
                             "2.0": ("ECU1", "module", "Real", "2.7", None)},
                            "not a valid {vtype} for {model}.{var}: not an integer (an Integer is not rounded)"),
    "Real 2.7 -> Boolean": ({"1.0": ("Driver", "testVehicle", "Real", "2.7", None),
                             "2.0": ("CanBus", "wireTime", "Real", "2.7", None)},
                            "not a valid {vtype} for {model}.{var}: a Boolean is true, false, 1 or 0"),
    "Integer 2 -> Boolean": ({"1.0": ("Driver", "testVehicle", "Integer", "2", None),
                              "2.0": ("CanBus", "wireTime", "Integer", "2", None)},
                             "not a valid {vtype} for {model}.{var}: a Boolean is true, false, 1 or 0"),
    "above max": ({"1.0": ("Driver", "nSpeed", "Integer", "11", None),
                   "2.0": ("ECU1", "module", "Integer", "4", None)}, "outside"),
    "below min": ({"1.0": ("Driver", "nSpeed", "Integer", "-5", None),
                   "2.0": ("ECU1", "module", "Integer", "0", None)}, "outside"),
    "NaN -> Integer": ({"1.0": ("Driver", "nSpeed", "Real", "NaN", None),
                        "2.0": ("ECU1", "module", "Real", "NaN", None)},
                       "not a valid {vtype} for {model}.{var}: not an integer (an Integer is not rounded)"),
    "a unit of another dimension": ({"1.0": ("Driver", "vSet", "Real", "3", "rad"),
                                     "2.0": ("ECU1", "vDir", "Real", "1", "rad")}, "dimension"),
    "a unit on an Integer": ({"1.0": ("Driver", "nSpeed", "Real", "2", "m"),
                              "2.0": ("ECU1", "module", "Real", "2", "m")},
                             "a value with a unit ('m') for {model}.{var}, an {vtype}: a unit belongs to a Real "
                             "value (give the value without a unit)"),
}


def expected(version, case, line, where):
    """the message, as the rule says it, from the FMU's own description"""
    (spec, reason) = CASES[case]
    comp, var, kind, value, unit = spec[version]
    model, fmu = fmu_of(version, comp)
    vtype, lo, hi, vunit = variable(fmu, var)
    shown = {"Real": repr(float(value)), "Integer": value}[kind] + (f" {unit}" if unit else "")
    head = f"artibus: error: {where}:{line}: Parameter '{comp}.{var}' = {shown}"
    if reason == "outside":
        assert vtype in ("Integer", "Int32") and not int(lo) <= int(value) <= int(hi)
        return re.escape(f"{head} is outside [{lo}, {hi}] of {model}")
    if reason == "dimension":
        return (re.escape(f"{head}: unit '{unit}' (") + r"[^)]*" + re.escape(f") cannot be converted to the "
                f"variable's unit '{vunit}' (") + r"[^)]*" + re.escape("): another dimension"))
    return re.escape(f"{head}: {reason.format(model=model, var=var, vtype=vtype)}")


@pytest.mark.parametrize("command", ["run", "check"])
@pytest.mark.parametrize("version", ["1.0", "2.0"])
@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_binding_is_refused_alike_in_ssp_1_and_2(tmp_path, case, version, command):
    comp, var, kind, value, unit = CASES[case][0][version]
    ssp, where, line = edited(tmp_path, version, lambda root: bind(component(root, comp), var, kind, value, unit))
    args = ["run", ssp, "--stop-time", "0.04", "-o", tmp_path / "out.csv"] if command == "run" else ["check", ssp]
    code, err = artibus(*args)
    assert code != 0 and re.fullmatch(expected(version, case, line, where), err), err
    assert not (tmp_path / "out.csv").exists()


def connect(root, start, end):
    """one more Connection start -> end ("Comp.connector"), after the others: that Connection"""
    conns = root.find("ssd:System/ssd:Connections", NS)
    (a, ca), (b, cb) = start.split(".", 1), end.split(".", 1)
    c = etree.SubElement(conns, f"{{{NS['ssd']}}}Connection", startElement=a, startConnector=ca,
                         endElement=b, endConnector=cb)
    return c


TWICE = {"1.0": [("Bus.x[0]", "Driver.y")],
         "2.0": [("Bus.v", "ECU1.vVehicle"),            # a node's input fed twice
                 ("Driver.delta", "Bus.delta[2]")]}     # a plant input fed by a node (Act1) and the driver


@pytest.mark.parametrize("command", ["run", "check"])
@pytest.mark.parametrize("version, start, end", [(v, s, e) for v, pairs in TWICE.items() for s, e in pairs])
def test_an_input_connected_twice_is_refused_alike(tmp_path, version, start, end, command):
    ssp, where, line = edited(tmp_path, version, lambda root: connect(root, start, end))
    args = ["run", ssp, "--stop-time", "0.04", "-o", tmp_path / "out.csv"] if command == "run" else ["check", ssp]
    code, err = artibus(*args)
    assert code != 0 and err == (f"artibus: error: {where}:{line}: Connection {start} -> {end}: "
                                 f"input {end} is connected twice"), err


# ---- LS-BUS: clock associations (SSP 2.0 ssd:Connector's ssd:Clock) ----------------------

def clock_of(root, comp, connector, name):
    """the connector's clock association renamed (None: removed): the Connector"""
    k = next(k for k in component(root, comp).iterfind("ssd:Connectors/ssd:Connector", NS)
             if k.get("name") == connector)
    assoc = k.find("ssd:Clock", NS)
    if name is None:
        k.remove(assoc)
    else:
        assoc.set("name", name)
    return k


@pytest.mark.parametrize("command", ["run", "check"])
@pytest.mark.parametrize("name, what", [(None, "no clock association <Clock name=\"SteeringCAN.Tx_Clock\">"),
                                        ("vVehicle", "<Clock name=\"vVehicle\">: vVehicle is an ssc:Float64 "
                                                     "connector, not an ssc:Clock"),
                                        ("SteeringCAN.Rx_Clock", "<Clock name=\"SteeringCAN.Rx_Clock\">: the "
                                                                 "FMU's SteeringCAN.Tx_Data is clocked by "
                                                                 "SteeringCAN.Tx_Clock"),
                                        ("nothing", "<Clock name=\"nothing\">: ECU1 has no connector 'nothing'")])
def test_a_clock_association_missing_or_not_a_clock_is_refused(tmp_path, name, what, command):
    ssp, where, line = edited(tmp_path, "2.0", lambda root: clock_of(root, "ECU1", "SteeringCAN.Tx_Data", name))
    args = ["run", ssp, "--stop-time", "0.04", "-o", tmp_path / "out.csv"] if command == "run" else ["check", ssp]
    code, err = artibus(*args)
    assert code != 0 and err.startswith(f"artibus: error: {where}:{line}: <Connector name=\"SteeringCAN.Tx_Data\"> "
                                        f"of ECU1: {what}"), err


# ---- units --------------------------------------------------------------------------------

def ssv(tmp_path, units, value="6100", unit="mm", name="WithUnits.ssv"):
    """a BusKinematics set (Urbino18's L0 given with a unit) with the <ssv:Units> given"""
    text = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet {SSV_NS} version="1.0" name="u">\n'
            '<ssv:Parameters>\n<ssv:Parameter name="N"><ssv:Integer value="1"/></ssv:Parameter>\n'
            f'<ssv:Parameter name="L0"><ssv:Real value="{value}" unit="{unit}"/></ssv:Parameter>\n'
            '<ssv:Parameter name="L[1]"><ssv:Real value="6.9"/></ssv:Parameter>\n'
            '<ssv:Parameter name="Lh[1]"><ssv:Real value="1.5"/></ssv:Parameter>\n</ssv:Parameters>\n'
            f'<ssv:Units>\n{units}</ssv:Units>\n</ssv:ParameterSet>\n')
    path = tmp_path / name
    path.write_text(text)
    return path, text


def unit(name, factor, **exponents):
    e = " ".join(f'{k}="{v}"' for k, v in exponents.items())
    return f'<ssc:Unit name="{name}"><ssc:BaseUnit {e} factor="{factor}"/></ssc:Unit>\n'


def line_of(text, needle, nth=1):
    lines = [k + 1 for k, l in enumerate(text.splitlines()) if needle in l]
    return lines[nth - 1]


@pytest.mark.parametrize("units, needle, nth, what", [
    # 6100 mm read as 6100 m
    (unit("mm", 0.001, m=1) + unit("mm", 1, m=1), '<ssc:Unit name="mm"', 2, "defined twice"),
    (unit("m", 1000, m=1), '<ssc:Unit name="m"', 1, "SI unit"),                                      # m as 1000 m
    (unit("s", 60, s=1), '<ssc:Unit name="s"', 1, "SI unit"),
    (unit("kg", 1, m=1), '<ssc:Unit name="kg"', 1, "SI unit"),                                       # another dimension
    (unit("N", 1000, kg=1, m=1, s=-2), '<ssc:Unit name="N"', 1, "SI unit"),
    (unit("rad", 0.0174532925199433, rad=1), '<ssc:Unit name="rad"', 1, "SI unit"),
])
def test_a_unit_defined_twice_or_an_si_unit_redefined_is_an_error_naming_file_and_line(tmp_path, units, needle,
                                                                                           nth, what):
    path, text = ssv(tmp_path, units)
    code, err = artibus("check", path)
    assert code != 0 and err.startswith(f"artibus: error: {path}:{line_of(text, needle, nth)}: <Unit "), err
    assert what in err, err


def test_a_duplicate_unit_in_a_bench_ssd_is_an_error_naming_its_line(tmp_path):
    def edit(root):
        units = etree.Element(f"{{{NS['ssd']}}}Units")
        root.find("ssd:System", NS).addnext(units)
        for factor in ("0.001", "1"):
            u = etree.SubElement(units, f"{{{NS['ssc']}}}Unit", name="mm")
            etree.SubElement(u, f"{{{NS['ssc']}}}BaseUnit", m="1", factor=factor)
        bind(component(root, "Driver"), "R", "Real", "17500", "mm")
        return u
    for version in ("1.0", "2.0"):
        ssp, where, line = edited(tmp_path, version, edit, name=f"units{version}")
        for args in (["check", ssp], ["run", ssp, "--stop-time", "0.04", "-o", tmp_path / "out.csv"]):
            code, err = artibus(*args)
            head = f"artibus: error: {where}:{line}: <Unit name=\"mm\">: defined twice"
            assert code != 0 and err.startswith(head), err


def test_check_reports_the_units_a_file_uses_and_their_factors(tmp_path):
    # (SI's own definitions of its units are no redefinition: accepted as new names are)
    path, text = ssv(tmp_path, unit("mm", 0.001, m=1) + unit("t", 1000, kg=1) + unit("m", 1, m=1)
                     + unit("rad", 1, rad=1) + unit("N", 1, kg=1, m=1, s=-2))
    r = subprocess.run([str(ARTIBUS), "check", str(path)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    rows = [l.split() for l in r.stdout.splitlines()]
    mm = next(row for row in rows if row[:1] == ["mm"])
    # mm: 0.001 of the base unit m, defined at its line of the file; t is defined but not used
    line = line_of(text, '<ssc:Unit name="mm"')
    assert mm[1:4] == ["0.001", "0", "m"] and mm[4] == f"{path}:{line}", r.stdout
    assert not any(row[:1] == ["t"] for row in rows), r.stdout


def test_a_unit_on_an_integer_in_a_run_ssv_is_a_clean_message(tmp_path):
    """`artibus run --ssv` with a unit on an Integer: the message names the file, the line and
    the value with its unit, no Python repr (Quantity(...))"""
    f = tmp_path / "user.ssv"
    text = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet {SSV_NS} version="1.0" name="u">\n'
            '<ssv:Parameters>\n<ssv:Parameter name="Driver.nSpeed"><ssv:Real value="2" unit="m"/>'
            '</ssv:Parameter>\n</ssv:Parameters>\n</ssv:ParameterSet>\n')
    f.write_text(text)
    code, err = artibus("run", ssp_mod.ssp_path("Urbino18_Circle"), "--stop-time", "0.04", "--ssv", f,
                        "-o", tmp_path / "out.csv")
    line = line_of(text, "Driver.nSpeed")
    assert code != 0 and err == (f"artibus: error: {f}:{line}: Parameter 'Driver.nSpeed' = 2.0 m: a value with a unit "
                                 "('m') for RoadFollowDriver.nSpeed, an Integer: a unit belongs to a Real value "
                                 "(give the value without a unit)"), err


@pytest.mark.parametrize("command", ["run", "check"])
def test_an_ssp2_plant_binding_of_ssp2_s_types_is_bound_as_ssp1_s(tmp_path, command):
    """SSP 2.0's value elements (Float64, Int32) on an SSP 2.0 bench's plant component: the
    message of the same value as an SSP 1.0 Real on the same FMU's variable (the driver's
    nSpeed), and a good value runs (before: "= None: not a valid Integer")"""
    ssp, where, line = edited(tmp_path, "2.0", lambda root: bind(component(root, "Driver"), "nSpeed", "Float64", "2.7"))
    args = ["run", ssp, "--stop-time", "0.04", "-o", tmp_path / "out.csv"] if command == "run" else ["check", ssp]
    code, err = artibus(*args)
    assert code != 0 and re.fullmatch(expected("1.0", "Real 2.7 -> Integer", line, where), err), err
    ok, _, _ = edited(tmp_path, "2.0", lambda root: bind(component(root, "Driver"), "vSet", "Float64", "3.0"), "ok")
    args = ["run", ok, "--stop-time", "0.04", "-o", tmp_path / "ok.csv"] if command == "run" else ["check", ok]
    code, err = artibus(*args)
    assert code == 0, err
