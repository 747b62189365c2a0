"""The FMI-LS-BUS 1.0 CAN nodes (issue 24: SteeringECU_LSBUS, SteeringActuator_LSBUS,
SteeringSensors_LSBUS) driven as an importer drives them, with FMPy's FMU3Slave in Event
Mode (fmi3SetClock, fmi3SetBinary, fmi3UpdateDiscreteStates, fmi3GetBinary): the operations
are built and read here from the standard's tables (fmi-ls-bus v1.0.0, 4____network_
abstraction.adoc and 4_4_1_can.adoc: OP Code u32, Length u32 with the header, little-endian;
Transmit = ID u32, Ide u8, Rtr u8, DL u16, Data; Configuration = kind u8, baud rate u32;
Format Error = DL u16, Data), the frames' bytes by the runner's Python encoder (cantools,
strict, with artibus.can's E2E CRC and the network's alive counter). Checked: the Tx frames
equal the Python encoder's; a node fed frames commands exactly what the FMI 2.0 ECU fed the
decoded Real signals commands; the stale detection after nStale cycles of silence; the E2E
check; malformed operations answered with Format Error, never a crash; call-order errors;
fmpy validate."""
import math
import random
import shutil
import struct

import cantools
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from artibus import ROOT, fmu_dir
from artibus.can import e2e_crc
from artibus.can.dbc import _conversion
from conftest import fmu3

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
NODES = ["SteeringECU_LSBUS", "SteeringActuator_LSBUS", "SteeringSensors_LSBUS"]
TS = 0.01
RAD_DEG, DEG_RAD = _conversion("rad", "deg", "test"), _conversion("deg", "rad", "test")
MS_KMH, KMH_MS = _conversion("m/s", "km/h", "test"), _conversion("km/h", "m/s", "test")


# ---- the operations, from the standard's tables ---------------------------------------

def op_transmit(can_id, data, ide=0, rtr=0):
    return struct.pack("<IIIBBH", 0x10, 16 + len(data), can_id, ide, rtr, len(data)) + bytes(data)


def read_ops(buf):
    """[(op code, arguments bytes)] of a buffer; asserts its Lengths add up"""
    out, pos = [], 0
    while pos < len(buf):
        code, length = struct.unpack_from("<II", buf, pos)
        assert length >= 8 and pos + length <= len(buf), (code, length, pos, len(buf))
        out.append((code, bytes(buf[pos + 8:pos + length])))
        pos += length
    return out


def frames_of(buf):
    """{id: data} of the CAN Transmit operations, with the header's DL checked"""
    out = {}
    for code, args in read_ops(buf):
        if code == 0x10:
            can_id, ide, rtr, dl = struct.unpack_from("<IBBH", args)
            assert (ide, rtr, dl) == (0, 0, len(args) - 8)
            out[can_id] = args[8:]
    return out


def python_frame(db, name, values, counter):
    """the runner's Network._encode: cantools strict, AliveCounter, then the E2E CRC"""
    m = db.get_message_by_name(name)
    data = bytearray(m.encode(dict(values, AliveCounter=counter, CRC=0), scaling=True, strict=True))
    data[0] = e2e_crc(data, int(m.dbc.attributes["E2EDataID"].value))
    return m.frame_id, bytes(data)


# ---- a node in Event Mode ----------------------------------------------------------------

