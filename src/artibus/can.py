"""CAN in the loop: connections of a bench that travel over a CAN network.

A bench routes connections over CAN with two SSP annotations of type
``org.artibus.can``:

- on its System, ``<Can xmlns="urn:artibus" source="resources/X.dbc" period="0.01"/>``:
  the DBC packed in the .ssp and the network's tick (s);
- on each routed Connection, ``<Route xmlns="urn:artibus" message="M" signal="S"/>``.

Every connection from one output to several inputs may share a signal (one
sender, several receivers). A Route may also name a message's AliveCounter:
its receivers get the counter of each frame they accept (as a Real), for
their own stale detection (AUTOSAR E2E); the network fills the counter, so the
value of that connection's source (an output of the sender) is not sent.
The DBC is loaded with cantools and checked: every
frame has an 8-bit CRC in byte 0 and a 4-bit alive counter in bits 8-11 (the
AUTOSAR E2E profile-2 layout; the CRC is cantools.autosar.end_to_end's
profile-2 CRC over the payload with the message's data ID, DBC attribute
``E2EDataID``), a cycle time (``GenMsgCycleTime``) that is a multiple of the
tick, 11-bit identifiers, no multiplexing.

At each tick whose time is a multiple of a message's cycle time the runner
(``Network.tick``) reads the senders' outputs as they are at that time,
converts them to the signal's unit, encodes the frame with cantools
(``strict=True``: a value outside the signal's range is an error naming it),
fills counter and CRC, and sends the tick's frames on a python-can bus in
order of identifier (the arbitration order when they are queued at once),
time-stamped in simulated time: the tick plus the time the frames before it
and itself take on the wire at the bit rate (actual bits, stuffing
included). It receives them back, checks CRC and counter (a frame failing
either is not used: its receivers keep the last good value) and decodes them
into the receivers' inputs, converted to their units. The receivers use them
from that tick on; the transmission time (below a millisecond here: the
worst cases are printed) is not added. Nothing runs on threads or the wall
clock: ``virtual`` is python-can's VirtualBus on a channel of its own per
run with ``preserve_timestamps``, ``INTERFACE:CHANNEL`` a real interface
(frames echoed with ``receive_own_messages``, restamped in simulated time).

The traffic can be logged as .blf or .asc with python-can's writers; the log's
times are simulated seconds from the run's start time (a marker at the start
fixes the writers' origin). ``decode_log`` reads a log back through the DBC.

Bus load counts the bits of the frames actually sent (stuff bits counted
exactly, CRC-15 included, plus 3 bits of interframe space). Worst-case response
times follow Davis, Burns, Bril and Lukkien, "Controller Area Network (CAN)
schedulability analysis: refuted, revisited and revised", Real-Time Systems
35 (2007) 239-272, section 4 (busy period, every instance in it), with the
worst-case frame length C = (34 + 8 s + 13 + floor((34 + 8 s - 1) / 4)) bit
times for s data bytes (11-bit identifiers), no queuing jitter (the frames
are queued exactly at the tick), deadline = period.
"""
import functools
import itertools
import math
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from artibus import ArtibusError

#: units a signal or a connected variable may carry: (SI unit, factor to it)
UNITS = {
    "": ("", 1.0), "1": ("", 1.0),
    "rad": ("rad", 1.0), "deg": ("rad", math.pi / 180),
    "rad/s": ("rad/s", 1.0), "deg/s": ("rad/s", math.pi / 180),
    "m": ("m", 1.0), "mm": ("m", 1e-3),
    "m/s": ("m/s", 1.0), "km/h": ("m/s", 1 / 3.6),
    "m/s2": ("m/s2", 1.0),
    "N": ("N", 1.0), "kN": ("N", 1e3), "N.m": ("N.m", 1.0),
}
CRC_SIGNAL, COUNTER_SIGNAL = "CRC", "AliveCounter"
DEFAULT_BITRATE = 500_000
_channels = itertools.count()


def _conversion(unit_from, unit_to, where):
    """factor k with value_to = k * value_from."""
    a, b = UNITS.get(unit_from or ""), UNITS.get(unit_to or "")
    if a is None or b is None or a[0] != b[0]:
        raise ArtibusError(f"{where}: cannot convert '{unit_from or ''}' to '{unit_to or ''}' "
                           f"(units known to the CAN path: {', '.join(u for u in UNITS if u)})")
    return a[1] / b[1]


