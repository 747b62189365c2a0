"""The FMI-LS-BUS benches as SSP 2.0 system structures (issue 24; artibus.bench.ssp2).

What is expected comes from elsewhere: the SSP 2.0 standard's XSDs (vendored unchanged,
src/artibus/bench/schema/ssp2/SOURCE.md), the FMUs' own terminalsAndIcons.xml and
modelDescription.xml, the FMI-LS-BUS 1.0 text (4____network_abstraction.adoc "Bus Terminal": a
terminal's four members Tx_Data, Tx_Clock, Rx_Data, Rx_Clock, Tx connected to Rx and vice versa;
4_4_1_can.adoc: the CAN MIME type written out below) and the Real-wired bench Bus36m_Circle_CAN
(which ECUs and actuators the network has). The KPIs equal to Bus36m_Circle_CAN's:
tests/test_lsbus_bench.py.
"""
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from lxml import etree

from artibus import ROOT, ArtibusError
from artibus.bench import ssp

LSBUS_BENCHES = ["Bus36m_Circle_LSBUS", "Bus36m_Circle_LSBUS_Backwards"]
SCHEMAS = ROOT / "src" / "artibus" / "bench" / "schema" / "ssp2"
# fmi-ls-bus 1.0, 4_4_1_can.adoc: the MIME type of CAN bus operations (Rx_Data, Tx_Data)
CAN_MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
SSC = "{http://ssp-standard.org/SSP1/SystemStructureCommon}"
RX_OF = {"Tx_Data": "Rx_Data", "Tx_Clock": "Rx_Clock"}


def xsd():
    """the vendored SSD, SSV and SSM schemas, imported by one wrapper (lax inline parameter sets)"""
    files = {"SystemStructureDescription": "SystemStructureDescription.xsd",
             "SystemStructureParameterValues": "SystemStructureParameterValues.xsd",
             "SystemStructureParameterMapping": "SystemStructureParameterMapping.xsd"}
    imports = "".join(f'<xs:import namespace="http://ssp-standard.org/SSP1/{ns}" '
                      f'schemaLocation="{(SCHEMAS / f).as_uri()}"/>' for ns, f in files.items())
    return etree.XMLSchema(etree.fromstring(f'<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">{imports}'
                                            '</xs:schema>'))


def ssd_of(bench):
    return etree.parse(str(ssp.BENCH_DIR / bench / "SystemStructure.ssd"))


def test_the_schemas_are_vendored_with_their_license_and_commit():
    source = (SCHEMAS / "SOURCE.md").read_text()
    assert re.search(r"\b[0-9a-f]{40}\b", source) and "github.com/modelica/ssp-standard" in source
    assert "BSD 2-Clause" in (SCHEMAS / "LICENSE.txt").read_text() or "Redistribution and use" in \
        (SCHEMAS / "LICENSE.txt").read_text()
    for f in ("SystemStructureCommon", "SystemStructureDescription", "SystemStructureParameterValues"):
        assert "Version: 2.0" in (SCHEMAS / f"{f}.xsd").read_text(), f


@pytest.mark.parametrize("bench", LSBUS_BENCHES)
def test_the_lsbus_benches_are_valid_ssp_2_0(bench):
    tree = ssd_of(bench)
    assert tree.getroot().get("version") == "2.0"
    s = xsd()
    assert s.validate(tree), s.error_log


@pytest.mark.parametrize("broken", [
    ("Binary", "mimeType", CAN_MIME),               # FMI's spelling, not SSP's mime-type
    ("Clock", "intervalVariability", "periodic"),   # not one of SSP 2.0's values
])
def test_a_broken_copy_is_not_valid(broken):
    tree = ssd_of("Bus36m_Circle_LSBUS")
    tag, attr, value = broken
    tree.find(f".//{SSC}{tag}").set(attr, value)
    assert not xsd().validate(tree)


def fmu_xml(source):
    """(modelDescription variables {name: element}, {terminal: {member: variable}}, is the bus)"""
    from artibus import fmu_dir
    path = fmu_dir() / source[len("resources/"):]
    if not path.is_file():
        pytest.skip(f"{path} not built")
    with zipfile.ZipFile(path) as z:
        md = etree.fromstring(z.read("modelDescription.xml"))
        tai = etree.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        manifest = "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"
        bus = manifest in z.namelist() and etree.fromstring(z.read(manifest)).get("isBusSimulationFMU") == "true"
    terminals = {t.get("name"): {m.get("memberName"): m.get("variableName") for m in t.findall("TerminalMemberVariable")}
                 for t in tai.iter("Terminal") if t.get("terminalKind") == "org.fmi-ls-bus.network-terminal"}
    return {v.get("name"): v for v in md.find("ModelVariables")}, terminals, bus


