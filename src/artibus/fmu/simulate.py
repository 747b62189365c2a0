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
    """
    parameters = parameters or {}
    inputs = inputs or {}
    with Fmu(path) as fmu:
        de = fmu.md.defaultExperiment
        claim_logger_proxy()
        if stop_time is None:
            stop_time = float(de.stopTime) if de is not None and de.stopTime else DEFAULT_STOP_TIME
        check_times(start_time, stop_time, step, path)
        if step is None:
            step = default_step(fmu.md, start_time, stop_time)
            check_times(start_time, stop_time, step, f"{path}: default experiment")
        if outputs is None:      # (a Binary or a Clock is no number for the table: not recorded)
            outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"
                       and v.type not in NOT_NUMBERS]
        types = [fmu.var(n).type for n in outputs]
        for n, ty in zip(outputs, types):
            if ty in NOT_NUMBERS:
                raise ArtibusError(f"{path}: {n} is an FMI 3.0 {ty}: not a number a result table can hold")
        from artibus.runner.results import check_room      # as `run` does: refused before it starts
        check_room(int(round((stop_time - start_time) / step)) + 1, len(outputs) + 1, path)
        strings = [n for n, t in zip(outputs, types) if t == "String"]
        result = Result(["time"] + list(outputs))
        result.strings = {n: [] for n in strings}
        result.units = {"time": "s", **{n: unit_of(fmu.var(n)) for n in outputs}}

        def record(t):
            values = fmu.get_values(outputs)
            result.rows.append([t] + _row(values, types))
            for n, x, ty in zip(outputs, values, types):
                if ty == "String":
                    result.strings[n].append(x)

        t = start_time
        try:
            fmu.enter_initialization_mode(start_time)
            fmu.set_values(parameters)
            fmu.set_values({n: f(t) for n, f in inputs.items()})
            fmu.slave.exitInitializationMode()
            record(t)
            n = int(round((stop_time - start_time) / step))
            for i in range(n):
                try:
                    t_end = fmu.do_step(t, step)
                    if t_end is not None:              # FMI 3.0 terminateSimulation: a normal end
                        t_end = t_end if t_end == t_end else start_time + (i + 1) * step   # (NaN: the step's end)
                        if t_end > t:
                            record(t_end)
                        result.terminated = Termination(fmu.md.modelName, t_end, "terminateSimulation")
                        break
                except FMICallException as e:
                    t_end = terminated(fmu.slave, e.status) if e.function == "fmi2DoStep" else None
                    if t_end is None:
                        raise
                    # the FMU ended the simulation: its values at its last successful time
                    # (getters are allowed after fmi2Discard), as FMPy's simulate_fmu records them
                    t_end = t_end if t_end == t_end else start_time + (i + 1) * step
                    if t_end > t:
                        record(t_end)
                    result.terminated = Termination(fmu.md.modelName, t_end)
                    break
                t = start_time + (i + 1) * step
                record(t)
                fmu.set_values({n_: f(t) for n_, f in inputs.items()})
        except KeyboardInterrupt as e:   # Ctrl-C or SIGTERM (artibus.cli): the rows so far go with it
            n_rows = min([len(result.rows)] + [len(c) for c in result.strings.values()])
            del result.rows[n_rows:]     # (a row whose texts were not all taken)
            for c in result.strings.values():
                del c[n_rows:]
            e.result = result
            raise
        except FMICallException:
            # keep the state the FMU stopped in (getters are allowed in the error state)
            try:
                t_fail = fmu.last_successful_time()
                if t_fail > result.rows[-1][0] if result.rows else True:
                    record(t_fail)
                    t = t_fail
            except Exception:
                pass
            last = fmu.log[-1] if fmu.log else "no message"
            raise SimulationError(f"{path}: {fmu.md.modelName} failed at t = {t:g} s: {last}",
                                  result, list(fmu.log)) from None
        return result
