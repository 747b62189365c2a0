"""Run one FMU on its own: parameters in, input functions of time, outputs
recorded at every communication point. If the FMU fails midway the result up
to the failure is kept and handed over with the error and the FMU's log. An
FMU that ends the simulation itself (fmi2Discard with fmi2Terminated, as the
Reference-FMUs' Stair does at t = 9 s) ends the run there as a normal end:
the result up to its last successful time, with ``Result.terminated``. A clocked FMI 3.0
FMU runs with Event Mode, its time-based input Clocks activated when they are due
(artibus.fmu.clocks; _event)."""
from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
from artibus.bench.units import unit_of
from artibus.fmu.instance import Fmu, claim_logger_proxy
from artibus.fmu.model import NOT_NUMBERS
from artibus.fmu.result import Result, SimulationError, Termination, terminated


#: a default experiment without stepSize (FMI 2.0 allows it): this many steps
#: from start to stop
DEFAULT_STEPS = 500
#: a default experiment without stopTime: FMPy's default stop time
DEFAULT_STOP_TIME = 1.0


def default_step(md, start_time, stop_time):
    """The FMU's default experiment's stepSize, else (stop - start) / DEFAULT_STEPS."""
    de = md.defaultExperiment
    if de is not None and de.stepSize:
        return float(de.stepSize)
    return (stop_time - start_time) / DEFAULT_STEPS


def check_times(start_time, stop_time, step, where):
    """A finite start and stop time, stop after start, a finite step > 0 that
    fits into the span at least once: else ArtibusError naming the value."""
    import math
    for label, x in (("start time", start_time), ("stop time", stop_time), ("step", step)):
        if x is not None and not math.isfinite(x):
            raise ArtibusError(f"{where}: {label} = {x} is not a finite number of seconds")
    if not stop_time > start_time:
        raise ArtibusError(f"{where}: stop time {stop_time:g} s must be after the start time {start_time:g} s")
    if step is not None and not step > 0:
        raise ArtibusError(f"{where}: step = {step:g} s must be > 0")


#: the most communication steps one run takes: beyond, t = start + i step is no longer exact in
#: a double (2**53) and the run would never end
MAX_STEPS = 2 ** 53


def step_count(start_time, stop_time, step, where):
    """The number of steps from start to stop, (stop - start) / step rounded; ArtibusError
    naming it where it is no number (1e300 s in steps of 1e-300 s: infinite) -- before
    anything runs. (Then check_room, then check_steps.)"""
    import math
    n = (stop_time - start_time) / step
    if not math.isfinite(n):
        raise ArtibusError(f"{where}: (stop - start) / step = ({stop_time:g} - {start_time:g}) / {step:g} = "
                           f"{n:g} steps, more than a run can take ({MAX_STEPS:g}): give a larger --step "
                           f"or a shorter --stop-time")
    return max(int(round(n)), 0)


def check_steps(n, where):
    """More than MAX_STEPS steps (a table that fits, where the memory is not known):
    ArtibusError naming the count, before anything runs."""
    if n > MAX_STEPS:
        raise ArtibusError(f"{where}: {n:g} steps, more than a run can take ({MAX_STEPS:g}): give a larger "
                           f"--step or a shorter --stop-time")


def needs_event_mode(path):
    """Whether an FMU runs with Event Mode (FMI 3.0 eventModeUsed): an FMI 3.0 FMU with
    hasEventMode and clocks (FMI 3.0 5.2.2: clocks tick in Event Mode only); without clocks the
    FMU handles its events within its steps (FMI 3.0 4.2.1, eventModeUsed = false)."""
    from artibus.fmu.instance import read_model
    try:
        md = read_model(str(path))
    except ArtibusError:
        return False                     # (Fmu names why it cannot be read)
    return bool(md.fmi == 3 and md.coSimulation is not None and md.coSimulation.hasEventMode
                and any(v.kind == "Clock" for v in md.modelVariables))


#: the kinds recorded as text (Result.strings): a String as it is, a Binary as hex digits
TEXTS = ("String", "Binary")
#: the types whose values a float64 does not hold exactly (FMI 3.0's 64-bit integers): recorded
#: also as integers (Result.integers), as FMPy's simulate_fmu keeps them (an int64/uint64 field)
WIDE = ("Int64", "UInt64")