@pytest.mark.parametrize("bench", LSBUS_BENCHES)
def test_each_terminal_is_its_four_connections(bench):
    root = ssd_of(bench).getroot()
    comps = {c.get("name"): c for c in root.iter(f"{SSD}Component")}
    fmi3 = {n: c for n, c in comps.items() if c.get("source").startswith("resources/fmi3/")}
    info = {n: fmu_xml(c.get("source")) for n, c in fmi3.items()}
    (bus,) = [n for n, (_, _, is_bus) in info.items() if is_bus]
    nodes = [n for n in fmi3 if n != bus]
    # the network of the Real-wired bench, one LS-BUS node per ECU and actuator, and the sensors' frames
    can = etree.parse(str(ssp.BENCH_DIR / bench.replace("LSBUS", "CAN") / "SystemStructure.ssd")).getroot()
    stems = [Path(c.get("source")).stem for c in can.iter(f"{SSD}Component")]
    want = {f"{s}_LSBUS": stems.count(s) for s in ("SteeringECU", "SteeringActuator")}
    got = [Path(fmi3[n].get("source")).stem for n in nodes]
    assert {s: got.count(s) for s in want} == want and want["SteeringECU_LSBUS"] == 3
    assert got.count("SteeringSensors_LSBUS") == 1 and len(nodes) == 7

    conns = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
             for c in root.iter(f"{SSD}Connection")]

    def connector(comp, name):
        (k,) = [k for k in comps[comp].iter(f"{SSD}Connector") if k.get("name") == name]
        (t,) = [t for t in k if t.tag.startswith(SSC)]
        return k, t

    used = []
    for n in nodes:
        variables, terminals, _ = info[n]
        ((term, members),) = terminals.items()
        assert set(members) >= {"Tx_Data", "Tx_Clock", "Rx_Data", "Rx_Clock"}
        mine = [c for c in conns if (c[0], c[1]) in {(n, v) for v in members.values()}
                or (c[2], c[3]) in {(n, v) for v in members.values()}]
        assert len(mine) == 4, (n, mine)
        peers = set()
        for m, var in members.items():
            if m not in ("Tx_Data", "Tx_Clock", "Rx_Data", "Rx_Clock"):
                continue
            k, t = connector(n, var)
            data = m.endswith("_Data")
            assert t.tag == f"{SSC}{'Binary' if data else 'Clock'}", (n, var)
            assert k.get("kind") == variables[var].get("causality")
            if data:
                assert t.get("mime-type") == CAN_MIME == variables[var].get("mimeType")
            if m.startswith("Tx"):       # the node's Tx to a bus terminal's Rx
                (c,) = [c for c in mine if c[:2] == (n, var)]
                assert c[2] == bus
                peer_term = [t_ for t_, mm in info[bus][1].items() if mm[RX_OF[m]] == c[3]]
            else:                        # the bus terminal's Tx to the node's Rx
                (c,) = [c for c in mine if c[2:] == (n, var)]
                assert c[0] == bus
                peer_term = [t_ for t_, mm in info[bus][1].items()
                             if mm[{v: k_ for k_, v in RX_OF.items()}[m]] == c[1]]
            assert len(peer_term) == 1, (n, m, c)
            peers.add(peer_term[0])
            bk, bt = connector(bus, c[3] if m.startswith("Tx") else c[1])
            assert bt.tag == t.tag and bt.get("mime-type") == t.get("mime-type")
        assert len(peers) == 1, (n, peers)    # all four to one terminal of the bus
        used.append(peers.pop())
    assert len(set(used)) == len(nodes)
    # the runner's network: the nodes in the order of the bus terminals they are on (its k-th node
    # on the bus's k-th terminal, artibus.runner.lsbus.Network), the same Real connections
    from artibus.bench.ssp2 import network_of_ssp
    net = network_of_ssp(ssp.ssp_path(bench))
    order = list(info[bus][1])
    assert list(net.nodes) == [n for _, n in sorted((order.index(t), n) for n, t in zip(nodes, used))]
    assert used and all(order.index(t) < len(nodes) for t in used)
    members = {(n, v) for n in fmi3 for t in info[n][1].values() for v in t.values()}
    real = [c for c in conns if (c[0] in nodes or c[2] in nodes) and (c[0], c[1]) not in members]
    assert sorted(net.inputs) == sorted((b, kb, f"{a}.{ka}") for a, ka, b, kb in real if b in nodes)
    assert sorted(net.outputs) == sorted((a, ka, f"{b}.{kb}") for a, ka, b, kb in real if b not in nodes)
    assert len(net.inputs) >= 4 and len(net.outputs) >= 5
    # the Real signals between the plant and the nodes: ordinary connections of Real types
    for a, ka, b, kb in conns:
        if a in fmi3 and b in fmi3:
            continue
        if a in nodes or b in nodes:
            ta, tb = connector(a, ka)[1].tag, connector(b, kb)[1].tag
            assert {ta, tb} <= {f"{SSC}Real", f"{SSC}Float64"}, (a, ka, b, kb)