class Node:
    def __init__(self, name, tmp, **params):
        path = fmu3(name)
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.dir = extract(str(path), unzipdir=str(tmp / name))
        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(eventModeUsed=True)
        self.fmu.enterInitializationMode(startTime=0.0)
        for k, v in params.items():
            if isinstance(v, int) and not isinstance(v, bool):
                self.fmu.setInt32([self.vr[k]], [v])
            else:
                self.fmu.setFloat64([self.vr[k]], [float(v)])
        self.fmu.exitInitializationMode()          # Event Mode at t = 0
        self.t = 0.0
        self.in_event = True
        t = "SteeringCAN."
        self.rx, self.tx, self.rxc, self.txc = (self.vr[t + m] for m in ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock"))

    def event(self, rx=b"", tx=True, **inputs):
        """one Event Mode at the current time: inputs, the active clocks, Rx_Data, update;
        returns Tx_Data (b"" when the Tx clock was not active)"""
        if not self.in_event:
            self.fmu.enterEventMode()
        for k, v in inputs.items():
            self.fmu.setFloat64([self.vr[k]], [v])
        if tx:
            self.fmu.setClock([self.txc], [True])
        if rx:
            self.fmu.setClock([self.rxc], [True])
            self.fmu.setBinary([self.rx], [rx])
        self.fmu.updateDiscreteStates()
        out = self.fmu.getBinary([self.tx])[0] if tx else b""
        self.fmu.enterStepMode()
        self.in_event = False
        return out

    def step(self, h=TS):
        self.fmu.doStep(self.t, h)
        self.t += h

    def get(self, *names):
        return self.fmu.getFloat64([self.vr[n] for n in names])

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.mark.parametrize("name", NODES)
def test_fmpy_validates_the_node(name):
    assert validate_fmu(str(fmu3(name))) == []


@pytest.mark.parametrize("name", NODES)
def test_the_node_declares_its_terminal_as_the_standard_says(name):
    import zipfile
    import xml.etree.ElementTree as ET
    with zipfile.ZipFile(fmu3(name)) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    assert root.find("CoSimulation").get("hasEventMode") == "true"
    var = {v.get("name"): v for v in root.find("ModelVariables")}
    vr = {v.get("valueReference"): v for v in root.find("ModelVariables")}
    for m, clock in (("Rx_Data", "Rx_Clock"), ("Tx_Data", "Tx_Clock")):
        v = var["SteeringCAN." + m]
        assert v.tag == "Binary" and v.get("mimeType") == 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
        assert v.get("maxSize") == "1024" and v.get("variability") == "discrete"
        assert vr[v.get("clocks")].get("name") == "SteeringCAN." + clock
    assert var["SteeringCAN.Rx_Data"].get("causality") == "input"
    assert var["SteeringCAN.Tx_Data"].get("causality") == "output"
    assert var["SteeringCAN.Rx_Clock"].get("intervalVariability") == "triggered"
    assert var["SteeringCAN.Rx_Clock"].get("causality") == var["SteeringCAN.Tx_Clock"].get("causality") == "input"
    # Tx_Clock periodic with the DBC's GenMsgCycleTime of every message (10 ms)
    db = cantools.database.load_file(str(DBC))
    assert {m.cycle_time for m in db.messages} == {10}
    assert var["SteeringCAN.Tx_Clock"].get("intervalVariability") == "constant"
    assert float(var["SteeringCAN.Tx_Clock"].get("intervalDecimal")) == 0.010
    with zipfile.ZipFile(fmu3(name)) as z:
        ti = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        man = ET.fromstring(z.read("extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"))
    term = ti.find("Terminals/Terminal")
    assert (term.get("terminalKind"), term.get("matchingRule")) == ("org.fmi-ls-bus.network-terminal",
                                                                    "org.fmi-ls-bus.transceiver")
    members = {e.get("memberName"): e.get("variableName") for e in term.findall("TerminalMemberVariable")}
    assert members == {m: "SteeringCAN." + m for m in ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock")}
    conf = term.find("Terminal")
    assert conf.get("terminalKind") == "org.fmi-ls-bus.network-terminal.configuration"
    bn = conf.find("TerminalMemberVariable").get("variableName")
    assert (var[bn].tag, var[bn].get("causality"), var[bn].get("variability"), var[bn].get("start")) == \
        ("Boolean", "parameter", "fixed", "false")
    ns = "{http://fmi-standard.org/fmi-ls-manifest}"
    assert man.get(ns + "fmi-ls-name") == "org.fmi-standard.fmi-ls-bus"
    assert man.get(ns + "fmi-ls-version") == "1.0.0"
    assert man.get(ns + "fmi-ls-description") == ("Layered Standard for the simulation of bus communication on a "
                                                  "Physical Signal Abstraction or Network Abstraction based level.")
    assert man.get("isBusSimulationFMU") == "false"


def test_the_sensors_send_the_python_encoders_bytes(tmp_path, db):
    node = Node("SteeringSensors_LSBUS", tmp_path)
    rng = random.Random(1)
    try:
        for k in range(40):
            a1, g1, g2, a6 = (rng.uniform(-0.8, 0.8), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5),
                              rng.uniform(-0.8, 0.8))
            tx = node.event(gamma1=a1, **{"dPsi[1]": g1, "dPsi[2]": g2}, gammaA6=a6)
            ops = read_ops(tx)
            if k == 0:      # the Configuration (CAN_BAUDRATE 0x01, 500 kbit/s) before the first Transmit
                assert ops[0] == (0x40, struct.pack("<BI", 0x01, 500000))
                ops = ops[1:]
            assert [c for c, _ in ops] == [0x10] * 4
            want = dict([python_frame(db, "SensorA1_Angle", {"RoadWheelAngleA1": RAD_DEG * a1}, k % 16),
                         python_frame(db, "SensorG1_Angle", {"ArtAngleG1": RAD_DEG * g1}, k % 16),
                         python_frame(db, "SensorG2_Angle", {"ArtAngleG2": RAD_DEG * g2}, k % 16),
                         python_frame(db, "SensorA6_Angle", {"RoadWheelAngleA6": RAD_DEG * a6}, k % 16)])
            assert frames_of(tx) == want
            node.step(TS / 2)                   # a step between ticks: nothing sent there
            assert node.event(tx=False) == b""
            node.step(TS / 2)
    finally:
        node.close()


def ecu_frames(db, k, a1, g1, g2, a6, direction, v):
    c = k % 16
    return dict([python_frame(db, "SensorA1_Angle", {"RoadWheelAngleA1": RAD_DEG * a1}, c),
                 python_frame(db, "SensorG1_Angle", {"ArtAngleG1": RAD_DEG * g1}, c),
                 python_frame(db, "SensorG2_Angle", {"ArtAngleG2": RAD_DEG * g2}, c),
                 python_frame(db, "SensorA6_Angle", {"RoadWheelAngleA6": RAD_DEG * a6}, c),
                 python_frame(db, "TractorECU_State", {"DrivingDirection": direction,
                                                       "VehicleSpeed": MS_KMH * v}, c)])


def decoded(db, frames):
    """what the runner's network delivers into the FMI 2.0 ECU's inputs (Network._deliver)"""
    get = {m.frame_id: m for m in db.messages}
    d = {i: get[i].decode(data, scaling=True, decode_choices=False) for i, data in frames.items()}
    return {"gamma1": DEG_RAD * d[0x101]["RoadWheelAngleA1"], "dPsi[1]": DEG_RAD * d[0x102]["ArtAngleG1"],
            "dPsi[2]": DEG_RAD * d[0x103]["ArtAngleG2"], "gammaA6": DEG_RAD * d[0x104]["RoadWheelAngleA6"],
            "direction": float(d[0x110]["DrivingDirection"]), "v": KMH_MS * d[0x110]["VehicleSpeed"],
            **{a: float(frames[i][1] & 0x0F) for a, i in (("aliveA1", 0x101), ("aliveG1", 0x102),
                                                           ("aliveG2", 0x103), ("aliveA6", 0x104),
                                                           ("aliveState", 0x110))}}


def fmi2_ecu(tmp_path, module, inputs):
    path = fmu_dir() / "SteeringECU.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built")
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(path), unzipdir=str(tmp_path / "ecu2"))
    f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="SteeringECU", instanceName="ecu2")
    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setInteger([vr["module"]], [module])
    f.setReal([vr[k] for k in inputs], list(inputs.values()))
    f.exitInitializationMode()
    return f, vr


