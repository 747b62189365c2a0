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
- in each Event Mode the calls go in the standard's order: the Float64 inputs, fmi3SetClock,
  fmi3SetBinary, fmi3UpdateDiscreteStates, repeated while discreteStatesNeedUpdate; a clock
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
import xml.etree.ElementTree as ET
import zipfile
from collections import defaultdict
from pathlib import Path

from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError

CHANGED = 2          # fmi3IntervalChanged (FMI 3.0.2 headers, fmi3FunctionTypes.h)
EPS = 1e-9           # s: two times this close are one instant
MAX_ITERATIONS = 100  # event iterations per Event Mode before giving up
NETWORK_TERMINAL = "org.fmi-ls-bus.network-terminal"
MEMBERS = ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock")


class LsBusError(ArtibusError):
    """A bad network, bad input or a refused call; the message names the FMU and the variable
    (an ArtibusError: the command line says it in one line, no traceback)."""


# the CAN operations on the wire, for the log (here as before)
from artibus.runner.lsbus_log import can_transmits, write_can_log  # noqa: E402,F401



# ---- what the FMU declares -----------------------------------------------------------------

class Terminal:
    """One bus terminal of an FMU: the value references of its four members and, for a
    time-based Tx clock, its period and shift."""

    def __init__(self, fmu_name, name, members, variables, clocks, max_sizes=None):
        self.name = name
        missing = [m for m in MEMBERS if m not in members]
        if missing:
            raise LsBusError(f"{fmu_name}: terminal {name} has no member {', '.join(missing)}")
        v = {m: variables[members[m]] for m in MEMBERS}
        self.rx_data, self.tx_data = v["Rx_Data"].valueReference, v["Tx_Data"].valueReference
        self.rx_clock, self.tx_clock = v["Rx_Clock"].valueReference, v["Tx_Clock"].valueReference
        tx = v["Tx_Clock"]
        self.tx_kind = tx.intervalVariability
        self.period = self.shift = None
        if self.tx_kind in ("constant", "fixed"):
            interval, shift = clocks.get(tx.name, (None, None))
            try:
                self.period, self.shift = float(interval), float(shift or 0.0)
            except (TypeError, ValueError):
                self.period = None
            if not self.period or self.period <= 0 or not math.isfinite(self.period):
                raise LsBusError(f"{fmu_name}: {tx.name} is {self.tx_kind} but has intervalDecimal="
                                 f"{interval!r}: no period to tick it with")
        elif self.tx_kind not in ("countdown", "triggered"):
            raise LsBusError(f"{fmu_name}: {tx.name} has intervalVariability={self.tx_kind!r}; "
                             "this master ticks constant, fixed, countdown and triggered clocks")
        self.tx_name = tx.name
        # Rx_Data's maxSize (FMI 3.0.2, 2.4.7.6, Binary: "maximal size of a value" in bytes), None: unbounded
        size = (max_sizes or {}).get(v["Rx_Data"].name)
        self.rx_max = int(size) if size and size.isdigit() else None

    def next_tick(self, t0, t):
        """the first tick of a periodic Tx clock after the instant t, i.e. later than t + EPS
        (ticks at t0 + shift + k period), the same instants as ticks_at"""
        k = math.floor((t + EPS - t0 - self.shift) / self.period) + 1
        return t0 + self.shift + max(k, 0) * self.period

    def ticks_at(self, t0, t):
        if self.period is None:
            return False
        k = round((t - t0 - self.shift) / self.period)
        return k >= 0 and abs(t0 + self.shift + k * self.period - t) <= EPS


from artibus.bench.ssp2 import CAN_MIME_TYPE as CAN_MIME, is_can_mime   # noqa: E402 (one definition)


