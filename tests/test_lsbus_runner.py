"""The LS-BUS master artibus.runner.lsbus (issue 24) on the FMI 3.0 LS-BUS nodes and CanBus.

What is expected comes from elsewhere, computed here:
- (a) the ECU node's outputs: the FMI 2.0 SteeringECU, run here, fed the Real signals the
  frames carry (the DBC's encoding by cantools with artibus.can's E2E CRC, decoded again:
  the resolution of each signal), at the same 10 ms ticks;
- (b) through CanBus with wireTime off the bus adds no delay: the same outputs as (a);
- (c) with wire time: each frame's delivery time from its bits (the closed form of
  tests/test_canbus.py: 44 + 8 DLC bits, stuffing over SOF..CRC with the CRC-15, 3 bits
  intermission, at 500 kbit/s), the frames of one tick back to back in identifier order
  (ISO 11898-1 arbitration: the lowest identifier wins) from the tick on the 10 ms grid;
- (d) the stale detection: stale in the nStale-th (3rd) cycle without a new frame
  (SteeringECU's nStale, can_fallback.h), counted from the last frame the bus let through
  before faultStart;
- (e) the standard's call order (FMI 3.0.2, 5.2.2): a clock after fmi3UpdateDiscreteStates
  that asked for no further iteration is refused.
"""
import math
import struct
from pathlib import Path

import cantools
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from artibus import ROOT, fmu_dir
from artibus.can import e2e_crc
from artibus.can.dbc import _conversion
from artibus.runner.lsbus import LsBusError, Network

from test_canbus import wire_time
from conftest import fmu3

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
TS = 0.01
RAD_DEG, DEG_RAD = _conversion("rad", "deg", "test"), _conversion("deg", "rad", "test")
SENSORS = (("SensorA1_Angle", "RoadWheelAngleA1", "gamma1", "aliveA1"),
           ("SensorG1_Angle", "ArtAngleG1", "dPsi[1]", "aliveG1"),
           ("SensorG2_Angle", "ArtAngleG2", "dPsi[2]", "aliveG2"),
           ("SensorA6_Angle", "RoadWheelAngleA6", "gammaA6", "aliveA6"))
OUTS = ("gammaFront", "gammaRear", "fallback", "stale", "fault", "gammaFrontCalc", "gammaRearCalc",
        "drivingDirection", "gamma1", "dPsi[1]", "dPsi[2]", "gammaA6")


def signals(t):
    """the plant's angles (rad) and the vehicle speed (m/s): backwards at 3 m/s, so module 1
    (the tractor ECU) steers A1 and A2 from SensorA6_Angle and both hinges (SteeringECU.xml)"""
    return {"gamma1": 0.05 * math.sin(t), "dPsi[1]": 0.2 * math.sin(2 * math.pi * t / 1.5) + 0.01,
            "dPsi[2]": 0.15 * math.sin(0.8 * t), "gammaA6": 0.3 * math.sin(1.3 * t)}, -3.0 - 0.1 * math.sin(t)


def inputs(t):
    s, v = signals(t)
    return {"sensors": s, "ecu": {"vVehicle": v}}


def quantized(db, s, k):
    """the Real inputs the FMI 2.0 ECU gets from tick k's frames: each signal encoded with
    the DBC and decoded again, the alive counters k mod 16"""
    out = {}
    for msg, sig, name, alive in SENSORS:
        m = db.get_message_by_name(msg)
        data = bytearray(m.encode({sig: RAD_DEG * s[name], "AliveCounter": k % 16, "CRC": 0},
                                  scaling=True, strict=True))
        data[0] = e2e_crc(data, int(m.dbc.attributes["E2EDataID"].value))
        out[name] = DEG_RAD * m.decode(bytes(data), scaling=True)[sig]
        out[alive] = float(data[1] & 0x0F)
    return out