def _row(values, kinds):
    """A recorded row as floats: a Boolean as 0/1, an Integer or Enumeration
    as its number, a String or Binary as NaN (its text goes to Result.strings), a
    value not read (a clocked variable whose Clock is inactive) as NaN."""
    return [float("nan") if k in TEXTS or x is None else float(x) for x, k in zip(values, kinds)]


def _text(x, kind):
    """A String's or Binary's (hex digits) text; "" for a value not read."""
    if x is None:
        return ""
    return x.hex() if kind == "Binary" else x


def simulate(path, parameters=None, inputs=None, stop_time=None, step=None,
             outputs=None, start_time=0.0, output_interval=None, tolerance=None, logging=False,
             messages=None, events=(), interface="cs", me_method="bdf", me_jacobian=False, on_result=None):
    """Simulate one FMU (FMI 2.0 or 3.0, Co-Simulation or Model Exchange).

    parameters: {name: value} set in initialization mode (checked against
    each variable's type, see artibus.bench.parameters.coerce).
    inputs: {name: f(t)} evaluated at each communication point (held over the step).
    outputs: names to record, of any type (default: every output but Binary and Clock ones;
    a Binary asked for is recorded as hex text, a clocked variable only at its Clock's ticks).
    Without stop_time/step: the default experiment's, else DEFAULT_STOP_TIME
    and (stop - start) / DEFAULT_STEPS. output_interval: the results every so many
    seconds, a whole number of steps (without step: the step, as FMPy's simulate_fmu
    takes it in Co-Simulation). tolerance: the relative tolerance the FMU is told
    (fmi2SetupExperiment, fmi3EnterInitializationMode). logging: the FMU's loggingOn;
    messages: a list the FMU's log messages are added to when the run ends, however.
    interface: "cs" (Co-Simulation) or "me" (Model Exchange: the FMU integrated between the
    communication points with CVODE, its events handled, artibus.fmu.me; me_method "bdf" or
    "adams", CVODE's method; me_jacobian: CVODE's Jacobian from the FMU's directional derivatives).
    events: times the inputs jump (artibus.fmu.inputs.InputTable.events): the steps are cut
    there and the point recorded, where the FMU takes a variable communication step
    (canHandleVariableCommunicationStepSize), as FMPy's simulate_fmu does.
    on_result: called with the Result and the model's name before the first row is recorded
    (artibus.fmu.isolated: its rows written as they come).
    Returns a Result; raises SimulationError (with the partial Result) on failure.
    Ctrl-C or SIGTERM (KeyboardInterrupt) ends it between two steps, the rows so
    far in ``e.result``: each doStep returns in bounded time (the FMUs refuse a
    step longer than their limit, docs/developer/fmi-layer.md).
    """
    parameters = dict(parameters or {})
    inputs = inputs or {}
    me = interface == "me"           # Model Exchange: integrated by the ME facade (artibus.fmu.me)
    event_mode = not me and needs_event_mode(path)
    with Fmu(path, event_mode=event_mode, logging=logging, interface=interface) as fmu:
        claim_logger_proxy()
        fmu.configure({n: parameters.pop(n) for n in list(parameters)       # (FMI 3.0: they size arrays)
                       if n in fmu.vars and fmu.vars[n].causality == "structuralParameter"})
        if step is None and output_interval is not None:
            step = output_interval
        stop_time, step = _experiment(fmu, start_time, stop_time, step, path)
        every = _every(output_interval, step, path)
        variables = _recorded(fmu, outputs, path)
        from artibus.runner.results import check_room      # as `run` does: refused before it starts
        n = step_count(start_time, stop_time, step, path)
        check_room(n + 1, sum(v.size for v in variables) + 1, path)
        check_steps(n, path)
        result, record = _recorder(fmu, variables)
        if on_result is not None:
            on_result(result, fmu.md.modelName)
        clocks = _schedule(fmu, path) if event_mode else None
        if me:                           # CVODE's method; no input changes: CVODE steps freely
            fmu.calls.facade.use_method(me_method)
            if me_jacobian:              # refused by the facade where the FMU provides none: named here
                try:
                    fmu.calls.facade.use_jacobian()
                except ArtibusError as e:
                    raise ArtibusError(f"{path}: --me-jacobian: {e}") from None
            if not inputs:
                fmu.calls.facade.free_running()
        try:
            fmu.calls.enter_initialization(start_time, tolerance=tolerance)
            fmu.set_values(parameters)
            fmu.set_values({n: f(start_time) for n, f in inputs.items()})
            if clocks is not None:
                clocks.start(start_time)        # (intervals asked in Initialization Mode, FMI 3.0 2.2)
            fmu.calls.exit_initialization()
            if clocks is not None:              # eventModeUsed: Event Mode first (FMI 3.0 4.2.1)
                _event(fmu, clocks, start_time, record, asked=True)
            else:
                record(start_time)
            cut = events if me or fmu.md.coSimulation.canHandleVariableCommunicationStepSize else ()
            _steps(fmu, n, start_time, step, inputs, record, result, every, [e for e in cut if e < stop_time],
                   clocks)
        except KeyboardInterrupt as e:   # Ctrl-C or SIGTERM (artibus.cli): the rows so far go with it
            side = [*result.strings.values(), *result.integers.values()]
            n_rows = min([len(result.rows)] + [len(c) for c in side])
            del result.rows[n_rows:]     # (a row whose texts or integers were not all taken)
            for c in side:
                del c[n_rows:]
            e.result = result
            raise
        except FMICallException:
            raise _failure(fmu, result, record, path, start_time) from None
        finally:
            if messages is not None:
                messages.extend(fmu.log)
        return result