OUTS = ("gammaFront", "gammaRear", "fallback", "stale", "fault", "gammaFrontCalc", "gammaRearCalc",
        "drivingDirection")


@pytest.mark.parametrize("module", [2, 3])
def test_the_ecu_node_commands_what_the_fmi2_ecu_fed_the_signals_commands(tmp_path, db, module):
    """200 cycles of a steering sine with noise, then SensorA1_Angle silent for 10 cycles (its
    stale detection, the fallback), then back: at every tick the node's Module<m>ECU_Cmd frame
    is the Python encoder's frame of the FMI 2.0 ECU's set-points, and every output equal"""
    rng = random.Random(module)
    cmd = {2: ("Module2ECU_Cmd", "SteerCmdA3", "SteerCmdA4"), 3: ("Module3ECU_Cmd", "SteerCmdA5", "SteerCmdA6")}[module]
    cmd_id = db.get_message_by_name(cmd[0]).frame_id

    def signals(k):
        t = k * TS
        return (0.3 * math.sin(2 * math.pi * t / 1.5) + rng.uniform(-0.01, 0.01), 0.2 * math.sin(t) + 0.01,
                0.15 * math.sin(0.8 * t), 0.0, 0, 3.0 + 0.1 * math.sin(t))

    silent = range(120, 130)
    sig = [signals(k) for k in range(200)]
    frames0 = ecu_frames(db, 0, *sig[0])
    node = Node("SteeringECU_LSBUS", tmp_path, module=module)
    ecu, vr = fmi2_ecu(tmp_path, module, decoded(db, frames0))
    last = dict(frames0)
    stale_seen = None
    try:
        for k in range(200):
            frames = ecu_frames(db, k, *sig[k])
            if k in silent:
                del frames[0x101]           # the front axle's sensor is silent
            rx = b"".join(op_transmit(i, d) for i, d in sorted(frames.items()))
            want = ecu.getReal([vr[n] for n in OUTS])
            tx = node.event(rx=rx)
            # the frame sent at this tick: the FMI 2.0 ECU's set-points before this tick's sample
            counter = k % 16
            assert frames_of(tx) == dict([python_frame(db, cmd[0], {cmd[1]: RAD_DEG * want[0],
                                                                     cmd[2]: RAD_DEG * want[1]}, counter)]), k
            for i, data in frames.items():      # Network._deliver: a silent message keeps its last frame
                last[i] = data
            got = decoded(db, last)
            ecu.setReal([vr[n] for n in got], list(got.values()))
            node.step()
            ecu.doStep(k * TS, TS)
            assert node.get(*OUTS) == ecu.getReal([vr[n] for n in OUTS]), k
            if stale_seen is None and node.get("stale")[0] != 0:
                stale_seen = k
        # nStale = 3: stale in the 3rd cycle without a new frame (can_fallback.h)
        assert stale_seen == silent[0] + 2
    finally:
        node.close()
        ecu.terminate()
        ecu.freeInstance()


