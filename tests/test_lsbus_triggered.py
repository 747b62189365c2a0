"""Our FMI-LS-BUS nodes with their Tx clock in the triggered form (issue 39): the variants
fmus/fmi3/lsbus-triggered/<Name>_LSBUS_Triggered.fmu, whose Tx_Clock is an output triggered
clock (fmi-ls-bus 1.0, 4____network_abstraction.adoc, "Triggered Tx Clocks": the node signals
a tick by eventHandlingNeeded at the end of fmi3DoStep; the importer then reads the clock with
fmi3GetClock in Event Mode, FMI 3.0.2, 2.2.9, and the clocked Tx_Data while it is active).

What is expected comes from elsewhere: the frames of the periodic form (the default) under
the importer written from the standard's text alone (tests/test_lsbus_importer.py, sharing no
code with artibus.runner.lsbus), and the model description's clock as the standard defines
the triggered form."""
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

from conftest import fmu3
from test_lsbus_importer import TS, Importer, bench_inputs

KINDS = ("SteeringSensors", "SteeringECU", "SteeringActuator")
#: the bench's components of each kind (ssp/benches/Bus36m_Circle_LSBUS)
COMPONENTS = {"SteeringSensors": ["Sensors"], "SteeringECU": ["ECU1", "ECU2", "ECU3"],
              "SteeringActuator": ["Act1", "Act2", "Act3"]}


def node(kind, triggered):
    if not triggered:
        return fmu3(f"{kind}_LSBUS")
    path = Path(fmu3("CanBus")).parent / "lsbus-triggered" / f"{kind}_LSBUS_Triggered.fmu"
    if not path.is_file():
        pytest.fail(f"{path} not built")
    return path


def bench_nodes(triggered):
    """Bus36m_Circle_LSBUS's seven nodes in its order, in one Tx clock form"""
    return [("sensors", node("SteeringSensors", triggered), {})] + \
        [(f"ecu{m}", node("SteeringECU", triggered), {"module": m}) for m in (1, 2, 3)] + \
        [(f"act{m}", node("SteeringActuator", triggered), {"module": m}) for m in (1, 2, 3)]