def _every(output_interval, step, path):
    """The number of steps between two recorded points (1 without output_interval)."""
    if output_interval is None:
        return 1
    k = round(output_interval / step)
    if not (output_interval > 0 and k >= 1 and abs(k * step - output_interval) <= 1e-9 * output_interval):
        raise ArtibusError(f"{path}: output interval {output_interval:g} s is not a whole number of "
                           f"steps of {step:g} s")
    return k


def _experiment(fmu, start_time, stop_time, step, path):
    """(stop time, step): the given ones, else the default experiment's, else
    DEFAULT_STOP_TIME and (stop - start) / DEFAULT_STEPS; checked."""
    de = fmu.md.defaultExperiment
    if stop_time is None:
        stop_time = float(de.stopTime) if de is not None and de.stopTime else DEFAULT_STOP_TIME
    check_times(start_time, stop_time, step, path)
    if step is None:
        step = default_step(fmu.md, start_time, stop_time)
        check_times(start_time, stop_time, step, f"{path}: default experiment")
    return stop_time, step


def _recorded(fmu, outputs, path):
    """The recorded Variables: those asked for, else every output but the Binary and Clock ones
    (no numbers: a Binary asked for is recorded as hex text; a Clock is refused, its ticks are
    not values)."""
    if outputs is None:
        return [v for v in fmu.md.modelVariables if v.causality == "output" and v.kind not in NOT_NUMBERS]
    variables = [fmu.var(n) for n in outputs]
    for v in variables:
        if v.kind == "Clock":
            raise ArtibusError(f"{path}: {v.name} is an FMI 3.0 Clock: not a value a result table can hold")
    return variables


def _clocks_of(v):
    """The value references of the Clocks of a clocked variable (FMI 3.0 attribute clocks), else empty"""
    return frozenset(c.valueReference for c in (getattr(v, "clocks", None) or ()))


def columns(v):
    """The result's column names of the Variable ``v``: its name, or for an array one column
    per element in row-major order, named as FMI 3.0's structured naming convention writes
    an element (2.4.7.6 and 2.3.1: ``x[1,2]``, 1-based)."""
    if not v.shape:
        return [v.name]
    import itertools
    return [f"{v.name}[{','.join(str(i + 1) for i in k)}]" for k in itertools.product(*map(range, v.shape))]