# ---- malformed .ssd files: an ArtibusError naming the file, the element and the value ---------

def edited(tmp_path, edit, bench="Bus36m_Circle_LSBUS"):
    """a copy of the bench's .ssp whose SystemStructure.ssd is edit(text)"""
    src = ssp.ssp_path(bench)
    out = tmp_path / f"{bench}_edited.ssp"
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w") as z:
        for n in a.namelist():
            data = a.read(n)
            if n == "SystemStructure.ssd":
                new = edit(data.decode())
                assert new != data.decode()
                data = new.encode()
            z.writestr(n, data)
    return out


def setup_error(path):
    from artibus.runner import Simulation
    with pytest.raises(ArtibusError) as e:
        with Simulation(path):
            pass
    return str(e.value)


def test_a_binary_connected_to_a_real_is_refused(tmp_path):
    path = edited(tmp_path, lambda s: s.replace(
        'startElement="Act1" startConnector="delta[2]" endElement="Bus"',
        'startElement="Act1" startConnector="SteeringCAN.Tx_Data" endElement="Bus"'))
    msg = setup_error(path)
    assert str(path) in msg and "<Connection" in msg and "SteeringCAN.Tx_Data" in msg
    assert "Binary" in msg and "Real" in msg


def test_a_clock_connected_to_a_binary_is_refused(tmp_path):
    path = edited(tmp_path, lambda s: s.replace(
        'startConnector="SteeringCAN.Tx_Clock" endElement="CanBus" endConnector="Node1.Rx_Clock"',
        'startConnector="SteeringCAN.Tx_Clock" endElement="CanBus" endConnector="Node1.Rx_Data"'))
    msg = setup_error(path)
    assert str(path) in msg and "<Connection" in msg and "Node1.Rx_Data" in msg
    assert "Clock" in msg and "Binary" in msg


def test_a_terminal_member_connected_to_nothing_is_refused(tmp_path):
    path = edited(tmp_path, lambda s: re.sub(
        r'\s*<ssd:Connection startElement="CanBus" startConnector="Node7.Tx_Clock"[^>]*/>', "", s))
    msg = setup_error(path)
    assert str(path) in msg and 'Component name="Act3"' in msg and "SteeringCAN.Rx_Clock" in msg
    assert "connected to nothing" in msg


@pytest.mark.parametrize("everywhere", [False, True])
def test_a_wrong_mime_type_is_refused(tmp_path, everywhere):
    """on one connector (ECU2's Tx_Data), or on every Binary connector alike (each connection then
    joins equal types, but not those of the FMUs' variables: SSP 2.0 5.3.2)"""
    wrong = 'application/org.fmi-standard.fmi-ls-bus.can; version="0.9.0"'

    def edit(s):
        if everywhere:
            return s.replace(f"mime-type='{CAN_MIME}'", f"mime-type='{wrong}'")
        head, sep, tail = s.partition('<ssd:Component name="ECU2"')
        return head + sep + tail.replace(f"mime-type='{CAN_MIME}'", f"mime-type='{wrong}'", 1)
    path = edited(tmp_path, edit)
    msg = setup_error(path)
    assert str(path) in msg and "SteeringCAN.Tx_Data" in msg and ("ECU2" in msg or everywhere)
    assert 'version="0.9.0"' in msg


def test_a_terminal_connected_backwards_is_refused(tmp_path):
    """Rx to Tx: the standard's connections go from Tx to Rx"""
    path = edited(tmp_path, lambda s: s.replace(
        '<ssd:Connection startElement="Sensors" startConnector="SteeringCAN.Tx_Data" endElement="CanBus" '
        'endConnector="Node1.Rx_Data"/>', '<ssd:Connection startElement="CanBus" startConnector="Node1.Rx_Data" '
        'endElement="Sensors" endConnector="SteeringCAN.Tx_Data"/>'))
    msg = setup_error(path)
    assert str(path) in msg and "<Connection" in msg and "member Rx_Data" in msg and "member Tx_Data" in msg


