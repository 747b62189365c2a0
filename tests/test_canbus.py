"""CanBus, the FMI-LS-BUS 1.0 CAN bus simulation FMU (fmus/fmi3/CanBus.fmu), driven
through FMPy's low-level FMU3Slave as an importer would: in Event Mode fmi3SetClock
(NodeK.Rx_Clock), fmi3SetBinary (NodeK.Rx_Data), fmi3UpdateDiscreteStates; the countdown
NodeK.Tx_Clock's interval (fmi3GetIntervalDecimal), a step to it, fmi3SetClock
(NodeK.Tx_Clock), fmi3GetBinary (NodeK.Tx_Data).

What is expected comes from the standards, computed here on their own:
- the operations' bytes from the tables of fmi-ls-bus v1.0.0 docs/4_4_1_can.adoc
  (parsed here with struct, not with the FMU's codec);
- the order of same-instant frames from CAN arbitration (ISO 11898-1: the lower
  identifier is dominant and wins), the losers' fate from 4_4_1_can.adoc "Arbitration"
  (BUFFER_AND_RETRANSMIT: retried, no Arbitration Lost; DISCARD_AND_NOTIFY: dropped,
  Arbitration Lost);
- a frame's time on the wire from its bits: a CAN 2.0A data frame has 44 + 8 DLC bits
  (SOF, 11-bit ID, RTR, IDE, r0, DLC 4, data, CRC 15, CRC delimiter, ACK 2, EOF 7), plus
  the stuff bits over SOF..CRC (a complement bit after five equal bits: the CRC-15 is
  computed here by polynomial division), plus the 3 bits of intermission; checked
  against the worst case 44 + 8n + floor((34 + 8n - 1) / 4) (Davis et al., Real-Time
  Systems 35, 2007, eq. 1) and the issue's 0.22-0.27 ms for 8 bytes at 500 kbit/s;
- the bus load as the frames' wire time over the time elapsed.
"""
import ctypes
import math
import struct
import zipfile

import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from artibus import fmu_dir

N = 8
BAUD = 500_000
MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
# value references: node k's members at 100 k + 1..5 (modelDescription/fmi3/CanBus.xml)
RX_DATA, TX_DATA, RX_CLOCK, TX_CLOCK, BUS_NOTIFICATIONS = 1, 2, 3, 4, 5
VR = {"baudrate": 1, "wireTime": 2, "arbitrationLostBehavior": 3, "faultStart": 4,
      "faultSilentNode": 5, "faultCorruptId": 6, "faultBusOffNode": 7, "nNodes": 8,
      "busLoad": 10, "nFrames": 11, "nBusErrors": 12, "nArbitrationLost": 13}
CHANGED = 2   # fmi3IntervalChanged
UNCHANGED, NOT_YET_KNOWN = 1, 0   # fmi3IntervalUnchanged, fmi3IntervalNotYetKnown


def vr(k, member):
    return 100 * k + member


# ---- the standard's operations, written and read here ---------------------------

def transmit(can_id, data, ide=0, rtr=0):
    """CAN Transmit 0x10: Length = 16 + DL (4_4_1_can.adoc, table-can-transmit-operation)."""
    return struct.pack("<IIIBBH", 0x10, 16 + len(data), can_id, ide, rtr, len(data)) + bytes(data)


def configuration(kind, value):
    """Configuration 0x40: kind 0x01 baud rate (u32), 0x04 arbitration lost behaviour (u8)."""
    arg = struct.pack("<I", value) if kind in (1, 2, 3) else bytes([value])
    return struct.pack("<IIB", 0x40, 9 + len(arg), kind) + arg


def status(value):
    return struct.pack("<IIB", 0x41, 9, value)


def parse(buf):
    """[(name, fields)] of a Tx_Data buffer; asserts it is well formed."""
    ops, pos = [], 0
    while pos < len(buf):
        code, length = struct.unpack_from("<II", buf, pos)
        assert 8 <= length <= len(buf) - pos, (buf.hex(), pos)
        a = buf[pos + 8:pos + length]
        if code == 0x10:
            can_id, ide, rtr, dl = struct.unpack_from("<IBBH", a)
            assert length == 16 + dl
            ops.append(("Transmit", (can_id, bytes(a[8:8 + dl]))))
        elif code == 0x20:
            assert length == 12
            ops.append(("Confirm", struct.unpack("<I", a)[0]))
        elif code == 0x30:
            assert length == 12
            ops.append(("ArbitrationLost", struct.unpack("<I", a)[0]))
        elif code == 0x31:
            assert length == 15
            ops.append(("BusError", struct.unpack("<IBBB", a)))
        elif code == 0x01:
            dl, = struct.unpack_from("<H", a)
            assert length == 10 + dl
            ops.append(("FormatError", bytes(a[2:2 + dl])))
        elif code == 0x42:
            assert length == 8
            ops.append(("Wakeup", None))
        else:
            raise AssertionError(f"unexpected operation 0x{code:02x} in {buf.hex()}")
        pos += length
    return ops


