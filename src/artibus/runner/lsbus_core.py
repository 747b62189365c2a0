"""The FMI-LS-BUS network of a bench (artibus.runner.lsbus_bench.LsBusSteering) as the
stepping core's ac_lsbus (src/runner_core/lsbus.h), ticked by the core where the Python master
would tick (LsBusSteering.tick): ``_LsBusCore``.

The FMUs stay FMPy's FMU3Slave instances of the steering's lsbus.Network (instantiated and
initialised in Python); the core calls their FMI 3.0 functions through the pointers of the
libraries FMPy loaded. The network's state (each FMU's mode, pending iteration, next event
time and Event Mode entries; the bus's announced countdown ticks; the time) goes into the
struct before the run and comes back after it, and the frames on the wire become the
Network's frames, so Network.wire_frames, LsBusSteering.summary and finish read as after the
Python master. The core does exactly what lsbus.Network.advance does, in the same order
(tests/test_lsbus_core.py: bit for bit).
"""
import math
from ctypes import addressof, c_double, c_ubyte, c_void_p, cast, sizeof

import numpy as np

from artibus.base import ArtibusError
from artibus.runner.corelib import struct

_MODES = {"event": 0, "updated": 1, "step": 2}
_NAMES = {v: k for k, v in _MODES.items()}
_FUNCTIONS = ("EnterEventMode", "EnterStepMode", "UpdateDiscreteStates", "SetClock", "SetBinary", "GetBinary",
              "GetClock", "GetIntervalDecimal", "SetFloat64", "GetFloat64", "DoStep")
MAX_TERMS = 64                 # lsbus.c: terminals of one FMU
BUFFER = 1 << 16               # bytes routed to one terminal within one instant, at most
FRAMES_PER_TICK = 64           # the record of the frames on the wire: per tick and node, at most
#: time the network's FMU calls (LsBusSteering.fmu_wall): benchmarks/suite.py sets it; two
#: time stamps a call cost ~7 % of Bus36m_Circle_LSBUS's run, so not in an ordinary run
TIME_FMU_CALLS = False


def core_stimuli(steering, sim):
    """{unit index: [struct("ac_stimulus")]} of the steering's stimuli on the plant's inputs
    (Simulation._propagate: inp[i] = (inp[i] if base is None else base) + f(t), f(t) =
    value - steering.base.get(to, 0.0)), reading the steering's value buffer; None if a unit
    has a stimulus of another origin (then the network ticks in Python, called back by the core)."""
    values, slots = steering.core_values()
    own = steering.stimulus_functions
    out = {}
    for j, u in enumerate(sim.units):
        for i, f, base in u.stimuli:
            key = f"{u.path}.{u.in_names[i]}"
            if own.get(key) is not f:
                return None
            out.setdefault(j, []).append(struct("ac_stimulus")(
                dst=addressof(u.raw.inp) + sizeof(c_double) * i,
                value=addressof(values) + sizeof(c_double) * slots[key],
                base=0.0 if base is None else base, minus=steering.base.get(key, 0.0), has_base=base is not None))
    return out


class _WireFrames:
    """The frames on the wire the core recorded, [(t, id, ide, data)] as Network.wire_frames
    lists them: made into tuples when first read (a run that neither logs nor summarises
    them does not pay for 56000 tuples)."""

    def __init__(self, t, ids, ides, dls, ats, pool):
        self._arrays, self._list = (t, ids, ides, dls, ats, pool), None

    def __len__(self):
        return len(self._arrays[0])

    def __iter__(self):
        if self._list is None:
            t, ids, ides, dls, ats, pool = self._arrays
            pool = pool.tobytes()
            self._list = list(zip(t.tolist(), ids.tolist(), ides.tolist(),
                                  [pool[a:a + d] for a, d in zip(ats.tolist(), dls.tolist())]))
        return iter(self._list)