def test_an_invalid_ssd_is_refused_naming_the_line(tmp_path):
    path = edited(tmp_path, lambda s: s.replace('intervalVariability="triggered"', 'intervalVariability="sometimes"', 1))
    msg = setup_error(path)
    assert f"{path}/SystemStructure.ssd:" in msg and "SSP 2.0" in msg and "sometimes" in msg


def test_the_cli_checks_the_network_and_prints_one_line_errors(tmp_path):
    env_cmd = [sys.executable, "-m", "artibus", "check"]
    r = subprocess.run(env_cmd + ["Bus36m_Circle_LSBUS"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "FMI-LS-BUS network (SSP 2.0): 7 nodes on CanBus" in r.stdout
    path = edited(tmp_path, lambda s: re.sub(
        r'\s*<ssd:Connection startElement="ECU1" startConnector="SteeringCAN.Tx_Data"[^>]*/>', "", s))
    r = subprocess.run(env_cmd + [str(path)], capture_output=True, text=True, timeout=300)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert "ECU1" in r.stderr and "SteeringCAN.Tx_Data" in r.stderr and "connected to nothing" in r.stderr


def test_the_portable_pack_refuses_an_ssp_2_0_bench_saying_why():
    from artibus.bench.portable import pack_portable
    with pytest.raises(ArtibusError, match="SSP 1.0 only"):
        pack_portable("Bus36m_Circle_LSBUS")


def test_an_ssp_2_0_bench_without_a_network_runs_as_its_ssp_1_0_twin(tmp_path):
    """Bus36m_Circle with version="2.0" (valid SSP 2.0 as it is: 2.0 keeps 1.0's elements): the
    same components, connections and result, bit for bit, over 1 s"""
    import numpy as np
    from artibus.runner import Simulation
    path = edited(tmp_path, lambda s: s.replace('version="1.0" name="Bus36m_Circle"', 'version="2.0" name="Bus36m_Circle"'),
                  bench="Bus36m_Circle")
    one, two = ssp.read(ssp.ssp_path("Bus36m_Circle")), ssp.read(path)
    assert (one.version, two.version) == ("1.0", "2.0")
    assert list(one.components) == list(two.components)
    assert [(c.start, c.end) for c in one.connections] == [(c.start, c.end) for c in two.connections]
    with Simulation("Bus36m_Circle") as a, Simulation(path) as b:
        ra, rb = a.run(stop_time=1.0), b.run(stop_time=1.0)
        assert a.can is None and b.can is None
    assert ra.names == rb.names and len(ra.time) > 50
    np.testing.assert_array_equal(ra.array(), rb.array())


def test_a_node_parameter_the_fmu_has_not_is_refused_naming_the_line(tmp_path):
    """a typo in an LS-BUS node's parameter binding: an error naming the .ssd's line, the
    parameter and the FMU (no traceback from the instance the master makes later)"""
    path = edited(tmp_path, lambda s: s.replace('name="module"', 'name="modul"', 1))
    msg = setup_error(path)
    assert f"{path}/SystemStructure.ssd:" in msg and 'name="modul"' in msg and "no such variable" in msg
    assert "SteeringECU_LSBUS.fmu" in msg


@pytest.mark.parametrize("mime,ok", [
    ('application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"', True),
    ('application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0-beta.1"', True),   # the examples'
    ('application/org.fmi-standard.fmi-ls-bus.can; version="1.2.3"', True),
    ('application/org.fmi-standard.fmi-ls-bus.can; version="2.0.0"', False),
    ('application/org.fmi-standard.fmi-ls-bus.can; version="1.0"', False),           # not semver
    ('application/org.fmi-standard.fmi-ls-bus.can', False),                           # no version
    ('application/org.fmi-standard.fmi-ls-bus.ethernet; version="1.0.0"', False),
    (None, False),
])
def test_one_reading_of_the_can_mime_type_for_benches_and_fmus(mime, ok):
    """fmi-ls-bus 1.0 "MIME Types": major version 1, semantic versioning, pre-releases too; the
    bench's connectors (artibus.bench.ssp2) and the FMUs' terminals (runner.lsbus.check_mime)"""
    from artibus.bench.ssp2 import is_can_mime
    from artibus.runner.lsbus import LsBusError, check_mime
    assert is_can_mime(mime) is ok
    if ok:
        check_mime("x.fmu", "Tx_Data", mime)
    else:
        with pytest.raises(LsBusError, match="x.fmu: Tx_Data has mimeType"):
            check_mime("x.fmu", "Tx_Data", mime)