# ---- a CAN 2.0 frame's bits, computed on their own ---------------------------------

# x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1, coefficients from x^15 down (ISO 11898-1)
CRC15_GENERATOR = [1, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1]


def _bits(value, width):
    return [(value >> i) & 1 for i in range(width - 1, -1, -1)]


def crc15(bits):
    """The remainder of bits * x^15 divided by the generator (long division, mod 2)."""
    r = list(bits) + [0] * 15
    for i in range(len(bits)):
        if r[i]:
            for j, g in enumerate(CRC15_GENERATOR):
                r[i + j] ^= g
    return r[-15:]


def frame_bits(can_id, data, ide=False):
    """Bits on the wire of a data frame: the stuffed SOF..CRC, CRC delimiter, ACK slot and
    delimiter, EOF, then 3 bits of intermission."""
    if ide:
        head = [0] + _bits(can_id >> 18, 11) + [1, 1] + _bits(can_id & 0x3FFFF, 18) + [0, 0, 0]
    else:
        head = [0] + _bits(can_id, 11) + [0, 0, 0]
    body = head + _bits(len(data), 4) + [b for byte in data for b in _bits(byte, 8)]
    body += crc15(body)
    stuffed = []
    for b in body:
        stuffed.append(b)
        if len(stuffed) >= 5 and len(set(stuffed[-5:])) == 1:
            stuffed.append(1 - b)
    return len(stuffed) + 1 + 2 + 7 + 3


def wire_time(can_id, data, ide=False):
    return frame_bits(can_id, data, ide) / BAUD


# ---- an importer -------------------------------------------------------------------

@pytest.fixture(scope="module")
def unzipped():
    path = fmu_dir() / "fmi3" / "CanBus.fmu"
    assert path.is_file(), f"{path} not built: run the set-up command of the README"
    return path, read_model_description(str(path)), extract(str(path))


class Importer:
    """A master for CanBus alone: the nodes' operations handed in by send(), the bus's
    operations for each node recorded as (time, node, ops) in self.rx, and each Tx_Data
    as it came, (time, node, bytes), in self.raw."""

    def __init__(self, unzipped, **params):
        path, md, d = unzipped
        self.log = []
        self.fmu = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="CanBus",
                             instanceName="bus")
        self.fmu.instantiate(eventModeUsed=True, loggingOn=False,
                             logMessage=lambda env, st, cat, msg: self.log.append((st, msg.decode())))
        self.fmu.enterInitializationMode(startTime=0.0)
        for name, value in params.items():
            if isinstance(value, bool):
                self.fmu.setBoolean([VR[name]], [value])
            elif isinstance(value, float):
                self.fmu.setFloat64([VR[name]], [value])
            else:
                self.fmu.setInt32([VR[name]], [value])
        self.fmu.exitInitializationMode()        # in Event Mode now (eventModeUsed)
        self.t = 0.0
        self.event_mode, self.updated, self.need = True, False, False
        self.ticks = {}                            # node -> the time its Tx clock ticks
        self.rx = []
        self.raw = []

    def close(self):
        try:
            self.fmu.terminate()
        except FMICallException:          # a test that left it in the error state
            pass
        self.fmu.freeInstance()

    def _intervals(self):
        vrs = (ctypes.c_uint32 * N)(*[vr(k, TX_CLOCK) for k in range(1, N + 1)])
        iv, q = (ctypes.c_double * N)(), (ctypes.c_int * N)()
        self.fmu.getIntervalDecimal(vrs, iv, q)
        for k in range(1, N + 1):
            if q[k - 1] == CHANGED:
                self.ticks[k] = self.t + iv[k - 1]

    def _enter_event_mode(self):
        if not self.event_mode:
            self.fmu.enterEventMode()
            self.event_mode = True
            self.updated = False

    def _update(self):
        self.need = self.fmu.updateDiscreteStates()[0]
        self.updated = True

    def _settle(self):
        """In Event Mode: tick the Tx clocks due now (before fmi3UpdateDiscreteStates, or
        in the further iteration it asks for), read their Tx_Data."""
        while True:
            self._intervals()
            now = sorted(k for k, t in self.ticks.items() if t <= self.t + 1e-12)
            if not now or (self.updated and not self.need):
                if not self.updated:
                    self._update()
                    continue
                return
            for k in now:
                del self.ticks[k]
            self.fmu.setClock([vr(k, TX_CLOCK) for k in now], [True] * len(now))
            self._update()
            for k, data in zip(now, self.fmu.getBinary([vr(k, TX_DATA) for k in now])):
                if data:
                    self.rx.append((self.t, k, parse(data)))
                    self.raw.append((self.t, k, bytes(data)))

    def send(self, ops):
        """{node: bytes} sent in the same instant, in the standard's order: clocks, binaries,
        fmi3UpdateDiscreteStates (in an Event Mode of their own)."""
        self._leave_event_mode()
        self._enter_event_mode()
        nodes = sorted(ops)
        self.fmu.setClock([vr(k, RX_CLOCK) for k in nodes], [True] * len(nodes))
        self.fmu.setBinary([vr(k, RX_DATA) for k in nodes], [ops[k] for k in nodes])
        self._update()
        self._settle()

    def _leave_event_mode(self):
        if self.event_mode:
            self._settle()
            self.fmu.enterStepMode()
            self.event_mode = False

    def run(self, t_stop):
        """Step from tick to tick of the Tx clocks up to t_stop."""
        while True:
            self._leave_event_mode()
            t_next = min(self.ticks.values(), default=math.inf)
            t_to = min(t_next, t_stop)
            if t_to > self.t:
                self.fmu.doStep(self.t, t_to - self.t)
                self.t = t_to
            self._enter_event_mode()
            self._settle()
            if t_next > t_stop:
                return

    def ops(self, node, name=None):
        return [(t, op) for t, k, ops in self.rx if k == node for op in ops
                if name is None or op[0] == name]

    def int32(self, name):
        return self.fmu.getInt32([VR[name]])[0]