def cmd_frame(db, k, a, b, counter=None):
    return python_frame(db, "Module2ECU_Cmd", {"SteerCmdA3": RAD_DEG * a, "SteerCmdA4": RAD_DEG * b},
                        k % 16 if counter is None else counter)


def test_the_actuator_node_detects_a_silent_ecu_after_nstale_cycles(tmp_path, db):
    """Module2ECU_Cmd every cycle for 20 cycles, then none: stale (and the hold) in the
    nStale-th = 3rd cycle without a frame (can_fallback.h), the axles held at the last set-points"""
    node = Node("SteeringActuator_LSBUS", tmp_path, module=2)
    try:
        for k in range(30):
            rx = op_transmit(*cmd_frame(db, k, 0.1, -0.05)) if k < 20 else b""
            node.event(rx=rx, tx=False)
            node.step()
            stale, fallback = node.get("stale", "fallback")
            silent = k - 19                      # cycles without a new frame
            assert stale == (1.0 if silent >= 3 else 0.0), k
            assert fallback == (1.0 if 3 <= silent <= 3 + 19 else 0.0), k
        assert node.get("delta[1]", "delta[2]") == [DEG_RAD * (573 * 0.01), DEG_RAD * (-286 * 0.01)]
    finally:
        node.close()


def test_the_actuator_node_rejects_what_the_e2e_check_rejects(tmp_path, db):
    node = Node("SteeringActuator_LSBUS", tmp_path, module=2)
    try:
        node.event(rx=op_transmit(*cmd_frame(db, 0, 0.1, 0.1)), tx=False)
        node.step()
        assert node.get("cmdRx[1]")[0] == DEG_RAD * (573 * 0.01)      # 0.1 rad = 5.73 deg
        i, good = cmd_frame(db, 1, 0.2, 0.2)
        bad_crc = bytes([good[0] ^ 0x01]) + good[1:]
        for bad in (bad_crc, cmd_frame(db, 0, 0.3, 0.3)[1],        # a wrong CRC, the counter repeated
                    cmd_frame(db, 9, 0.3, 0.3)[1]):                # 9 after 0, one cycle later: wrong sequence
            node.event(rx=op_transmit(i, bad), tx=False)
            node.step()
            assert node.get("cmdRx[1]", "alive") == [DEG_RAD * (573 * 0.01), 0.0]
        # a frame of another module, and one of another DLC, are not its command either
        node.event(rx=op_transmit(*python_frame(db, "Module3ECU_Cmd", {"SteerCmdA5": 1.0, "SteerCmdA6": 1.0}, 10))
                   + op_transmit(i, good[:4]), tx=False)
        node.step()
        assert node.get("cmdRx[1]", "alive") == [DEG_RAD * (573 * 0.01), 0.0]
        node.event(rx=op_transmit(*cmd_frame(db, 10, 0.2, 0.2)), tx=False)    # 10 after 9's resync
        node.step()
        assert node.get("cmdRx[1]", "alive") == [DEG_RAD * (1146 * 0.01), 10.0]
    finally:
        node.close()