def load_dbc(path, label=None):
    """The DBC as a cantools database, checked for what the network needs
    (see the module's docstring); errors name the file, message and signal."""
    import cantools
    label = label or str(path)
    try:
        db = cantools.database.load_file(str(path), database_format="dbc", strict=True)
    except FileNotFoundError:
        raise ArtibusError(f"{label}: no such file") from None
    except Exception as e:      # cantools' parse and consistency errors
        raise ArtibusError(f"{label}: not a valid DBC: {e}") from None
    if not db.messages:
        raise ArtibusError(f"{label}: the DBC defines no message")
    for m in db.messages:
        head = f"{label}: message {m.name} (0x{m.frame_id:03X})"
        if m.is_extended_frame or m.is_fd:
            raise ArtibusError(f"{head}: only classic CAN frames with 11-bit identifiers are supported")
        if m.is_multiplexed():
            raise ArtibusError(f"{head}: multiplexed messages are not supported")
        sig = {s.name: s for s in m.signals}
        for name, start, length in ((CRC_SIGNAL, 0, 8), (COUNTER_SIGNAL, 8, 4)):
            s = sig.get(name)
            if s is None or s.start != start or s.length != length or s.is_signed or s.byte_order != "little_endian":
                raise ArtibusError(f"{head}: signal {name}: every frame needs an unsigned {length}-bit "
                                   f"{name} at bit {start} (E2E profile 2 layout)")
        if m.length < 2:
            raise ArtibusError(f"{head}: DLC {m.length}: CRC and counter need 2 bytes")
        attr = m.dbc.attributes.get("E2EDataID") if m.dbc else None
        if attr is None:
            raise ArtibusError(f"{head}: no E2EDataID attribute (the data ID of its CRC)")
        if not m.cycle_time:
            raise ArtibusError(f"{head}: no GenMsgCycleTime (the network sends cyclically)")
    return db


def _crc8h2f_table():
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = ((c << 1) ^ 0x2F) & 0xFF if c & 0x80 else (c << 1) & 0xFF
        table.append(c)
    return table


_CRC8H2F = _crc8h2f_table()


def e2e_crc(data, data_id):
    """AUTOSAR E2E profile 2's CRC of a frame: CRC-8H2F (polynomial 0x2F,
    start and final XOR 0xFF) over bytes 1.. and the data ID; the same number
    as cantools.autosar.end_to_end.compute_profile2_crc(data, data_id), with a
    table (the tests compare them), 10 x faster."""
    crc = 0xFF
    for b in data[1:]:
        crc = _CRC8H2F[crc ^ b]
    return _CRC8H2F[crc ^ data_id] ^ 0xFF


@functools.lru_cache(maxsize=1 << 16)
def frame_bits(can_id, data):
    """Bits a classic data frame with an 11-bit identifier takes on the wire:
    SOF to CRC with its stuff bits counted exactly (a complement bit after
    five equal bits), CRC delimiter, ACK, EOF, 3 bits of interframe space.
    data: bytes."""
    head = (can_id << 7) | len(data)            # SOF 0, ID, RTR 0, IDE 0, r0 0, DLC
    n = 19 + 8 * len(data)
    v = (head << (8 * len(data))) | int.from_bytes(data, "big")
    crc = 0
    for i in range(n - 1, -1, -1):              # CRC-15, polynomial 0x4599 (ISO 11898-1)
        if ((v >> i) & 1) ^ (crc >> 14):
            crc = ((crc << 1) & 0x7FFF) ^ 0x4599
        else:
            crc = (crc << 1) & 0x7FFF
    bits = format((v << 15) | crc, f"0{n + 15}b")
    stuff, run, prev = 0, 0, ""
    for b in bits:
        if b == prev:
            run += 1
            if run == 5:                            # a complement bit; it starts the next run
                stuff += 1
                prev, run = ("1" if b == "0" else "0"), 1
        else:
            prev, run = b, 1
    return n + 15 + stuff + 10 + 3


def worst_case_bits(dlc):
    """Davis et al. 2007, eq. (1) with g = 34 (11-bit identifiers): the longest
    frame of dlc data bytes, worst-case stuffing, interframe space included."""
    return 34 + 8 * dlc + 13 + (34 + 8 * dlc - 1) // 4