@pytest.fixture
def bus(unzipped):
    made = []

    def make(**params):
        b = Importer(unzipped, **params)
        made.append(b)
        return b

    yield make
    for b in made:
        b.close()


# ---- the closed form itself ----------------------------------------------------------

@pytest.mark.parametrize("data", [b"", bytes(8), bytes([0xFF] * 8), bytes(range(8)), b"\x55" * 4])
@pytest.mark.parametrize("can_id", [0x000, 0x110, 0x7FF, 0x555])
def test_frame_bits_between_no_stuffing_and_the_worst_case(can_id, data):
    n = len(data)
    bits = frame_bits(can_id, data)
    assert 44 + 8 * n + 3 <= bits <= 44 + 8 * n + (34 + 8 * n - 1) // 4 + 3


# ---- arbitration ----------------------------------------------------------------------

def test_same_instant_frames_go_in_identifier_order_losers_buffered(bus):
    b = bus()          # arbitrationLostBehavior = 1: BUFFER_AND_RETRANSMIT
    frames = {1: (0x300, bytes([1] * 8)), 2: (0x100, bytes([2] * 8)), 3: (0x200, bytes([3] * 8))}
    b.send({k: transmit(i, d) for k, (i, d) in frames.items()})
    b.run(0.01)
    order = sorted(frames.values())                       # the lowest identifier wins
    ends = []
    t = 0.0
    for i, d in order:
        t += wire_time(i, d)
        ends.append(t)
    got = b.ops(4, "Transmit")                            # node 4 only listens
    assert [op[1] for _, op in got] == order
    assert [tt for tt, _ in got] == pytest.approx(ends, abs=1e-12)
    for k, (i, d) in frames.items():
        assert [op for _, op in b.ops(k, "Confirm")] == [("Confirm", i)]
        end = ends[order.index((i, d))]
        assert b.ops(k, "Confirm")[0][0] == pytest.approx(end, abs=1e-12)
        assert not b.ops(k, "ArbitrationLost")             # buffered: none (4_4_1_can.adoc)
        # a node hears the others' frames, not its own
        assert sorted(op[1] for _, op in b.ops(k, "Transmit")) == sorted(v for j, v in frames.items() if j != k)
    # the first arbitration has two losers, the second one
    assert b.int32("nArbitrationLost") == 3
    assert b.int32("nFrames") == 3


def test_discard_and_notify_loser_gets_arbitration_lost_and_retries(bus):
    b = bus()
    # node 1 configures DISCARD_AND_NOTIFY (Configuration 0x40, kind 0x04, value 0x02)
    b.send({1: configuration(0x04, 0x02) + transmit(0x200, b"\x01\x02"), 2: transmit(0x100, b"\x03")})
    lost = b.ops(1, "ArbitrationLost")
    assert lost == [(0.0, ("ArbitrationLost", 0x200))]    # at once, in the same instant
    assert b.int32("nArbitrationLost") == 1
    b.send({1: transmit(0x200, b"\x01\x02")})            # the node retries at once
    b.run(0.01)
    t1 = wire_time(0x100, b"\x03")
    t2 = t1 + wire_time(0x200, b"\x01\x02")              # waits for the bus, then goes
    got = b.ops(3, "Transmit")
    assert [op[1] for _, op in got] == [(0x100, b"\x03"), (0x200, b"\x01\x02")]
    assert [t for t, _ in got] == pytest.approx([t1, t2], abs=1e-12)
    assert b.ops(1, "Confirm") == [(pytest.approx(t2, abs=1e-12), ("Confirm", 0x200))]


