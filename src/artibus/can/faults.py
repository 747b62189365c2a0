"""Faults injected into the CAN network: their text form (``parse_fault``,
``Fault``) and what they do to a run's frames (``_FaultInjection``, the part of
``Network`` that binds them to messages and nodes, produces each frame with the
faults acting on it, and bursts a node off the bus)."""
import math
from dataclasses import dataclass

from artibus.base import ArtibusError
from artibus.can.codec import frame_bits

#: kinds of fault: the positional value each takes, the options it accepts
FAULT_KINDS = {
    "loss": ("rate", {"seed"}),                       # frames not sent, with probability rate
    "latency": ("delay", {"jitter", "seed"}),         # frames queued delay + U(0, jitter) s late
    "corrupt": ("mode", {"rate", "seed"}),            # crc | repeat | skip
    "silent": (None, set()),                          # the node sends nothing
    "busoff": (None, {"recover"}),                    # error burst, bus-off, optional recovery
}
CORRUPT_MODES = ("crc", "repeat", "skip")
FAULT_SYNTAX = ("KIND:TARGET[:VALUE][:KEY=VALUE...][@T0[-T1]] with KIND loss (VALUE rate 0..1, seed=), "
                "latency (VALUE delay s, jitter= s, seed=), corrupt (VALUE crc|repeat|skip, rate=, seed=), "
                "silent, busoff (recover or recover=DELAY s); TARGET a message or a node of the DBC "
                "(silent/busoff: a node); @T0-T1 the window in simulated s (default: the whole run)")
BUSOFF_ATTEMPTS = 32          # TEC +8 per failed transmission: 32 of them reach 256 (ISO 11898-1)
ERROR_FRAME_BITS = 17         # error flag 6, error delimiter 8, interframe space 3
RECOVERY_BITS = 128 * 11      # 128 occurrences of 11 recessive bits (ISO 11898-1, bus-off recovery)
_FLOAT = r"[0-9]+(?:\.[0-9]*)?(?:[eE][+-]?[0-9]+)?"


@dataclass
class Fault:
    """A fault injected into the CAN network (see ``parse_fault`` for the text form).

    kind: loss, latency, corrupt, silent, busoff; target: a message or a node
    (the sender of messages) of the DBC; rate (loss, corrupt): probability per
    frame; delay, jitter (latency, s): a frame is queued delay + U(0, jitter)
    late; mode (corrupt): crc, repeat or skip; start, end: the window of
    production times [start, end) in simulated s; seed: of the fault's own
    numpy Generator; recover (busoff): None (stays off) or the application's
    restart delay after the minimum recovery time (s)."""
    kind: str
    target: str
    rate: float = 1.0
    delay: float = 0.0
    jitter: float = 0.0
    mode: str = "crc"
    start: float = -math.inf
    end: float = math.inf
    seed: int = 0
    recover: float | None = None
    text: str = ""

    def __str__(self):
        return self.text or f"{self.kind}:{self.target}"