class _LsBusCore:
    """The steering's network as core.h's ac_lsbus, over the steering's Network (made by
    LsBusSteering.start, which the run calls before the core's steps)."""

    lsbus = True

    def __init__(self, sim, lib):
        self.steering, self.sim, self.lib = sim.lsbus, sim, lib
        self.ratio = sim.lsbus_ratio
        self.c = None

    def begin(self, n):
        """Before the run of n base steps: the struct over the Network's FMUs, its state in."""
        st, sim = self.steering, self.sim
        net = st.net
        everyone = net.nodes + [net.bus]
        self._keep = []
        self.fmus = (struct("ac_ls_fmu") * len(everyone))()
        index = {f.name: i for i, f in enumerate(net.nodes)}
        bus_terms = list(net.bus.terminals.values())
        for k, (a, f) in enumerate(zip(self.fmus, everyone)):
            terms = list(f.terminals.values())
            if len(terms) > MAX_TERMS:
                raise ArtibusError(f"{f.path}: {len(terms)} network terminals; the stepping core takes at most "
                                   f"{MAX_TERMS} (run with ARTIBUS_CORE=0)")
            arr = (struct("ac_ls_terminal") * len(terms))()
            for j, (q, t) in enumerate(zip(arr, terms)):
                buf = (c_ubyte * BUFFER)()
                self._keep.append(buf)
                q.rx_data, q.tx_data, q.rx_clock, q.tx_clock = t.rx_data, t.tx_data, t.rx_clock, t.tx_clock
                q.period, q.shift = t.period or 0.0, t.shift or 0.0
                q.countdown = t.tx_kind == "countdown"
                q.tx_output = t.tx_output
                q.peer = k if f is not net.bus else (j if j < len(net.nodes) else -1)
                q.buf, q.cap = addressof(buf), BUFFER
            self._keep.append(arr)
            a.instance = f.fmu.component
            for name in _FUNCTIONS:
                setattr(a, name[0].lower() + name[1:], cast(getattr(f.fmu.dll, f"fmi3{name}"), c_void_p).value)
            a.n_terms, a.terms = len(terms), addressof(arr)
            a.mode, a.need = _MODES[f.mode], int(bool(f.need))
            a.next_event, a.n_events, a.flagged = f.next_event, f.n_events, int(f.flagged)
        self._bus_terms = bus_terms
        # the inputs (LsBusSteering.src, its order) and the outputs onto the steering's values
        values, slots = st.core_values()
        ins = (struct("ac_ls_input") * max(1, len(st.src)))()
        for q, (node, var, out, j) in zip(ins, st.src):
            q.node, q.vr = index[node], self._float64(net.by_name[node], var)
            if isinstance(out, str):         # another node's output, read at the tick
                q.src, q.src_node, q.src_vr = None, index[out], self._float64(net.by_name[out], j)
            else:
                q.src = addressof(out) + sizeof(c_double) * j
        outs = (struct("ac_ls_output") * max(1, len(st.outputs)))()
        for q, (node, var, to) in zip(outs, st.outputs):
            q.node, q.vr = index[node], self._float64(net.by_name[node], var)
            q.dst = addressof(values) + sizeof(c_double) * slots[to]
        self._keep += [ins, outs]
        # the frames on the wire: lazily zeroed arrays (pages taken as they are written)
        ticks = -(-n // self.ratio) + 1
        cap = ticks * FRAMES_PER_TICK * len(net.nodes)
        self.frame_t, self.frame_id = np.zeros(cap), np.zeros(cap, dtype=np.uint32)
        self.frame_ide, self.frame_dl = np.zeros(cap, dtype=np.int32), np.zeros(cap, dtype=np.int32)
        self.frame_at, self.pool = np.zeros(cap, dtype=np.int64), np.zeros(cap * 8, dtype=np.uint8)
        self.c = c = struct("ac_lsbus")(n_nodes=len(net.nodes), fmus=addressof(self.fmus), ratio=self.ratio, period=st.period,
                              t0=net.t0, t=net.t, n_inputs=len(st.src), n_outputs=len(st.outputs),
                              inputs=addressof(ins), outputs=addressof(outs), bus_flagged=int(net.bus_flagged),
                              timed=int(TIME_FMU_CALLS),
                              frame_cap=cap, frame_t=self.frame_t.ctypes.data, frame_id=self.frame_id.ctypes.data,
                              frame_ide=self.frame_ide.ctypes.data, frame_dl=self.frame_dl.ctypes.data,
                              frame_at=self.frame_at.ctypes.data, pool=self.pool.ctypes.data, pool_cap=len(self.pool))
        # the bus's announced countdown ticks, in the dict's order
        seq = 0
        bus = self.fmus[len(net.nodes)]
        barr = (struct("ac_ls_terminal") * bus.n_terms).from_address(bus.terms)
        for term, tt in net.bus_ticks.items():
            seq += 1
            q = barr[bus_terms.index(term)]
            q.tick, q.tick_seq = tt, seq
        c.seq = seq
        self._barr = barr
        return addressof(c)

    @staticmethod
    def _float64(f, name):
        v = f.var(name)
        if v.type != "Float64":
            raise ArtibusError(f"{f.path}: {name} of FMU {f.name} is a {v.type}; the stepping core sets and reads "
                               "Float64 (run with ARTIBUS_CORE=0)")
        return v.valueReference

    def end(self, start, h):
        """After the run (or its failure, or an interrupt): the state back into the Network."""
        st, c = self.steering, self.c
        net = st.net
        for a, f in zip(self.fmus, net.nodes + [net.bus]):
            f.mode, f.need = _NAMES[a.mode], bool(a.need)
            f.next_event = a.next_event if a.next_event != math.inf else math.inf
            f.n_events, f.flagged = a.n_events, bool(a.flagged)
        net.t, net.bus_flagged = c.t, bool(c.bus_flagged)
        net.n_instants += c.instants
        ticks = sorted((q.tick_seq, j) for j, q in enumerate(self._barr) if q.tick_seq)
        net.bus_ticks = {self._bus_terms[j]: self._barr[j].tick for _, j in ticks}
        st.ticks += c.ticks
        st.wall += c.wall
        st.fmu_wall += c.fmu_wall
        values, slots = st.core_values(fill=False)
        for to, i in slots.items():
            st.value[to] = values[i]
        n = min(c.frames, c.frame_cap)         # the frames on the wire, for Network.wire_frames
        net.core_frames = _WireFrames(self.frame_t[:n], self.frame_id[:n], self.frame_ide[:n], self.frame_dl[:n],
                                      self.frame_at[:n], self.pool[:c.pool_used])

    def failure(self, t):
        """The core's tick failed (at the tick from t): the error the Python master raises, with
        the FMU that failed, which the core knows, and what that FMU said last."""
        from fmpy.fmi1 import FMICallException
        from artibus.runner.lsbus import LsBusError
        c, net = self.c, self.steering.net
        everyone = net.nodes + [net.bus]
        name = everyone[c.fail_fmu].name if 0 <= c.fail_fmu < len(everyone) else None
        if c.fail_function:
            e = FMICallException(function=c.fail_function.decode(), status=c.fail_status)
            failed = [everyone[c.fail_fmu]] if name else everyone
            said = [(f.name, m) for f in failed for m in f.errors()]
            why = f"; {said[-1][0]} said: {said[-1][1]}" if said else ""
            return LsBusError(f"t = {c.t:.6f} s: {f'FMU {name}: ' if name else ''}{e}{why}")
        text = c.message.decode(errors="replace")      # the master refused: when, too
        return LsBusError(f"t = {c.t:.6f} s: FMU {name}: {text}" if name else f"t = {c.t:.6f} s: {text}")