def test_standard_identifier_beats_extended_with_the_same_base(bus):
    b = bus()
    base = 0x123
    ext = (base << 18) | 0x1
    b.send({1: transmit(ext, b"\x00", ide=1), 2: transmit(base, b"\x00")})
    b.run(0.01)
    assert [op[1][0] for _, op in b.ops(3, "Transmit")] == [base, ext]   # SRR/IDE recessive
    assert b.ops(3, "Transmit")[0][0] == pytest.approx(wire_time(base, b"\x00"), abs=1e-12)


def test_error_active_nodes_are_preferred_to_error_passive_ones(bus):
    b = bus()
    # node 1 reports ERROR_PASSIVE (Status 0x41, 0x02): its lower identifier waits
    # (4_4_1_can.adoc, Arbitration: the Suspend Transmission Time)
    b.send({1: status(0x02) + transmit(0x100, b"\x01"), 2: transmit(0x200, b"\x02")})
    b.run(0.01)
    assert [op[1][0] for _, op in b.ops(3, "Transmit")] == [0x200, 0x100]


def test_a_nodes_own_frames_go_in_the_order_it_sent_them(bus):
    b = bus()
    b.send({1: transmit(0x300, b"\x01") + transmit(0x100, b"\x02")})
    b.run(0.01)
    got = b.ops(2, "Transmit")
    assert [op[1][0] for _, op in got] == [0x300, 0x100]
    assert got[1][0] == pytest.approx(wire_time(0x300, b"\x01") + wire_time(0x100, b"\x02"), abs=1e-12)
    assert [op[1] for _, op in b.ops(1, "Confirm")] == [0x300, 0x100]


# ---- the wire time -----------------------------------------------------------------------

@pytest.mark.parametrize("can_id,data", [(0x110, bytes([2] * 8)), (0x000, bytes(8)), (0x7FF, bytes([0xFF] * 8)),
                                         (0x120, b"\xde\xad\xbe\xef"), (0x010, b""),
                                         (0x155, bytes([0x55, 0xAA] * 4))])
def test_wire_time_is_the_frames_bits_at_the_baud_rate(bus, can_id, data):
    b = bus()
    b.send({1: transmit(can_id, data)})
    b.run(0.01)
    expected = wire_time(can_id, data)
    (t, op), = b.ops(2, "Transmit")
    assert op[1] == (can_id, data)
    assert t == pytest.approx(expected, abs=1e-12)
    if len(data) == 8:
        assert 0.222e-3 <= t <= 0.27e-3                   # the figure for 8 bytes
    assert b.ops(1, "Confirm") == [(pytest.approx(expected, abs=1e-12), ("Confirm", can_id))]



def _countdown(b, k):
    """NodeK.Tx_Clock's (qualifier, interval) from fmi3GetIntervalDecimal now"""
    vrs = (ctypes.c_uint32 * 1)(vr(k, TX_CLOCK))
    iv, q = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
    b.fmu.getIntervalDecimal(vrs, iv, q)
    return q[0], iv[0]


def test_an_unchanged_countdown_interval_is_the_one_given_not_the_time_left(bus):
    """FMI 3.0.2, 2.2.9, fmi3GetIntervalDecimal: fmi3IntervalUnchanged "returns the unchanged
    interval value provided in a previous call" (the importer keeps the time it was given at;
    fmu-manipulation-toolbox's container counts down from it). A frame of node 1 put on the wire
    at t = 0 is announced to node 2 with its wire time (closed form); at half of it, in a new
    Event Mode, the interval is unchanged and still that wire time, not the half left"""
    b = bus()
    b.send({1: transmit(0x110, bytes(8))})
    wt = wire_time(0x110, bytes(8))
    assert b.ticks[2] == pytest.approx(wt, abs=1e-12)        # given with fmi3IntervalChanged at t = 0
    b._leave_event_mode()
    b.fmu.doStep(0.0, wt / 2)
    b.t = wt / 2
    b._enter_event_mode()
    b.fmu.updateDiscreteStates()
    q, iv = _countdown(b, 2)
    assert q == UNCHANGED and iv == pytest.approx(wt, abs=1e-12), (q, iv, wt)