def response_times(messages, bitrate):
    """Worst-case response times (s) of periodic messages on CAN, Davis et al.
    2007, section 4: messages = [(identifier, dlc, period s)], priority by
    identifier, no jitter, deadline = period. Returns {identifier: R} (inf
    when the busy period does not end)."""
    tau = 1.0 / bitrate
    msgs = sorted((i, worst_case_bits(d) * tau, T) for i, d, T in messages)
    out = {}
    for n, (mid, C, T) in enumerate(msgs):
        hp = msgs[:n]
        B = max((c for _, c, _ in msgs[n + 1:]), default=0.0)
        if sum(Ck / Tk for _, Ck, Tk in msgs[:n + 1]) >= 1.0:   # the busy period never ends
            out[mid] = math.inf
            continue
        t = C                                       # busy period, eq. (8)
        for _ in range(10000):
            t_new = B + sum(math.ceil(t / Tk) * Ck for _, Ck, Tk in msgs[:n + 1])
            if t_new == t:
                break
            t = t_new
        else:
            out[mid] = math.inf
            continue
        R = 0.0
        for q in range(math.ceil(t / T)):           # every instance in the busy period, eqs. (9)-(11)
            w = B + q * C
            for _ in range(10000):
                w_new = B + q * C + sum(math.ceil((w + tau) / Tk) * Ck for _, Ck, Tk in hp)
                if w_new == w:
                    break
                w = w_new
            R = max(R, w - q * T + C)
        out[mid] = R
    return out


@dataclass
class _Receiver:
    unit: object         # the receiving runner Unit
    index: int
    factor: float        # DBC unit -> input's unit
    name: str
    buffer: object = None  # its input buffer (ctypes array), once the runner made it


@dataclass
class _Route:
    signal: object       # cantools Signal
    unit: object         # the sending runner Unit
    index: int
    factor: float        # output's unit -> DBC unit
    source: str          # "Comp.var"
    receivers: list = field(default_factory=list)
    buffer: object = None  # its output buffer (ctypes array), once the runner made it


@dataclass
class _Message:
    msg: object          # cantools Message
    data_id: int
    ratio: int           # cycle time / tick
    routes: list
    fixed: dict          # signals no connection feeds: their start values (DBC GenSigStartValue, else 0)
    counter: int = 0     # next counter to send
    last_counter: int = None   # of the last frame accepted
    sent: int = 0
    rejected: int = 0
    bits: int = 0


