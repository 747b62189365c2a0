"""SSP 1.0's parameter bindings at every level (issue 31): a binding on a
System (with ``prefix``, or names "Comp.var") gives what the same values bound
on the component give; a higher level takes precedence over a lower one
(SSP 1.0, 5.3.5: the system's over the component's, the root's over a
sub-system's); a mapping at system level; a system connector bound. The
checks are the FMUs' own kinematics (BusKinematics, seed 003 eq. 19: kappa0 =
tan(gammaF) / L0), independent of the runner. What the runner does not apply
is one warning naming the file and the element; `artibus check BENCH` lists it
with what is artibus-specific."""

import numpy as np
import pytest

from artibus import ArtibusError
from artibus.bench import portability
from artibus.bench.check import main as check_main
from artibus.runner import run
from artibus.testing import make_ssp
from test_runner import NS, QUIET, component, connection, mapping_entries, VEHICLE_SSV


def ssv(name, **values):
    params = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v!r}"/></ssv:Parameter>' for k, v in values.items())
    return (f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {NS} version="1.0" name="{name}">'
            f'<ssv:Parameters>{params}</ssv:Parameters></ssv:ParameterSet>')


def bindings(*items):
    """<ssd:ParameterBindings> of (source, prefix, inner XML) items."""
    out = "".join(f'<ssd:ParameterBinding source="resources/{s}"' + (f' prefix="{p}"' if p else "")
                  + f">{inner}</ssd:ParameterBinding>" for s, p, inner in items)
    return f"<ssd:ParameterBindings>{out}</ssd:ParameterBindings>"


def bench(tmp_path, name, elements, connections, system="", files=None, stop=6.0, after=""):
    """A .ssp whose root System carries ``system`` (its Connectors, ParameterBindings) before its Elements."""
    return make_ssp(tmp_path, elements, connections, stop, ssv=files, name=name, system=system, after=after)


FILES = {"four.ssv": ssv("four", L0=4.0), "eight.ssv": ssv("eight", L0=8.0),
         "follow4.ssv": ssv("follow4", **{"Follow.L0": 4.0}), "vehicle.ssv": VEHICLE_SSV}
LEAD = component("Lead", [("beta[1]", "output")])
LINK = connection("Lead", "beta[1]", "Follow", "gammaF")


def follow(extra=""):
    return component("Follow", [("gammaF", "input"), ("kappa[0]", "output")], extra)


def kappa(r, L0):
    return np.tan(r["Lead.beta[1]"]) / L0


@pytest.fixture(scope="module")
def on_component(tmp_path_factory):
    """The reference: L0 = 4 m bound on the component itself."""
    p = bench(tmp_path_factory.mktemp("ref"), "ref", LEAD + follow(bindings(("four.ssv", "", ""))), LINK, files=FILES)
    r = run(p, step=0.05, overrides=QUIET)
    assert np.max(np.abs(r["Lead.beta[1]"])) > 0.05           # it steers
    np.testing.assert_allclose(r["Follow.kappa[0]"], kappa(r, 4.0), rtol=1e-12)
    return r


@pytest.mark.parametrize("case", ["prefix", "hierarchical name", "over the component's own", "later binding wins"])
def test_a_system_level_binding_equals_the_component_binding(tmp_path, on_component, case):
    follow_own, system = {
        "prefix": ("", bindings(("four.ssv", "Follow.", ""))),
        "hierarchical name": ("", bindings(("follow4.ssv", "", ""))),
        # SSP 1.0: a binding at system level takes precedence over one at component level
        "over the component's own": (bindings(("eight.ssv", "", "")), bindings(("four.ssv", "Follow.", ""))),
        # and a later binding at one level over an earlier one
        "later binding wins": ("", bindings(("eight.ssv", "Follow.", ""), ("four.ssv", "Follow.", ""))),
    }[case]
    p = bench(tmp_path, "sys", LEAD + follow(follow_own), LINK, system=system, files=FILES)
    r = run(p, step=0.05, overrides=QUIET)
    for name in on_component.names:
        np.testing.assert_array_equal(r[name], on_component[name], err_msg=name)


@pytest.mark.parametrize("prefix", ["", "Follow."])
def test_a_mapping_at_system_level(tmp_path, on_component, prefix):
    """wheelbase_mm -> Follow.L0 (x 0.001) on the System: L0 = 4 m, as on the component; the
    prefix is prepended to the source's names before the mapping (SSP 1.0, ParameterBinding)."""
    entry = mapping_entries((f"{prefix}wheelbase_mm", "Follow.L0", 0.001))
    mapping = f'<ssd:ParameterMapping><ssm:ParameterMapping version="1.0">{entry}</ssm:ParameterMapping></ssd:ParameterMapping>'
    p = bench(tmp_path, "sysmap", LEAD + follow(), LINK, system=bindings(("vehicle.ssv", prefix, mapping)), files=FILES)
    r = run(p, step=0.05, overrides=QUIET)
    np.testing.assert_array_equal(r["Follow.kappa[0]"], on_component["Follow.kappa[0]"])


