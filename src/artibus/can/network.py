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

The runner's stepping core in C (src/runner_core/core.c) does the same tick,
bit for bit (tests/test_can_core.py), where it can (``Network.core_support``:
no faults, no tamper function, the virtual bus, integer signals): its own codec
(cantools' scaling and rounding, checked against cantools on every signal),
CRC, counter, the receivers' check and the counts, and the initialisation's
``settle`` too (artibus.runner.can_core._CanCore.settle); the frames go to the log
after the run (``log_frames``), the bus carries none. Faults, a tamper function
or a real interface tick here (``Network.tick``), as the run's
``Simulation.stepping`` says.

The traffic can be logged as .blf, .asc or .mf4 with python-can's writers; the log's
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
import itertools
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from artibus.base import ArtibusError
from artibus.bench.units import declared_unit
from artibus.can.codec import e2e_crc, frame_bits, response_times, worst_case_bits
from artibus.can.dbc import COUNTER_SIGNAL, CRC_SIGNAL, DEFAULT_BITRATE, _conversion, load_dbc
from artibus.can.faults import _FaultInjection

_channels = itertools.count()


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
    last_counter: int = None   # the receivers' reference counter (last accepted, or resynchronised)
    good_tick: int = None      # tick of the last accepted frame
    produced: int = 0    # frames the sender made (one per cycle)
    sent: int = 0        # frames on the wire
    lost: int = 0        # loss fault: not sent
    suppressed: int = 0  # silent or bus-off sender: not sent
    delayed: int = 0     # latency fault: sent late
    corrupted: int = 0   # corrupt fault: sent with a bad CRC or counter
    overwritten: int = 0  # in the receive buffer, overwritten by a newer frame before the receivers read it
    rejected: int = 0    # failed the receivers' E2E check (never used as data)
    why: dict = field(default_factory=lambda: {"crc": 0, "repeated": 0, "sequence": 0})
    bits: int = 0
    since: list = field(default_factory=list)   # per tick: cycles since the last accepted frame
    since_before: list = field(default_factory=list)   # earlier ticks' since, as arrays (the stepping core's)
    longest: int = 0     # the longest such run, and the time it reached it
    longest_at: float = float("nan")
    faults: list = field(default_factory=list)  # the _FaultStates acting on it
    node: str = ""       # its sender


class Network(_FaultInjection):
    """The CAN path of one run (see the module's docstring)."""

    def __init__(self, bench, dbc_file, links, interface="virtual", log=None, faults=None):
        """links: the runner's Links of the connections the bench routes over
        CAN, each with its Connection (``link.connection``); faults: Faults or
        their text forms (``parse_fault``). Validates everything before
        anything is opened or written."""
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
                                             _conversion(declared_unit(src_var), sig.unit, label),
                                             f"{c.start[0]}.{c.start[1]}")
            elif route.source != f"{c.start[0]}.{c.start[1]}":
                raise ArtibusError(f"{label}: signal {msg.name}.{sig.name} is already sent from {route.source}")
            route.receivers.append(_Receiver(link.dst, link.dst_index,
                                             _conversion(sig.unit, declared_unit(dst_var), label), link.name))
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
        for m in self.messages:
            m.node = m.msg.senders[0] if m.msg.senders else ""
        self._bind_faults(faults or [])
        self.tamper = None     # tests: f(can.Message) -> can.Message, between sending and receiving
        self.frames = 0
        self.error_frames = 0
        self.ticks = 0
        self.wall = 0.0        # s inside its ticks, timed by the stepping core (not when it ticks in Python)
        self.observed = {}     # identifier -> longest time from queuing to the end of the frame, s
        self._seq = 0          # production order of frames
        self._at_tick = {}     # tick -> delayed frames queued exactly at it: [(seq, _Message, data, burst)]
        self._mid = {}         # tick -> delayed frames queued after it, before the next: [(time, seq, m, data)]
        self._mailbox = {}     # identifier -> frames received since the receivers last read (newest last)
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
        from artibus.can.logs import LOG_SUFFIXES, log_writer
        if self.log_path is not None and self.log_path.suffix.lower() not in LOG_SUFFIXES:
            raise ArtibusError(f"--can-log {log}: the log is written as {', '.join(LOG_SUFFIXES)} (by its suffix; "
                               f".mf4: ASAM MDF 4 CAN bus logging)")
        try:
            self.bus = can.Bus(interface=kind, channel=channel, receive_own_messages=True,
                               preserve_timestamps=True, bitrate=self.bitrate)
        except Exception as e:
            raise ArtibusError(f"--can {self.interface}: cannot open the interface: {e}") from None
        self.writer = None
        self.log_error = None  # why the log could not be written (_log_failed); the run goes on without it
        if self.log_path is not None:
            self._part = self.log_path.with_name(self.log_path.name + ".part")
            try:
                self._part.parent.mkdir(parents=True, exist_ok=True)
                self.writer = log_writer(self.log_path, self._part)
            except OSError as e:
                self.bus.shutdown()
                self._part.unlink(missing_ok=True)
                raise ArtibusError(f"--can-log {log}: cannot write the log: {e.strerror or e}") from None

    # --- one tick ------------------------------------------------------------------

    def _encode(self, m, t, counter=None):
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
        values[COUNTER_SIGNAL] = m.counter if counter is None else counter
        values[CRC_SIGNAL] = 0
        try:
            data = bytearray(m.msg.encode(values, scaling=True, strict=True))
        except Exception as e:
            raise ArtibusError(f"{self.dbc_label}: message {m.msg.name}: {e} (t = {t:g} s)") from None
        data[0] = e2e_crc(data, m.data_id)
        return data

    def _deliver(self, m, data, k=None):
        """The receivers' E2E check, then the signals decoded into their inputs.
        As an AUTOSAR E2E profile 2 receiver with MaxDeltaCounterInit = 1: a
        wrong CRC is rejected; a counter equal to the reference counter
        (repeated) is rejected; a counter ahead by more than the cycles since
        the last accepted frame (at most 15) is a wrong sequence, rejected, and
        becomes the reference (re-synchronisation; no SyncCounter). A rejected
        frame is never used: the receivers keep the last good value."""
        counter = data[1] & 0x0F
        why = None
        if e2e_crc(data, m.data_id) != data[0]:
            why = "crc"
        elif m.last_counter is not None:
            delta = (counter - m.last_counter) % 16
            allowed = 15 if k is None or m.good_tick is None else min(max((k - m.good_tick) // m.ratio, 1), 15)
            if delta == 0:
                why = "repeated"
            elif delta > allowed:
                why = "sequence"
                m.last_counter = counter
        if why is not None:
            m.rejected += 1
            m.why[why] += 1
            return False
        m.last_counter = counter
        if k is not None:
            m.good_tick = k
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

    def core_support(self):
        """None when the runner's stepping core in C can tick this network
        (src/runner_core/core.c: no faults, no tamper function, the virtual
        bus, integer signals of at most 52 bits with a range; a log is written
        from the frames the core records, ``log_frames``), else what it cannot
        do: then the network ticks in Python (Network.tick)."""
        if self.faults:
            return "faults (--can-fault)"
        if self.tamper is not None:
            return "a tamper function"
        if self.interface != "virtual":
            return f"a real interface (--can {self.interface})"
        if len(self.messages) > 64:
            return "more than 64 messages"
        for m in self.messages:
            if m.msg.length > 8 or m.data_id > 255:
                return f"message {m.msg.name}: DLC {m.msg.length}, data ID {m.data_id}"
            for s in m.msg.signals:
                if s.conversion.is_float or s.length > 52 or s.minimum is None or s.maximum is None:
                    return f"signal {m.msg.name}.{s.name}: a float, longer than 52 bits or without a range"
        return None

    def fixed_frame(self, m):
        """Message m's frame with the signals no connection feeds (their start
        values, see _Message.fixed) and every other bit 0, as cantools encodes
        it: the stepping core adds the routed signals, counter and CRC."""
        values = dict(m.fixed)
        for s in m.msg.signals:
            if s.name not in values:            # raw 0
                values[s.name] = s.conversion.raw_to_scaled(0, decode_choices=False)
        return m.msg.encode(values, scaling=True, strict=False)

    def log_frames(self, frames):
        """Frames the stepping core sent, (stamp s, identifier, data), into the
        log as Network._transmit logs them: the frame as the virtual bus gives
        it back (its channel, not received from another node)."""
        import can
        if self.writer is None:
            return
        for stamp, can_id, data in frames:
            if self.writer is None:     # (it failed: _log_failed)
                return
            self._log(can.Message(
                timestamp=stamp, arbitration_id=can_id, is_extended_id=False, dlc=len(data), data=data,
                channel=self.bus.channel_id, is_rx=False))

    def _log(self, msg):
        """One frame into the log; a write that fails (a full disk) ends the log, not the run."""
        try:
            self.writer.on_message_received(msg)
        except OSError as e:
            self._log_failed(e)

    def _log_failed(self, e):
        """The log cannot be written (ENOSPC, EDQUOT, EIO...): its writer
        dropped, its file closed and removed (nothing half-written is left),
        the reason kept in ``log_error`` for the end of the run (the runner
        says it after the results are saved: artibus.runner.Simulation)."""
        import contextlib
        writer, self.writer = self.writer, None
        if writer is not None:
            with contextlib.suppress(Exception):
                writer.file.close()
        self._part.unlink(missing_ok=True)
        if self.log_error is None:
            self.log_error = (f"--can-log {self.log_path}: cannot write the log: {e.strerror or e}; "
                              f"no log written (the run's other outputs are complete)")

    def settle(self):
        """Initialisation: the receivers get the senders' values through the
        codec (quantised as on the bus), nothing is sent. The value counts as
        the frame of the cycle before the first tick."""
        for m in self.messages:
            data = self._encode(m, float("nan"))
            m.last_counter = None
            self._deliver(m, data)
            m.last_counter = None
            m.good_tick = -m.ratio

    def start(self, t0):
        """Before the first tick: the writers' time origin is the run's start."""
        self.t0 = t0
        if self.writer is not None:
            try:
                self.writer.log_event(f"artibus: simulated time in s from t = {t0:g} s (the run's start)", t0)
            except OSError as e:
                self._log_failed(e)

    def _transmit(self, m, data, stamp, bits):
        """One frame on the bus at simulated time `stamp` (end of its EOF),
        received back into the receivers' buffer and logged."""
        import can
        msg = can.Message(timestamp=stamp, arbitration_id=m.msg.frame_id, is_extended_id=False,
                          dlc=len(data), data=data)
        self.bus.send(msg if self.tamper is None else self.tamper(msg))
        rx = self.bus.recv(timeout=0.0 if self.interface == "virtual" else 1.0)
        while rx is not None and rx.arbitration_id not in self._by_id:   # others' traffic on a real bus
            rx = self.bus.recv(timeout=1.0)
        if rx is None:
            raise ArtibusError(f"--can {self.interface}: frame 0x{msg.arbitration_id:03X} sent at "
                               f"t = {stamp:g} s did not come back")
        if self.interface != "virtual":
            rx.timestamp = msg.timestamp if rx.arbitration_id == msg.arbitration_id else stamp
        m.sent += 1
        m.bits += bits
        self.frames += 1
        self._mailbox.setdefault(rx.arbitration_id, []).append(rx)
        if self.writer is not None:
            self._log(rx)

    def tick(self, k, t):
        """The network's k-th tick at simulated time t: the frames queued at t
        go on the wire in order of identifier (older first within one), the
        receivers read their buffers (the newest frame of each message), then
        the frames queued late (latency) before the next tick are sent."""
        tau = 1.0 / self.bitrate
        queue = self._at_tick.pop(k, [])
        for m in self.messages:
            if k % m.ratio == 0:
                item = self._produce(m, k, t)
                if item is not None:
                    queue.append(item)
        queue.sort(key=lambda e: (e[1].msg.frame_id, e[0]))
        busy = 0
        for seq, m, data, burst in queue:
            if burst:
                busy += self._burst(m, data, t, busy)
                continue
            bits = frame_bits(m.msg.frame_id, data)
            busy += bits
            end = (busy - 3) * tau                   # end of its EOF, the frames before it queued ahead
            self.observed[m.msg.frame_id] = max(self.observed.get(m.msg.frame_id, 0.0), end)
            self._transmit(m, data, t + end, bits)
        self.ticks += 1
        for m in self.messages:                     # the receivers read their buffers
            frames = self._mailbox.pop(m.msg.frame_id, None)
            if frames:
                m.overwritten += len(frames) - 1
                self._deliver(m, frames[-1].data, k)
            since = (k - m.good_tick) // m.ratio
            m.since.append(since)
            if since > m.longest:
                m.longest, m.longest_at = since, t
        free = t + busy * tau                       # frames queued between this tick and the next
        for q, seq, m, data in sorted(self._mid.pop(k, []), key=lambda e: (e[0], e[1])):
            bits = frame_bits(m.msg.frame_id, data)
            start = max(q, free)
            free = start + bits * tau
            self.observed[m.msg.frame_id] = max(self.observed.get(m.msg.frame_id, 0.0), free - 3 * tau - q)
            self._transmit(m, data, free - 3 * tau, bits)

    def since_series(self):
        """{message: array over the ticks of the cycles since its last accepted
        frame, after that tick's delivery}."""
        import numpy as np
        return {m.msg.name: np.concatenate(m.since_before + [np.array(m.since, dtype=float)])
                for m in self.messages}

    def add_since(self, m, series):
        """The since series (floats) of ticks the stepping core did, after those before."""
        import numpy as np
        if m.since:
            m.since_before.append(np.array(m.since, dtype=float))
            m.since.clear()
        m.since_before.append(series)

    # --- figures ---------------------------------------------------------------------

    def report(self, duration):
        """Bus load of the frames sent over `duration` s, worst-case response
        times, and per message what the faults did."""
        bits = sum(m.bits for m in self.messages)
        wcrt = response_times([(m.msg.frame_id, m.msg.length, m.ratio * self.period) for m in self.messages],
                              self.bitrate)
        return {
            "bitrate": self.bitrate, "frames": self.frames, "bits": bits, "error_frames": self.error_frames,
            "load": bits / (self.bitrate * duration) if duration > 0 else float("nan"),
            "worst_load": sum(worst_case_bits(m.msg.length) / (m.ratio * self.period) for m in self.messages)
                          / self.bitrate,
            "faults": [str(fs.fault) for fs in self.faults],
            "messages": [dict(name=m.msg.name, id=m.msg.frame_id, dlc=m.msg.length, period=m.ratio * self.period,
                              node=m.node, produced=m.produced, sent=m.sent, lost=m.lost, suppressed=m.suppressed,
                              delayed=m.delayed, corrupted=m.corrupted, overwritten=m.overwritten,
                              rejected=m.rejected, rejected_why=dict(m.why), longest=m.longest,
                              longest_at=m.longest_at, wcrt=wcrt[m.msg.frame_id],
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
        if r["faults"]:
            lines.append(f"    faults: {'; '.join(r['faults'])}"
                         + (f"; {r['error_frames']} error frames (bus-off bursts)" if r["error_frames"] else ""))
            lines.append(f"    {'message':18s} {'made':>6s} {'sent':>6s} {'lost':>5s} {'silent':>6s} {'late':>5s} "
                         f"{'corrupt':>7s} {'overwr':>6s} {'rejected':>8s} {'(crc/rep/seq)':>13s}  "
                         f"longest run of cycles without a good frame")
            for m in r["messages"]:
                w = m["rejected_why"]
                why = f"({w['crc']}/{w['repeated']}/{w['sequence']})"
                gap = f"{m['longest']}, reached at t = {m['longest_at']:.2f} s" if m["longest"] else "0"
                lines.append(f"    {m['name']:18s} {m['produced']:6d} {m['sent']:6d} {m['lost']:5d} "
                             f"{m['suppressed']:6d} {m['delayed']:5d} {m['corrupted']:7d} {m['overwritten']:6d} "
                             f"{m['rejected']:8d} {why:>13s}  {gap}")
        if self.log_path is not None:
            lines.append(f"    log: {self.log_path}" + (" (not written: a write failed)" if self.log_error else ""))
        return "\n".join(lines)

    def finish(self):
        """The run finished: the log is complete, put in place under its name."""
        writer = self.writer
        if writer is not None:
            try:
                writer.stop()           # (the last frames written, the header completed)
                self._part.replace(self.log_path)
            except OSError as e:
                self._log_failed(e)
            self.writer = None

    def close(self):
        """Shut the bus; a log still open (the run did not finish) is removed:
        a failed run leaves no log."""
        writer, self.writer = getattr(self, "writer", None), None
        if writer is not None:
            try:
                writer.stop()
            except OSError:             # (a full disk: the log is removed all the same)
                import contextlib
                with contextlib.suppress(Exception):
                    writer.file.close()
            self._part.unlink(missing_ok=True)
        bus, self.bus = getattr(self, "bus", None), None
        if bus is not None:
            bus.shutdown()