def check_mime(path, name, mime):
    """A terminal's Rx_Data/Tx_Data carries CAN operations of FMI-LS-BUS 1.x: the MIME type
    application/org.fmi-standard.fmi-ls-bus.can with a version parameter of major version 1
    (fmi-ls-bus v1.0.0 4____network_abstraction.adoc, "MIME Types": the version marks the set
    of operations and follows semantic versioning, so 1.x keeps 1.0.0's operations). A
    pre-release of it is taken too: the fmi-ls-bus-examples declare version="1.0.0-beta.1",
    and their headers (fmi-ls-bus 468127f) lay out every CAN operation as v1.0.0's do.
    Anything else (another bus, version 2, no version) is an LsBusError naming it."""
    if not is_can_mime(mime):
        raise LsBusError(f"{path}: {name} has mimeType {mime!r}; this master connects FMI-LS-BUS CAN "
                         f'terminals: {CAN_MIME}; version="1.x.y" (1.0.0 or a pre-release of it)')


def read_terminals(path, md, fmu_name):
    """{name: Terminal} of the network terminals in terminalsAndIcons/terminalsAndIcons.xml
    (FMI 3.0.2, 2.4.9; the terminal kind of 4____network_abstraction.adoc, "Bus Terminal")."""
    with zipfile.ZipFile(path) as z:
        try:
            root = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        except KeyError:
            raise LsBusError(f"{path}: no terminalsAndIcons/terminalsAndIcons.xml: not an LS-BUS FMU") from None
        # the clocks' intervalDecimal and shiftDecimal, the binaries' mimeType (FMPy 0.3 reads neither)
        md_root = ET.fromstring(z.read("modelDescription.xml"))
        clocks = {c.get("name"): (c.get("intervalDecimal"), c.get("shiftDecimal")) for c in md_root.iter("Clock")}
        mimes = {b.get("name"): b.get("mimeType") for b in md_root.iter("Binary")}
        sizes = {b.get("name"): b.get("maxSize") for b in md_root.iter("Binary")}
    variables = {v.name: v for v in md.modelVariables}
    out = {}
    for t in root.iter("Terminal"):
        if t.get("terminalKind") != NETWORK_TERMINAL:
            continue
        members = {m.get("memberName"): m.get("variableName") for m in t.findall("TerminalMemberVariable")}
        for m, name in members.items():
            if name not in variables:
                raise LsBusError(f"{path}: terminal {t.get('name')} member {m} names {name!r}, "
                                 "which modelDescription.xml does not declare")
        for m in ("Rx_Data", "Tx_Data"):
            if m in members:
                check_mime(path, members[m], mimes.get(members[m]))
        out[t.get("name")] = Terminal(fmu_name, t.get("name"), members, variables, clocks, sizes)
    if not out:
        raise LsBusError(f"{path}: terminalsAndIcons.xml has no terminal of kind {NETWORK_TERMINAL}")
    return out


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
        """one Event Mode of a node: Float64 inputs, clocks, Rx_Data, fmi3UpdateDiscreteStates
        (while it asks), Tx_Data copied"""
        f.fresh_event()
        for name, value in inputs.items():
            f.set(name, value)
        f.set_clocks([t.tx_clock for t in ticking] + [t.rx_clock for t in rx])
        if rx:
            f.fmu.setBinary([t.rx_data for t in rx], list(rx.values()))
        try:
            f.settle()
        except LsBusError as e:       # bounded: a node that never leaves Event Mode, named with its clocks
            clocks = [t.tx_name for t in ticking] + [f"{t.name}.Rx_Clock" for t in rx]
            raise LsBusError(f"t = {self.t:.6f} s: node {f.name} ({', '.join(clocks) or 'no clock'} active): "
                             f"{e}") from None
        if not ticking:
            return {}
        out = f.fmu.getBinary([t.tx_data for t in ticking])
        return {t: bytes(d) for t, d in zip(ticking, out)}

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
            if not ticking and not rx and f.mode != "event":
                continue
            out = self._node_event(f, ticking, rx, values.get(f.name, {}) if ticking or f.mode == "event" else {})
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