def fmi2_reference(tmp_path, db, n_steps, silent_from=None):
    """SteeringECU (FMI 2.0, module 1) fed the frames' signals every 10 ms; a silent sensor
    node keeps its last values and counters (the receiver sees no new frame)"""
    path = fmu_dir() / "SteeringECU.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built")
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(path), unzipdir=str(tmp_path / "ecu2"))
    f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="SteeringECU", instanceName="ecu2")

    def feed(k):
        s, v = signals(k * TS)
        got = quantized(db, s, k) if silent_from is None or k < silent_from else {}
        got["v"] = v
        f.setReal([vr[n] for n in got], list(got.values()))

    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setInteger([vr["module"]], [1])
    feed(0)
    f.exitInitializationMode()
    rows = []
    for k in range(n_steps):
        feed(k)
        f.doStep(k * TS, TS)
        rows.append(f.getReal([vr[n] for n in OUTS]))
    f.terminate()
    f.freeInstance()
    return rows


def network(bus=None):
    nodes = {"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1})}
    return Network(nodes, bus=(fmu3("CanBus"), dict({"nNodes": 2}, **bus)) if bus is not None else None)


def ecu_rows(net):
    """the ECU node's outputs at the 10 ms grid (the steps of a run with wire time end
    between ticks too)"""
    rows = []
    for i, t in enumerate(net.time):
        if abs(t / TS - round(t / TS)) < 1e-6:
            rows.append([net.results["ecu"][n][i] for n in OUTS])
    return rows


N = 150           # 1.5 s: one period of the hinge angle's sine


@pytest.fixture(scope="module")
def reference(tmp_path_factory, db):
    return fmi2_reference(tmp_path_factory.mktemp("ref"), db, N)


def run(bus=None, t_stop=N * TS):
    with network(bus) as net:
        net.run(t_stop, inputs, {"ecu": list(OUTS)})
        return ecu_rows(net), net.frames


def test_direct_mode_the_ecu_commands_what_the_fmi2_ecu_commands(reference):
    rows, frames = run()
    assert len(rows) == N
    assert rows == reference                        # exactly: the same C code, the same inputs
    # it steers: A1 and A2 move backwards (not a test that passes on zeros)
    assert max(abs(r[0]) for r in rows) > 0.01 and max(abs(r[1]) for r in rows) > 0.001
    assert all(r[3] == 0 for r in rows)            # nothing stale
    # 1 + 150 ticks of each node, every one a frame to the other
    assert sum(1 for f in frames if f[1] == "sensors") == N + 1


def test_through_canbus_without_wire_time_equals_direct_mode(reference):
    with network(bus={"wireTime": False}) as net:
        net.run(N * TS, inputs, {"ecu": list(OUTS)})
        rows, frames, n_frames = ecu_rows(net), net.frames, net.bus.get("nFrames")
    assert rows == reference
    # the bus's deliveries are at the ticks themselves
    assert {round(f[0] / TS, 6) % 1 for f in frames if f[1] == "bus"} == {0.0}
    # every Transmit the nodes sent went over the bus
    assert n_frames == sum(len(transmits(f[4])) for f in frames if f[2] == "bus") > 0


def transmits(buf):
    """[(id, data)] of the CAN Transmit operations (4_4_1_can.adoc, Transmit: OP Code 0x10,
    Length, ID u32, Ide u8, Rtr u8, DL u16, Data)"""
    out, pos = [], 0
    while pos < len(buf):
        code, length = struct.unpack_from("<II", buf, pos)
        if code == 0x10:
            can_id, _, _, dl = struct.unpack_from("<IBBH", buf, pos + 8)
            out.append((can_id, bytes(buf[pos + 16:pos + 16 + dl])))
        pos += length
    return out


def test_with_wire_time_every_frame_arrives_after_its_bits_in_identifier_order():
    n_ticks = 30
    with network(bus={}) as net:
        net.run(n_ticks * TS, inputs, {"ecu": list(OUTS)})
        frames = net.frames
    sent = {}                                       # tick -> [(id, data)] both nodes sent
    for t, src, dst, _, data in frames:
        if dst == "bus":
            k = round(t / TS)
            assert abs(t - k * TS) < 1e-12          # sent on the 10 ms grid
            sent.setdefault(k, []).extend(transmits(data))
    got = [(t, src_dst, f) for t, src, dst, _, data in frames if src == "bus"
           for src_dst in [dst] for f in transmits(data)]
    assert len(sent) == n_ticks + 1
    del sent[n_ticks]                               # sent at the stop time: the run ends there
    for k, tick in sent.items():
        assert {i for i, _ in tick} == {0x101, 0x102, 0x103, 0x104, 0x110, 0x118} or k == 0
        t = k * TS
        for i, d in sorted(tick):                  # arbitration: lowest identifier first
            t += wire_time(i, d)
            receiver = "ecu" if i < 0x110 else "sensors"
            match = [g for g in got if g[2] == (i, d) and g[1] == receiver and k * TS < g[0] < (k + 1) * TS]
            assert len(match) == 1, (k, hex(i))
            assert match[0][0] == pytest.approx(t, abs=1e-12), (k, hex(i))
        assert t - k * TS < TS                      # the tick's frames fit into the cycle


def test_node_order_does_not_change_arbitration():
    """the ECU first: its frames and the sensors' of the same tick still go by identifier"""
    nodes = {"ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1}), "sensors": (fmu3("SteeringSensors_LSBUS"), {})}
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 2})) as net:
        net.run(3 * TS, inputs)
        order = [i for t, src, dst, _, data in net.frames if src == "bus" and 0.02 < t < 0.03
                 for i, _ in transmits(data)]
    assert order == [0x101, 0x102, 0x103, 0x104, 0x110, 0x118]