def _recorder(fmu, variables):
    """(the Result, record(t, active): a row of the variables' values at t, an array's elements
    in columns of their own, Strings and Binaries in Result.strings, an Int64's or UInt64's exact
    value also in Result.integers (a float64 holds 53 bits); a clocked variable read
    only while one of its Clocks is among the ``active`` ones (FMI 3.0 2.2, "Model Partitions
    and Clocked Variables": "can be queried only when their Clock is active"), else NaN/"")."""
    names = [c for v in variables for c in columns(v)]
    result = Result(["time"] + names)
    strings = [c for v in variables if v.kind in TEXTS for c in columns(v)]
    result.strings = {c: [] for c in strings}
    result.integers = {c: [] for v in variables if v.type in WIDE for c in columns(v)}
    result.units = {"time": "s", **{c: unit_of(v) for v in variables for c in columns(v)}}
    result.descriptions = {"time": "simulation time",
                           **{c: getattr(v, "description", None) or "" for v in variables for c in columns(v)}}
    kinds = [v.kind for v in variables for _ in columns(v)]
    clocked = [_clocks_of(v) for v in variables]

    def record(t, active=()):
        readable = [v for v, c in zip(variables, clocked) if not c or c & set(active)]
        got = dict(zip(map(id, readable), fmu.calls.get(readable) if readable else ()))
        values = [got.get(id(v)) for v in variables]
        flat = [x for v, x in zip(variables, values)
                for x in ((x if x is not None else [None] * v.size) if v.shape else [x])]
        for c, x, kind in zip(names, flat, kinds):      # (before the row: artibus.fmu.isolated
            if kind in TEXTS:                           # writes them with it)
                result.strings[c].append(_text(x, kind))
            elif c in result.integers:
                result.integers[c].append(None if x is None else int(x))
        result.rows.append([t] + _row(flat, kinds))
    return result, record


def _points(start_time, step, n, events, ticks=None):
    """(t, i, kind) of each communication point: the regular ones start + (i + 1) step (kind
    "step"), and between them the input events (i None, kind "event"; one within 1e-9 relative
    of a regular point is that point, as FMPy's simulate_fmu takes it) and the Clocks' ticks
    (kind "tick"; ``ticks()``: the next one's time, asked again after each point is taken)."""
    import math
    ev = sorted(e for e in events if e > start_time)
    k, last = 0, start_time
    for i in range(n):
        t = start_time + (i + 1) * step
        while True:
            while k < len(ev) and (ev[k] < last or math.isclose(ev[k], last)):
                k += 1
            e = ev[k] if k < len(ev) else math.inf
            c = ticks() if ticks is not None else math.inf
            c = math.inf if c < last or math.isclose(c, last) else c      # (one at a point: taken there)
            x = min(e, c)
            if not x < t or math.isclose(x, t):
                break
            yield x, None, "event" if x == e else "tick"
            last = x
        yield t, i, "step"
        last = t


def _steps(fmu, n, start_time, step, inputs, record, result, every=1, events=(), clocks=None):
    """n steps from start_time (cut at the input ``events`` and at the ``clocks``' ticks: a
    Schedule, artibus.fmu.clocks), each recorded (every ``every``-th regular one, each input
    event), the inputs set after it (at a tick: in its Event Mode, _event); an FMU's own end
    (FMI 3.0 terminateSimulation, FMI 2.0 fmi2Discard with fmi2Terminated) ends them with
    Result.terminated, its values at its last successful time recorded (getters are
    allowed after fmi2Discard), as FMPy's simulate_fmu records them."""
    from artibus.runner.markers import PIECE, mark
    t = start_time

    def set_inputs(t):
        fmu.set_values({n_: f(t) for n_, f in inputs.items()})
    asked = []                    # an event a step meets (eventHandlingNeeded): handled after the step
    if clocks is not None:
        fmu.calls.on_event = asked.append
    for t_next, i, point in _points(start_time, step, n, events, clocks and clocks.next_time):
        if point == "tick" and not fmu.md.coSimulation.canHandleVariableCommunicationStepSize:
            raise ArtibusError(f"{fmu.path}: a Clock ticks at t = {t_next:g} s, between two communication "
                               f"points, and {fmu.md.modelName} takes no variable communication step: give a "
                               "--step that divides its Clocks' intervals")
        try:
            t_end = fmu.do_step(t, t_next - t)
            kind = "terminateSimulation"
        except FMICallException as e:
            t_end = terminated(fmu.slave, e.status) if e.function == "fmi2DoStep" else None
            if t_end is None:
                raise
            kind = None
        if t_end is not None:                   # a normal end (NaN: at the step's end)
            t_end = t_end if t_end == t_end else t_next
            if t_end > t:
                record(t_end)
            result.terminated = (Termination(fmu.md.modelName, t_end, kind) if kind
                                 else Termination(fmu.md.modelName, t_end))
            return
        t = t_next
        row = point == "event" or (point == "step" and ((i + 1) % every == 0 or i + 1 == n))
        if clocks is not None and (asked or clocks.due(t)):
            _event(fmu, clocks, t, record if row else None, set_inputs, bool(asked))
            asked.clear()
        else:
            if row:
                record(t)
            set_inputs(t)
        if i is not None and (i + 1) % PIECE == 0 and i + 1 < n:     # for the tests (artibus.runner.markers)
            mark(f"t={t!r}")