def test_the_frames_end_is_announced_by_the_tx_clocks_not_again_as_next_event_time(bus):
    """FMI 3.0.2, 2.3, Event Mode: time events are announced "through the argument nextEventTime
    of fmi3UpdateDiscreteStates, or the arguments of fmi3GetShift and fmi3GetInterval". The end of
    a frame is the tick of its receivers' countdown Tx clocks: announced there, once (an importer
    that shortens its step to nextEventTime and counts an unchanged interval down by that step,
    as fmu-manipulation-toolbox 2.0's container does, would lose the clock)"""
    b = bus()
    b._leave_event_mode()
    b._enter_event_mode()
    b.fmu.setClock([vr(1, RX_CLOCK)], [True])
    b.fmu.setBinary([vr(1, RX_DATA)], [transmit(0x110, bytes(8))])
    need, _, _, _, defined, _ = b.fmu.updateDiscreteStates()
    assert not need and not defined
    assert _countdown(b, 2) == (CHANGED, pytest.approx(wire_time(0x110, bytes(8)), abs=1e-12))
    assert _countdown(b, 1) == (CHANGED, pytest.approx(wire_time(0x110, bytes(8)), abs=1e-12))   # its Confirm


def test_baud_rate_from_a_configuration(bus):
    b = bus()
    b.send({1: configuration(0x01, 250_000) + transmit(0x110, bytes(8))})
    b.run(0.01)
    (t, _), = b.ops(2, "Transmit")
    assert t == pytest.approx(frame_bits(0x110, bytes(8)) / 250_000, abs=1e-12)


def test_wire_time_off_delivers_in_the_same_instant_in_identifier_order(bus):
    b = bus(wireTime=False)
    b.send({1: transmit(0x300, b"\x01"), 2: transmit(0x100, b"\x02"), 3: transmit(0x200, b"\x03")})
    got = b.ops(4, "Transmit")
    assert [t for t, _ in got] == [0.0, 0.0, 0.0]
    assert [op[1][0] for _, op in got] == [0x100, 0x200, 0x300]
    assert b.ops(1, "Confirm") == [(0.0, ("Confirm", 0x300))]


# ---- the bus load ----------------------------------------------------------------------------

def test_bus_load_is_the_wire_time_over_the_time_elapsed(bus):
    b = bus()
    frames = [(0x100, bytes(range(8))), (0x200, b"\x11\x22\x33")]
    b.send({1: transmit(*frames[0]), 2: transmit(*frames[1])})
    b.run(0.010)
    busy = sum(wire_time(i, d) for i, d in frames)
    assert b.fmu.getFloat64([VR["busLoad"]])[0] == pytest.approx(busy / 0.010, rel=1e-9)
    b.send({3: transmit(0x300, b"")})
    b.run(0.020)
    busy += wire_time(0x300, b"")
    assert b.fmu.getFloat64([VR["busLoad"]])[0] == pytest.approx(busy / 0.020, rel=1e-9)


# ---- faults --------------------------------------------------------------------------------------

def test_a_silent_node_reaches_nobody_from_fault_start(bus):
    b = bus(faultSilentNode=1, faultStart=0.005)
    b.send({1: transmit(0x101, b"\x01")})
    b.run(0.006)
    b.send({1: transmit(0x101, b"\x02")})
    b.run(0.010)
    assert [op[1][1] for _, op in b.ops(2, "Transmit")] == [b"\x01"]   # only the one before
    assert len(b.ops(1, "Confirm")) == 1
    assert b.int32("nFrames") == 1


def test_a_corrupted_frame_gives_every_node_a_crc_bus_error(bus):
    b = bus(faultCorruptId=0x123, nNodes=4)
    b.send({2: transmit(0x123, b"\x01\x02"), 3: transmit(0x124, b"\x03")})
    b.run(0.01)
    errors = {k: [op[1] for _, op in b.ops(k, "BusError")] for k in range(1, 5)}
    # (ID, Error Code CRC_ERROR 0x04, Error Flag, Is Sender): the sender's with Is Sender,
    # the primary flag once, for the first receiver (4_4_1_can.adoc, Bus Error)
    assert errors[2] == [(0x123, 0x04, 0x02, 1)]
    assert errors[1] == [(0x123, 0x04, 0x01, 0)]
    assert errors[3] == [(0x123, 0x04, 0x02, 0)] and errors[4] == [(0x123, 0x04, 0x02, 0)]
    assert not b.ops(2, "Confirm")
    assert [op[1][0] for _, op in b.ops(1, "Transmit")] == [0x124]     # the other frame goes
    assert b.int32("nBusErrors") == 1 and b.int32("nFrames") == 1


def test_a_bus_off_node_neither_sends_nor_receives_and_no_confirm_without_receivers(bus):
    b = bus(faultBusOffNode=2, nNodes=2)
    b.send({2: transmit(0x200, b"\x01")})
    b.send({1: transmit(0x100, b"\x02")})
    b.run(0.01)
    assert not b.ops(1, "Transmit") and not b.ops(2, "Transmit")
    # every node but the sender bus-off: no Confirm (4_4_1_can.adoc, Transmission and Acknowledge)
    assert not b.ops(1, "Confirm")
    assert any("bus-off" in m for _, m in b.log)