@pytest.mark.parametrize("wire", [False, True])
def test_a_silent_sensor_node_makes_the_ecu_stale_after_nstale_cycles(tmp_path, db, wire):
    """CanBus faultSilentNode = 1 (the sensors) from 0.505 s: the last frames are those of the
    tick at 0.50 s (k = 50); stale in the 3rd cycle without them, and the ECU as the FMI 2.0
    ECU that gets no new frame after k = 50. With wire time the frames of tick k arrive
    0.2-1.1 ms after it, so the ECU samples them at tick k + 1: one cycle later."""
    n = 70
    rows, _ = run(bus={"wireTime": wire, "faultSilentNode": 1, "faultStart": 0.505}, t_stop=n * TS)
    stale = [r[OUTS.index("stale")] for r in rows]
    first = stale.index(next(s for s in stale if s != 0))
    # rows[k] is after the step from tick k; without wire time the ticks 51, 52, 53 have no
    # new frame, with it the ticks 52, 53, 54 (tick 51 still gets tick 50's frames)
    assert first == (54 if wire else 53)
    assert all(s == 0 for s in stale[:first])
    if not wire:
        assert rows == fmi2_reference(tmp_path, db, n, silent_from=51)


def test_a_clock_after_the_discrete_states_is_refused():
    with network() as net:
        ecu = net.by_name["ecu"]
        (term,) = ecu.terminals.values()
        ecu.set_clocks([term.tx_clock])
        assert ecu.update() is False
        with pytest.raises(LsBusError, match=r"ecu: fmi3SetClock\(SteeringCAN.Rx_Clock\) after "
                                             r"fmi3UpdateDiscreteStates"):
            ecu.set_clocks([term.rx_clock])
        with pytest.raises(FMICallException):       # the FMU itself refuses its periodic Tx clock a second
            ecu.fmu.setClock([term.tx_clock], [True])   # update (FMI 3.0.2, 2.3; a triggered Rx clock it takes)


def test_an_fmu_without_a_bus_terminal_is_refused_by_name():
    path = fmu_dir() / "SteeringECU.fmu"
    with pytest.raises(LsBusError, match=r"SteeringECU.fmu: FMU ecu is no FMI 3.0 Co-Simulation FMU"):
        Network({"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu": (path, {})})


def test_an_fmu_error_is_raised_with_its_message():
    """a value outside its signal's range: the sensors node refuses it (logStatusError), the
    master says when and what the FMU said"""
    with network() as net:
        with pytest.raises(LsBusError, match=r"t = 0.020000 s: .*sensors said: "):
            net.run(0.05, lambda t: {"sensors": {"gamma1": 0.0 if t < 0.015 else 5.0}})


