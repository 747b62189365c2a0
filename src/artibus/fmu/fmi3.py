"""FMI 3.0 Co-Simulation, one instance (``Calls``): FMPy's FMU3Slave with the calls artibus
makes, by Variable (artibus.fmu.model): values of every FMI 3.0 type, arrays whole (nValues,
FMI 3.0 2.2.6.2: the sum of the variables' sizes), and Event Mode for any FMU that has it.

The calls follow FMI 3.0's state machine for Co-Simulation (section 4.2, "Co-Simulation
State Machine"): instantiate, enterInitializationMode, the values, exitInitializationMode,
then Step Mode, or Event Mode first when the instance was made with eventModeUsed (FMI 3.0
4.2.1, fmi3InstantiateCoSimulation); in Event Mode the clocks, then the inputs, then
fmi3UpdateDiscreteStates until it asks for no further iteration (FMI 3.0 5.2.2 and 3.2.5,
"Event Mode"), then fmi3EnterStepMode. fmi3DoStep says when the FMU ended the run itself
(terminateSimulation, with lastSuccessfulTime) and when an event needs Event Mode
(eventHandlingNeeded, honoured only with eventModeUsed: FMI 3.0 4.2.1)."""
import math

from fmpy.fmi3 import FMU3Slave

from artibus.base import ArtibusError

#: the get/set call of each FMI 3.0 type (an Enumeration is an fmi3Int64, FMI 3.0 2.2.3)
ACCESSOR = {"Float64": "Float64", "Float32": "Float32", "Int8": "Int8", "UInt8": "UInt8",
            "Int16": "Int16", "UInt16": "UInt16", "Int32": "Int32", "UInt32": "UInt32",
            "Int64": "Int64", "UInt64": "UInt64", "Enumeration": "Int64", "Boolean": "Boolean",
            "String": "String", "Binary": "Binary", "Clock": "Clock"}
#: event iterations (fmi3UpdateDiscreteStates asking for another) before an error
MAX_EVENT_ITERATIONS = 100
_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal"]


def logger(log, messages=None):
    """An fmi3LogMessageCallback appending "[status] category: message" to ``log`` and
    (status, category, message) to ``messages``."""
    from fmpy.fmi3 import fmi3LogMessageCallback

    def message(env, status, category, text):
        category, text = (category or b"").decode(errors="replace"), (text or b"").decode(errors="replace")
        log.append(f"[{_STATUS[status] if 0 <= status < len(_STATUS) else status}] {category}: {text}")
        if messages is not None:
            messages.append((status, category, text))
    return fmi3LogMessageCallback(message)