def test_a_node_reporting_bus_off_is_not_put_on_the_bus(bus):
    b = bus()
    b.send({1: status(0x03) + transmit(0x100, b"\x01")})
    b.run(0.01)
    assert not b.ops(2, "Transmit")
    b.send({2: transmit(0x101, b"\x02")})
    b.run(0.02)
    assert [op[1][0] for _, op in b.ops(3, "Transmit")] == [0x101]
    assert not b.ops(1, "Transmit")                                    # bus-off: receives nothing


def test_wakeup_reaches_every_node_but_its_sender(bus):
    b = bus(nNodes=3)
    b.send({2: struct.pack("<II", 0x42, 8)})
    assert [k for k in (1, 2, 3) if b.ops(k, "Wakeup")] == [1, 3]


# ---- malformed operations and calls ---------------------------------------------------------------

def test_malformed_operations_are_answered_with_a_format_error(bus):
    b = bus()
    wrong_length = struct.pack("<IIIBBH", 0x10, 17, 0x123, 0, 0, 2) + b"\xab"   # 16 + DL = 18
    unknown = struct.pack("<II", 0x77, 9) + b"\x00"
    truncated = struct.pack("<II", 0x10, 24) + b"\x01\x00"                     # Length beyond the end
    b.send({1: wrong_length + unknown + transmit(0x155, b"\x01") + truncated})
    fe = [op[1] for _, op in b.ops(1, "FormatError")]
    assert fe == [wrong_length, unknown, truncated]                   # each op's bytes, back to the sender
    b.run(0.01)
    assert [op[1] for _, op in b.ops(2, "Transmit")] == [(0x155, b"\x01")]     # the good one goes
    warnings = [m for st, m in b.log if st == 1]
    assert len(warnings) == 3 and "wrong length" in warnings[0] and "unknown operation" in warnings[1]
    assert "truncated" in warnings[2]


@pytest.mark.parametrize("payload", [transmit(0x100, bytes(9))[:25], transmit(0x800, b""),
                                     struct.pack("<IIIBBH", 0x10, 16, 1, 2, 0, 0)])
def test_out_of_range_arguments_are_a_format_error(bus, payload):
    b = bus()
    b.send({1: payload})
    assert [op[1] for _, op in b.ops(1, "FormatError")] == [payload]
    b.run(0.01)
    assert not b.ops(2, "Transmit")


def test_every_cut_of_a_buffer_is_safe(bus):
    """Every prefix of two operations: whole ones delivered, the rest a Format Error (also
    under ASan: nothing read past the binary's end)."""
    whole = transmit(0x100, bytes(range(8))) + transmit(0x101, b"\x07")
    for cut in range(len(whole) + 1):
        b = bus(wireTime=False)
        b.send({1: whole[:cut]})
        n_whole = (cut >= 24) + (cut == len(whole))
        partial = cut not in (0, 24, len(whole))
        assert len(b.ops(2, "Transmit")) == n_whole
        assert len(b.ops(1, "FormatError")) == int(partial)


def test_random_bytes_never_crash_the_bus(bus):
    """Random buffers and mutated operations (also under ASan/UBSan): every answer is a
    well-formed buffer of the standard's operations."""
    import random
    rng = random.Random(24)
    b = bus(wireTime=False, nNodes=2)
    good = [transmit(0x100, b"\x01\x02"), configuration(0x01, 500_000), status(0x01),
            struct.pack("<II", 0x42, 8), struct.pack("<III", 0x20, 12, 5)]
    for i in range(300):
        if i % 2:
            buf = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 64)))
        else:
            buf = bytearray(b"".join(rng.choice(good) for _ in range(rng.randrange(1, 4))))
            for _ in range(rng.randrange(1, 4)):
                buf[rng.randrange(len(buf))] = rng.randrange(256)
            buf = bytes(buf[:rng.randrange(len(buf) + 1)])
        b.send({1: buf})
    assert b.rx                                  # it answered, every buffer parsed by parse()
    assert not [m for st, m in b.log if st >= 3]


def _raises(b, call, *words):
    with pytest.raises(FMICallException):
        call()
    assert any(st == 3 and all(w in m for w in words) for st, m in b.log), b.log


def test_a_binary_above_max_size_is_an_error(bus):
    b = bus()
    b.fmu.setClock([vr(1, RX_CLOCK)], [True])
    _raises(b, lambda: b.fmu.setBinary([vr(1, RX_DATA)], [bytes(2049)]), "Node1.Rx_Data", "2049", "maxSize")


def test_rx_data_without_its_clock_is_an_error(bus):
    b = bus()
    _raises(b, lambda: b.fmu.setBinary([vr(2, RX_DATA)], [transmit(1, b"")]), "Node2.Rx_Clock", "not active")