def parse_fault(text):
    """A fault from its text form, e.g. ``loss:SensorG2_Angle:0.1:seed=7``,
    ``latency:Module2ECU_Cmd:0.02:jitter=0.005:seed=3``,
    ``corrupt:TractorECU_State:crc@20.0-20.5``, ``silent:Module3ECU@20``,
    ``busoff:Module2ECU@30:recover``. The target's name is checked against the
    DBC when the network is built."""
    import re
    head = f"--can-fault {text}"
    body, at, window = text.strip().partition("@")
    # options may also follow the window: busoff:Module2ECU@30:recover
    if at:
        window, _, tail = window.partition(":")
        body = body + (":" + tail if tail else "")
    parts = [p.strip() for p in body.split(":")]
    if len(parts) < 2 or not parts[0] or not parts[1]:
        raise ArtibusError(f"{head}: expected {FAULT_SYNTAX}")
    kind, target, rest = parts[0].lower(), parts[1], parts[2:]
    if kind not in FAULT_KINDS:
        raise ArtibusError(f"{head}: unknown fault '{parts[0]}' (faults: {', '.join(FAULT_KINDS)})")
    positional, keys = FAULT_KINDS[kind]
    f = Fault(kind, target, text=text.strip())
    values = {}
    for i, p in enumerate(rest):
        key, eq, value = p.partition("=")
        if not eq:
            if key == "recover" and "recover" in keys:
                values["recover"] = "0"
            elif i == 0 and positional:
                values[positional] = key
            else:
                raise ArtibusError(f"{head}: unexpected '{p}' (expected {FAULT_SYNTAX})")
        elif key not in keys:
            raise ArtibusError(f"{head}: {kind} takes no option '{key}'"
                               + (f" (options: {', '.join(sorted(keys))})" if keys else ""))
        else:
            values[key] = value
    if positional and positional not in values and kind != "corrupt":
        raise ArtibusError(f"{head}: {kind} needs its {positional}, e.g. "
                           + ("loss:SensorG2_Angle:0.1" if kind == "loss" else "latency:Module2ECU_Cmd:0.02"))

    def number(key, lo, hi, unit=""):
        try:
            v = float(values[key])
        except ValueError:
            v = float("nan")
        if not (math.isfinite(v) and lo <= v <= hi):
            raise ArtibusError(f"{head}: {key} = {values[key]!r}: expected a number in [{lo:g}, {hi:g}]{unit}")
        return v

    if "rate" in values:
        f.rate = number("rate", 0.0, 1.0)
    if "delay" in values:
        f.delay = number("delay", 0.0, 3600.0, " s")
    if "jitter" in values:
        f.jitter = number("jitter", 0.0, 3600.0, " s")
    if "recover" in values:
        f.recover = number("recover", 0.0, 3600.0, " s")
    if "seed" in values:
        try:
            f.seed = int(values["seed"])
            if f.seed < 0:
                raise ValueError
        except ValueError:
            raise ArtibusError(f"{head}: seed = {values['seed']!r}: expected an integer >= 0") from None
    if kind == "corrupt":
        f.mode = values.get("mode", "crc").lower()
        if f.mode not in CORRUPT_MODES:
            raise ArtibusError(f"{head}: corrupt mode '{values['mode']}': expected {', '.join(CORRUPT_MODES)}")
    if at:
        m = re.fullmatch(rf"\s*({_FLOAT})\s*(?:-\s*({_FLOAT})\s*)?", window)
        if m is None:
            raise ArtibusError(f"{head}: window '@{window}': expected @T0 or @T0-T1 in s")
        f.start = float(m.group(1))
        if m.group(2) is not None:
            f.end = float(m.group(2))
            if not f.end > f.start:
                raise ArtibusError(f"{head}: window '@{window}': the end must be after the start")
    return f


class _FaultState:
    """A fault bound to the network: its messages and its own random numbers."""

    def __init__(self, fault, messages):
        import numpy as np
        self.fault = fault
        self.messages = messages          # the _Messages it acts on
        self.rng = np.random.default_rng(fault.seed)

    def active(self, t):
        f = self.fault
        return f.start - 1e-9 <= t < f.end - 1e-9


@dataclass
class _Node:
    """A sending node's state under silent/busoff faults."""
    name: str
    off_until: float = -math.inf       # sends nothing before this time (bus-off)
    burst_pending: bool = False
    burst_at: float = math.nan         # time its error burst started


