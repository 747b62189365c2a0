"""Run one FMU on its own: parameters in, input functions of time, outputs
recorded at every communication point. If the FMU fails midway the result up
to the failure is kept and handed over with the error and the FMU's log."""
import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from artibus.base import ArtibusError


class SimulationError(ArtibusError):
    """The FMU returned an error; ``result`` holds what was computed before."""

    def __init__(self, message, result, log):
        super().__init__(message)
        self.result = result
        self.log = log


@dataclass
class Result:
    """Recorded trajectories: ``result['x[1]']`` is an array over ``result.time``."""
    names: list
    rows: list = field(default_factory=list)

    @classmethod
    def from_array(cls, names, table):
        """A result from a filled table (a row per time), kept as its array;
        its rows a view of the table's (no list of a row object per time)."""
        result = cls.__new__(cls)           # (the fields' defaults without __init__'s calls)
        result.__dict__.update(names=list(names), rows=_ArrayRows(table), strings={}, units={}, _array=table)
        return result

    #: String columns: {name: [text per row]} (their column in the array is NaN)
    strings: dict = field(default_factory=dict)
    #: {name: unit} of the columns, from the FMUs' model descriptions (the variable's
    #: unit, else its declaredType's; "" for none; "s" for time)
    units: dict = field(default_factory=dict)

    def __getitem__(self, name):
        if name in self.strings:
            return np.array(self.strings[name], dtype=object)
        return self.array()[:, self.names.index(name)]

    @property
    def time(self):
        return self["time"]

    def array(self):
        cached = getattr(self, "_array", None)
        if cached is None or len(cached) != len(self.rows):
            cached = self._array = np.array(self.rows, dtype=float).reshape(-1, len(self.names))
        return cached

    def to_csv(self, path):
        header = ",".join(f'"{n}"' for n in self.names)
        if not self.strings:
            np.savetxt(path, self.array(), delimiter=",", header=header, comments="", fmt="%.12g")
            return
        # a String column as quoted text (CSV's quoting: "" for a quote)
        cols = [self.strings.get(n) for n in self.names]
        with open(path, "w") as f:
            f.write(header + "\n")
            for i, row in enumerate(self.array()):
                f.write(",".join('"' + c[i].replace('"', '""') + '"' if c is not None else f"{x:.12g}"
                                 for x, c in zip(row, cols)) + "\n")


def unit_of(var):
    """A model variable's unit: its own unit=, else its declaredType's, else ""."""
    if getattr(var, "unit", None):
        return var.unit
    declared = getattr(var, "declaredType", None)
    return getattr(declared, "unit", None) or ""


class _ArrayRows(Sequence):
    """Result.rows of a result made from a table: its rows without copying them."""

    def __init__(self, table):
        self._table = table

    def __len__(self):
        return len(self._table)

    def __getitem__(self, i):
        return self._table[i]


def _callbacks(log):
    """FMI callbacks of one instance, whose messages go to ``log`` only
    ("[status] category: message").

    FMPy's logger proxy (fmpy/logging) formats the printf arguments in C and
    then calls the one logger it keeps in a static pointer, the last one given
    to addLoggerProxy, passing the componentEnvironment through. Every
    instance here gets a callback set of its own whose componentEnvironment is
    a number naming its log, and the proxy's logger is one dispatcher for the
    whole process: each message reaches the log of the instance that sent it,
    whichever was instantiated last. The dispatcher lives as long as the
    process, so the proxy's pointer never dangles."""
    from ctypes import byref
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    env = next(_ENVS)
    _LOGS[env] = log
    cb = fmi2CallbackFunctions()
    cb.logger = _dispatcher()
    from artibus.fmu import memory     # the process's calloc/free (a preloaded ASan sees the FMUs' heap)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(memory.calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(memory.free)
    cb.componentEnvironment = env
    claim_logger_proxy()
    _proxy().addLoggerProxy(byref(cb))
    cb._env = env
    return cb


_LOGS = {}                       # componentEnvironment -> that instance's log
_ENVS = iter(range(1, 2**62))
_DISPATCH = []                   # the process's one dispatcher (kept alive here)
_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]


def _proxy():
    import fmpy.logging
    return fmpy.logging


def _dispatcher():
    if not _DISPATCH:
        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        def dispatch(env, instance, status, category, message):
            log = _LOGS.get(env)
            if log is not None:
                log.append(f"[{_STATUS[status] if 0 <= status < 6 else status}] "
                           f"{(category or b'').decode(errors='replace')}: "
                           f"{(message or b'').decode(errors='replace')}")
        _DISPATCH.append(fmi2CallbackLoggerTYPE(dispatch))
    return _DISPATCH[0]


def claim_logger_proxy():
    """Make the dispatcher FMPy's proxied logger again: FMPy's own
    instantiations (fmpy.simulate_fmu in the same process) take the proxy's
    one pointer for their logger, which dangles once they are gone; called
    before each run and initialisation here."""
    from ctypes import byref
    from fmpy.fmi2 import fmi2CallbackFunctions
    cb = fmi2CallbackFunctions()
    cb.logger = _dispatcher()
    _proxy().addLoggerProxy(byref(cb))


_MDS = {}                        # modelDescription.xml's (CRC-32, size) -> its description
_MDS_KEPT = 64


def _model_description(path):
    """fmpy.read_model_description (validated against the XSD), once per content:
    an FMU whose modelDescription.xml has the CRC-32 and size of one read before
    (the zip's directory says, without unpacking) gets that description again. A
    bench's instances of one FMU, each run's unpacked copy of it and a sweep's
    cases parse it once; the last _MDS_KEPT descriptions are kept."""
    import zipfile
    try:
        with zipfile.ZipFile(path) as z:
            info = z.getinfo("modelDescription.xml")
        key = (info.CRC, info.file_size)
    except (OSError, KeyError, zipfile.BadZipFile):
        return read_model_description(path)       # its own error, named
    md = _MDS.get(key)
    if md is None:
        md = read_model_description(path)
        if len(_MDS) >= _MDS_KEPT:
            _MDS.pop(next(iter(_MDS)))
        _MDS[key] = md
    return md


