"""What the official FMI-LS-BUS examples send, into our CanBus and our ECU node.

The only public C example of FMI-LS-BUS CAN, modelica/fmi-ls-bus-examples (a CAN node,
can-node-triggered-output, and a two-node bus simulation, can-bus-simulation), is on GitHub
only: no registry carries it (not crates.io's fmi-sys 0.6.0, which has the standard's
headers and no example; not fmu-manipulation-toolbox on PyPI, whose wheel and sdist leave
out the example FMUs of its repository's tests/ls-bus), so it cannot be built on a clean
machine. What it puts on the bus is here, built by hand from its source (App.c of both, at
503b64e, with the standard's tables, fmi-ls-bus v1.0.0 4_4_1_can.adoc):
- the node: at instantiation a Configuration CAN_BAUDRATE 100 kbit/s and a Configuration
  ARBITRATION_LOST_BEHAVIOR BUFFER_AND_RETRANSMIT, sent at its first Tx_Clock; then every
  0.3 s a CAN Transmit of ID 0x1 (standard, no RTR), 4 bytes 01 02 03 04;
- the bus simulation, to a node: the other node's frames as CAN Transmit, a Confirm of the
  node's own frame, a Bus Error (CRC error, primary error flag, Is Sender) for a frame it
  corrupts, an Arbitration Lost for a DISCARD_AND_NOTIFY loser.
Both declare the MIME type 'application/org.fmi-standard.fmi-ls-bus.can;
version="1.0.0-beta.1"' (a SemVer pre-release of ours, "1.0.0"); their headers (fmi-ls-bus at
468127f, before v1.0.0-beta.1) and v1.0.0's differ in comments and one typedef only, not in
any operation's code or layout, so the bytes are the same under both versions: an FMU sees
only the bytes (the MIME type is a modelDescription attribute, for the importer).
Checked: our CanBus carries the example node's frame at 100 kbit/s with its Confirm; our ECU
node, fed the example bus's operations besides its DBC frames, commands exactly what it
commands without them and answers none with a Format Error; our master (artibus.runner.lsbus)
runs a node that declares the pre-release MIME version."""
import math
import random
import struct
import zipfile

import pytest

from test_canbus import Importer, frame_bits, transmit, unzipped  # noqa: F401
from test_lsbus_node import Node, ecu_frames, op_transmit, read_ops

EXAMPLE_MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0-beta.1"'
OUR_MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'


# ---- the example node's and bus simulation's operations, by hand from 4_4_1_can.adoc -------

def configuration(kind, value):
    """Configuration 0x40: Parameter Type u8, then the baud rate u32 (0x01-0x03) or the
    arbitration lost behaviour u8 (0x04)"""
    arg = struct.pack("<I", value) if kind in (1, 2, 3) else bytes([value])
    return struct.pack("<IIB", 0x40, 9 + len(arg), kind) + arg


def confirm(can_id):
    return struct.pack("<III", 0x20, 12, can_id)


def arbitration_lost(can_id):
    return struct.pack("<III", 0x30, 12, can_id)


def bus_error(can_id, code, flag, is_sender):
    return struct.pack("<IIIBBB", 0x31, 15, can_id, code, flag, is_sender)


EXAMPLE_BAUD = 100_000
EXAMPLE_CONFIG = configuration(0x01, EXAMPLE_BAUD) + configuration(0x04, 0x01)   # BUFFER_AND_RETRANSMIT
EXAMPLE_FRAME = (0x1, bytes([1, 2, 3, 4]))
EXAMPLE_PERIOD = 0.3


def test_the_hand_built_operations_have_the_tables_lengths():
    # Configuration: 8 + 1 + 4 (baud rate) and 8 + 1 + 1; Transmit 16 + DL; Confirm and
    # Arbitration Lost 12; Bus Error 15 (4_4_1_can.adoc, each operation's table)
    assert [len(b) for b in (configuration(0x01, 1), configuration(0x04, 1), transmit(*EXAMPLE_FRAME),
                             confirm(1), arbitration_lost(1), bus_error(1, 4, 1, 1))] == [13, 10, 20, 12, 12, 15]
    assert read_ops(EXAMPLE_CONFIG) == [(0x40, b"\x01\xa0\x86\x01\x00"), (0x40, b"\x04\x01")]


