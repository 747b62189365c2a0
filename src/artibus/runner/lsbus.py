"""A small FMI-LS-BUS 1.0 co-simulation master for FMI 3.0 Co-Simulation with Event Mode
(issue 24): CAN network nodes, connected directly (two nodes) or through a bus simulation FMU
such as CanBus, on artibus's FMU instances with Event Mode (artibus.fmu.fmi3). The C stepping core does what Network.advance does, in
the same order, on the same instances (src/runner_core/lsbus.c, artibus.runner.lsbus_core);
this is its reference and the runner's fallback (ARTIBUS_CORE=0).

What it does, with the sections it follows:

- the nodes' time-based Tx clocks (``intervalVariability`` constant or fixed, periodic with the
  description's ``intervalDecimal`` and ``shiftDecimal``) are the master's clock sources: they
  tick at t0 + shift + k * interval (FMI 3.0.2 docs/2_2_common_mechanisms.adoc, Clocks: periodic
  time-based input clocks, set by the importer in Event Mode; fmi-ls-bus v1.0.0
  docs/4____network_abstraction.adoc, "Time-based Tx Clocks");
- the bus simulation FMU's countdown Tx clocks are read with fmi3GetIntervalDecimal after each
  fmi3UpdateDiscreteStates (qualifier changed: a tick at t + interval), and an
  eventHandlingNeeded of its fmi3DoStep brings it into Event Mode at the step's end;
- the communication steps are cut at the next of these ticks (the next bus communication
  point), so every tick is an event at its exact time;
- a node's triggered output Tx clock (fmi-ls-bus 1.0, "Triggered Tx Clocks"): the node is taken
  into Event Mode after an fmi3DoStep that returned eventHandlingNeeded, or when time reaches the
  nextEventTime it announced (the steps are cut there; FMI 3.0.2, 4.2, fmi3EnterEventMode), and
  its output clocks read with fmi3GetClock there; an active output clock of no terminal is an
  error naming the node, the clock and the time (Fmu.active_output_clocks);
- in each Event Mode the calls go in the standard's order: the Float64 inputs, fmi3SetClock,
  fmi3SetBinary, fmi3GetClock of the output clocks, Tx_Data of the active Tx clocks read (while
  they are active: FMI 3.0.2, 2.2.8, "Getting and Setting Variable Values"), then
  fmi3UpdateDiscreteStates, which ends the activation (2.3), repeated while discreteStatesNeedUpdate; a clock
  set after the discrete states that asked for no further iteration is refused here, before
  the FMU sees it (FMI 3.0.2, 5.2.2);
- the Rx clocks are triggered: a node's Rx_Clock ticks when Tx data arrive for it; a zero-size
  Tx_Data activates nothing (4____network_abstraction.adoc, "Rx Clocks");
- a terminal's Rx_Data/Tx_Data must declare the CAN MIME type of FMI-LS-BUS 1.x (version 1.0.0
  or a pre-release of it, as the fmi-ls-bus-examples' "1.0.0-beta.1"; ``check_mime``);
- Tx_Data is copied (``bytes``) before the next FMU is called, and routed through the
  terminals: node Tx_Data -> CanBus NodeK.Rx_Data, CanBus NodeK.Tx_Data -> node Rx_Data
  (2____common_concepts.adoc, "Composition with dedicated Bus Simulation FMU"), or, without a
  bus FMU, one node's Tx_Data -> the other's Rx_Data (the direct composition of two nodes).

The order within an instant (one Event Mode per FMU and instant where it can):
1. the bus's operations due now (frames whose wire time ends now) go to their nodes;
2. the nodes, in the order given (sensors, the tractor ECU, the other ECUs, the actuators):
   each gets its Tx tick and what has arrived for it so far; without a bus, its Tx_Data reaches
   the other node at once, within the same instant;
3. all Tx_Data of the instant go to the bus in one Event Mode (fmi3SetClock of every
   NodeK.Rx_Clock, then the binaries, then fmi3UpdateDiscreteStates), so frames sent in the
   same instant arbitrate together, by identifier, as on the wire (4_4_1_can.adoc,
   "Arbitration");
4. what the bus answers within the instant (frames with wire time off, Confirm, Format Error)
   reaches each node in a further Event Mode at the same time, with its Rx clock only.
With the bus's wire time off a node thus receives the frames of its instant after its own Tx
tick, in a second Event Mode at the same time; its next step sees the same inputs as in the
direct composition. Only its very first Tx (at t0) is built before its first frames arrive.

``Network.wire_frames`` lists each CAN frame once, at its delivery; ``write_can_log`` writes them
to .blf/.asc with python-can, as the Real-wired benches' --can-log does.
"""
import contextlib
import ctypes
import math
from collections import defaultdict
from pathlib import Path

