"""The CAN network of a run (artibus.can.Network) as the stepping core's
ac_can (core.h): ``can_signal`` (a cantools Signal as core.h's ac_can_signal)
and ``_CanCore``."""
from ctypes import addressof, c_double, sizeof

import numpy as np

from artibus.base import ArtibusError
from artibus.runner.corelib import struct


def can_signal(s, q=None):
    """core.h's ac_can_signal of a cantools Signal (its range, conversion and
    place; no source, no receivers): q filled, or a new one."""
    q = struct("ac_can_signal")() if q is None else q
    conv = getattr(s.conversion, "_conversion", s.conversion)   # NamedSignalConversion's own
    q.minimum, q.maximum = s.minimum, s.maximum
    q.scale, q.offset = conv.scale, conv.offset
    q.integer = type(conv).__name__ in ("IdentityConversion", "LinearIntegerConversion")
    if q.integer:
        q.iscale, q.ioffset = int(conv.scale), int(conv.offset)
    q.start, q.length = s.start, s.length
    q.big_endian, q.is_signed = s.byte_order == "big_endian", bool(s.is_signed)
    return q


class _CanCore:
    """The CAN network (artibus.can.Network) as core.h's ac_can: its messages in
    identifier order, each routed signal with cantools' conversion and place in
    the frame, pointing into the senders' output and the receivers' input
    buffers; the network's state goes in before the run and comes back after
    (counters, the receivers' E2E state, counts, bits, the since series), so
    Network.report, summary and since_series read as after the network's Python ticks."""

    def __init__(self, sim, lib):
        from artibus.can import COUNTER_SIGNAL
        net = self.net = sim.can
        double = sizeof(c_double)
        self._keep = []
        self.messages = (struct("ac_can_message") * len(net.messages))()
        for a, m in zip(self.messages, net.messages):
            sigs = (struct("ac_can_signal") * max(1, len(m.routes)))()
            for q, r in zip(sigs, m.routes):
                s = r.signal
                rcs = (struct("ac_can_receiver") * max(1, len(r.receivers)))(
                    *((addressof(rc.unit.raw.inp) + double * rc.index, rc.factor) for rc in r.receivers))
                self._keep.append(rcs)
                can_signal(s, q)
                q.src = None if s.name == COUNTER_SIGNAL else addressof(r.unit.raw.out) + double * r.index
                q.factor = r.factor
                q.n_receivers, q.receivers = len(r.receivers), addressof(rcs)
            self._keep.append(sigs)
            a.id, a.dlc, a.ratio, a.data_id = m.msg.frame_id, m.msg.length, m.ratio, m.data_id
            a.fixed[:m.msg.length] = net.fixed_frame(m)
            a.n_signals, a.signals = len(m.routes), addressof(sigs)
        self.c = struct("ac_can")(n_messages=len(net.messages), messages=addressof(self.messages), ratio=sim.can_ratio,
                        tau=1.0 / net.bitrate)
        self.ratio = sim.can_ratio
        self.lib = lib

    def settle(self):
        """Network.settle through the core's codec (artibus_core_can_settle), the
        same frames, receivers' inputs and E2E state."""
        net = self.net
        for a, m in zip(self.messages, net.messages):
            a.counter = m.counter
        bad = self.lib.artibus_core_can_settle(addressof(self.c))
        for m in net.messages[:bad] if bad >= 0 else net.messages:    # the messages it settled
            m.last_counter = None
            m.good_tick = -m.ratio
        if bad >= 0:                   # Network._encode raises its error (t = nan in the initialisation)
            self.refused(bad, float("nan"))

    def begin(self, n):
        """Before the run of n base steps: the network's state in."""
        ticks = -(-n // self.ratio)
        self.since = np.zeros((len(self.net.messages), max(1, ticks)))
        for i, (a, m) in enumerate(zip(self.messages, self.net.messages)):
            a.counter = m.counter
            a.last_counter = -1 if m.last_counter is None else m.last_counter
            a.good_tick = m.good_tick
            a.produced = a.sent = a.rejected = a.rejected_crc = a.rejected_repeated = a.rejected_sequence = 0
            a.bits, a.end_bits = 0, -1
            a.since = self.since[i].ctypes.data
        self.c.ticks = self.c.frames = 0
        self.c.wall = 0.0
        if self.net.writer is not None:     # every frame recorded, for the log (Network.log_frames)
            cap = sum(-(-ticks // m.ratio) for m in self.net.messages)
            self.frame_tick = np.zeros(cap, dtype=np.int64)      # (c_long: LP64)
            self.frame_stamp = np.zeros(cap)
            self.frame_data = np.zeros((cap, 16), dtype=np.uint8)
            self.c.frame_cap, self.c.frame_tick = cap, self.frame_tick.ctypes.data
            self.c.frame_stamp, self.c.frame_data = self.frame_stamp.ctypes.data, self.frame_data.ctypes.data
        return addressof(self.c)

    def end(self, start, h):
        """After the run (or its failure, or an interrupt): the state back into the network."""
        net, ticks = self.net, self.c.ticks
        for i, (a, m) in enumerate(zip(self.messages, net.messages)):
            m.counter = a.counter
            m.last_counter = None if a.last_counter < 0 else a.last_counter
            m.good_tick = a.good_tick
            m.produced += a.produced
            m.sent += a.sent
            m.rejected += a.rejected
            for why, count in (("crc", a.rejected_crc), ("repeated", a.rejected_repeated),
                               ("sequence", a.rejected_sequence)):
                m.why[why] += count
            m.bits += a.bits
            if a.end_bits >= 0:
                fid = m.msg.frame_id
                net.observed[fid] = max(net.observed.get(fid, 0.0), a.end_bits * (1.0 / net.bitrate))
            since = self.since[i, :ticks]
            net.add_since(m, since)
            if ticks and since.max() > m.longest:      # Network.tick: the first tick reaching the longest run
                j = int(np.argmax(since))
                m.longest, m.longest_at = int(since[j]), start + ((net.ticks + j) * self.ratio) * h
        net.frames += self.c.frames
        net.ticks += ticks
        net.wall += self.c.wall
        if self.c.frame_cap:
            n = min(self.c.frames, self.c.frame_cap)
            ids = self.frame_data[:n, 0].astype(int) | (self.frame_data[:n, 1].astype(int) << 8)
            net.log_frames((float(t), int(i), bytearray(f[8:8 + f[4]]))
                           for t, i, f in zip(self.frame_stamp[:n], ids, self.frame_data[:n]))

    def refused(self, index, t):
        """The core could not encode message index's frame at t: Network._encode's error."""
        m = self.net.messages[index]
        self.net._encode(m, t)
        raise ArtibusError(f"{self.net.dbc_label}: message {m.msg.name}: the stepping core refused its frame "
                           f"at t = {t:g} s, artibus.can's encoder did not (a defect: run with ARTIBUS_CORE=0)")