def test_canbus_carries_the_example_nodes_frame_at_its_baud_rate(unzipped):  # noqa: F811
    b = Importer(unzipped)
    try:
        b.send({1: EXAMPLE_CONFIG})                  # its first Tx_Clock (t = 0): the configuration
        b.run(EXAMPLE_PERIOD)
        b.send({1: transmit(*EXAMPLE_FRAME)})        # t = 0.3 s: its first frame
        b.run(EXAMPLE_PERIOD + 0.01)
        # the frame's bits at the node's 100 kbit/s (ISO 11898-1, with the stuff bits:
        # test_canbus.frame_bits), not at CanBus's own 500 kbit/s
        t_end = EXAMPLE_PERIOD + frame_bits(*EXAMPLE_FRAME) / EXAMPLE_BAUD
        # between no stuffing (44 + 8 * 4 + 3 bits) and the worst case (+ (34 + 32 - 1) // 4 stuff
        # bits, Davis et al. 2007, eq. 1)
        assert 0.3 + 79 / EXAMPLE_BAUD <= t_end <= 0.3 + 95 / EXAMPLE_BAUD
        for k in range(2, 9):                         # every other node hears it, then nothing
            assert b.ops(k) == [(pytest.approx(t_end, abs=1e-12), ("Transmit", EXAMPLE_FRAME))], k
        assert b.ops(1) == [(pytest.approx(t_end, abs=1e-12), ("Confirm", 0x1))]
        assert b.int32("nFrames") == 1 and b.int32("nBusErrors") == 0
        assert not [m for st, m in b.log if st >= 2]  # no warning, no error
    finally:
        b.close()


def example_bus_extras(db, module):
    """what the example bus simulation hands a node besides the frames it forwards: the
    example node's frame, a Confirm and an Arbitration Lost of this node's command frame, a
    Bus Error (CRC 0x04, primary flag 0x01) of it, Is Sender true, and one of the other's"""
    cmd = db.get_message_by_name(f"Module{module}ECU_Cmd").frame_id
    return (transmit(*EXAMPLE_FRAME) + confirm(cmd) + arbitration_lost(cmd) + bus_error(cmd, 0x04, 0x01, 0x01)
            + bus_error(EXAMPLE_FRAME[0], 0x04, 0x01, 0x00))


OUTS = ("gammaFront", "gammaRear", "fallback", "stale", "fault", "gammaFrontCalc", "gammaRearCalc",
        "drivingDirection")


def test_the_ecu_node_takes_the_example_buses_operations_in_its_stride(tmp_path, db):
    """two ECU nodes (module 2) fed the same DBC frames for 60 cycles, one of them with the
    example bus's other operations before and after them: the same Tx_Data (no Format Error:
    the standard lets a node ignore what it does not use, 4_4_1_can.adoc) and the same outputs
    at every tick"""
    rng = random.Random(24)
    clean = Node("SteeringECU_LSBUS", tmp_path / "clean", module=2)
    mixed = Node("SteeringECU_LSBUS", tmp_path / "mixed", module=2)
    extras = example_bus_extras(db, 2)
    try:
        for k in range(60):
            t = k * 0.01
            sig = (0.3 * math.sin(2 * math.pi * t / 1.5) + rng.uniform(-0.01, 0.01), 0.2 * math.sin(t) + 0.01,
                   0.15 * math.sin(0.8 * t), 0.0, 0, 3.0)
            rx = b"".join(op_transmit(i, d) for i, d in sorted(ecu_frames(db, k, *sig).items()))
            tx_clean = clean.event(rx=rx)
            tx_mixed = mixed.event(rx=extras + rx + extras)
            assert tx_mixed == tx_clean, k
            assert [c for c, _ in read_ops(tx_mixed)] in ([0x10], [0x40, 0x10]), k   # no Format Error 0x01
            clean.step()
            mixed.step()
            assert mixed.get(*OUTS) == clean.get(*OUTS), k
        assert clean.get("stale", "fallback") == [0.0, 0.0]       # the frames were taken all along
    finally:
        clean.close()
        mixed.close()


