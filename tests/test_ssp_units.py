"""Units on parameter values (issue 25, SSP 1.0: ``<ssv:Real value="5128"
unit="mm"/>``, the unit defined in the file's <ssv:Units> by its BaseUnit
exponents and factor): converted to the FMU variable's unit, so a set in mm
and t.m2 gives what the SI set gives, bit for bit (5128 mm = 5.128 m and
68.8 t.m2 = 68800 kg.m2 are exact in binary once converted, as the SI file's
numbers); through `artibus simulate --ssv`, a bench's binding and a parameter
mapping. An unknown unit, or one of another dimension, is an error naming the
file, the parameter and both units. Our own sets (SI, the FMUs' own unit
names) are applied unchanged."""
import re

import numpy as np
import pytest

from artibus import ArtibusError, fmu_path
from artibus.bench import check, ssp
from artibus.bench.parameters import PARAMETER_DIR, read_parameters
from artibus.fmu import simulate
from artibus.runner import run
from artibus.testing import make_ssp
from test_runner import NS, QUIET, component, connection

SI = PARAMETER_DIR / "Scania18m.ssv"
UNITS = ('<ssv:Units><ssc:Unit name="mm"><ssc:BaseUnit m="1" factor="0.001"/></ssc:Unit>'
         '<ssc:Unit name="t.m2"><ssc:BaseUnit kg="1" m="2" factor="1000"/></ssc:Unit>'
         '<ssc:Unit name="t"><ssc:BaseUnit kg="1" factor="1000"/></ssc:Unit></ssv:Units>')


def rewritten(tmp_path, changes, units=UNITS, name="Scania18m_mm.ssv"):
    """Scania18m.ssv with {parameter: (value, unit)} changed, and <ssv:Units> added."""
    text = SI.read_text()
    for p, (value, unit) in changes.items():
        pat = rf'(<ssv:Parameter name="{re.escape(p)}"><ssv:Real) value="[^"]*" unit="[^"]*"'
        text, n = re.subn(pat, rf'\1 value="{value}" unit="{unit}"', text)
        assert n == 1, p
    text = text.replace("</ssv:Parameters>", "</ssv:Parameters>" + units, 1)
    path = tmp_path / name
    path.write_text(text)
    return path


MM = {"lHf[1]": ("5128", "mm"), "Jz[1]": ("68.8", "t.m2"), "Jz[2]": ("52.9", "t.m2")}


def test_the_si_set_is_what_the_file_says():
    """The references: the SI file's own numbers, applied unchanged."""
    p = read_parameters(SI, fmu_path("BusDynamics"))
    assert (p["lHf[1]"], p["Jz[1]"], p["Jz[2]"]) == (5.128, 68800.0, 52900.0)


def test_mm_and_t_m2_give_the_si_results_through_simulate(tmp_path):
    """`artibus simulate BusDynamics --ssv` with the set in mm and t.m2: the SI run, bit for bit
    (steered by the FMU's test stimulus, so that lHf and Jz act)."""
    fmu = fmu_path("BusDynamics")
    si, mm = read_parameters(SI, fmu), read_parameters(rewritten(tmp_path, MM), fmu)
    assert si == mm
    a = simulate(fmu, parameters={**si, "testSteerAmp": 0.05}, stop_time=2.0, step=0.01)
    b = simulate(fmu, parameters={**mm, "testSteerAmp": 0.05}, stop_time=2.0, step=0.01)
    assert max(abs(a["artAngle[1]"])) > 0.01
    for n in a.names:
        np.testing.assert_array_equal(a[n], b[n], err_msg=n)


def _bus_bench(tmp_path, ssv_path, name):
    bus = ('<ssd:Component name="Bus" source="resources/BusDynamics.fmu"><ssd:ParameterBindings>'
           '<ssd:ParameterBinding source="resources/vehicle.ssv"/></ssd:ParameterBindings></ssd:Component>')
    return make_ssp(tmp_path, bus, None, 1, ssv={"vehicle.ssv": ssv_path}, name=name, fmu=False,
                    fmus=["BusDynamics"])


def test_mm_and_t_m2_give_the_si_results_bound_in_a_bench(tmp_path):
    a = ssp.read(_bus_bench(tmp_path, SI, "si"))
    b = ssp.read(_bus_bench(tmp_path, rewritten(tmp_path, MM), "mm"))
    assert a.components["Bus"].parameters == b.components["Bus"].parameters
    assert a.components["Bus"].converted == {}                       # SI: nothing to convert
    assert b.components["Bus"].converted["lHf[1]"] == (5128.0, "mm", 5.128, "m")
    ra = run(_bus_bench(tmp_path, SI, "si2"), step=0.01, overrides={"Bus.testSteerAmp": 0.05})
    rb = run(_bus_bench(tmp_path, rewritten(tmp_path, MM, name="b.ssv"), "mm2"), step=0.01,
             overrides={"Bus.testSteerAmp": 0.05})
    for n in ra.names:
        np.testing.assert_array_equal(ra[n], rb[n], err_msg=n)