def test_sub_system_levels_and_a_system_connector(tmp_path, on_component):
    """Follow inside a sub-system Sub: Sub binds L0 = 8 m, the root binds Sub.Follow.L0 = 4 m
    and wins (the higher level); then the root binds Sub's parameter connector L0, connected
    to Follow.L0: the value reaches the FMU's variable."""
    sub_conn = ('<ssd:Connectors><ssd:Connector name="steer" kind="input"><ssc:Real/></ssd:Connector>'
                '<ssd:Connector name="L0" kind="parameter"><ssc:Real/></ssd:Connector></ssd:Connectors>')
    inner = component("Follow", [("gammaF", "input"), ("kappa[0]", "output"), ("L0", "parameter")])
    files = {**FILES, "sub4.ssv": ssv("sub4", **{"Sub.Follow.L0": 4.0}), "conn4.ssv": ssv("conn4", **{"Sub.L0": 4.0})}
    for root_binding, sub_extra in (("sub4.ssv", ""),
                                    ("conn4.ssv", connection(None, "L0", "Follow", "L0"))):
        sub = (f'<ssd:System name="Sub">{sub_conn}{bindings(("eight.ssv", "Follow.", ""))}<ssd:Elements>{inner}'
               f'</ssd:Elements><ssd:Connections>{connection(None, "steer", "Follow", "gammaF")}{sub_extra}'
               f'</ssd:Connections></ssd:System>')
        if sub_extra:   # the sub-system's own binding is then on the connector's target too
            sub = sub.replace(bindings(("eight.ssv", "Follow.", "")), "")
        p = bench(tmp_path, f"nested_{root_binding[:-4]}", LEAD + sub, connection("Lead", "beta[1]", "Sub", "steer"),
                  system=bindings((root_binding, "", "")), files=files)
        r = run(p, step=0.05, overrides={"Lead.testSteerAmp": 0.2, "Sub.Follow.testSteerAmp": 0.0})
        np.testing.assert_array_equal(r["Sub.Follow.kappa[0]"], on_component["Follow.kappa[0]"])


def test_a_system_level_name_that_names_nothing_is_an_error(tmp_path):
    files = {**FILES, "typo.ssv": ssv("typo", **{"Folow.L0": 4.0})}
    p = bench(tmp_path, "typo", LEAD + follow(), LINK, system=bindings(("typo.ssv", "", "")), files=files)
    with pytest.raises(ArtibusError) as e:
        run(p, step=0.05)
    msg = str(e.value)
    assert "typo.ssv" in msg and "'Folow.L0'" in msg and "Follow" in msg, msg


# ---- what the runner does not apply: one warning each, naming the file and the element -------------

UNKNOWN_ANNOTATION = ('<ssd:Annotations><ssc:Annotation type="com.example.solver">'
                      '<Solver xmlns="urn:example" order="4"/></ssc:Annotation></ssd:Annotations>')
UNKNOWN_ELEMENT = ('<ssd:SignalDictionaries><ssd:SignalDictionary name="bus">'
                   '<ssb:SignalDictionary xmlns:ssb="http://ssp-standard.org/SSP1/SystemStructureSignalDictionary" '
                   'version="1.0"/></ssd:SignalDictionary></ssd:SignalDictionaries>')


@pytest.mark.parametrize("what", ["annotation", "element", "attribute"])
def test_what_is_not_applied_is_one_warning_naming_file_and_element(tmp_path, capsys, what):
    elements = LEAD + (follow(UNKNOWN_ANNOTATION) if what == "annotation" else follow())
    link = LINK.replace("<ssd:Connection ", '<ssd:Connection suppressUnitConversion="true" ') \
        if what == "attribute" else LINK
    p = bench(tmp_path, what, elements, link, files=FILES, after=UNKNOWN_ELEMENT if what == "element" else "")
    run(p, step=0.05, stop_time=0.2)
    run(p, step=0.05, stop_time=0.2)          # again, in the same process: no second warning
    err = capsys.readouterr().err
    key = {"annotation": 'Annotation type="com.example.solver"', "element": "<SignalDictionaries>",
           "attribute": '<Connection suppressUnitConversion="true">'}[what]
    lines = [ln for ln in err.splitlines() if key in ln]
    assert len(lines) == 1, err
    assert lines[0].startswith("warning: ") and f"{p}/SystemStructure.ssd:" in lines[0], lines[0]
    assert len([n for n in portability.not_applied(p) if "SignalDictionar" in n.element]) == (
        2 if what == "element" else 0)     # the element and the one inside it, each named


def test_our_benches_hold_nothing_the_runner_does_not_apply():
    from artibus.bench import ssp
    for name in ssp.bench_names():
        assert portability.not_applied(ssp.ssp_path(name)) == [], name


def test_check_lists_multi_rate_steps_and_variants_of_the_damping_bench():
    lines = []
    assert check_main(["Scania18m_Damping"], out=lines.append) == 0
    text = "\n".join(lines)
    assert "multi-rate steps" in text and "0.02 s" in text and "0.01 s" in text, text
    assert "variants" in text and "heavyRear" in text, text
    assert "another master" in text and "rebinds" in text, text


def test_a_parameter_source_inside_the_fmu_is_a_named_error(tmp_path):
    p = bench(tmp_path, "inside", LEAD + follow('<ssd:ParameterBindings><ssd:ParameterBinding '
                                                'source="resources/params.ssv" sourceBase="component"/>'
                                                '</ssd:ParameterBindings>'), LINK, files=FILES)
    with pytest.raises(ArtibusError, match=r'SystemStructure\.ssd:1: <ParameterBinding source="resources/params\.ssv" '
                                           r'sourceBase="component">: a source inside the component'):
        run(p, step=0.05)
