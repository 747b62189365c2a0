"""Our FMI-LS-BUS nodes and CanBus under an importer written here from the standards' text
alone (issue 39), sharing no code with artibus.runner.lsbus or src/runner_core/lsbus.c: FMPy's
FMU3Slave called directly, the terminals read from terminalsAndIcons.xml.

What the importer does, and where the text says so:
- FMI 3.0.2, 2.2.8 (2_2_common_mechanisms.adoc, "Getting and Setting Variable Values"):
  clocked variables are set and read "only during Event Mode when their respective Clocks are
  active"; so Tx_Data is read after its Tx_Clock is activated (input clock: fmi3SetClock;
  triggered output clock: fmi3GetClock says active) and BEFORE fmi3UpdateDiscreteStates,
  which ends the clocks' activation (2_3_common_states.adoc, Event Mode);
- 2_2_common_mechanisms.adoc, "Model Partitions and Clocked Variables": reading an output of
  an active clock computes it (the output function f_event), so inputs are set first:
  Float64 inputs, clocks, Rx_Data, then Tx_Data is read;
- time-based input clocks: periodic (constant/fixed: t0 + shift + k interval) and countdown
  (the interval from fmi3GetIntervalDecimal in every Event Mode, qualifier changed, relative
  to the current Event Mode; interval >= 0, "Countdown aperiodic Clock" restrictions); a
  countdown interval of 0 is served in the same instant: an event iteration when the FMU
  asked for one (discreteStatesNeedUpdate), otherwise a new Event Mode at the same time;
- eventHandlingNeeded of fmi3DoStep: the FMU enters Event Mode at the step's end
  (fmi-ls-bus 1.0, 4____network_abstraction.adoc, "Triggered Tx Clocks");
- routing (fmi-ls-bus 1.0, 2____common_concepts.adoc, composition with a bus simulation FMU
  or directly): Tx_Data -> the linked Rx_Data, a zero-size Tx_Data activates no Rx_Clock
  (4____network_abstraction.adoc, "Tx/Rx Data Variables", "Rx Clocks");
- per instant: the nodes, then the bus, then what the bus answers, until nothing is left
  (super-dense time), bounded.

What is checked, against closed forms computed here: the frames every node sends per tick
(the DBC's ids, alive counters k mod 16, E2E CRC, payloads = the inputs at the DBC's
resolution), every frame reaching every other node once and its Confirm its sender
(4_4_1_can.adoc, "Confirm"), arbitration by identifier with wire time (ISO 11898-1; frame
bits of tests/test_canbus.py), the direct composition of two nodes, and that our master
(artibus.runner.lsbus) puts the same frames on the wire as this importer.
"""
import math
import xml.etree.ElementTree as ET
import zipfile
from collections import defaultdict

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from artibus.can import e2e_crc

from conftest import fmu3
from test_canbus import wire_time

TS = 0.01            # s: the DBC's GenMsgCycleTime, the nodes' Tx_Clock interval
EPS = 1e-9
CHANGED = 2          # fmi3IntervalChanged (fmi3FunctionTypes.h)
NETWORK_TERMINAL = "org.fmi-ls-bus.network-terminal"
TRANSMIT, CONFIRM = 0x10, 0x20     # 4_4_1_can.adoc, the CAN operation codes


def ops(data):
    """[(op code, body)] of a Tx/Rx_Data: each operation OP Code u32, Length u32 (whole
    operation), then its arguments (4____network_abstraction.adoc, operation layout)"""
    out, pos = [], 0
    while pos < len(data):
        code, length = int.from_bytes(data[pos:pos + 4], "little"), int.from_bytes(data[pos + 4:pos + 8], "little")
        assert length >= 8 and pos + length <= len(data), data.hex()
        out.append((code, data[pos + 8:pos + length]))
        pos += length
    return out


