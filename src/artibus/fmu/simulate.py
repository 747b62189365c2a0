"""Run one FMU on its own: parameters in, input functions of time, outputs
recorded at every communication point. If the FMU fails midway the result up
to the failure is kept and handed over with the error and the FMU's log. An
FMU that ends the simulation itself (fmi2Discard with fmi2Terminated, as the
Reference-FMUs' Stair does at t = 9 s) ends the run there as a normal end:
the result up to its last successful time, with ``Result.terminated``."""
from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
from artibus.bench.fmi import NOT_NUMBERS
from artibus.bench.units import unit_of
from artibus.fmu.instance import Fmu, claim_logger_proxy
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


def _row(values, types):
    """A recorded row as floats: a Boolean as 0/1, an Integer or Enumeration
    as its number, a String as NaN (its text goes to Result.strings)."""
    return [float("nan") if t == "String" else float(x) for x, t in zip(values, types)]


def simulate(path, parameters=None, inputs=None, stop_time=None, step=None,
             outputs=None, start_time=0.0):
    """Simulate one FMU (FMI 2.0 or 3.0, Co-Simulation).

    parameters: {name: value} set in initialization mode (checked against
    each variable's type, see artibus.bench.parameters.coerce).
    inputs: {name: f(t)} evaluated at each communication point (held over the step).
    outputs: names to record, of any type (default: every output).
    Without stop_time/step: the default experiment's, else DEFAULT_STOP_TIME
    and (stop - start) / DEFAULT_STEPS.
    Returns a Result; raises SimulationError (with the partial Result) on failure.
    Ctrl-C or SIGTERM (KeyboardInterrupt) ends it between two steps, the rows so
    far in ``e.result``: each doStep returns in bounded time (the FMUs refuse a
    step longer than their limit, docs/developer/fmi-layer.md).
    """
    parameters = parameters or {}
    inputs = inputs or {}
    with Fmu(path) as fmu:
        claim_logger_proxy()
        stop_time, step = _experiment(fmu, start_time, stop_time, step, path)
        outputs, types = _recorded(fmu, outputs, path)
        from artibus.runner.results import check_room      # as `run` does: refused before it starts
        n = step_count(start_time, stop_time, step, path)
        check_room(n + 1, len(outputs) + 1, path)
        check_steps(n, path)
        result, record = _recorder(fmu, outputs, types)
        try:
            fmu.enter_initialization_mode(start_time)
            fmu.set_values(parameters)
            fmu.set_values({n: f(start_time) for n, f in inputs.items()})
            fmu.slave.exitInitializationMode()
            record(start_time)
            _steps(fmu, n, start_time, step, inputs, record, result)
        except KeyboardInterrupt as e:   # Ctrl-C or SIGTERM (artibus.cli): the rows so far go with it
            n_rows = min([len(result.rows)] + [len(c) for c in result.strings.values()])
            del result.rows[n_rows:]     # (a row whose texts were not all taken)
            for c in result.strings.values():
                del c[n_rows:]
            e.result = result
            raise
        except FMICallException:
            raise _failure(fmu, result, record, path, start_time) from None
        return result


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
    """(names, types) of the recorded variables: those asked for, else every output
    (a Binary or a Clock is no number for the table: not recorded, refused if asked for)."""
    if outputs is None:
        outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"
                   and v.type not in NOT_NUMBERS]
    types = [fmu.var(n).type for n in outputs]
    for n, ty in zip(outputs, types):
        if ty in NOT_NUMBERS:
            raise ArtibusError(f"{path}: {n} is an FMI 3.0 {ty}: not a number a result table can hold")
    return outputs, types


def _recorder(fmu, outputs, types):
    """(the Result, record(t): a row of the outputs' values at t, Strings in Result.strings)."""
    result = Result(["time"] + list(outputs))
    result.strings = {n: [] for n, t in zip(outputs, types) if t == "String"}
    result.units = {"time": "s", **{n: unit_of(fmu.var(n)) for n in outputs}}

    def record(t):
        values = fmu.get_values(outputs)
        result.rows.append([t] + _row(values, types))
        for n, x, ty in zip(outputs, values, types):
            if ty == "String":
                result.strings[n].append(x)
    return result, record


def _steps(fmu, n, start_time, step, inputs, record, result):
    """n steps from start_time, each recorded, the inputs set after it; an FMU's own end
    (FMI 3.0 terminateSimulation, FMI 2.0 fmi2Discard with fmi2Terminated) ends them with
    Result.terminated, its values at its last successful time recorded (getters are
    allowed after fmi2Discard), as FMPy's simulate_fmu records them."""
    from artibus.runner.markers import PIECE, mark
    t = start_time
    for i in range(n):
        try:
            t_end = fmu.do_step(t, step)
            kind = "terminateSimulation"
        except FMICallException as e:
            t_end = terminated(fmu.slave, e.status) if e.function == "fmi2DoStep" else None
            if t_end is None:
                raise
            kind = None
        if t_end is not None:                   # a normal end (NaN: at the step's end)
            t_end = t_end if t_end == t_end else start_time + (i + 1) * step
            if t_end > t:
                record(t_end)
            result.terminated = (Termination(fmu.md.modelName, t_end, kind) if kind
                                 else Termination(fmu.md.modelName, t_end))
            return
        t = start_time + (i + 1) * step
        record(t)
        fmu.set_values({n_: f(t) for n_, f in inputs.items()})
        if (i + 1) % PIECE == 0 and i + 1 < n:     # for the tests (artibus.runner.markers)
            mark(f"t={t!r}")


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