class Network:
    """The CAN path of one run (see the module's docstring)."""

    def __init__(self, bench, dbc_file, links, interface="virtual", log=None):
        """links: the runner's Links of the connections the bench routes over
        CAN, each with its Connection (``link.connection``). Validates
        everything before anything is opened or written."""
        where = bench.file
        spec = bench.can
        self.where = where
        self.dbc_label = f"{Path(where).parent}/{spec['source']}"
        try:
            self.period = float(spec["period"])
        except (TypeError, ValueError):
            self.period = float("nan")
        if not self.period > 0:
            raise ArtibusError(f"{where}:{spec['line']}: <Can period=\"{spec['period']}\">: "
                               f"the network's tick must be a time > 0 in s")
        if not spec["source"] or not Path(dbc_file).is_file():
            raise ArtibusError(f"{where}:{spec['line']}: <Can source=\"{spec['source']}\">: no such file in the .ssp")
        self.db = load_dbc(dbc_file, self.dbc_label)
        attr = self.db.dbc.attributes.get("Baudrate") if self.db.dbc else None
        self.bitrate = int(attr.value) if attr is not None else DEFAULT_BITRATE
        routes = {}       # (message, signal) -> _Route
        for link in links:
            c = link.connection
            r = c.can
            label = (f"{where}:{r['line']}: Connection {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]} "
                     f"routed as {r['message']}.{r['signal']}")
            try:
                msg = self.db.get_message_by_name(r["message"])
            except KeyError:
                raise ArtibusError(f"{label}: {self.dbc_label} has no message '{r['message']}' "
                                   f"(messages: {', '.join(m.name for m in self.db.messages)})") from None
            sig = next((s for s in msg.signals if s.name == r["signal"]), None)
            if sig is None or sig.name == CRC_SIGNAL:
                raise ArtibusError(f"{label}: message {msg.name} of {self.dbc_label} has no data signal "
                                   f"'{r['signal']}' (signals: {', '.join(s.name for s in msg.signals if s.name not in (CRC_SIGNAL, COUNTER_SIGNAL))}; "
                                   f"or its {COUNTER_SIGNAL})")
            if (c.factor, c.offset) != (1.0, 0.0):
                raise ArtibusError(f"{label}: a connection routed over CAN takes its scaling from the DBC; "
                                   f"remove its LinearTransformation")
            src_var, dst_var = link.src.fmu.var(c.start[1]), link.dst.fmu.var(c.end[1])
            key = (msg.name, sig.name)
            route = routes.get(key)
            if route is None:
                # the alive counter is the network's (E2E): the receivers get it, the source's value is not sent
                route = routes[key] = _Route(sig, link.src, link.src_index,
                                             1.0 if sig.name == COUNTER_SIGNAL else
                                             _conversion(_unit(link.src, src_var), sig.unit, label),
                                             f"{c.start[0]}.{c.start[1]}")
            elif route.source != f"{c.start[0]}.{c.start[1]}":
                raise ArtibusError(f"{label}: signal {msg.name}.{sig.name} is already sent from {route.source}")
            route.receivers.append(_Receiver(link.dst, link.dst_index,
                                             _conversion(sig.unit, _unit(link.dst, dst_var), label), link.name))
        self.messages = []
        for m in sorted(self.db.messages, key=lambda m: m.frame_id):
            ratio = m.cycle_time / 1000 / self.period
            if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
                raise ArtibusError(f"{self.dbc_label}: message {m.name}: cycle time {m.cycle_time} ms is not "
                                   f"a multiple of the network's tick {self.period * 1000:g} ms ({where}:{spec['line']})")
            mine = [routes[k] for k in routes if k[0] == m.name]
            fed = {r.signal.name for r in mine} | {CRC_SIGNAL, COUNTER_SIGNAL}
            fixed = {s.name: s.conversion.raw_to_scaled(s.raw_initial or 0)
                     for s in m.signals if s.name not in fed}
            self.messages.append(_Message(m, int(m.dbc.attributes["E2EDataID"].value), int(round(ratio)),
                                          mine, fixed))
        self._by_id = {m.msg.frame_id: m for m in self.messages}
        self.tamper = None     # tests: f(can.Message) -> can.Message, between sending and receiving
        self.frames = 0
        self.ticks = 0
        self.observed = {}     # identifier -> longest time from the tick to the end of the frame, s
        self._open(interface, log)

    def _open(self, interface, log):
        import can
        self.interface = interface or "virtual"
        if self.interface == "virtual":
            kind, channel = "virtual", f"artibus-{os.getpid()}-{next(_channels)}"
        else:
            kind, sep, channel = self.interface.partition(":")
            if not sep or not kind or not channel:
                raise ArtibusError(f"--can {self.interface}: expected 'virtual' or INTERFACE:CHANNEL "
                                   f"(e.g. socketcan:vcan0)")
            if kind not in can.interfaces.VALID_INTERFACES:
                raise ArtibusError(f"--can {self.interface}: python-can has no interface '{kind}' "
                                   f"(known: {', '.join(sorted(can.interfaces.VALID_INTERFACES))})")
        self.log_path = Path(log) if log else None
        if self.log_path is not None and self.log_path.suffix.lower() not in (".blf", ".asc"):
            raise ArtibusError(f"--can-log {log}: the log is written as .blf or .asc (by its suffix)")
        try:
            self.bus = can.Bus(interface=kind, channel=channel, receive_own_messages=True,
                               preserve_timestamps=True, bitrate=self.bitrate)
        except Exception as e:
            raise ArtibusError(f"--can {self.interface}: cannot open the interface: {e}") from None
        self.writer = None
        if self.log_path is not None:
            self._part = self.log_path.with_name(self.log_path.name + ".part")
            try:
                self._part.parent.mkdir(parents=True, exist_ok=True)
                cls = can.BLFWriter if self.log_path.suffix.lower() == ".blf" else can.ASCWriter
                self.writer = cls(str(self._part))
            except OSError as e:
                self.bus.shutdown()
                raise ArtibusError(f"--can-log {log}: {e}") from None

    # --- one tick ------------------------------------------------------------------

    def _encode(self, m, t):
        values = dict(m.fixed)
        for r in m.routes:
            if r.signal.name == COUNTER_SIGNAL:     # routed to receivers only: the network fills it
                continue
            v = r.factor * r.buffer[r.index]
            s = r.signal
            if not (math.isfinite(v) and s.minimum <= v <= s.maximum):
                raise ArtibusError(f"{self.dbc_label}: message {m.msg.name}, signal {s.name}: "
                                   f"{r.source} = {v:.6g} {s.unit or ''} at t = {t:g} s is outside "
                                   f"the signal's range [{s.minimum:g}, {s.maximum:g}]")
            values[s.name] = v
        values[COUNTER_SIGNAL] = m.counter
        values[CRC_SIGNAL] = 0
        try:
            data = bytearray(m.msg.encode(values, scaling=True, strict=True))
        except Exception as e:
            raise ArtibusError(f"{self.dbc_label}: message {m.msg.name}: {e} (t = {t:g} s)") from None
        data[0] = e2e_crc(data, m.data_id)
        return bytes(data)

    def _deliver(self, m, data):
        """CRC and counter checked; the signals decoded into the receivers'
        inputs. A frame failing a check is not used."""
        counter = data[1] & 0x0F
        if e2e_crc(data, m.data_id) != data[0] or counter == m.last_counter:
            m.rejected += 1
            return False
        m.last_counter = counter
        decoded = m.msg.decode(bytes(data), scaling=True, decode_choices=False)
        for r in m.routes:
            v = decoded[r.signal.name]
            for rc in r.receivers:
                rc.buffer[rc.index] = rc.factor * v
        return True

    def bind(self):
        """The units' value buffers exist now (the runner made them): point the
        routes at them."""
        for m in self.messages:
            for r in m.routes:
                r.buffer = r.unit.raw.out
                for rc in r.receivers:
                    rc.buffer = rc.unit.raw.inp

    def settle(self):
        """Initialisation: the receivers get the senders' values through the
        codec (quantised as on the bus), nothing is sent."""
        for m in self.messages:
            data = self._encode(m, float("nan"))
            m.last_counter = None
            self._deliver(m, data)
            m.last_counter = None

    def start(self, t0):
        """Before the first tick: the writers' time origin is the run's start."""
        self.t0 = t0
        if self.writer is not None:
            self.writer.log_event(f"artibus: simulated time in s from t = {t0:g} s (the run's start)", t0)

    def tick(self, k, t):
        """The network's k-th tick at simulated time t."""
        import can
        tau = 1.0 / self.bitrate
        sent, busy = [], 0
        for m in self.messages:
            if k % m.ratio:
                continue
            data = self._encode(m, t)
            bits = frame_bits(m.msg.frame_id, data)
            busy += bits
            m.bits += bits
            m.sent += 1
            m.counter = (m.counter + 1) % 16
            end = (busy - 3) * tau                   # end of its EOF, the frames before it queued ahead
            self.observed[m.msg.frame_id] = max(self.observed.get(m.msg.frame_id, 0.0), end)
            msg = can.Message(timestamp=t + end, arbitration_id=m.msg.frame_id, is_extended_id=False,
                              dlc=len(data), data=data)
            sent.append(msg)
            self.bus.send(msg if self.tamper is None else self.tamper(msg))
        self.ticks += 1
        self.frames += len(sent)
        for msg in sent:
            rx = self.bus.recv(timeout=0.0 if self.interface == "virtual" else 1.0)
            while rx is not None and rx.arbitration_id not in self._by_id:   # others' traffic on a real bus
                rx = self.bus.recv(timeout=1.0)
            if rx is None:
                raise ArtibusError(f"--can {self.interface}: frame 0x{msg.arbitration_id:03X} sent at "
                                   f"t = {t:g} s did not come back")
            if self.interface != "virtual":
                rx.timestamp = msg.timestamp if rx.arbitration_id == msg.arbitration_id else t
            self._deliver(self._by_id[rx.arbitration_id], rx.data)
            if self.writer is not None:
                self.writer.on_message_received(rx)

    # --- figures ---------------------------------------------------------------------

    def report(self, duration):
        """Bus load of the frames sent over `duration` s, worst-case response times."""
        bits = sum(m.bits for m in self.messages)
        wcrt = response_times([(m.msg.frame_id, m.msg.length, m.ratio * self.period) for m in self.messages],
                              self.bitrate)
        return {
            "bitrate": self.bitrate, "frames": self.frames, "bits": bits,
            "load": bits / (self.bitrate * duration) if duration > 0 else float("nan"),
            "worst_load": sum(worst_case_bits(m.msg.length) / (m.ratio * self.period) for m in self.messages)
                          / self.bitrate,
            "messages": [dict(name=m.msg.name, id=m.msg.frame_id, dlc=m.msg.length, period=m.ratio * self.period,
                              sent=m.sent, rejected=m.rejected, wcrt=wcrt[m.msg.frame_id],
                              observed=self.observed.get(m.msg.frame_id, float("nan")))
                         for m in self.messages],
        }

    def summary(self, duration):
        r = self.report(duration)
        lines = [f"CAN ({self.interface}, {r['bitrate'] / 1000:g} kbit/s, {self.dbc_label}): {r['frames']} frames, "
                 f"bus load {100 * r['load']:.1f} % (bits sent, stuffing counted; worst-case stuffing "
                 f"{100 * r['worst_load']:.1f} %)"]
        for m in r["messages"]:
            lines.append(f"    0x{m['id']:03X} {m['name']:18s} {m['dlc']} B every {m['period'] * 1e3:g} ms: "
                         f"worst-case response {m['wcrt'] * 1e3:.3f} ms (observed {m['observed'] * 1e3:.3f} ms), "
                         f"{m['sent']} sent, {m['rejected']} rejected")
        if self.log_path is not None:
            lines.append(f"    log: {self.log_path}")
        return "\n".join(lines)

    def finish(self):
        """The run finished: the log is complete, put in place under its name."""
        writer, self.writer = self.writer, None
        if writer is not None:
            writer.stop()
            self._part.replace(self.log_path)

    def close(self):
        """Shut the bus; a log still open (the run did not finish) is removed:
        a failed run leaves no log."""
        writer, self.writer = getattr(self, "writer", None), None
        if writer is not None:
            writer.stop()
            self._part.unlink(missing_ok=True)
        bus, self.bus = getattr(self, "bus", None), None
        if bus is not None:
            bus.shutdown()