def standard_frames(triggered, n):
    with Importer(bench_nodes(triggered), bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as imp:
        return imp.run(n * TS, bench_inputs).wire()


@pytest.fixture(scope="module")
def periodic_frames():
    """the default form's frames under the standard's importer: 8 a tick, ticks 0..30"""
    frames = standard_frames(False, 30)
    assert len(frames) == 8 * 31
    return frames


@pytest.mark.parametrize("kind", KINDS)
def test_the_triggered_form_declares_tx_clock_an_output_triggered_clock(kind):
    """FMI-LS-BUS 1.0, "Triggered Tx Clocks": Tx_Clock causality output, intervalVariability
    triggered, no interval; listed among the outputs (FMI 3.0.2, 2.4.8, <Output>: every
    output, output clocks too); Rx_Clock stays an input triggered clock ("Rx Clocks")"""
    with zipfile.ZipFile(node(kind, True)) as z:
        md = ET.fromstring(z.read("modelDescription.xml"))
    clocks = {c.get("name").split(".")[-1]: c.attrib for c in md.iter("Clock")}
    assert clocks["Tx_Clock"]["causality"] == "output" and clocks["Tx_Clock"]["intervalVariability"] == "triggered"
    assert "intervalDecimal" not in clocks["Tx_Clock"]
    assert clocks["Rx_Clock"]["causality"] == "input" and clocks["Rx_Clock"]["intervalVariability"] == "triggered"
    outputs = {o.get("valueReference") for o in md.iter("Output")}
    assert clocks["Tx_Clock"]["valueReference"] in outputs


def test_both_tx_clock_forms_put_the_same_frames_on_the_wire_under_the_standard_importer(periodic_frames):
    """the triggered form under the standard's importer (output clocks read after an
    eventHandlingNeeded or at nextEventTime): the same frames, times, ids and payloads"""
    assert standard_frames(True, 30) == periodic_frames


def test_our_master_runs_the_triggered_form_as_the_standard_importer_runs_the_periodic_one(periodic_frames):
    """artibus.runner.lsbus.Network with the nodes in the triggered form: the frames of the
    periodic form under the standard's importer, each once"""
    from artibus.runner.lsbus import Network
    nodes = {name: (path, p) for name, path, p in bench_nodes(True)}
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as net:
        net.run(30 * TS, bench_inputs)
        ours = sorted((round(t, 9), i, bytes(d)) for t, i, _, d in net.wire_frames())
    assert ours == periodic_frames


def test_our_master_reads_tx_data_while_the_clock_is_active_before_the_update():
    """FMI 3.0.2, 2.2.8 ("Getting and Setting Variable Values": a clocked variable is read
    only while its clock is active) and 2.3 (fmi3UpdateDiscreteStates ends the activation):
    every fmi3GetBinary of a node's Tx_Data comes between the activation of its Tx clock
    (fmi3SetClock or an fmi3GetClock saying active) and the next fmi3UpdateDiscreteStates"""
    from artibus.runner.lsbus import Network
    for triggered in (False, True):
        calls = []
        nodes = {name: (path, p) for name, path, p in bench_nodes(triggered)[:2]}
        with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 2, "wireTime": False})) as net:
            for f in net.nodes:
                tx = next(iter(f.terminals.values())).tx_data
                for name in ("getBinary", "updateDiscreteStates", "setClock", "getClock"):
                    real = getattr(f.fmu, name)

                    def spy(*a, _real=real, _name=name, _f=f, _tx=tx):
                        out = _real(*a)
                        if _name != "getBinary" or list(a[0]) == [_tx]:
                            calls.append((_f.name, _name, out if _name == "getClock" else None))
                        return out
                    setattr(f.fmu, name, spy)
            net.run(5 * TS, bench_inputs)
        reads = 0
        for who in nodes:
            active = False
            for _, name, out in (c for c in calls if c[0] == who):
                if name in ("setClock",) or (name == "getClock" and any(out)):
                    active = True
                elif name == "updateDiscreteStates":
                    active = False
                elif name == "getBinary":
                    assert active, (triggered, who)
                    reads += 1
        assert reads == 2 * 6, triggered          # two nodes, ticks 0..5


def test_a_node_that_activates_an_unknown_clock_is_named_with_the_clock_and_the_time(tmp_path):
    """a node FMU with an output clock that is no member of its network terminal (here one
    added to the sensors' model description, activated at t = 0.03 s): the master cannot
    serve it (FMI 3.0.2, 2.2.9: an active output clock's clocked variables are to be read and
    its partition handled) and stops with one line naming the node, the clock and the time"""
    from artibus.runner.lsbus import LsBusError, Network
    src = node("SteeringSensors", True)
    path = tmp_path / "SteeringSensors_LSBUS_Triggered.fmu"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(path, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                clock = ('<Clock name="Diagnosis.Clock" valueReference="990" causality="output" '
                         'variability="discrete" intervalVariability="triggered" />\n  </ModelVariables>')
                text = text.replace("</ModelVariables>", clock, 1)
                text = text.replace("<ModelStructure>", '<ModelStructure>\n    <Output valueReference="990" '
                                    'dependencies="" />', 1)
                data = text.encode()
            zout.writestr(item, data)
    nodes = {"sensors": (path, {}), "ecu": (node("SteeringECU", True), {"module": 2})}
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 2, "wireTime": False})) as net:
        sensors = net.by_name["sensors"]
        real = sensors.fmu.getClock

        def get_clock(vrs):
            vrs = list(vrs)
            known = [v for v in vrs if v != 990]
            got = dict(zip(known, real(known))) if known else {}
            return [got[v] if v != 990 else net.t > 0.025 for v in vrs]
        sensors.fmu.getClock = get_clock
        with pytest.raises(LsBusError) as e:
            net.run(10 * TS, bench_inputs)
    msg = str(e.value)
    assert msg.startswith("t = 0.030000 s: node sensors: output clock Diagnosis.Clock"), msg
    assert "\n" not in msg