def transmits(data):
    """[(id, payload)] of the CAN Transmit operations (ID u32, Ide u8, Rtr u8, Data Length
    u16, Data: 4_4_1_can.adoc, "CAN Transmit")"""
    out = []
    for code, body in ops(data):
        if code == TRANSMIT:
            n = int.from_bytes(body[6:8], "little")
            out.append((int.from_bytes(body[:4], "little"), bytes(body[8:8 + n])))
    return out


# ---- the importer ---------------------------------------------------------------------------

class Terminal:
    def __init__(self, unit, name, members, clocks, variables):
        self.unit, self.name = unit, name
        vr = {m: variables[v].valueReference for m, v in members.items()}
        self.rx_data, self.tx_data, self.rx_clock, self.tx_clock = (
            vr["Rx_Data"], vr["Tx_Data"], vr["Rx_Clock"], vr["Tx_Clock"])
        c = clocks[members["Tx_Clock"]]
        self.kind, self.causality = c.get("intervalVariability"), c.get("causality")
        self.periodic = self.causality == "input" and self.kind in ("constant", "fixed")
        if self.periodic:
            self.interval = float(c["intervalDecimal"])
            self.shift = float(c.get("shiftDecimal", "0"))
        self.due = None          # a countdown clock's announced activation time
        self.last = None         # a periodic clock's last activation (once per instant)

    def ticks(self, t0, t):
        if not self.periodic or (self.last is not None and abs(self.last - t) < EPS):
            return False
        k = round((t - t0 - self.shift) / self.interval)
        return k >= 0 and abs(t0 + self.shift + k * self.interval - t) < EPS

    def next_tick(self, t0, t):
        k = math.floor((t + EPS - t0 - self.shift) / self.interval) + 1
        return t0 + self.shift + max(k, 0) * self.interval