def _unit(unit, var):
    from artibus.runner import _unit_of
    return _unit_of(unit.fmu.md, var)


def dbc_in(ssp_dir, spec):
    return Path(ssp_dir) / (spec.get("source") or "")


# --- logs ---------------------------------------------------------------------------

def read_log(path):
    """The CAN frames of a .blf or .asc log (python-can's readers)."""
    import can
    path = Path(path)
    if not path.is_file():
        raise ArtibusError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in (".blf", ".asc"):
        raise ArtibusError(f"{path}: a CAN log is .blf or .asc")
    reader = can.BLFReader(str(path)) if suffix == ".blf" else can.ASCReader(str(path))
    try:
        return [m for m in reader if not m.is_error_frame and not m.is_remote_frame]
    except Exception as e:
        raise ArtibusError(f"{path}: cannot read the log: {e}") from None


def decode_log(path, dbc):
    """Rows (time s, message, signal, value, unit, e2e) of every frame of a log
    that the DBC knows; e2e is 'ok', 'crc' or 'counter' (the frame would not
    be used by the receivers)."""
    from cantools.autosar.end_to_end import compute_profile2_crc
    db = load_dbc(dbc) if not hasattr(dbc, "messages") else dbc
    rows, last = [], {}
    for frame in read_log(path):
        try:
            m = db.get_message_by_frame_id(frame.arbitration_id)
        except KeyError:
            continue
        data = bytes(frame.data)
        data_id = int(m.dbc.attributes["E2EDataID"].value)
        counter = data[1] & 0x0F
        e2e = ("crc" if compute_profile2_crc(data, data_id) != data[0] else
               "counter" if last.get(m.frame_id) == counter else "ok")
        if e2e != "crc":
            last[m.frame_id] = counter
        for name, v in m.decode(data, scaling=True, decode_choices=False).items():
            rows.append((frame.timestamp, m.name, name, v, m.get_signal_by_name(name).unit or "", e2e))
    return rows