def test_a_network_without_bus_is_two_nodes():
    with pytest.raises(LsBusError, match="two nodes connect directly, not 1"):
        Network({"ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1})})


# ---- the whole steering network on CanBus --------------------------------------------------

class Fmi2Ecu:
    """the FMI 2.0 SteeringECU of one module, initialised with and fed the Real inputs"""

    def __init__(self, tmp_path, module, first):
        path = fmu_dir() / "SteeringECU.fmu"
        if not path.is_file():
            pytest.skip(f"{path} not built")
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        d = extract(str(path), unzipdir=str(tmp_path / f"ecu{module}"))
        self.f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="SteeringECU", instanceName=f"m{module}")
        self.f.instantiate()
        self.f.setupExperiment(startTime=0.0)
        self.f.enterInitializationMode()
        self.f.setInteger([self.vr["module"]], [module])
        self.feed(first)
        self.f.exitInitializationMode()

    def feed(self, values):
        self.f.setReal([self.vr[n] for n in values], list(values.values()))

    def get(self, names):
        return self.f.getReal([self.vr[n] for n in names])

    def close(self):
        self.f.terminate()
        self.f.freeInstance()


def forwards(t):
    s, v = signals(t)
    return s, -v                                     # 3 m/s forwards: modules 2 and 3 steer


def state_inputs(db, direction, v, k):
    """TractorECU_State as the ECUs of modules 2 and 3 receive it: DrivingDirection and the
    speed in km/h at the DBC's resolution, the alive counter"""
    m = db.get_message_by_name("TractorECU_State")
    kmh = _conversion("m/s", "km/h", "test") * v
    d = m.decode(m.encode({"DrivingDirection": int(direction), "VehicleSpeed": kmh, "AliveCounter": k % 16, "CRC": 0},
                          scaling=True, strict=True), scaling=True, decode_choices=False)
    return {"direction": float(d["DrivingDirection"]), "v": _conversion("km/h", "m/s", "test") * d["VehicleSpeed"],
            "aliveState": float(k % 16)}


def test_the_steering_network_on_canbus_equals_the_fmi2_ecus(tmp_path, db):
    """sensors, the three ECUs and the three actuator modules on CanBus without wire time:
    module 2 and 3's ECUs get the sensors' frames and the tractor ECU's TractorECU_State of
    their tick (the FMI 2.0 ECUs fed those signals give the same outputs), the actuators
    the set-points their ECU sent at the tick, at 0.01 deg resolution, never stale"""
    n = 100
    ecu, act = fmu3("SteeringECU_LSBUS"), fmu3("SteeringActuator_LSBUS")
    nodes = {"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu1": (ecu, {"module": 1}),
             "ecu2": (ecu, {"module": 2}), "ecu3": (ecu, {"module": 3}),
             "act1": (act, {"module": 1}), "act2": (act, {"module": 2}), "act3": (act, {"module": 3})}

    def inp(t):
        s, v = forwards(t)
        return {"sensors": s, "ecu1": {"vVehicle": v}}

    outs = {"ecu1": ["drivingDirection"], "ecu2": list(OUTS), "ecu3": list(OUTS),
            "act2": ["cmdRx[1]", "cmdRx[2]", "stale"], "act3": ["cmdRx[1]", "cmdRx[2]", "stale"]}
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as net:
        net.run(n * TS, inp, outs)
        res, n_time, frames = net.results, len(net.time), net.frames
    assert n_time == n

    s0, v0 = forwards(0.0)
    ref1 = Fmi2Ecu(tmp_path, 1, dict(quantized(db, s0, 0), v=v0))
    direction0 = 0.0            # drivingDirection's start: the tractor ECU's first frame precedes its init
    first = dict(quantized(db, s0, 0), **state_inputs(db, direction0, v0, 0))
    refs = {m: Fmi2Ecu(tmp_path, m, first) for m in (2, 3)}
    rows = {2: [], 3: []}
    direction = direction0
    try:
        for k in range(n):
            s, v = forwards(k * TS)
            sens = quantized(db, s, k)
            ref1.feed(dict(sens, v=v))
            state = state_inputs(db, direction, v, k)
            for m in (2, 3):
                refs[m].feed(dict(sens, **state))
                refs[m].f.doStep(k * TS, TS)
                rows[m].append(refs[m].get(OUTS))
            ref1.f.doStep(k * TS, TS)
            direction = ref1.get(["drivingDirection"])[0]
    finally:
        for r in [ref1, *refs.values()]:
            r.close()

    for m in (2, 3):
        got = [[res[f"ecu{m}"][o][k] for o in OUTS] for k in range(n)]
        assert got == rows[m], m
        assert max(abs(r[0]) for r in got) > 1e-3        # it steers
        # the actuators: the set-points the ECU sent at tick k (its outputs of the step before),
        # at the DBC's 0.01 deg
        for k in range(1, n):
            for i in (0, 1):
                want = DEG_RAD * (round(RAD_DEG * rows[m][k - 1][i] / 0.01) * 0.01)
                assert res[f"act{m}"][f"cmdRx[{i + 1}]"][k] == pytest.approx(want, abs=1e-12), (m, k, i)
        assert not any(res[f"act{m}"]["stale"])
    # the actuators send only their Configuration (0x40, CAN_BAUDRATE) at t0, then zero-size
    # Tx_Data at every tick, which activate no clock and reach no one
    acts = [f for f in frames if f[1].startswith("act")]
    assert [(f[0], f[1], struct.unpack_from("<I", f[4])[0], len(f[4])) for f in acts] == \
        [(0.0, f"act{m}", 0x40, 13) for m in (1, 2, 3)]


# ---- the frames in a CAN log ------------------------------------------------------------------

def sensor_frame(db, msg, sig, value, k):
    """the sensors' frame as the runner's Python encoder builds it (cantools strict, the
    alive counter k mod 16, then the E2E profile 2 CRC)"""
    m = db.get_message_by_name(msg)
    data = bytearray(m.encode({sig: RAD_DEG * value, "AliveCounter": k % 16, "CRC": 0}, scaling=True, strict=True))
    data[0] = e2e_crc(data, int(m.dbc.attributes["E2EDataID"].value))
    return bytes(data)


@pytest.mark.parametrize("wire,suffix", [(False, ".asc"), (True, ".blf")])
def test_the_can_log_has_every_frame_on_its_grid_with_the_encoders_bytes(tmp_path, db, wire, suffix):
    """the whole network for 0.5 s into a log, read back with python-can (artibus.can.decode_log,
    the receivers' E2E check): every frame E2E-good; without wire time each message at
    k * 10 ms exactly, with it at the tick plus the wire time of the tick's frames up to it in
    identifier order; the sensors' payloads those of the Python encoder, byte for byte"""
    import can
    from artibus.can import decode_log
    from artibus.runner.lsbus import write_can_log
    n = 50
    ecu, act = fmu3("SteeringECU_LSBUS"), fmu3("SteeringActuator_LSBUS")
    nodes = {"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu1": (ecu, {"module": 1}),
             "ecu2": (ecu, {"module": 2}), "ecu3": (ecu, {"module": 3}),
             "act1": (act, {"module": 1}), "act2": (act, {"module": 2}), "act3": (act, {"module": 3})}

    def inp(t):
        s, v = forwards(t)
        return {"sensors": s, "ecu1": {"vVehicle": v}}

    log = tmp_path / f"frames{suffix}"
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": wire})) as net:
        net.run(n * TS, inp)
        write_can_log(net.wire_frames(), log)
    rows = decode_log(log, db)
    assert rows and all(r[5] == "ok" for r in rows)          # E2E: 100 %
    with can.LogReader(str(log)) as reader:
        msgs = [(m.timestamp, m.arbitration_id, bytes(m.data)) for m in reader]
    ids = {m.frame_id for m in db.messages}
    by_tick = {}
    for t, i, d in msgs:
        by_tick.setdefault(math.floor(t / TS + 1e-9), []).append((t, i, d))
    assert sorted(by_tick) == list(range(n if wire else n + 1))   # frames sent at the stop time: not on the wire yet
    for k, frames in by_tick.items():
        assert sorted(i for _, i, _ in frames) == sorted(ids)     # each message once per tick
        t = k * TS
        for ft, i, d in sorted(frames, key=lambda f: f[1]):
            t += wire_time(i, d) if wire else 0.0
            assert ft == pytest.approx(t, abs=2e-6 if suffix == ".asc" else 1e-9), (k, hex(i))
        s, _ = forwards(k * TS)
        got = {i: d for _, i, d in frames}
        for msg, sig, name, _ in SENSORS:
            assert got[db.get_message_by_name(msg).frame_id] == sensor_frame(db, msg, sig, s[name], k)


def test_with_wire_time_the_ecu_works_one_cycle_later():
    """with wire time the frames of tick k (sent at t_k, on the wire 0.2-1.1 ms) reach the ECU
    after its tick k: it samples them at tick k + 1. So its outputs are those of the FMI 2.0
    ECU fed the frames of tick k - 1 at tick k, and nothing before the first frame (the node
    starts from its start values, as the FMI 2.0 ECU initialised without inputs)"""
    db = cantools.database.load_file(str(DBC), strict=True)
    n = 100
    rows, _ = run(bus={}, t_stop=n * TS)
    path = fmu_dir() / "SteeringECU.fmu"
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(path))
    f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="SteeringECU", instanceName="late")
    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setInteger([vr["module"]], [1])
    f.exitInitializationMode()
    want = []
    for k in range(n):
        s, v = signals(k * TS)
        got = dict(quantized(db, signals((k - 1) * TS)[0], k - 1) if k >= 1 else {}, v=v)
        f.setReal([vr[x] for x in got], list(got.values()))
        f.doStep(k * TS, TS)
        want.append(f.getReal([vr[x] for x in OUTS]))
    f.terminate()
    f.freeInstance()
    n_out = OUTS.index("gamma1")                     # the outputs, then the received inputs
    assert [r[:n_out] for r in rows] == [w[:n_out] for w in want]
    assert max(abs(r[0]) for r in rows) > 1e-3       # it steers
    # the received inputs it shows at t_(k+1) are tick k's: they arrived within the cycle
    for k, r in enumerate(rows):
        q = quantized(db, signals(k * TS)[0], k)
        assert r[n_out:] == [q[x] for x in OUTS[n_out:]], k