def test_a_countdown_tx_clock_set_after_the_discrete_states_is_an_error(bus):
    b = bus()
    b.send({1: transmit(0x100, b"")})        # ends with fmi3UpdateDiscreteStates, nothing due now
    _raises(b, lambda: b.fmu.setClock([vr(2, TX_CLOCK)], [True]), "Node2.Tx_Clock", "after fmi3UpdateDiscreteStates")


def test_a_triggered_rx_clock_set_after_the_discrete_states_is_taken(bus):
    """FMI 3.0.2, 2.3, Event Mode, fmi3SetClock: a clock must not be active for more than one
    fmi3UpdateDiscreteStates per Event Mode; "This restriction does not apply to triggered Clocks".
    NodeK.Rx_Clock is triggered: set after an update that asked for no iteration, in the same Event
    Mode, it begins a new super-dense instant and its operations go on the wire after node 1's"""
    b = bus()
    b.send({1: transmit(0x100, b"")})        # ends with fmi3UpdateDiscreteStates, nothing due now
    b.fmu.setClock([vr(2, RX_CLOCK)], [True])
    b.fmu.setBinary([vr(2, RX_DATA)], [transmit(0x200, b"\x07")])
    b._update()
    b.run(0.01)
    t1, t2 = wire_time(0x100, b""), wire_time(0x200, b"\x07")
    assert b.ops(3, "Transmit") == [(pytest.approx(t1, abs=1e-12), ("Transmit", (0x100, b""))),
                                    (pytest.approx(t1 + t2, abs=1e-12), ("Transmit", (0x200, b"\x07")))]
    assert not [m for st, m in b.log if st >= 3]


@pytest.mark.parametrize("name,value", [("baudrate", 0), ("nNodes", 9), ("arbitrationLostBehavior", 3),
                                        ("faultSilentNode", -1)])
def test_parameters_out_of_range_are_refused(unzipped, name, value):
    with pytest.raises(FMICallException):
        Importer(unzipped, **{name: value})


def test_without_event_mode_the_bus_runs_idle(unzipped):
    """eventModeUsed = false: no clock can tick (FMI 3.0.2, 4.2.1), so no frame can be sent; the bus
    still instantiates (a plain importer such as `fmpy simulate` steps it), says why once, carries
    nothing (busLoad 0, no frame) and refuses fmi3EnterEventMode."""
    path, md, d = unzipped
    log = []
    f = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="CanBus", instanceName="bus")
    f.instantiate(eventModeUsed=False, logMessage=lambda env, st, cat, msg: log.append(msg.decode()))
    assert sum("eventModeUsed" in m for m in log) == 1
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    t = 0.0
    for _ in range(100):
        f.doStep(t, 0.01)
        t += 0.01
    assert f.getFloat64([vr["busLoad"]]) == [0.0]
    with pytest.raises(Exception):
        f.enterEventMode()
    f.freeInstance()


def test_fmpy_simulate_runs_the_default_experiment(unzipped):
    """`fmpy simulate fmus/fmi3/CanBus.fmu` as a user types it: the default experiment without
    event mode ends without an error, the bus idle."""
    r = simulate_fmu(str(unzipped[0]))
    assert r["time"][-1] > 0 and max(abs(r["busLoad"])) == 0.0


# ---- the FMU's description ---------------------------------------------------------------------------

def test_fmpy_validate_finds_nothing(unzipped):
    assert validate_fmu(str(unzipped[0])) == []