class Unit:
    """one FMI 3.0 Co-Simulation FMU with Event Mode and its network terminals"""

    def __init__(self, name, path, params, t0, settle=False):
        self.name, self.log, self.settle = name, [], settle
        md = read_model_description(str(path))
        self.variables = {v.name: v for v in md.modelVariables}
        with zipfile.ZipFile(path) as z:
            clocks = {c.get("name"): c.attrib for c in ET.fromstring(z.read("modelDescription.xml")).iter("Clock")}
            icons = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        self.terminals = [Terminal(self, t.get("name"), {m.get("memberName"): m.get("variableName")
                                                         for m in t.findall("TerminalMemberVariable")},
                                   clocks, self.variables)
                          for t in icons.iter("Terminal") if t.get("terminalKind") == NETWORK_TERMINAL]
        self.fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), instanceName=name,
                             modelIdentifier=md.coSimulation.modelIdentifier)
        self.fmu.instantiate(eventModeUsed=True, logMessage=self._logger())
        self.fmu.enterInitializationMode(startTime=t0)
        for key, value in params.items():
            self.set(key, value)
        self.fmu.exitInitializationMode()          # Event Mode (FMI 3.0.2, 4.2.1: eventModeUsed)
        # the Event Mode after initialisation is handled as any other: its output clocks read
        self.state, self.need, self.flagged, self.next_event = "event", False, True, math.inf
        self.query_intervals(t0)

    def _logger(self):
        from fmpy.fmi3 import fmi3LogMessageCallback

        def log(env, status, category, message):
            self.log.append((status, message.decode()))
        self._keep = fmi3LogMessageCallback(log)
        return log

    def set(self, name, value):
        v = self.variables[name]
        setter = {"Float64": self.fmu.setFloat64, "Int32": self.fmu.setInt32,
                  "Boolean": self.fmu.setBoolean, "Enumeration": self.fmu.setInt64}[v.type]
        setter([v.valueReference], [value])

    def get(self, name):
        v = self.variables[name]
        return {"Float64": self.fmu.getFloat64, "Int32": self.fmu.getInt32,
                "Boolean": self.fmu.getBoolean}[v.type]([v.valueReference])[0]

    def query_intervals(self, t):
        """countdown Tx clocks: fmi3GetIntervalDecimal, changed -> due at t + interval"""
        import ctypes
        cd = [term for term in self.terminals if term.kind == "countdown"]
        if not cd:
            return
        vrs = (ctypes.c_uint32 * len(cd))(*[term.tx_clock for term in cd])
        iv, q = (ctypes.c_double * len(cd))(), (ctypes.c_int * len(cd))()
        self.fmu.getIntervalDecimal(vrs, iv, q)
        for i, term in enumerate(cd):
            if q[i] == CHANGED:
                assert iv[i] >= 0, (self.name, term.name, iv[i])
                term.due = t + iv[i]

    def begin_event(self, t):
        """Event Mode to activate clocks in: from Step Mode, a further iteration, or a new
        Event Mode at the same time after an update that asked for none; with settle, the
        same Event Mode: a new super-dense instant begins with fmi3SetClock (FMI 3.0.2, 2.3,
        Event Mode, fmi3SetClock: "No further constraints are imposed on the activation of
        time-based Clocks"; aperiodic clocks may be active for more than one update)"""
        if self.state == "updated" and not self.need and not self.settle:
            self.fmu.enterStepMode()
            self.state = "step"
        if self.state == "step":
            self.fmu.enterEventMode()
            self.query_intervals(t)
        self.state = "event"

    def event(self, t, tx_input, rx, inputs):
        """one activation: inputs, clocks, Rx_Data, Tx_Data read while its clock is active,
        then fmi3UpdateDiscreteStates; {terminal: Tx_Data}"""
        self.begin_event(t)
        for name, value in inputs.items():
            self.set(name, value)
        clocks = [term.tx_clock for term in tx_input] + [term.rx_clock for term in rx]
        if clocks:
            self.fmu.setClock(clocks, [True] * len(clocks))
        if rx:
            self.fmu.setBinary([term.rx_data for term in rx], list(rx.values()))
        active = list(tx_input)
        out_clocked = [term for term in self.terminals if term.causality == "output"]
        if out_clocked:
            flags = self.fmu.getClock([term.tx_clock for term in out_clocked])
            active += [term for term, on in zip(out_clocked, flags) if on]
        data = self.fmu.getBinary([term.tx_data for term in active]) if active else []
        self.need, terminate, _, _, defined, t_next = self.fmu.updateDiscreteStates()
        for _ in range(20 if self.settle else 0):   # settle: iterate until no update is asked for
            if not self.need:
                break
            self.need, terminate, _, _, defined, t_next = self.fmu.updateDiscreteStates()
        assert not terminate
        self.state = "updated"
        self.next_event = t_next if defined else math.inf
        self.query_intervals(t)
        return {term: bytes(d or b"") for term, d in zip(active, data)}

    def due_now(self, t0, t):
        return [term for term in self.terminals
                if term.ticks(t0, t) or (term.due is not None and term.due <= t + EPS)]

    def step(self, t, h):
        if self.state != "step":
            self.fmu.enterStepMode()
            self.state = "step"
        handling, terminate, early, _ = self.fmu.doStep(t, h)
        assert not terminate and not early
        self.flagged = handling

    def close(self):
        try:
            self.fmu.terminate()
        except Exception:            # an instance in the error state: freed all the same
            pass
        self.fmu.freeInstance()