def _schedule(fmu, path):
    """The Schedule of the FMU's Clocks (artibus.fmu.clocks); its nextEventTime a point to stop
    at where it takes variable communication steps"""
    from artibus.fmu.clocks import Schedule, read_clocks
    inputs, outputs = read_clocks(path)
    return Schedule(fmu.calls, inputs, path, outputs, fmu.md.coSimulation.canHandleVariableCommunicationStepSize)


def _event(fmu, clocks, t, record=None, set_inputs=None, asked=False):
    """Event Mode at t (FMI 3.0 2.3, "Event Mode"; 2.2, "Clocks"): the Clocks due at t activated
    (fmi3SetClock), the row recorded while they are active (a clocked variable is computed and
    read only then: 2.2, "Model Partitions and Clocked Variables"), the inputs set, the updates
    until the FMU asks for none (fmi3UpdateDiscreteStates, which deactivates the Clocks), the
    aperiodic Clocks' new intervals (2.2, "Clock Types": a countdown Clock's "in every Event
    Mode"); again while a Clock is due at t (an interval of 0: another super-dense instant);
    then Step Mode. ``record``: None where no row is wanted at t; with no Clock due, the row
    after the event iteration (as without Clocks). ``asked``: the FMU asked for this Event Mode
    (eventHandlingNeeded): the output Clocks it activated read first (fmi3GetClock), the row
    recorded while they are active."""
    from artibus.fmu.fmi3 import MAX_EVENT_ITERATIONS
    calls = fmu.calls
    calls.enter_event_mode()
    for _ in range(MAX_EVENT_ITERATIONS):
        vrs = clocks.due(t)
        if vrs:
            calls.enter_event_mode()            # (after an update: a further instant)
            calls.set_clocks(vrs)
            clocks.ticked(vrs)
        if asked:
            vrs, asked = vrs + clocks.active_outputs(), False
        if record is not None and vrs:
            record(t, vrs)
            record = None
        if set_inputs is not None:
            set_inputs(t)
            set_inputs = None
        calls.settle()
        clocks.update(t)
        if not clocks.due(t):
            calls.leave_event_mode()
            if record is not None:
                record(t)
            return
    raise ArtibusError(f"{fmu.path}: Clocks due again and again at t = {t:g} s "
                       f"({MAX_EVENT_ITERATIONS} super-dense instants)")


def _failure(fmu, result, record, path, start_time):
    """The SimulationError of a failed call, the state the FMU stopped in recorded
    (getters are allowed in the error state) at its last successful time."""
    t = result.rows[-1][0] if result.rows else start_time
    try:
        t_fail = fmu.last_successful_time()
        if t_fail > result.rows[-1][0] if result.rows else True:
            record(t_fail)
            t = t_fail
    except Exception:
        pass
    last = fmu.log[-1] if fmu.log else "no message"
    return SimulationError(f"{path}: {fmu.md.modelName} failed at t = {t:g} s: {last}", result, list(fmu.log))
