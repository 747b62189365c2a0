"""A bench whose steering network runs as FMI-LS-BUS 1.0 FMUs (issue 24): the plant stays
the runner's FMI 2.0 or 3.0 components, the network is an artibus.runner.lsbus.Network ticked once
per network period by the runner, through the interface of artibus.can.network.Network
(start, tick, finish, settle, since_series, close): by the one stepping loop, in Python
(its callback, artibus.runner.core._Hooks) or in C (below);
Simulation attaches it to every SSP 2.0 bench with FMI-LS-BUS components, as below.

The bench is an SSP 2.0 system structure (artibus.bench.ssp2): the LS-BUS FMUs are its
components with ssc:Binary/ssc:Clock connectors, each node's terminal its four connections to a
terminal of the bus simulation FMU (CanBus), the Real signals between the plant and the nodes
ordinary connections, the nodes' and the bus's parameters inline parameter bindings::

    <ssd:Component name="ECU1" source="resources/fmi3/SteeringECU_LSBUS.fmu" ...>
      <ssd:Connector name="SteeringCAN.Tx_Data" kind="output"><ssc:Binary mime-type="...can; version=&quot;1.0.0&quot;"/>...
    <ssd:Connection startElement="ECU1" startConnector="SteeringCAN.Tx_Data" endElement="CanBus" endConnector="Node2.Rx_Data"/>
    <ssd:Connection startElement="Bus" startConnector="vx[1]" endElement="ECU1" endConnector="vVehicle"/>

artibus.bench.ssp reads the rest (the plant) as it reads an SSP 1.0 bench; the network here is
read from those components and connections (artibus.bench.ssp2.read_network): the period is the
nodes' Tx_Clock interval, wireTime the bus's binding (or its FMU's default).
Nodes in the order of their instant (artibus.runner.lsbus), the k-th node on the bus's k-th
terminal (nNodes = the number of nodes). The sources are packed in the .ssp (artibus pack
packs every ``source``) and run from its unpacked copy. What each tick k at time t does, as the Real-wired
bench's CAN tick (artibus.can.network: the frames from the senders' outputs of the step
before, delivered before the receivers step):

1. the Inputs: the plant's outputs (or another node's) at t, set at the nodes' Tx ticks of t;
2. the network's instant at t and its steps to t + period (lsbus.Network.advance);
3. the Outputs: the nodes' outputs at t + period, fed to the plant's inputs (as stimuli on
   their start values) for its steps from t, as the Real-wired actuators' outputs reach
   the plant in the same macro step (Gauss-Seidel, the actuators before the plant).

The C stepping core ticks the network in C where the Python master would tick, the same calls in
the same order (artibus.runner.lsbus_core, src/runner_core/lsbus.c), unless the core is
switched off (ARTIBUS_CORE=0).
"""
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError
from artibus.bench import ssp2
from artibus.runner.lsbus import Network, write_can_log


def read_spec(path, label=None):
    """the parsed SSP 2.0 .ssd at path (label: how messages name it) when its System has
    FMI-LS-BUS components (artibus.bench.ssp2.lsbus_components), else None"""
    try:
        root = etree.fromstring(Path(path).read_bytes())
    except etree.XMLSyntaxError as e:
        raise ArtibusError(f"{label or path}: not well-formed XML: {e}") from None
    return root if ssp2.lsbus_components(root) else None


def _fmu(ssd, root, component):
    source = component.get("source")
    path = Path(root) / (source or "")
    if not source or not path.is_file():
        raise ArtibusError(f"{ssd}:{component.sourceline}: <Component name=\"{component.get('name')}\" "
                           f"source=\"{source}\">: no such file in the .ssp")
    return path