def test_the_tx_ticks_are_the_periods_multiples():
    """t0 + k * 10 ms, none skipped or doubled, from any time between them"""
    with network() as net:
        (term,) = net.by_name["ecu"].terminals.values()
        assert term.period == TS and term.shift == 0.0          # intervalDecimal="0.01" of the description
        for k in range(0, 1000, 7):
            tk = k * TS
            assert term.ticks_at(0.0, tk) and not term.ticks_at(0.0, tk + 1e-6)
            for t in (tk - 5e-10, tk, tk + 5e-10):              # the instant t_k itself, within EPS = 1 ns
                assert term.next_tick(0.0, t) == (k + 1) * TS
            if k:
                assert term.next_tick(0.0, tk - 5e-9) == tk     # 5 ns before it: another instant


def test_a_network_that_cannot_be_opened_frees_what_it_opened(monkeypatch):
    """the third node's parameter refused: the two instances opened before it are freed
    (fmi3FreeInstance called on each), the error names the FMU and the variable"""
    from artibus.runner import lsbus
    freed = []
    real = lsbus.Fmu.close

    def close(self):
        if self.fmu is not None:
            freed.append(self.name)
        real(self)

    monkeypatch.setattr(lsbus.Fmu, "close", close)
    nodes = {"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu": (fmu3("SteeringECU_LSBUS"), {"module": 1}),
             "act": (fmu3("SteeringActuator_LSBUS"), {"modul": 1})}
    with pytest.raises(LsBusError, match=r"SteeringActuator_LSBUS.fmu: FMU act has no variable 'modul'"):
        Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 3}))
    assert sorted(freed) == ["act", "ecu", "sensors"]