class Importer:
    """nodes [(name, path, params)], bus (path, params) or None (then two nodes linked
    directly); inputs(t) -> {node: {variable: value}} set at the node's Tx activations"""

    MAX_ROUNDS = 50

    def __init__(self, nodes, bus=None, t0=0.0, settle=False):
        """settle: the bus's updates repeated until it asks for no further one, then its
        clocks due now (a countdown interval of 0) set in the same Event Mode"""
        self.t0 = self.t = t0
        self.units = [Unit(n, p, params, t0) for n, p, params in nodes]
        self.links = {}
        if bus:
            self.bus = Unit("bus", bus[0], bus[1], t0, settle)
            for node, bt in zip(self.units, self.bus.terminals):
                self.links[node.terminals[0]] = bt
                self.links[bt] = node.terminals[0]
            self.units.append(self.bus)
        else:
            self.bus = None
            a, b = self.units[0].terminals[0], self.units[1].terminals[0]
            self.links = {a: b, b: a}
        self.routed = []        # (t, from unit, to unit, bytes)

    def instant(self, inputs):
        """every activation at self.t: rounds over the units in order until none has work"""
        pending = defaultdict(bytes)
        values = inputs(self.t) if inputs else {}
        for _ in range(self.MAX_ROUNDS):
            busy = False
            for u in self.units:
                # FMI 3.0.2, 4.2, fmi3EnterEventMode: Event Mode when the FMU's step returned
                # eventHandlingNeeded or time reached its nextEventTime (a triggered output
                # clock's tick: fmi-ls-bus 1.0, "Triggered Tx Clocks"); its output clocks read there
                woke = u.flagged or u.next_event <= self.t + EPS
                if woke:
                    u.begin_event(self.t)
                    u.flagged, u.next_event = False, math.inf
                due = u.due_now(self.t0, self.t)
                rx = {term: pending.pop(term) for term in u.terminals if term in pending}
                if not due and not rx and not woke:
                    continue
                busy = True
                for term in due:
                    term.due, term.last = None, self.t
                ticking = any(term.periodic for term in due) or woke    # woke: a triggered tick, maybe
                out = u.event(self.t, due, rx, values.get(u.name, {}) if ticking else {})
                for term, data in out.items():
                    if data:      # zero size: no Rx clock activated
                        dst = self.links[term]
                        self.routed.append((self.t, u.name, dst.unit.name, data))
                        pending[dst] += data
            if not busy:
                return
        raise AssertionError(f"t = {self.t}: still busy after {self.MAX_ROUNDS} rounds")

    def next_time(self, stop):
        cands = [stop]
        for u in self.units:
            for term in u.terminals:
                if term.periodic:
                    cands.append(term.next_tick(self.t0, self.t))
                if term.due is not None:
                    cands.append(term.due)
            cands.append(u.next_event)
        return min(c for c in cands if c > self.t + EPS)

    def run(self, stop, inputs=None):
        while True:
            self.instant(inputs)
            if self.t >= stop - EPS:
                return self
            t_next = self.next_time(stop)
            for u in self.units:
                u.step(self.t, t_next - self.t)
            self.t = t_next

    def wire(self):
        """[(t, id, payload)] each CAN frame once, as the bus delivers it (or, without a bus,
        as the sender sends it)"""
        seen = []
        for t, src, dst, data in self.routed:
            if self.bus and src != "bus":
                continue
            for f in transmits(data):
                if (t, src, f) not in seen:
                    seen.append((t, src, f))
        return sorted((round(t, 9), i, d) for t, _, (i, d) in seen)

    def close(self):
        for u in self.units:
            u.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---- the bench's nodes ----------------------------------------------------------------------

SENSOR_IDS = (0x101, 0x102, 0x103, 0x104)
SENT_BY = {"sensors": SENSOR_IDS, "ecu1": (0x110, 0x118), "ecu2": (0x120,), "ecu3": (0x130,)}


def bench_nodes():
    """Bus36m_Circle_LSBUS's seven nodes in its order (ssp/benches/Bus36m_Circle_LSBUS)"""
    ecu, act = fmu3("SteeringECU_LSBUS"), fmu3("SteeringActuator_LSBUS")
    return [("sensors", fmu3("SteeringSensors_LSBUS"), {})] + \
        [(f"ecu{m}", ecu, {"module": m}) for m in (1, 2, 3)] + [(f"act{m}", act, {"module": m}) for m in (1, 2, 3)]


def angles(t):
    """the plant's angles (rad) and the speed (m/s, forwards), smooth and within the DBC's ranges"""
    return {"gamma1": 0.05 * math.sin(3 * t), "dPsi[1]": 0.2 * math.sin(2 * math.pi * t / 1.5) + 0.01,
            "dPsi[2]": 0.15 * math.sin(0.8 * t + 0.3), "gammaA6": 0.03 * math.cos(t)}, 3.0 + 0.2 * math.sin(t)