def relabelled(src, dst, mime):
    """a copy of the FMU src whose Binary variables declare the MIME type mime"""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode("utf-8")
                ours = OUR_MIME.replace('"', "&quot;")
                assert text.count(ours) == 2, "Rx_Data and Tx_Data"
                data = text.replace(ours, mime.replace('"', "&quot;")).encode("utf-8")
            zout.writestr(item, data)
    return dst


def test_our_master_runs_a_node_declaring_the_pre_release_mime_version(tmp_path, db):
    """the sensors' node relabelled 'version="1.0.0-beta.1"' (as the examples declare it) on
    CanBus with the tractor ECU (module 1): the ECU receives its frames, every cycle"""
    from artibus.runner.lsbus import Network
    from conftest import fmu3
    from test_lsbus_node import DEG_RAD, RAD_DEG, python_frame
    sensors = relabelled(fmu3("SteeringSensors_LSBUS"), tmp_path / "SteeringSensors_LSBUS.fmu", EXAMPLE_MIME)
    inputs = {"gamma1": 0.12, "dPsi[1]": 0.21, "dPsi[2]": -0.13, "gammaA6": 0.05}
    net = Network({"sensors": (sensors, {}), "ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1})},
                  bus=(fmu3("CanBus"), {}))
    try:
        net.run(0.05, inputs=lambda t: {"sensors": inputs, "ecu": {"vVehicle": 3.0}},
                outputs={"ecu": ["gamma1", "dPsi[1]", "aliveA1", "stale", "fallback"]})
        got = net.results["ecu"]
    finally:
        net.close()
    m = db.get_message_by_name("SensorA1_Angle")
    _, data = python_frame(db, "SensorA1_Angle", {"RoadWheelAngleA1": RAD_DEG * inputs["gamma1"]}, 0)
    assert got["gamma1"][-1] == pytest.approx(DEG_RAD * m.decode(data)["RoadWheelAngleA1"], abs=1e-12)
    assert got["aliveA1"][-1] in (4.0, 5.0)          # the counter of the last frame received (ticks 0..0.05 s)
    assert got["stale"][-1] == 0 and got["fallback"][-1] == 0


@pytest.mark.parametrize("mime", [OUR_MIME, EXAMPLE_MIME, 'application/org.fmi-standard.fmi-ls-bus.can;version="1.1.0"',
                                  'Application/Org.Fmi-Standard.Fmi-Ls-Bus.Can; version="1.0.0-rc.3+build.7"'])
def test_the_master_takes_can_of_version_1(mime):
    from artibus.runner.lsbus import check_mime
    check_mime("x.fmu", "Bus.Rx_Data", mime)


@pytest.mark.parametrize("mime", ['application/org.fmi-standard.fmi-ls-bus.flexray; version="1.0.0"',
                                  'application/org.fmi-standard.fmi-ls-bus.can; version="2.0.0"',
                                  'application/org.fmi-standard.fmi-ls-bus.can; version="1.0"',
                                  "application/org.fmi-standard.fmi-ls-bus.can", "application/octet-stream", None])
def test_the_master_refuses_another_bus_or_version(mime):
    from artibus.runner.lsbus import LsBusError, check_mime
    with pytest.raises(LsBusError, match=r"x\.fmu: Bus\.Rx_Data has mimeType"):
        check_mime("x.fmu", "Bus.Rx_Data", mime)


def test_the_master_refuses_a_flexray_node_on_canbus(tmp_path):
    from artibus.runner.lsbus import LsBusError, Network
    from conftest import fmu3
    fr = relabelled(fmu3("SteeringSensors_LSBUS"), tmp_path / "SteeringSensors_LSBUS.fmu",
                    'application/org.fmi-standard.fmi-ls-bus.flexray; version="1.0.0"')
    with pytest.raises(LsBusError, match=r"SteeringSensors_LSBUS\.fmu: SteeringCAN\.(Rx|Tx)_Data has mimeType "
                                         r"'application/org\.fmi-standard\.fmi-ls-bus\.flexray"):
        Network({"sensors": (fr, {}), "ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1})}, bus=(fmu3("CanBus"), {}))