@pytest.mark.parametrize("changes, units, words", [
    ({"lHf[1]": ("5128", "furlong")}, UNITS, ["unknown unit 'furlong'", "'m'"]),
    ({"lHf[1]": ("5.128", "t")}, UNITS, ["unit 't'", "'m'", "another dimension"]),
    ({"Jz[1]": ("68.8", "t")}, UNITS, ["unit 't'", "'kg.m2'", "another dimension"]),
])
def test_unknown_unit_and_wrong_dimension_name_file_parameter_and_units(tmp_path, changes, units, words):
    bad = rewritten(tmp_path, changes, units)
    param = next(iter(changes))
    for read, file in ((lambda: read_parameters(bad, fmu_path("BusDynamics")), str(bad)),
                       (lambda: ssp.read(_bus_bench(tmp_path, bad, "bad")), "bad.ssp/resources/vehicle.ssv")):
        with pytest.raises(ArtibusError) as e:
            read()
        msg = str(e.value)
        assert file in msg and f"'{param}" in msg.replace("'Bus.", "'") and all(w in msg for w in words), msg


def test_a_unit_through_a_parameter_mapping(tmp_path):
    """wheelbase in mm mapped to BusKinematics' L0 (m): converted, then the entry's
    LinearTransformation (SSP 1.0, 7.1.1); with suppressUnitConversion only the
    transformation. Either way L0 = 4 m (kappa0 = tan(gammaF) / L0, seed 003 eq. 19)."""
    vehicle = (f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {NS} version="1.0" name="v">'
               '<ssv:Parameters><ssv:Parameter name="wheelbase"><ssv:Real value="2000" unit="mm"/></ssv:Parameter>'
               '</ssv:Parameters><ssv:Units><ssc:Unit name="mm"><ssc:BaseUnit m="1" factor="0.001"/></ssc:Unit>'
               '</ssv:Units></ssv:ParameterSet>')
    for entry in ('<ssm:MappingEntry source="wheelbase" target="L0"><ssc:LinearTransformation factor="2"/></ssm:MappingEntry>',
                  '<ssm:MappingEntry source="wheelbase" target="L0" suppressUnitConversion="true">'
                  '<ssc:LinearTransformation factor="0.002"/></ssm:MappingEntry>'):
        mapping = (f'<ssd:ParameterMapping><ssm:ParameterMapping version="1.0">{entry}</ssm:ParameterMapping>'
                   f'</ssd:ParameterMapping>')
        binding = (f'<ssd:ParameterBindings><ssd:ParameterBinding source="resources/v.ssv">{mapping}'
                   '</ssd:ParameterBinding></ssd:ParameterBindings>')
        elements = (component("Lead", [("beta[1]", "output")])
                    + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], binding))
        path = make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"), 5,
                        ssv={"v.ssv": vehicle}, name="m")
        assert ssp.read(path).components["Follow"].parameters["L0"] == 4.0
        r = run(path, step=0.05, overrides=QUIET)
        np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(r["Lead.beta[1]"]) / 4.0, rtol=1e-12)


def test_check_reports_the_converted_values(tmp_path):
    lines = []
    assert check.main([str(rewritten(tmp_path, MM))], out=lines.append) == 0
    text = "\n".join(lines)
    assert "lHf[1] = 5128 mm: converted to 5.128 m" in text and "Jz[1] = 68.8 t.m2: converted to 68800 kg.m2" in text, text
    assert "consistent" in text, text


def test_our_benches_read_with_their_units():
    """Every bench's bound values: in the FMUs' units already (nothing converted)."""
    for name in ssp.bench_names():
        b = ssp.read(ssp.ssp_path(name))
        assert all(not c.converted for c in b.components.values()), name


def _follow_bench(tmp_path, binding="", units=""):
    elements = (component("Lead", [("beta[1]", "output")])
                + component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], binding))
    return make_ssp(tmp_path, elements, connection("Lead", "beta[1]", "Follow", "gammaF"), 5, name="f",
                    outer=units)


def test_an_inline_ssd_value_with_a_unit_of_the_ssds_units(tmp_path):
    inline = ('<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>'
              '<ssv:ParameterSet version="1.0" name="inline"><ssv:Parameters><ssv:Parameter name="L0">'
              '<ssv:Real value="4000" unit="mm"/></ssv:Parameter></ssv:Parameters></ssv:ParameterSet>'
              '</ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>')
    units = '<ssd:Units><ssc:Unit name="mm"><ssc:BaseUnit m="1" factor="0.001"/></ssc:Unit></ssd:Units>'
    b = ssp.read(_follow_bench(tmp_path, inline, units))
    assert b.components["Follow"].parameters["L0"] == 4.0
    assert b.components["Follow"].converted["L0"] == (4000.0, "mm", 4.0, "m")


def test_run_ssv_values_with_a_unit(tmp_path):
    """`artibus run --ssv FILE` (names Component.variable): converted where the runner knows the variable."""
    f = tmp_path / "user.ssv"
    f.write_text(f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {NS} version="1.0" name="u">'
                 '<ssv:Parameters><ssv:Parameter name="Follow.L0"><ssv:Real value="400" unit="cm"/></ssv:Parameter>'
                 '</ssv:Parameters><ssv:Units><ssc:Unit name="cm"><ssc:BaseUnit m="1" factor="0.01"/></ssc:Unit>'
                 '</ssv:Units></ssv:ParameterSet>')
    user = read_parameters(f, keep_units=True)
    r = run(_follow_bench(tmp_path), step=0.05, overrides={**QUIET, **user})
    np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(r["Lead.beta[1]"]) / 4.0, rtol=1e-12)
    bad = f.read_text().replace('name="cm"><ssc:BaseUnit m="1"', 'name="cm"><ssc:BaseUnit kg="1"')
    f.write_text(bad)
    with pytest.raises(ArtibusError, match=r"user\.ssv:1: Parameter 'Follow\.L0' = 400\.0 cm: unit 'cm' .*'m'"):
        run(_follow_bench(tmp_path), step=0.05, overrides=read_parameters(f, keep_units=True))