class Fmu:
    """An FMU instance with the variables addressed by name."""

    def __init__(self, path, instance_name="artibus", logging=False):
        from pathlib import Path
        self.path = str(path)
        if not Path(self.path).is_file():
            raise ArtibusError(f"{self.path}: no such FMU file")
        try:
            self.md = _model_description(self.path)
        except Exception as e:   # not a zip, no or a broken modelDescription.xml
            raise ArtibusError(f"{self.path}: not a readable FMI 2.0 FMU: {e}") from None
        if self.md.fmiVersion != "2.0" or self.md.coSimulation is None:
            raise ArtibusError(f"{self.path}: {self.md.modelName} is not an FMI 2.0 co-simulation FMU")
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.log = []
        self.instance_name = instance_name
        self._dir = None
        try:
            self._dir = extract(self.path)
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName=instance_name)
        except Exception as e:   # a missing or broken binary
            if self._dir:
                shutil.rmtree(self._dir, ignore_errors=True)
            raise ArtibusError(f"{self.path}: {self.md.modelName}'s binary cannot be loaded: {e}") from None
        self._callbacks = _callbacks(self.log)
        try:
            self.slave.instantiate(loggingOn=logging, callbacks=self._callbacks)
        except Exception:
            shutil.rmtree(self._dir, ignore_errors=True)
            _LOGS.pop(self._callbacks._env, None)
            raise ArtibusError(f"{self.path}: {self.md.modelName} could not be instantiated: "
                               f"{' '.join(self.log) or 'no message'}") from None

    def var(self, name):
        try:
            return self.vars[name]
        except KeyError:
            from artibus.bench.parameters import no_variable
            raise ArtibusError(f"{self.path}: {no_variable(self.md, name)}") from None

    def set_values(self, values):
        """Set each {name: value}, the value checked against the variable's
        declared type first (artibus.parameters.coerce: no rounding, no
        "yes" for true, an Enumeration by item name or value)."""
        from artibus.bench.parameters import coerce
        for name, value in values.items():
            v = self.var(name)
            try:
                x = coerce(v, value, finite=False)     # NaN, Inf: the FMU refuses them, naming them
            except ValueError as e:
                raise ArtibusError(f"{self.instance_name}.{name} = {value!r}: not a valid {v.type} "
                                   f"for {self.md.modelName}: {e}") from None
            vr = [v.valueReference]
            if v.type == "Real":
                self.slave.setReal(vr, [x])
            elif v.type in ("Integer", "Enumeration"):
                self.slave.setInteger(vr, [x])
            elif v.type == "Boolean":
                self.slave.setBoolean(vr, [x])
            else:
                self.slave.setString(vr, [x])

    def get(self, *names):
        """The Real variables' values (fmi2GetReal in one call)."""
        reals = [self.var(n).valueReference for n in names]
        return self.slave.getReal(reals)

    def get_values(self, names):
        """The values of variables of any type, as Python values: float, int
        (Integer, Enumeration), bool, str; one call per type."""
        out = [None] * len(names)
        by_type = {}
        for i, n in enumerate(names):
            v = self.var(n)
            by_type.setdefault("Integer" if v.type == "Enumeration" else v.type, []).append((i, v.valueReference))
        for t, items in by_type.items():
            got = getattr(self.slave, f"get{t}")([vr for _, vr in items])
            for (i, _), x in zip(items, got):
                out[i] = (bool(x) if t == "Boolean" else x.decode("utf-8", errors="replace")
                          if t == "String" else x)
        return out

    def initialize(self, values, start_time=0.0):
        """setupExperiment, the values set in initialisation mode, exit it:
        the instance is ready to step from start_time. Returns self."""
        claim_logger_proxy()
        try:
            self.slave.setupExperiment(startTime=start_time)
            self.slave.enterInitializationMode()
            self.set_values(values)
            self.slave.exitInitializationMode()
        except Exception:
            self.close()
            raise
        return self

    def close(self):
        """Free the instance and its unpacked files; again is a no-op."""
        if getattr(self, "_closed", False):
            return
        self._closed = True
        try:
            self.slave.freeInstance()
        finally:
            shutil.rmtree(self._dir, ignore_errors=True)
            _LOGS.pop(self._callbacks._env, None)   # the instance is gone: it logs no more

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


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
    """Simulate one FMU.

    parameters: {name: value} set in initialization mode (checked against
    each variable's type, see artibus.parameters.coerce).
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
        if outputs is None:
            outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"]
        types = [fmu.var(n).type for n in outputs]
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
            fmu.slave.setupExperiment(startTime=start_time)
            fmu.slave.enterInitializationMode()
            fmu.set_values(parameters)
            fmu.set_values({n: f(t) for n, f in inputs.items()})
            fmu.slave.exitInitializationMode()
            record(t)
            n = int(round((stop_time - start_time) / step))
            for i in range(n):
                fmu.slave.doStep(t, step)
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
                t_fail = fmu.slave.getRealStatus(2)  # fmi2LastSuccessfulTime
                if t_fail > result.rows[-1][0] if result.rows else True:
                    record(t_fail)
                    t = t_fail
            except Exception:
                pass
            last = fmu.log[-1] if fmu.log else "no message"
            raise SimulationError(f"{path}: {fmu.md.modelName} failed at t = {t:g} s: {last}",
                                  result, list(fmu.log)) from None
        return result