def format_errors(tx):
    """the Data of each Format Error (0x01: DL u16, Data; Length 10 + DL)"""
    out = []
    for code, args in read_ops(tx):
        if code == 0x01:
            (dl,) = struct.unpack_from("<H", args)
            assert len(args) == 2 + dl
            out.append(args[2:])
    return out


MALFORMED = {
    "Transmit with a Length other than 16 + DL": struct.pack("<IIIBBH", 0x10, 20, 0x120, 0, 0, 6) + bytes(4),
    "Transmit with Ide = 2": struct.pack("<IIIBBH", 0x10, 22, 0x120, 2, 0, 6) + bytes(6),
    "Confirm with Length 13": struct.pack("<III", 0x20, 13, 0x120) + b"\x00",
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_a_malformed_operation_is_answered_with_a_format_error(tmp_path, db, case):
    """the bad operation comes back in a Format Error at the next Tx tick; the frame after it
    is still received"""
    node = Node("SteeringECU_LSBUS", tmp_path, module=2)
    try:
        node.event(tx=True)                                   # the Configuration out of the way
        node.step()
        bad = MALFORMED[case]
        frame = python_frame(db, "SensorG1_Angle", {"ArtAngleG1": 12.3}, 1)
        tx = node.event(rx=bad + op_transmit(*frame), tx=True)
        assert format_errors(tx) == [bad]
        assert node.get("dPsi[1]")[0] == DEG_RAD * (123 * 0.1)
        node.step()
    finally:
        node.close()


@pytest.mark.parametrize("cut", [1, 7, 8, 15, 19])   # of the 20 bytes of a 4-byte frame
def test_a_truncated_binary_gives_a_format_error_of_its_rest(tmp_path, db, cut):
    node = Node("SteeringECU_LSBUS", tmp_path, module=2)
    try:
        good = op_transmit(*python_frame(db, "SensorG1_Angle", {"ArtAngleG1": 1.0}, 0))
        tx = node.event(rx=good + good[:cut], tx=True)
        assert format_errors(tx) == [good[:cut]]
        assert node.get("dPsi[1]")[0] == DEG_RAD * (10 * 0.1)       # the whole frame before it was taken
    finally:
        node.close()


def test_unknown_operations_and_notifications_are_ignored(tmp_path, db):
    node = Node("SteeringECU_LSBUS", tmp_path, module=2)
    try:
        ops = (struct.pack("<II", 0x7777, 12) + b"abcd"              # an OP Code the standard does not have
               + struct.pack("<III", 0x20, 12, 0x120)                # Confirm of its own frame
               + struct.pack("<III", 0x30, 12, 0x120)                # Arbitration Lost
               + struct.pack("<IIIBBB", 0x31, 15, 0x120, 0x04, 0x01, 1)   # Bus Error (CRC, primary)
               + op_transmit(*python_frame(db, "SensorG1_Angle", {"ArtAngleG1": 2.0}, 0)))
        tx = node.event(rx=ops, tx=True)
        assert format_errors(tx) == []
        assert [c for c, _ in read_ops(tx)] == [0x40, 0x10]       # Configuration, its command frame
        assert node.get("dPsi[1]")[0] == DEG_RAD * (20 * 0.1)
    finally:
        node.close()


def test_call_order_errors_are_errors_not_crashes(tmp_path):
    node = Node("SteeringECU_LSBUS", tmp_path, module=2)
    f = node.fmu
    try:
        f.setClock([node.txc], [True])
        f.updateDiscreteStates()
        with pytest.raises(FMICallException):     # a periodic clock active at a second update of the Event Mode
            f.setClock([node.txc], [True])        # (FMI 3.0.2, 2.3, fmi3SetClock)
    finally:
        f.freeInstance()
    node = Node("SteeringECU_LSBUS", tmp_path / "b", module=2)
    try:
        with pytest.raises(FMICallException):                    # Rx_Data while Rx_Clock is inactive
            node.fmu.setBinary([node.rx], [b"\x10\x00\x00\x00"])
    finally:
        node.fmu.freeInstance()
    node = Node("SteeringECU_LSBUS", tmp_path / "c", module=2)
    try:
        with pytest.raises(FMICallException):                    # more than maxSize
            node.fmu.setClock([node.rxc], [True])
            node.fmu.setBinary([node.rx], [bytes(1025)])
    finally:
        node.fmu.freeInstance()


def _logged_node(name, tmp, **params):
    """the node with its log messages kept in node.log as (status, text)"""
    path = fmu3(name)
    md = read_model_description(str(path))
    node = Node.__new__(Node)
    node.md, node.log = md, []
    node.vr = {v.name: v.valueReference for v in md.modelVariables}
    node.dir = extract(str(path), unzipdir=str(tmp / name))
    node.fmu = FMU3Slave(guid=md.guid, unzipDirectory=node.dir, modelIdentifier=md.coSimulation.modelIdentifier,
                         instanceName=name)
    node.fmu.instantiate(eventModeUsed=True,
                         logMessage=lambda env, st, cat, msg: node.log.append((st, msg.decode())))
    node.fmu.enterInitializationMode(startTime=0.0)
    for k, v in params.items():
        node.fmu.setInt32([node.vr[k]], [v])
    node.fmu.exitInitializationMode()
    node.t, node.in_event = 0.0, True
    node.rx, node.tx, node.rxc, node.txc = (node.vr["SteeringCAN." + m] for m in
                                            ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock"))
    return node


@pytest.mark.parametrize("member", ["Rx_Clock", "Tx_Clock"])
def test_a_clock_activated_in_step_mode_is_an_error_naming_node_clock_and_time(tmp_path, member):
    """FMI 3.0.2, 4.2, Step Mode: "clocked variables can not be set or get because Clocks are only
    active during Event Mode": fmi3SetClock in Step Mode is refused, the message naming the node
    (its instance name: FMI 3.0's log callback carries none), the clock and the time"""
    node = _logged_node("SteeringECU_LSBUS", tmp_path, module=2)
    try:
        node.fmu.enterStepMode()
        node.fmu.doStep(0.0, 0.0125)
        with pytest.raises(FMICallException):
            node.fmu.setClock([node.vr["SteeringCAN." + member]], [True])
        errors = [m for st, m in node.log if st >= 3]
        assert errors and all(w in errors[-1] for w in ("SteeringECU_LSBUS", f"SteeringCAN.{member}",
                                                         "t = 0.0125")), errors
        assert "step mode" in errors[-1].lower(), errors
    finally:
        node.fmu.freeInstance()


def test_an_rx_clock_set_after_the_update_is_a_new_instant_of_the_event_mode(tmp_path, db):
    """FMI 3.0.2, 2.3, Event Mode, fmi3SetClock: a clock is active for at most one
    fmi3UpdateDiscreteStates per Event Mode, "This restriction does not apply to triggered Clocks";
    "The event mode may consist of several super-dense time instants". Rx_Clock is triggered: set
    again after the update, with Rx_Data, it is taken in that Event Mode: the ECU (module 2) receives
    the frames of the second instant (their values through the DBC, cantools) as in one instant"""
    node = _logged_node("SteeringECU_LSBUS", tmp_path, module=2)
    try:
        f = node.fmu
        f.setClock([node.txc], [True])
        f.updateDiscreteStates()                              # the tick at t = 0: its frames, no Rx yet
        frames = ecu_frames(db, 0, 0.1, 0.05, -0.02, 0.0, 0, 3.0)
        f.setClock([node.rxc], [True])
        f.setBinary([node.rx], [b"".join(op_transmit(i, d) for i, d in frames.items())])
        f.updateDiscreteStates()
        want = decoded(db, frames)
        got = dict(zip(("gamma1", "dPsi[1]", "dPsi[2]", "v"), f.getFloat64([node.vr[n] for n in
                                                                           ("gamma1", "dPsi[1]", "dPsi[2]", "v")])))
        assert got == pytest.approx({k: want[k] for k in got}, abs=1e-12)
        assert not [m for st, m in node.log if st >= 3], node.log
    finally:
        node.fmu.freeInstance()


def test_random_bytes_never_crash_the_node(tmp_path, db):
    """fuzz: random buffers, cut and spliced frames; every update returns, Tx_Data stays well formed"""
    rng = random.Random(7)
    node = Node("SteeringECU_LSBUS", tmp_path, module=3)
    good = op_transmit(*python_frame(db, "SensorG1_Angle", {"ArtAngleG1": 1.0}, 0))
    try:
        for k in range(300):
            kind = rng.random()
            if kind < 0.3:
                rx = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))
            elif kind < 0.6:
                b = bytearray(good * rng.randrange(1, 4))
                for _ in range(rng.randrange(1, 4)):
                    b[rng.randrange(len(b))] = rng.randrange(256)
                rx = bytes(b)
            else:
                rx = good[:rng.randrange(1, len(good) + 1)]
            tx = node.event(rx=rx, tx=True)
            read_ops(tx)
            node.step()
    finally:
        node.close()