def test_manifest_terminals_and_variables_follow_ls_bus(unzipped):
    import xml.etree.ElementTree as ET
    path, md, _ = unzipped
    with zipfile.ZipFile(path) as z:
        manifest = ET.fromstring(z.read("extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"))
        terminals = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        declared = {v.get("name"): v for v in ET.fromstring(z.read("modelDescription.xml")).find("ModelVariables")}
    ls = "{http://fmi-standard.org/fmi-ls-manifest}"
    assert manifest.get(ls + "fmi-ls-name") == "org.fmi-standard.fmi-ls-bus"
    assert manifest.get(ls + "fmi-ls-version") == "1.0.0"
    # fixed by fmi-ls-bus v1.0.0 schema/fmi3LayeredStandardBusManifest.xsd
    assert manifest.get(ls + "fmi-ls-description") == ("Layered Standard for the simulation of bus communication "
                                                       "on a Physical Signal Abstraction or Network Abstraction "
                                                       "based level.")
    assert manifest.get("isBusSimulationFMU") == "true"
    assert md.coSimulation.hasEventMode and md.coSimulation.canHandleVariableCommunicationStepSize
    by_name = {v.name: v for v in md.modelVariables}
    used = []
    nodes = terminals.find("Terminals").findall("Terminal")
    assert [t.get("name") for t in nodes] == [f"Node{k}" for k in range(1, N + 1)]
    for t in nodes:
        assert t.get("terminalKind") == "org.fmi-ls-bus.network-terminal"
        assert t.get("matchingRule") == "org.fmi-ls-bus.transceiver"
        members = {m.get("memberName"): m.get("variableName") for m in t.findall("TerminalMemberVariable")}
        assert sorted(members) == ["Rx_Clock", "Rx_Data", "Tx_Clock", "Tx_Data"]
        assert all(m.get("variableKind") == "signal" for m in t.findall("TerminalMemberVariable"))
        rx, tx = by_name[members["Rx_Data"]], by_name[members["Tx_Data"]]
        assert rx.type == tx.type == "Binary" and rx.causality == "input" and tx.causality == "output"
        for v in (rx, tx):       # FMPy reads neither attribute
            assert declared[v.name].get("mimeType") == MIME and declared[v.name].get("maxSize") == "2048"
        rxc, txc = by_name[members["Rx_Clock"]], by_name[members["Tx_Clock"]]
        assert rxc.intervalVariability == "triggered" and rxc.causality == "input"
        assert txc.intervalVariability == "countdown" and txc.causality == "input"
        assert [c.name for c in rx.clocks] == [rxc.name] and [c.name for c in tx.clocks] == [txc.name]
        conf, = t.findall("Terminal")
        assert (conf.get("name"), conf.get("terminalKind"), conf.get("matchingRule")) == \
            ("Configuration", "org.fmi-ls-bus.network-terminal.configuration", "bus")
        (bn,) = conf.findall("TerminalMemberVariable")
        assert bn.get("memberName") == "BusNotifications"
        v = by_name[bn.get("variableName")]
        assert (v.type, v.causality, v.variability, v.start) == ("Boolean", "output", "constant", "true")
        used += list(members.values()) + [bn.get("variableName")]
    assert len(used) == len(set(used))          # a variable in one terminal only


# ---- the triggered Tx form (fmus/fmi3/lsbus-triggered/CanBus_Triggered.fmu, issue 39) ---------

def test_the_triggered_form_signals_a_frames_end_and_activates_its_output_tx_clocks():
    """CanBus_Triggered: NodeK.Tx_Clock a triggered output clock (FMI 3.0.2, 2.2.9; fmi-ls-bus
    4____network_abstraction.adoc, "Triggered Tx Clocks": pending Tx data signalled by fmi3DoStep's
    eventHandlingNeeded). A frame of node 1 put on the wire at t = 0 ends after its wire time
    (closed form), given as nextEventTime (no countdown clock says it); at a step to it the bus asks
    for event handling; its update activates node 1's and node 2's Tx clocks for the next
    super-dense instant (discreteStatesNeedUpdate), which hold the Confirm and the Transmit; the
    next update deactivates them (FMI 3.0.2, 2.3: the FMU deactivates its active clocks)"""
    path = fmu_dir() / "fmi3" / "lsbus-triggered" / "CanBus_Triggered.fmu"
    assert path.is_file(), f"{path} not built"
    md = read_model_description(str(path))
    clocks = {v.name: v for v in md.modelVariables if v.type == "Clock"}
    assert all((c.causality, c.intervalVariability) == ("output", "triggered")
               for n, c in clocks.items() if n.endswith("Tx_Clock")) and len(clocks) == 2 * N
    assert not validate_fmu(str(path))
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier="CanBus_Triggered",
                    instanceName="bus")
    log = []
    fmu.instantiate(eventModeUsed=True, logMessage=lambda env, st, cat, msg: log.append((st, msg.decode())))
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    data = bytes(range(8))
    wt = wire_time(0x110, data)
    fmu.setClock([vr(1, RX_CLOCK)], [True])
    fmu.setBinary([vr(1, RX_DATA)], [transmit(0x110, data)])
    need, _, _, _, defined, t_next = fmu.updateDiscreteStates()
    assert not need and defined and t_next == pytest.approx(wt, abs=1e-12)
    fmu.enterStepMode()
    event, _, _, _ = fmu.doStep(0.0, wt)
    assert event
    fmu.enterEventMode()
    need = fmu.updateDiscreteStates()[0]
    assert need
    tx = [vr(k, TX_CLOCK) for k in (1, 2, 3)]
    assert list(fmu.getClock(tx)) == [True, True, True]        # nNodes 8: node 3 listens too
    got = [parse(b) for b in fmu.getBinary([vr(k, TX_DATA) for k in (1, 2)])]
    assert got == [[("Confirm", 0x110)], [("Transmit", (0x110, data))]]
    need = fmu.updateDiscreteStates()[0]
    assert not need and not any(fmu.getClock(tx))
    assert not [m for st, m in log if st >= 3]
    fmu.terminate()
    fmu.freeInstance()