def bench_inputs(t):
    s, v = angles(t)
    return {"sensors": s, "ecu1": {"vVehicle": v}}


def by_tick(routed, src):
    """{tick k: [(id, payload)]} of what src sent"""
    out = defaultdict(list)
    for t, s, _, data in routed:
        if s == src:
            k = round(t / TS)
            assert abs(t - k * TS) < EPS
            out[k] += transmits(data)
    return out


def test_every_frame_of_our_nodes_reaches_canbus_and_every_receiver(db):
    n = 20
    with Importer(bench_nodes(), bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as imp:
        imp.run(n * TS, bench_inputs)
        routed = imp.routed
        cmd2 = [imp.units[5].get(f"cmdRx[{i}]") for i in (1, 2)]
        ecu2_cmd = [imp.units[2].get(v) for v in ("gammaFront", "gammaRear")]
    # what each sender sends: its DBC messages at every tick 0..n, counters k mod 16, E2E CRC
    for node, ids in SENT_BY.items():
        ticks = by_tick(routed, node)
        assert sorted(ticks) == list(range(n + 1)), node
        for k, frames in ticks.items():
            assert [i for i, _ in frames] == list(ids), (node, k)
            for i, d in frames:
                m = db.get_message_by_frame_id(i)
                assert len(d) == m.length and d[1] & 0x0F == k % 16, (node, k, hex(i))
                assert d[0] == e2e_crc(d, int(m.dbc.attributes["E2EDataID"].value)), (node, k, hex(i))
    # the sensors' payloads: the inputs at the tick, within half the DBC's resolution
    for k, frames in by_tick(routed, "sensors").items():
        s, _ = angles(k * TS)
        for (i, d), name in zip(frames, ("gamma1", "dPsi[1]", "dPsi[2]", "gammaA6")):
            sig = db.get_message_by_frame_id(i).signals[2]
            value = db.decode_message(i, d)[sig.name]
            assert value == pytest.approx(math.degrees(s[name]), abs=sig.scale / 2 + 1e-9), (k, name)
    # every frame reaches every other node once at its own tick (wire time off), its sender a Confirm
    names = ["sensors", "ecu1", "ecu2", "ecu3", "act1", "act2", "act3"]
    got = defaultdict(list)
    for t, s, dst, data in routed:
        if s == "bus":
            got[(round(t / TS), dst)] += ops(data)
    for k in range(n + 1):
        sent = {node: by_tick(routed, node)[k] for node in SENT_BY}
        for dst in names:
            expect = sorted(f for node, frames in sent.items() if node != dst for f in frames)
            arrived = sorted(transmits(b"".join(c.to_bytes(4, "little") + (8 + len(b)).to_bytes(4, "little") + b
                                                for c, b in got[(k, dst)])))
            assert arrived == expect, (k, dst)
            confirms = sorted(int.from_bytes(b[:4], "little") for c, b in got[(k, dst)] if c == CONFIRM)
            assert confirms == sorted(i for i, _ in sent.get(dst, [])), (k, dst)
    # and consumed: a frame received at t is used by the receiver's sample at t, inside its
    # step from t (lsbus_node.h): module 2's actuator holds the set-points of ECU2's frame of
    # tick n - 1 (no step after tick n); ECU2's frame of tick n carries its last sample's
    # command, at the DBC's 0.01 deg
    def cmd(k):
        dec = db.decode_message(*by_tick(routed, "ecu2")[k][0])
        return [math.radians(dec["SteerCmdA3"]), math.radians(dec["SteerCmdA4"])]
    assert cmd2 == pytest.approx(cmd(n - 1), abs=1e-12)
    assert cmd(n - 1) != pytest.approx(cmd(n), abs=1e-6)       # the two ticks differ: the check can fail
    assert ecu2_cmd == pytest.approx(cmd(n), abs=math.radians(0.005) + 1e-12)


def test_our_master_puts_the_same_frames_on_the_wire_as_the_standard_importer():
    """Bus36m_Circle_LSBUS's nodes on CanBus (wire time off, as the bench): artibus.runner.lsbus
    and this importer give the same frames (time, id, payload), each one once"""
    from artibus.runner.lsbus import Network
    n = 30
    nodes = bench_nodes()
    with Importer(nodes, bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as imp:
        ours = imp.run(n * TS, bench_inputs).wire()
    with Network({name: (path, p) for name, path, p in nodes},
                 bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": False})) as net:
        net.run(n * TS, bench_inputs)
        theirs = sorted((round(t, 9), i, bytes(d)) for t, i, _, d in net.wire_frames())
    assert len(ours) == 8 * (n + 1)           # 8 frames a tick, ticks 0..n
    assert theirs == ours


def test_with_wire_time_the_frames_of_a_tick_go_by_identifier_back_to_back():
    """CanBus with wire time, under this importer: the tick's 8 frames arbitrate by identifier
    (ISO 11898-1: the lowest wins), each delivered when its bits are through (frame bits with
    stuffing, 500 kbit/s: tests/test_canbus.py), back to back from the tick; its Confirm
    reaches its sender at that same time"""
    n = 5
    with Importer(bench_nodes(), bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": True})) as imp:
        imp.run(n * TS, bench_inputs)
        routed = imp.routed
    for k in range(n):
        sent = sorted(f for node in SENT_BY for f in by_tick(routed, node)[k])
        assert len(sent) == 8
        t = k * TS
        for i, d in sent:
            t += wire_time(i, d)
            at = [(tt, dst) for tt, src, dst, data in routed if src == "bus" and (i, d) in transmits(data)]
            assert len(at) == 6 and all(tt == pytest.approx(t, abs=1e-12) for tt, _ in at), (k, hex(i), at)
            sender = next(node for node, ids in SENT_BY.items() if i in ids)
            conf = [tt for tt, src, dst, data in routed if src == "bus" and dst == sender
                    for c, b in ops(data) if c == CONFIRM and int.from_bytes(b[:4], "little") == i]
            assert [c for c in conf if k * TS < c < (k + 1) * TS] == [pytest.approx(t, abs=1e-12)], (k, hex(i))
        assert t < (k + 1) * TS


def test_two_nodes_connected_directly_under_the_standard_importer(db):
    """the sensors' node linked to module 2's ECU without a bus simulation (fmi-ls-bus 1.0,
    2____common_concepts.adoc, direct composition): the ECU gets every sensor frame at its
    tick, and its received angles are the last frame's, at the DBC's resolution"""
    n = 12
    nodes = [("sensors", fmu3("SteeringSensors_LSBUS"), {}), ("ecu2", fmu3("SteeringECU_LSBUS"), {"module": 2})]
    with Importer(nodes) as imp:
        imp.run(n * TS, lambda t: {"sensors": angles(t)[0]})
        routed = imp.routed
        got = {name: imp.units[1].get(name) for name in ("gamma1", "dPsi[1]", "dPsi[2]", "gammaA6")}
    to_ecu = by_tick([r for r in routed if r[2] == "ecu2"], "sensors")
    assert sorted(to_ecu) == list(range(n + 1))
    assert all([i for i, _ in f] == list(SENSOR_IDS) for f in to_ecu.values())
    s, _ = angles(n * TS)
    for (i, d), name in zip(to_ecu[n], got):
        sig = db.get_message_by_frame_id(i).signals[2]
        assert got[name] == pytest.approx(math.radians(db.decode_message(i, d)[sig.name]), abs=1e-12)
        assert got[name] == pytest.approx(s[name], abs=math.radians(sig.scale / 2) + 1e-12)
    ecu_sent = by_tick(routed, "ecu2")
    assert [i for i, _ in ecu_sent[n]] == [0x120]          # and the ECU's frames reach the sensors' node


@pytest.mark.parametrize("wire", [False, True])
def test_canbus_takes_a_countdown_clock_of_interval_0_after_an_update_that_asked_for_none(wire):
    """An importer that repeats fmi3UpdateDiscreteStates until the FMU asks for no more, then
    reads the countdown intervals (FMI 3.0.2, 2.3, Event Mode: "these functions should be called
    after fmi3UpdateDiscreteStates") and activates the clocks due now (interval 0, allowed for
    countdown clocks: 2.2.9, "Countdown aperiodic Clock", T_interval >= 0) in the same Event
    Mode, a new super-dense instant begun by fmi3SetClock (2.3: "No further constraints are
    imposed on the activation of time-based Clocks"; aperiodic clocks with interval 0 may be
    active for more than one update): CanBus takes them, and the same frames reach the wire
    as under the importer that iterates as CanBus asks"""
    n = 6
    runs = []
    for settle in (False, True):
        with Importer(bench_nodes(), bus=(fmu3("CanBus"), {"nNodes": 7, "wireTime": wire}), settle=settle) as imp:
            runs.append(imp.run(n * TS, bench_inputs).wire())
    assert len(runs[0]) == 8 * (n + 1) - (8 if wire else 0)   # with wire time the last tick's are still on the wire
    assert runs[1] == runs[0]


# ---- our master (artibus.runner.lsbus) on nodes that misbehave ---------------------------------

def two_nodes():
    return {"sensors": (fmu3("SteeringSensors_LSBUS"), {}), "ecu": (fmu3("SteeringECU_LSBUS"), {"module": 2})}


def sensors_only(t):
    return {"sensors": angles(t)[0]}


def test_a_node_that_never_leaves_event_mode_is_named_with_its_clock_and_the_time():
    """from t = 0.03 s on, the ECU's fmi3UpdateDiscreteStates always asks for a further
    iteration: after the master's bound, one error naming the node, the clock of that Event
    Mode and the time (FMI 3.0.2, 2.3: discreteStatesNeedUpdate keeps the importer in Event
    Mode; the master does not loop for ever)"""
    from artibus.runner.lsbus import LsBusError, Network
    with Network(two_nodes(), bus=(fmu3("CanBus"), {"nNodes": 2, "wireTime": False})) as net:
        ecu = net.by_name["ecu"]
        real = ecu.fmu.updateDiscreteStates

        def stuck():
            need, *rest = real()
            return (need or net.t > 0.025, *rest)
        ecu.fmu.updateDiscreteStates = stuck
        with pytest.raises(LsBusError) as e:
            net.run(10 * TS, sensors_only)
    msg = str(e.value)
    assert msg.startswith("t = 0.030000 s: node ecu (SteeringCAN.Tx_Clock active)"), msg
    assert "discreteStatesNeedUpdate after 100" in msg and "\n" not in msg


def test_a_tx_data_over_the_receiving_terminals_max_size_is_named_by_sender_clock_and_time():
    """at t = 0.03 s the sensors' node hands 2100 bytes of operations to CanBus's Node1.Rx_Data,
    whose maxSize is 2048 (modelDescription/fmi3/CanBus.xml; FMI 3.0.2, Binary maxSize): the
    master refuses it naming the sender, its Tx clock, the receiving terminal, both sizes and
    the time, before the bus sees it"""
    from artibus.runner.lsbus import LsBusError, Network
    with Network(two_nodes(), bus=(fmu3("CanBus"), {"nNodes": 2, "wireTime": False})) as net:
        sensors = net.by_name["sensors"]
        real = sensors.fmu.getBinary

        def big(vrs):
            out = real(vrs)
            return [bytes(2100) if net.t > 0.025 else d for d in out]
        sensors.fmu.getBinary = big
        with pytest.raises(LsBusError) as e:
            net.run(10 * TS, sensors_only)
        bus_log = net.bus.log
    msg = str(e.value)
    assert msg.startswith("t = 0.030000 s: node sensors: SteeringCAN.Tx_Data (SteeringCAN.Tx_Clock active) "
                          "has 2100 bytes"), msg
    assert "bus's Node1.Rx_Data" in msg and "maxSize 2048" in msg
    assert not [m for st, m in bus_log if st >= 3]           # refused before the bus was called