class LsBusSteering:
    """The LS-BUS network of a bench, with the runner's CAN-network interface."""

    def __init__(self, ssd, root, wire_time=None):
        """ssd: the .ssd (its label in messages, or inside its .ssp); root: the unpacked .ssp"""
        el = read_spec(Path(root) / "SystemStructure.ssd", ssd)
        if el is None:
            raise ArtibusError(f"{ssd}: no FMI-LS-BUS components (SSP 2.0, ssc:Binary/ssc:Clock connectors)")
        self.ssd = ssd
        net = ssp2.read_network(el, ssd, lambda c: _fmu(ssd, root, c))
        self.period = net.period
        bus, source, params = net.bus
        self.wire_time = bool(params["wireTime"]) if wire_time is None else bool(wire_time)
        self.nodes = {name: (Path(root) / src, p) for name, (src, p) in net.nodes.items()}
        self.bus_path = Path(root) / source
        self.inputs, self.outputs = net.inputs, net.outputs
        self.value = {to: 0.0 for _, _, to in self.outputs}   # the plant inputs, as of the last tick
        self.base = {}
        self.net = None
        self.log = None        # a .blf or .asc file for the frames on the wire (Simulation's can_log)
        self.log_error = None  # why it could not be written (finish)
        self.ticks = 0
        self.wall = 0.0        # s of the network in the C core's ticks (artibus.runner.lsbus_core)
        self.fmu_wall = 0.0    # of which inside its FMUs' calls

    def stimuli(self):
        """{"Comp.input": f(t)} for Simulation: the network's outputs onto the plant's inputs"""
        self.stimulus_functions = {to: (lambda t, to=to: self.value[to] - self.base.get(to, 0.0))
                                   for _, _, to in self.outputs}
        return dict(self.stimulus_functions)

    def bind(self, sim):
        """attach to a Simulation made with stimuli(): the plant's output buffers to read"""
        units = {u.path: u for u in sim.units}
        self.src = []
        for node, var, frm in self.inputs:
            comp, _, name = frm.partition(".")
            if comp in self.nodes:               # another node's output, as of the tick (read in tick)
                self.src.append((node, var, comp, name))
                continue
            if comp not in units or name not in units[comp].out_names:
                raise ArtibusError(f"{self.ssd}: the connection from {frm} to {node}.{var}: {frm} is not an output "
                                   "of the bench's components")
            u = units[comp]
            self.src.append((node, var, u.raw.out, u.column(name)))
        for u in sim.units:
            for i, _, base in u.stimuli:
                key = f"{u.path}.{u.in_names[i]}"
                if key in self.value:
                    self.base[key] = base or 0.0
        r = self.period / sim.base_step
        if abs(r - round(r)) > 1e-9 or round(r) < 1:
            raise ArtibusError(f"{self.ssd}: the LS-BUS period {self.period} s is not a multiple of the base step "
                               f"{sim.base_step} s")
        if sim.can is not None:
            raise ArtibusError(f"{self.ssd}: a bench with both an org.artibus.can and an FMI-LS-BUS network")
        sim.lsbus, sim.lsbus_ratio = self, int(round(r))
        # the network's FMUs instantiated now, as the bench's other FMUs are in the Simulation's
        # set-up, for a run from the bench's start time (start takes it; another start time: anew)
        self._ready = self._network(sim.bench.start_time)

    # -- the runner's CAN-network interface (artibus.can.network.Network)
    def settle(self):
        """the initialisation's rounds: the nodes initialise in their own Initialization Mode"""

    def core_support(self):
        """why the C stepping core does not run this bench (artibus.runner.core._core_stepper),
        None when it does: it ticks the network as tick does (artibus.runner.lsbus_core,
        src/runner_core/lsbus.c): the nodes' inputs and outputs Float64, at most 64 terminals
        an FMU (checked on the network bind made; without it, as the run begins)"""
        net = self.net or getattr(self, "_ready", None)
        if net is None:
            return None
        for node, var, *_ in self.inputs + self.outputs:
            t = net.by_name[node].var(var).type
            if t != "Float64":
                return f"an FMI-LS-BUS node's {t} variable ({node}.{var}; the core sets and reads Float64)"
        for f in net.nodes + [net.bus]:
            if len(f.terminals) > 64:
                return f"an FMI-LS-BUS FMU of {len(f.terminals)} terminals ({f.name}; the core takes 64)"
            if set(f.out_clocks) - set(f.tx_out):     # refused by name in Python (Fmu.active_output_clocks)
                return f"an FMI-LS-BUS FMU with an output clock of no network terminal ({f.name})"
        return None

    def core_values(self, fill=True):
        """(a c_double array of the outputs' values, {to: its index}): what the stimuli read in
        the C core (artibus.runner.lsbus_core), filled from self.value (fill)"""
        if getattr(self, "_core_values", None) is None:
            from ctypes import c_double
            slots = {to: i for i, to in enumerate(self.value)}
            self._core_values = ((c_double * max(1, len(slots)))(), slots)
        values, slots = self._core_values
        for to, i in slots.items() if fill else ():
            values[i] = self.value[to]
        return self._core_values

    def set_faults(self, faults):
        """--can-fault: the faults CanBus injects (artibus.runner.lsbus_faults), before bind"""
        from artibus.runner.lsbus_faults import bus_fault_parameters
        self.fault_parameters = bus_fault_parameters(faults, self.nodes, self.ssd)

    def _network(self, t0):
        bus = {"nNodes": len(self.nodes), "wireTime": self.wire_time, **getattr(self, "fault_parameters", {})}
        return Network(self.nodes, bus=(self.bus_path, bus), start_time=t0)

    def start(self, t0):
        ready, self._ready = getattr(self, "_ready", None), None
        self.close()
        if ready is not None and ready.t0 == float(t0):
            self.net = ready
        else:
            if ready is not None:
                ready.close()
            self.net = self._network(t0)

    def tick(self, k, t):
        self.ticks += 1
        values = {}
        for node, var, out, j in self.src:
            values.setdefault(node, {})[var] = self.net.by_name[out].get(j) if isinstance(out, str) else out[j]
        self.net.advance(t + self.period, lambda _t: values)
        for node, var, to in self.outputs:
            self.value[to] = self.net.by_name[node].get(var)

    def finish(self):
        """The frames into the --can-log; a write that fails (a full disk) is kept in
        ``log_error``, said after the run's results are saved (artibus.runner.Simulation)."""
        if self.log is not None:
            try:
                write_can_log(self.net.wire_frames(), self.log)
            except OSError as e:
                self.log_error = (f"--can-log {self.log}: cannot write the log: {e.strerror or e}; "
                                  f"no log written (the run's other outputs are complete)")

    def summary(self, duration):
        """what the run's log prints of the network (artibus.report.runs), as the CAN network's summary"""
        net = self.net
        frames = net.wire_frames()
        ids = {}
        for _, can_id, _, _ in frames:
            ids[can_id] = ids.get(can_id, 0) + 1
        per_id = ", ".join(f"0x{i:03X} {n}" for i, n in sorted(ids.items()))
        events = ", ".join(f"{f.name} {f.n_events}" for f in net.nodes + [net.bus])
        log = "" if self.log is None else \
            f"\n    log: {self.log}" + (" (not written: a write failed)" if self.log_error else "")
        return (f"FMI-LS-BUS ({self.bus_path.name}, wireTime {'on' if self.wire_time else 'off'}): {len(frames)} frames "
                f"in {duration:g} s, bus load {100 * net.bus.get('busLoad'):.1f} % ({per_id}); Event Mode entries: {events}"
                + log)

    def since_series(self):
        return {}

    def close(self):
        for net in (self.net, getattr(self, "_ready", None)):
            if net is not None:
                net.close()
        self.net = self._ready = None