class _FaultInjection:
    """Network's faults (see the module's docstring; Network, artibus.can.network,
    is this class with the rest of the path)."""

    def _bind_faults(self, faults):
        """Each fault's messages (a message, or every message a node sends)."""
        names = {m.msg.name: m for m in self.messages}
        nodes = {}
        for m in self.messages:
            nodes.setdefault(m.node, []).append(m)
        known_nodes = [n.name for n in self.db.nodes]
        self.faults = []
        self.nodes = {}
        for f in faults:
            f = parse_fault(f) if isinstance(f, str) else f
            head = f"--can-fault {f}"
            if f.kind in ("silent", "busoff"):
                if f.target not in known_nodes:
                    hint = (f" ({f.target} is a message; its sender is {names[f.target].node})"
                            if f.target in names else "")
                    raise ArtibusError(f"{head}: {self.dbc_label} has no node '{f.target}'{hint} "
                                       f"(nodes: {', '.join(known_nodes)})")
                msgs = nodes.get(f.target, [])
                if not msgs:
                    raise ArtibusError(f"{head}: node {f.target} sends no message in {self.dbc_label} "
                                       f"(senders: {', '.join(nodes)})")
                if f.kind == "busoff":
                    if f.target in self.nodes:
                        raise ArtibusError(f"{head}: node {f.target} already has a busoff fault")
                    self.nodes[f.target] = _Node(f.target)
            elif f.target in names:
                msgs = [names[f.target]]
            elif f.target in nodes:
                msgs = nodes[f.target]
            else:
                raise ArtibusError(f"{head}: {self.dbc_label} has no message or sending node '{f.target}' "
                                   f"(messages: {', '.join(names)}; nodes: {', '.join(nodes)})")
            if f.kind == "latency" and f.delay + f.jitter <= 0:
                raise ArtibusError(f"{head}: a latency of 0 s changes nothing")
            state = _FaultState(f, msgs)
            self.faults.append(state)
            for m in msgs:
                m.faults.append(state)

    def _produce(self, m, k, t):
        """The frame message m's sender makes at tick k, with the faults acting
        on it: None when it is not on the wire at this tick (lost, suppressed,
        or delayed: then filed for later), else (seq, m, data, burst)."""
        m.produced += 1
        seq = self._seq
        self._seq += 1
        lost = suppressed = burst = False
        corrupt, delay = None, 0.0
        for fs in m.faults:
            f = fs.fault
            if not fs.active(t):
                continue
            if f.kind == "loss":
                lost |= bool(fs.rng.random() < f.rate)
            elif f.kind == "latency":
                delay = max(delay, f.delay + (float(fs.rng.uniform(0.0, f.jitter)) if f.jitter > 0 else 0.0))
            elif f.kind == "corrupt":
                if f.rate >= 1.0 or fs.rng.random() < f.rate:
                    corrupt = f.mode
            elif f.kind == "silent":
                suppressed = True
            elif f.kind == "busoff":
                node = self.nodes[f.target]
                if not node.burst_pending and node.off_until == -math.inf:
                    node.burst_pending, node.off_until = True, math.inf    # this frame starts the burst
                    burst = True
                elif t < node.off_until - 1e-9:
                    suppressed = True
        counter = m.counter
        if corrupt == "repeat":          # the previous frame's counter again; the counter does not advance
            counter = (m.counter - 1) % 16
        elif corrupt == "skip":          # the counter jumps over one value
            counter = (m.counter + 1) % 16
            m.counter = (m.counter + 2) % 16
        else:
            m.counter = (m.counter + 1) % 16
        data = self._encode(m, t, counter)
        if corrupt is not None:
            m.corrupted += 1
            if corrupt == "crc":         # a payload bit flipped after the sender's CRC
                data[-1] ^= 0x01
        if burst:
            return seq, m, bytes(data), True
        if lost:
            m.lost += 1
            return None
        if suppressed:
            m.suppressed += 1
            return None
        if delay > 0.0:
            m.delayed += 1
            kq = k + delay / self.period
            if abs(kq - round(kq)) < 1e-6:
                self._at_tick.setdefault(int(round(kq)), []).append((seq, m, bytes(data), False))
            else:
                self._mid.setdefault(int(math.floor(kq)), []).append((t + delay, seq, m, bytes(data)))
            return None
        return seq, m, bytes(data), False

    def _burst(self, m, data, t, busy):
        """Bus-off: the node's frame fails BUSOFF_ATTEMPTS times in a row (each
        attempt the frame up to its ACK slot, then an error frame); its
        transmit error counter reaches 256 and it leaves the bus. Returns the
        bits the burst took."""
        import can
        tau = 1.0 / self.bitrate
        bits = BUSOFF_ATTEMPTS * (frame_bits(m.msg.frame_id, data) - 10 + ERROR_FRAME_BITS)
        node = self.nodes[m.node]
        end = t + (busy + bits) * tau
        fault = next(fs.fault for fs in m.faults if fs.fault.kind == "busoff")
        node.burst_pending = False
        node.off_until = math.inf if fault.recover is None else end + RECOVERY_BITS * tau + fault.recover
        node.burst_at = t + busy * tau
        self.error_frames += BUSOFF_ATTEMPTS
        m.suppressed += 1
        if self.writer is not None:
            self.writer.on_message_received(can.Message(timestamp=node.burst_at, arbitration_id=m.msg.frame_id,
                                                        is_error_frame=True, is_extended_id=False, dlc=0))
        return bits