class Calls:
    """The FMI 3.0 calls of one Co-Simulation instance (``slave``: FMPy's FMU3Slave) and,
    with Event Mode, where it is: ``mode`` "step", "event" (before fmi3UpdateDiscreteStates)
    or "updated" (after it; ``need``: it asked for another iteration); ``next_event`` the
    nextEventTime of the last update (inf: none); ``on_event(t)``: None, or what handles an
    event a step met in place of handle_event's plain Event Mode (a lone FMU's clocks,
    artibus.fmu.simulate)."""
    fmi = 3

    def __init__(self, model, unzip_dir, instance_name):
        self.model, self.name = model, instance_name
        self.slave = FMU3Slave(guid=model.instantiationToken, unzipDirectory=unzip_dir,
                               modelIdentifier=model.coSimulation.modelIdentifier,
                               instanceName=instance_name)
        self.event_mode_used = False
        self.messages = []                 # (status, category, message) of each log message
        self.mode, self.need, self.next_event, self.n_events = "init", False, math.inf, 0
        self.on_event = None

    def instantiate(self, log, logging=False, event_mode=False):
        """fmi3InstantiateCoSimulation; with ``event_mode`` (eventModeUsed) the FMU's events
        are handled in Event Mode (an FMU without hasEventMode: refused by name)."""
        if event_mode and not self.model.coSimulation.hasEventMode:
            raise ArtibusError(f"{self.model.modelName} has no Event Mode (hasEventMode is false): "
                               "its clocks and events cannot be handled by the importer")
        self._logger = logger(log, self.messages)
        self.event_mode_used = bool(event_mode)
        self.slave.instantiate(loggingOn=logging, eventModeUsed=self.event_mode_used, logMessage=self._logger)

    def configure(self, variables, values):
        """The structural parameters ``variables`` set in Configuration Mode (FMI 3.0 2.3, "State:
        Configuration Mode": between instantiation and initialisation; the arrays they dimension
        resized at fmi3ExitConfigurationMode)."""
        self.slave.enterConfigurationMode()
        self.set(variables, values)
        self.slave.exitConfigurationMode()

    def enter_initialization(self, start_time=0.0, tolerance=None, stop_time=None):
        self.slave.enterInitializationMode(tolerance=tolerance, startTime=start_time, stopTime=stop_time)

    def exit_initialization(self):
        """fmi3ExitInitializationMode: into Event Mode with eventModeUsed, else Step Mode (FMI 3.0 4.2.1)"""
        self.slave.exitInitializationMode()
        self.mode, self.need = ("event", False) if self.event_mode_used else ("step", False)

    def set(self, variables, values):
        """Set each Variable to its value: a Python value, or for an array the sequence of its
        values in row-major order (FMI 3.0 2.2.6.2); one call per type."""
        for t, (vrs, flat) in _groups(variables, values).items():
            getattr(self.slave, f"set{t}")(vrs, flat)

    def get(self, variables):
        """The Variables' values as Python values (an array as a list of its ``size`` values,
        row-major), one call per type, each call's nValues the sum of the sizes."""
        out = [None] * len(variables)
        groups = {}
        for i, v in enumerate(variables):
            groups.setdefault(ACCESSOR[v.type], []).append((i, v))
        for t, items in groups.items():
            got = getattr(self.slave, f"get{t}")([v.valueReference for _, v in items],
                                                 sum(v.size for _, v in items))
            k = 0
            for i, v in items:
                chunk = [bool(x) if t == "Boolean" else x for x in got[k:k + v.size]]
                out[i] = chunk if v.shape else chunk[0]
                k += v.size
        return out

    def do_step(self, t, h):
        """One step from t to t + h: None, or the time where the FMU ended the run itself
        (terminateSimulation, FMI 3.0 4.2.1: lastSuccessfulTime). With Event Mode an event the
        step met (eventHandlingNeeded) is handled at once (``handle_event``)."""
        event, terminate, _, last = self.slave.doStep(t, h)
        if terminate:
            return last
        if event and self.event_mode_used:
            self.on_event(t + h) if self.on_event is not None else self.handle_event()
        return None

    def handle_event(self):
        """Event Mode from Step Mode, its iteration and back (FMI 3.0 5.2.2): for an event
        the FMU announced, with nothing for the importer to set."""
        self.enter_event_mode()
        self.leave_event_mode()

    # -- Event Mode (FMI 3.0 5.2.2, 3.2.5)
    def enter_event_mode(self):
        """A fresh Event Mode: from Step Mode, or again at the same time after an update
        that asked for no further iteration."""
        if self.mode == "updated" and not self.need:
            self.slave.enterStepMode()
            self.mode = "step"
        if self.mode == "step":
            self.slave.enterEventMode()
            self.mode, self.need = "event", False
            self.n_events += 1

    def set_clocks(self, vrs):
        """fmi3SetClock of the clocks ``vrs`` (ticking): in Event Mode, before the update that
        asks for no further iteration (FMI 3.0 5.2.2); refused, naming them, otherwise."""
        if not vrs:
            return
        if self.mode not in ("event", "updated"):
            raise ArtibusError(f"FMU {self.name}: fmi3SetClock in Step Mode (clocks tick in Event Mode, "
                               "FMI 3.0.2, 5.2.2)")
        if self.mode == "updated" and not self.need:
            names = [v.name for v in self.model.modelVariables if v.valueReference in vrs]
            raise ArtibusError(f"FMU {self.name}: fmi3SetClock({', '.join(names)}) after fmi3UpdateDiscreteStates, "
                               "which asked for no further event iteration: refused (FMI 3.0.2, 5.2.2: clocks, "
                               "then inputs, then fmi3UpdateDiscreteStates)")
        self.slave.setClock(list(vrs), [True] * len(vrs))

    def update(self):
        """fmi3UpdateDiscreteStates once: whether it asks for another iteration."""
        need, terminate, _, _, defined, t_next = self.slave.updateDiscreteStates()
        if terminate:
            raise ArtibusError(f"FMU {self.name} asked to terminate the simulation")
        self.mode, self.need = "updated", bool(need)
        self.next_event = t_next if defined else math.inf
        return self.need

    def settle(self):
        """fmi3UpdateDiscreteStates until the FMU asks for no further iteration (at most
        MAX_EVENT_ITERATIONS: an FMU that never settles is an error, not a hang)."""
        for _ in range(MAX_EVENT_ITERATIONS):
            if not self.update():
                return
        raise ArtibusError(f"FMU {self.name}: discreteStatesNeedUpdate after {MAX_EVENT_ITERATIONS} "
                           "event iterations")

    def leave_event_mode(self):
        """The iteration finished and fmi3EnterStepMode."""
        if self.mode != "step":
            if self.mode == "event":
                self.settle()
            self.slave.enterStepMode()
            self.mode = "step"

    def last_successful_time(self):
        """where a failed step stopped: the independent variable (the instance's time)"""
        return self.slave.getFloat64([self.model.time.valueReference])[0]

    def free(self):
        self.slave.freeInstance()


def _groups(variables, values):
    """{accessor: ([value references], [values, arrays flattened])}"""
    groups = {}
    for v, x in zip(variables, values):
        vrs, flat = groups.setdefault(ACCESSOR[v.type], ([], []))
        vrs.append(v.valueReference)
        if v.shape:
            xs = list(x)
            if len(xs) != v.size:
                raise ArtibusError(f"{v.name}: an array of {v.size} values "
                                   f"({'x'.join(map(str, v.shape))}), given {len(xs)}")
            flat.extend(xs)
        else:
            flat.append(x)
    return groups