def test_an_fmu_instantiated_only_once_per_process_is_not_two_nodes(tmp_path):
    """canBeInstantiatedOnlyOncePerProcess="true" (FMI 3.0 2.2.5): the instances of one FMU
    would share its library, so a second node of it is refused, naming both"""
    import zipfile
    src, copy = fmu3("SteeringECU_LSBUS"), tmp_path / "OnceECU.fmu"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(copy, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b"<CoSimulation", b'<CoSimulation canBeInstantiatedOnlyOncePerProcess="true"', 1)
            zout.writestr(item, data)
    nodes = {"ecu1": (copy, {"module": 1}), "ecu2": (copy, {"module": 2})}
    with pytest.raises(LsBusError, match=r"FMU ecu2 and ecu1 are one FMU, which says canBeInstantiatedOnlyOnce"):
        Network(nodes)


def operations(buf):
    """[(op code, payload bytes)] of an FMI-LS-BUS buffer (4_2 operations: OP Code u32, Length u32
    counting the whole operation, then its arguments)"""
    out, pos = [], 0
    while pos < len(buf):
        code, length = struct.unpack_from("<II", buf, pos)
        out.append((code, bytes(buf[pos + 8:pos + length])))
        pos += length
    return out


def test_nodes_sending_as_the_standards_example_node_get_each_confirm_at_the_closed_form_time():
    """Our nodes in the Tx clock's triggered form (as the fmi-ls-bus example node: an output
    triggered Tx clock, a Configuration at the start, then Transmits) on CanBus with wire time,
    run by our master: each node's Configuration (OP Code 0x40) reaches the bus at t = 0; each
    Transmit arrives at the other node at the tick plus the wire times of the frames before it
    by identifier (as the periodic form's, test above), and its sender gets one Confirm (4_4_1_can.adoc,
    Confirm: OP Code 0x20, Length 12, the frame's ID) at that same time"""
    triggered = Path(fmu3("CanBus")).parent / "lsbus-triggered"
    nodes = {"sensors": (triggered / "SteeringSensors_LSBUS_Triggered.fmu", {}),
             "ecu": (triggered / "SteeringECU_LSBUS_Triggered.fmu", {"module": 1})}
    n_ticks = 12
    with Network(nodes, bus=(fmu3("CanBus"), {"nNodes": 2})) as net:
        net.run(n_ticks * TS, inputs, {"ecu": list(OUTS)})
        frames = net.frames
    to_bus = [(t, src, operations(d)) for t, src, dst, _, d in frames if dst == "bus"]
    for who in nodes:
        first = [ops for t, src, ops in to_bus if src == who and t == 0.0]
        assert any(code == 0x40 for ops in first for code, _ in ops), who        # Configuration first
    from_bus = [(t, dst, code, p) for t, src, dst, _, d in frames if src == "bus" for code, p in operations(d)]
    checked = 0
    for k in range(n_ticks):
        sent = sorted((struct.unpack_from("<I", p)[0], p[8:8 + struct.unpack_from("<H", p, 6)[0]], src)
                      for t, src, ops in to_bus if abs(t - k * TS) < 1e-12 for code, p in ops if code == 0x10)
        t = k * TS
        for i, d, src in sent:                       # arbitration: lowest identifier first
            t += wire_time(i, d)
            other = "ecu" if src == "sensors" else "sensors"
            during = [x for x in from_bus if k * TS < x[0] < (k + 1) * TS and struct.unpack_from("<I", x[3])[0] == i]
            got = [x for x in during if x[1] == other and x[2] == 0x10]
            assert len(got) == 1 and got[0][0] == pytest.approx(t, abs=1e-12), (k, hex(i), got)
            confirms = [x for x in during if x[1] == src and x[2] == 0x20]
            assert len(confirms) == 1 and len(confirms[0][3]) == 4, (k, hex(i), confirms)   # Length 12: the ID
            assert confirms[0][0] == pytest.approx(t, abs=1e-12), (k, hex(i))
            checked += 1
    assert checked >= 5 * (n_ticks - 1)              # the sensors' four frames and the ECU's, every tick