@pytest.mark.parametrize("name,base", [("SteeringECU_LSBUS", "SteeringECU"),
                                       ("SteeringActuator_LSBUS", "SteeringActuator")])
def test_the_node_has_its_base_models_variables(name, base):
    """one declaration: every variable of modelDescription/<base>.xml in the node's FMI 3.0
    description, with its value reference, type and unit; the received inputs as locals"""
    import xml.etree.ElementTree as ET
    import zipfile
    spec = ET.parse(ROOT / "modelDescription" / "lsbus" / f"{name}.xml").getroot()
    received = {r.get("name") for r in spec.findall("Received")}
    base_md = ET.parse(ROOT / "modelDescription" / f"{base}.xml").getroot()
    with zipfile.ZipFile(fmu3(name)) as z:
        node = {v.get("name"): v for v in ET.fromstring(z.read("modelDescription.xml")).find("ModelVariables")}
    fmi3 = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}
    for sv in base_md.find("ModelVariables").findall("ScalarVariable"):
        t = next(iter(sv))
        v = node[sv.get("name")]
        assert (v.tag, v.get("valueReference"), v.get("unit")) == (fmi3[t.tag], sv.get("valueReference"),
                                                                   t.get("unit")), sv.get("name")
        want = "local" if sv.get("name") in received else sv.get("causality")
        assert v.get("causality") == want, sv.get("name")
    assert received and received <= {sv.get("name") for sv in base_md.iter("ScalarVariable")
                                     if sv.get("causality") == "input"}


def test_a_node_file_naming_no_input_of_its_base_is_refused(tmp_path):
    import subprocess
    import sys
    bad = tmp_path / "Bad.xml"
    bad.write_text('<LsBusNode name="Bad" base="SteeringECU" guid="{x}" terminal="T" txInterval="0.01" '
                   'description="d"><Received name="gammaFront"/></LsBusNode>')
    r = subprocess.run([sys.executable, str(ROOT / "src" / "fmi" / "lsbus_node.py"), str(bad),
                        str(ROOT / "modelDescription"), str(tmp_path / "o.xml"), str(tmp_path / "o.h")],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "Bad.xml" in r.stderr and '<Received name="gammaFront">' in r.stderr and "no input" in r.stderr
    assert "Traceback" not in r.stderr