def triggered_bench(tmp_path, kinds=KINDS):
    """a copy of Bus36m_Circle_LSBUS's .ssp whose node FMUs of kinds are the triggered form's
    (the same file names), their Tx_Clock connectors an output triggered ssc:Clock (SSP 2.0: a
    connector's kind is its variable's causality)"""
    from artibus.bench import ssp
    src = ssp.ssp_path("Bus36m_Circle_LSBUS", fmi="3")
    out = tmp_path / "Bus36m_Circle_LSBUS_triggered.ssp"
    swapped = []
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w") as z:
        for n in a.namelist():
            data = a.read(n)
            kind = next((k for k in kinds if n.endswith(f"/{k}_LSBUS.fmu")), None)
            if kind:
                data = node(kind, True).read_bytes()
                swapped.append(kind)
            if n == "SystemStructure.ssd":
                periodic = ('<ssd:Connector name="SteeringCAN.Tx_Clock" kind="input"><ssc:Clock '
                            'intervalVariability="constant" intervalDecimal="0.01"/>')
                text = data.decode()
                assert text.count(periodic) == 7
                for kind in kinds:
                    for c in COMPONENTS[kind]:
                        at = text.index(periodic, text.index(f'<ssd:Component name="{c}"'))
                        text = text[:at] + ('<ssd:Connector name="SteeringCAN.Tx_Clock" kind="output"><ssc:Clock '
                                            'intervalVariability="triggered"/>') + text[at + len(periodic):]
                data = text.encode()
            z.writestr(n, data)
    assert sorted(swapped) == sorted(kinds)
    return out


def bench_run(path, core, stop):
    from artibus.runner.simulation import Simulation
    with Simulation(path, fmi="3" if path == "Bus36m_Circle_LSBUS" else None) as sim:
        result = sim.run(stop_time=stop, core=core)
        assert sim.stepping.startswith("C core")
        assert ("in Python: the network" in sim.stepping) != core, sim.stepping
        frames = sorted((round(t, 9), i, bytes(d)) for t, i, _, d in sim.lsbus.net.wire_frames())
        return result, frames


@pytest.mark.parametrize("core", [True, False])
def test_the_bench_with_triggered_nodes_runs_as_with_periodic_ones(tmp_path, core):
    """Bus36m_Circle_LSBUS with the sensors and the actuators in the triggered form (the ECUs
    periodic: the runner ticks the network with their interval), the network in C (the
    stepping core, src/runner_core/lsbus.c) or in Python: every recorded column and every
    frame on the wire as the bench's own run (periodic nodes, network in C)"""
    stop = 1.0
    ref, ref_frames = bench_run("Bus36m_Circle_LSBUS", True, stop)
    got, frames = bench_run(triggered_bench(tmp_path, ("SteeringSensors", "SteeringActuator")), core, stop)
    assert len(ref_frames) == 8 * 100 and frames == ref_frames      # ticks 0..0.99 s
    assert got.names == ref.names
    a, b = ref.array(), got.array()
    assert a.shape == b.shape
    for j, name in enumerate(ref.names):
        assert a[:, j].tobytes() == b[:, j].tobytes(), name


def test_a_bench_whose_nodes_all_have_a_triggered_tx_clock_is_refused_naming_them(tmp_path):
    """the runner ticks a bench's network with the nodes' time-based Tx_Clock interval: with
    every node's Tx_Clock a triggered output clock there is none, and the refusal names the
    nodes and why, in one line (no traceback)"""
    from artibus.base import ArtibusError
    from artibus.runner.simulation import Simulation
    path = triggered_bench(tmp_path)
    with pytest.raises(ArtibusError) as e:
        with Simulation(path):
            pass
    msg = str(e.value)
    assert "Tx_Clock is a triggered output clock (Sensors, ECU1, ECU2, ECU3, Act1, Act2, Act3)" in msg, msg
    assert str(path) in msg and "\n" not in msg