from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
# what an FMU declares (its terminals), the network's error; the CAN operations on the wire, for the log
from artibus.runner.lsbus_log import can_transmits, write_can_log  # noqa: F401
from artibus.runner.lsbus_terminals import (EPS, MEMBERS, NETWORK_TERMINAL, LsBusError, Terminal,  # noqa: F401
                                             check_mime, read_terminals)

CHANGED = 2          # fmi3IntervalChanged (FMI 3.0.2 headers, fmi3FunctionTypes.h)
MAX_ITERATIONS = 100  # event iterations per Event Mode before giving up


# ---- one FMU instance -----------------------------------------------------------------------

class Fmu:
    """An FMI 3.0 CS node or bus FMU of the network: artibus's FMU instance (artibus.fmu.Fmu)
    made with eventModeUsed, its Event Mode in the standard's call order (artibus.fmu.fmi3:
    ``mode`` 'event', 'updated' or 'step', ``need``, ``next_event``, ``n_events``), its bus
    terminals; a refused call an LsBusError naming the FMU."""

    def __init__(self, name, path, parameters=None, start_time=0.0):
        self.name, self.path = name, Path(path)
        if not self.path.is_file():
            raise LsBusError(f"{self.path}: no such FMU (FMU {name})")
        self.instance = None
        try:
            self._open(parameters, start_time)
        except BaseException as e:     # nothing left behind: the instance freed, its own copy removed
            self.close()
            if isinstance(e, (LsBusError, KeyboardInterrupt)):
                raise
            raise LsBusError(f"{self.path}: FMU {name}: {e}") from None

    def _open(self, parameters, start_time):
        from artibus.fmu.instance import Fmu as Instance, read_model
        md = read_model(str(self.path))
        if md.fmi != 3 or not md.coSimulation or not md.coSimulation.hasEventMode:
            raise LsBusError(f"{self.path}: FMU {self.name} is no FMI 3.0 Co-Simulation FMU with hasEventMode")
        self.md, self.vars = md, md.by_name
        self.terminals = read_terminals(self.path, md, self.name)
        # {vr: name} of every output clock (FMI 3.0.2, 2.2.9: the FMU activates it, read with
        # fmi3GetClock), and {vr: terminal} of those that are a terminal's Tx_Clock
        self.out_clocks = {v.valueReference: v.name for v in md.modelVariables
                           if v.type == "Clock" and v.causality == "output"}
        self.tx_out = {t.tx_clock: t for t in self.terminals.values() if t.tx_output}
        self.flagged = False        # its last fmi3DoStep returned eventHandlingNeeded
        self.instance = Instance(self.path, instance_name=self.name, event_mode=True)
        self.calls, self.fmu = self.instance.calls, self.instance.slave
        self.calls.enter_initialization(start_time)
        for key, value in (parameters or {}).items():
            self.set(key, value)
        self.calls.exit_initialization()        # in Event Mode now (FMI 3.0.2, 4.2.1: eventModeUsed)

    def close(self):
        if self.instance is not None:
            if getattr(self.fmu, "component", None):
                try:
                    self.fmu.terminate()
                except Exception:                 # an instance left in the error state
                    pass
            self.instance.close()
        self.instance = None

    @property
    def log(self):
        """The FMU's messages so far: (status, message), status 0 OK ... 4 Fatal"""
        return [(st, m) for st, _, m in self.calls.messages] if self.instance is not None else []

    def errors(self):
        """The FMU's error messages (status Error or Fatal) so far"""
        return [m for st, m in self.log if st >= 3]

    def var(self, name):
        if name not in self.vars:
            raise LsBusError(f"{self.path}: FMU {self.name} has no variable {name!r}")
        return self.vars[name]

    def set(self, name, value):
        v = self.var(name)
        if v.kind not in ("Real", "Integer", "Enumeration", "Boolean") or v.shape:
            raise LsBusError(f"{self.path}: {name} of FMU {self.name} is a {v.type}: set it through a terminal")
        self.calls.set([v], [bool(value) if v.kind == "Boolean" else float(value) if v.kind == "Real"
                             else int(value)])

    def get(self, name):
        v = self.var(name)
        if v.kind not in ("Real", "Integer", "Enumeration", "Boolean") or v.shape:
            raise LsBusError(f"{self.path}: {name} of FMU {self.name} is a {v.type}, not a number")
        return self.calls.get([v])[0]

    # -- the standard's call order (FMI 3.0.2, 5.2.2): artibus.fmu.fmi3's Event Mode
    mode = property(lambda self: self.calls.mode, lambda self, m: setattr(self.calls, "mode", m))
    need = property(lambda self: self.calls.need, lambda self, n: setattr(self.calls, "need", n))
    next_event = property(lambda self: self.calls.next_event, lambda self, t: setattr(self.calls, "next_event", t))
    n_events = property(lambda self: self.calls.n_events, lambda self, k: setattr(self.calls, "n_events", k))

    def fresh_event(self):
        """Event Mode with nothing set yet: from Step Mode, or a further Event Mode at the
        same time after an update that asked for no iteration."""
        self.calls.enter_event_mode()

    def set_clocks(self, vrs):
        with _as_lsbus_error():
            self.calls.set_clocks(vrs)

    def update(self):
        with _as_lsbus_error():
            return self.calls.update()

    def settle(self):
        """fmi3UpdateDiscreteStates until the FMU asks for no further iteration"""
        with _as_lsbus_error():
            self.calls.settle()

    def leave_event_mode(self):
        with _as_lsbus_error():
            self.calls.leave_event_mode()

    def active_output_clocks(self, t):
        """the terminals whose output Tx clock fmi3GetClock says active (in Event Mode, before
        the update: FMI 3.0.2, 2.2.9 and 2.3); an active output clock of no terminal stops the
        run, named with the node and the time: its clocked variables would go unread"""
        if not self.out_clocks:
            return []
        vrs = list(self.out_clocks)
        with _as_lsbus_error():
            flags = self.fmu.getClock(vrs)
        active = [vr for vr, on in zip(vrs, flags) if on]
        unknown = [vr for vr in active if vr not in self.tx_out]
        if unknown:
            raise LsBusError(f"t = {t:.6f} s: node {self.name}: output clock {self.out_clocks[unknown[0]]} "
                             f"(value reference {unknown[0]}) is active, but it is no Tx_Clock of a network "
                             f"terminal ({', '.join(self.terminals)}): this master does not know it and would "
                             "leave its clocked variables unread (FMI 3.0.2, 2.2.9)")
        return [self.tx_out[vr] for vr in active]

    def intervals(self, terminals):
        """{terminal: interval} of the countdown Tx clocks that announce a new interval"""
        if not terminals:
            return {}
        n = len(terminals)
        vrs = (ctypes.c_uint32 * n)(*[t.tx_clock for t in terminals])
        iv, q = (ctypes.c_double * n)(), (ctypes.c_int * n)()
        self.fmu.getIntervalDecimal(vrs, iv, q)
        return {t: iv[i] for i, t in enumerate(terminals) if q[i] == CHANGED}


@contextlib.contextmanager
def _as_lsbus_error():
    """artibus.fmu.fmi3's refusals as the network's LsBusError (the same message)"""
    try:
        yield
    except LsBusError:
        raise
    except ArtibusError as e:
        raise LsBusError(str(e)) from None


# ---- the master -------------------------------------------------------------------------------

class Network:
    """Nodes ({name: (fmu path, parameters)}, in their order within an instant), connected
    through a bus simulation FMU (bus=(path, parameters): the k-th node's terminal to the
    bus's k-th terminal) or, without bus, two nodes directly.

    run(stop_time, inputs, outputs): inputs(t) -> {node: {variable: value}} set at each of
    the node's ticks; outputs {node: [variables]} recorded after every step in
    self.results[node][variable], beside self.time. Every Tx_Data routed is in self.frames
    as (t, sender, receiver, terminal, bytes)."""

    def __init__(self, nodes, bus=None, start_time=0.0):
        if not bus and len(nodes) != 2:
            raise LsBusError(f"without a bus simulation FMU two nodes connect directly, not {len(nodes)}")
        self.t0 = self.t = float(start_time)
        self.nodes, self.bus = [], None
        try:               # a node that cannot be opened: the ones opened before it freed
            for name, (path, params) in nodes.items():
                once = [f for f in self.nodes if f.path == Path(path)
                        and f.md.coSimulation.canBeInstantiatedOnlyOncePerProcess]
                if once:           # (its instances would share the one library loaded: FMI 3.0 2.2.5)
                    raise LsBusError(f"{path}: FMU {name} and {once[0].name} are one FMU, which says "
                                     "canBeInstantiatedOnlyOncePerProcess=\"true\": one node of it per run")
                self.nodes.append(Fmu(name, path, params, start_time))
            self.bus = Fmu("bus", bus[0], bus[1], start_time) if bus else None
            self._connect()
        except BaseException:
            self.close()
            raise

    def _connect(self):
        self.by_name = {f.name: f for f in self.nodes}
        self.links = defaultdict(list)            # (fmu, terminal) -> [(fmu, terminal)]
        for f in self.nodes:
            if len(f.terminals) != 1:
                raise LsBusError(f"{f.path}: node {f.name} has {len(f.terminals)} network terminals; "
                                 "this master connects nodes of one terminal")
        if self.bus:
            bus_terms = list(self.bus.terminals.values())
            if len(self.nodes) > len(bus_terms):
                raise LsBusError(f"{self.bus.path}: {len(self.nodes)} nodes but the bus has "
                                 f"{len(bus_terms)} terminals")
            for f, bt in zip(self.nodes, bus_terms):
                (nt,) = f.terminals.values()
                self.links[(f, nt)].append((self.bus, bt))
                self.links[(self.bus, bt)].append((f, nt))
            self.countdown = [t for t in bus_terms if t.tx_kind == "countdown"]
            self.bus_ticks = {}                  # terminal -> time its countdown clock ticks
            self.bus_flagged = False
        else:
            (a, ta), (b, tb) = [(f, next(iter(f.terminals.values()))) for f in self.nodes]
            self.links[(a, ta)].append((b, tb))
            self.links[(b, tb)].append((a, ta))
        self.frames = []
        self.core_frames = None                   # the frames on the wire when the C core ran it (lsbus_core)
        self.time, self.results = [], {}
        self.n_instants = 0

    def wire_frames(self):
        """[(t, id, ide, data)] of each CAN frame once, at the time it reached its receivers
        (with a bus FMU its deliveries, without one the sender's Tx_Data); those the stepping
        core recorded (artibus.runner.lsbus_core) first"""
        seen, out = set(), list(self.core_frames or ())
        for t, src, dst, _, data in self.frames:
            if self.bus and src != self.bus.name:
                continue
            for frame in can_transmits(data):
                key = (t, src, frame)
                if key not in seen:
                    seen.add(key)
                    out.append((t, *frame))
        return out

    def close(self):
        for f in self.nodes + ([self.bus] if self.bus else []):
            f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- the bus simulation FMU
    def _bus_read_intervals(self):
        for term, iv in self.bus.intervals(self.countdown).items():
            self.bus_ticks[term] = self.t + iv

    def _bus_settle(self, pending):
        """In the bus's Event Mode: fmi3UpdateDiscreteStates, then the countdown Tx clocks due
        now in the further iterations it asks for; their Tx_Data routed to the nodes."""
        if self.bus.mode == "event":
            self.bus.update()
        for _ in range(MAX_ITERATIONS):
            self._bus_read_intervals()
            now = [t for t, tt in self.bus_ticks.items() if tt <= self.t + EPS]
            if not now or not self.bus.need:
                return
            for term in now:
                del self.bus_ticks[term]
            self.bus.set_clocks([term.tx_clock for term in now])
            self.bus.update()
            data = self.bus.fmu.getBinary([term.tx_data for term in now])
            for term, d in zip(now, data):
                self._route(self.bus, term, bytes(d), pending)
        raise LsBusError(f"FMU {self.bus.name} asked for further event iterations with clocks due at "
                         f"t = {self.t:g} s {MAX_ITERATIONS} times")

    def _bus_due(self, pending):
        """the bus's operations due at this instant (frames that end now)"""
        now = [t for t, tt in self.bus_ticks.items() if tt <= self.t + EPS]
        if not now and not self.bus_flagged:
            return
        self.bus_flagged = False
        self.bus.fresh_event()
        if self.bus.mode == "event":
            self._bus_read_intervals()             # announced by the step that ended here
            now = [t for t, tt in self.bus_ticks.items() if tt <= self.t + EPS]
        for term in now:
            del self.bus_ticks[term]
        self.bus.set_clocks([term.tx_clock for term in now])
        self.bus.update()
        data = self.bus.fmu.getBinary([term.tx_data for term in now]) if now else []
        for term, d in zip(now, data):
            self._route(self.bus, term, bytes(d), pending)
        self._bus_settle(pending)

    def _bus_send(self, batch, pending):
        """the nodes' Tx_Data of the instant into the bus's NodeK.Rx_Data, in one Event Mode"""
        terms = list(batch)
        self.bus.fresh_event()
        self.bus.set_clocks([term.rx_clock for term in terms])
        self.bus.fmu.setBinary([term.rx_data for term in terms], [batch[term] for term in terms])
        self._bus_settle(pending)

    # -- routing through the terminals
    def _route(self, src, term, data, pending, batch=None):
        """Tx_Data of (src, term) to every Rx_Data linked to it; zero-size data activate no
        clock (4____network_abstraction.adoc, "Rx Clocks")"""
        if not data:
            return
        for dst, dterm in self.links[(src, term)]:
            held = len(batch.get(dterm, b"")) if dst is self.bus else sum(map(len, pending.get((dst, dterm), ())))
            if dterm.rx_max is not None and held + len(data) > dterm.rx_max:
                raise LsBusError(f"t = {self.t:.6f} s: {'node ' if src is not self.bus else ''}{src.name}: "
                                 f"{term.name}.Tx_Data ({term.tx_name} active) has {len(data)} bytes, "
                                 f"{held + len(data)} with what the instant holds for {dst.name}'s "
                                 f"{dterm.name}.Rx_Data, over its maxSize {dterm.rx_max} (FMI 3.0.2, 2.4.7.6, "
                                 "Binary maxSize)")
            self.frames.append((self.t, src.name, dst.name, dterm.name, data))
            if dst is self.bus:
                batch[dterm] = batch.get(dterm, b"") + data
            else:
                pending[(dst, dterm)].append(data)

    def _node_event(self, f, ticking, rx, inputs):
        """one Event Mode of a node: Float64 inputs, clocks, Rx_Data, the output Tx clocks
        (fmi3GetClock), Tx_Data of the active Tx clocks read and copied while they are active,
        then fmi3UpdateDiscreteStates (while it asks): FMI 3.0.2, 2.2.8 ("Getting and Setting
        Variable Values": clocked variables only while their clock is active) and 2.3 (the update
        ends the activation)"""
        f.fresh_event()
        for name, value in inputs.items():
            f.set(name, value)
        f.set_clocks([t.tx_clock for t in ticking] + [t.rx_clock for t in rx])
        if rx:
            f.fmu.setBinary([t.rx_data for t in rx], list(rx.values()))
        sending = list(ticking) + [t for t in f.active_output_clocks(self.t) if t not in ticking]
        out = {}
        if sending:
            with _as_lsbus_error():
                data = f.fmu.getBinary([t.tx_data for t in sending])
            out = {t: bytes(d) for t, d in zip(sending, data)}
        try:
            f.settle()
        except LsBusError as e:       # bounded: a node that never leaves Event Mode, named with its clocks
            clocks = [t.tx_name for t in sending] + [f"{t.name}.Rx_Clock" for t in rx]
            raise LsBusError(f"t = {self.t:.6f} s: node {f.name} ({', '.join(clocks) or 'no clock'} active): "
                             f"{e}") from None
        return out

    def _instant(self, inputs):
        """every event at self.t, in the order of the module's docstring"""
        self.n_instants += 1
        pending, batch = defaultdict(list), {}
        if self.bus:
            self._bus_due(pending)
        values = inputs(self.t) if inputs else {}
        for f in self.nodes:
            ticking = [t for t in f.terminals.values() if t.ticks_at(self.t0, self.t)]
            rx = {t: b"".join(pending.pop((f, t))) for t in list(f.terminals.values()) if (f, t) in pending}
            # FMI 3.0.2, 4.2, fmi3EnterEventMode: Event Mode after an eventHandlingNeeded or at the
            # nextEventTime the node announced (a triggered output Tx clock's tick)
            woke = f.flagged or f.next_event <= self.t + EPS
            f.flagged = False
            if not ticking and not rx and not woke and f.mode != "event":
                continue
            out = self._node_event(f, ticking, rx, values.get(f.name, {})
                                   if ticking or woke or f.mode == "event" else {})
            for term, data in out.items():
                self._route(f, term, data, pending, batch)
        if batch:
            self._bus_send(batch, pending)
        for _ in range(MAX_ITERATIONS):           # data for nodes whose Event Mode was earlier
            if not pending:
                break
            (f, term), chunks = next(iter(pending.items()))
            del pending[(f, term)]
            self._node_event(f, [], {term: b"".join(chunks)}, {})
        else:
            raise LsBusError(f"t = {self.t}: the nodes keep sending in the same instant ({MAX_ITERATIONS} rounds)")
        if self.bus and self.bus.mode == "event":
            self._bus_settle(pending)

    def _next_point(self, stop_time):
        """the next bus communication point: a periodic Tx tick, a countdown tick of the bus,
        the bus's nextEventTime"""
        t_next = stop_time
        for f in self.nodes:
            for term in f.terminals.values():
                if term.period is not None:
                    t_next = min(t_next, term.next_tick(self.t0, self.t))
            if f.tx_out and self.t + EPS < f.next_event < t_next:    # a triggered Tx clock's next tick
                t_next = f.next_event
        if self.bus:
            t_next = min([t_next, self.bus.next_event if self.bus.next_event > self.t + EPS else math.inf]
                         + [tt for tt in self.bus_ticks.values() if tt > self.t + EPS])
        return t_next

    def _record(self, outputs):
        self.time.append(self.t)
        for name, names in outputs.items():
            f = self.by_name[name]
            rec = self.results.setdefault(name, {n: [] for n in names})
            for n in names:
                rec[n].append(f.get(n))

    def run(self, stop_time, inputs=None, outputs=None):
        """simulate from the current time to stop_time; an FMU's error is raised as an
        LsBusError with the time, the FMU and what its logger said"""
        try:
            return self._run(stop_time, inputs, outputs)
        except FMICallException as e:
            said = [(f.name, m) for f in self.nodes + ([self.bus] if self.bus else []) for m in f.errors()]
            why = f"; {said[-1][0]} said: {said[-1][1]}" if said else ""
            raise LsBusError(f"t = {self.t:.6f} s: {e}{why}") from None

    def advance(self, t_end, inputs=None, outputs=None):
        """the instant at the current time, then the steps to t_end (cut at the bus
        communication points, each with its instant); t_end's own instant is left to the next
        call (a master that ticks the network once per macro step, artibus.runner.lsbus_bench)"""
        try:
            everyone = self.nodes + ([self.bus] if self.bus else [])
            while True:
                self._instant(inputs)
                t_next = self._next_point(t_end)
                self._step_all(everyone, t_next)
                self._record(outputs or {})
                if self.t >= t_end - EPS:
                    return self
        except FMICallException as e:
            said = [(f.name, m) for f in self.nodes + ([self.bus] if self.bus else []) for m in f.errors()]
            why = f"; {said[-1][0]} said: {said[-1][1]}" if said else ""
            raise LsBusError(f"t = {self.t:.6f} s: {e}{why}") from None

    def _step_all(self, everyone, t_next):
        for f in everyone:
            f.leave_event_mode()
        for f in everyone:
            event_needed, terminate, _, _ = f.fmu.doStep(self.t, t_next - self.t)
            if terminate:
                raise LsBusError(f"FMU {f.name} asked to terminate the simulation at t = {t_next}")
            if f is self.bus and event_needed:
                self.bus_flagged = True
            elif event_needed:
                f.flagged = True
        self.t = t_next

    def _run(self, stop_time, inputs, outputs):
        outputs = outputs or {}
        for name in outputs:
            if name not in self.by_name:
                raise LsBusError(f"outputs: no node {name!r} (nodes: {', '.join(self.by_name)})")
        everyone = self.nodes + ([self.bus] if self.bus else [])
        while True:
            self._instant(inputs)
            if self.t >= stop_time - EPS:
                break
            self._step_all(everyone, self._next_point(stop_time))
            self._record(outputs)
        for f in everyone:
            f.leave_event_mode()
        return self
