"""Run one FMU on its own: parameters in, input functions of time, outputs
recorded at every communication point. If the FMU fails midway the result up
to the failure is kept and handed over with the error and the FMU's log."""
import shutil
from dataclasses import dataclass, field

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from artibus import ArtibusError


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
        """A result from a filled table (a row per time), kept as its array."""
        result = cls(list(names), list(table))
        result._array = table
        return result

    def __getitem__(self, name):
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
        np.savetxt(path, self.array(), delimiter=",", header=header, comments="", fmt="%.12g")


def _callbacks(log):
    """FMI callbacks whose logger appends "[status] category: message" to ``log``
    (FMPy's logger proxy formats the printf arguments)."""
    from ctypes import byref
    from fmpy.fmi2 import (fmi2CallbackFunctions, fmi2CallbackLoggerTYPE,
                           fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           calloc, free)
    from fmpy.logging import addLoggerProxy

    status_names = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]

    def logger(env, instance, status, category, message):
        log.append(f"[{status_names[status] if 0 <= status < 6 else status}] "
                   f"{category.decode()}: {message.decode(errors='replace')}")

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(logger)
    from artibus import memory     # the process's calloc/free (a preloaded ASan sees the FMUs' heap)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(memory.calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(memory.free)
    addLoggerProxy(byref(cb))
    cb._keep = logger  # keep the Python function alive
    # FMPy's proxy keeps the last logger given to addLoggerProxy in one static
    # pointer (s_logger in fmpy/logging), which every proxied callback set then
    # calls, FMPy's own default callbacks included: once this instance is freed
    # that pointer would dangle (a crash when an FMU logs in fmpy.simulate_fmu
    # after an Fmu was closed). The callback sets stay alive for the process.
    _LIVE_CALLBACKS.append(cb)
    return cb


_LIVE_CALLBACKS = []


class Fmu:
    """An FMU instance with the variables addressed by name."""

    def __init__(self, path, instance_name="artibus", logging=False):
        self.path = str(path)
        self.md = read_model_description(self.path)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.log = []
        self._dir = extract(self.path)
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=instance_name)
        self._callbacks = _callbacks(self.log)
        try:
            self.slave.instantiate(loggingOn=logging, callbacks=self._callbacks)
        except Exception:
            shutil.rmtree(self._dir, ignore_errors=True)
            raise ArtibusError(f"{self.path}: {self.md.modelName} could not be instantiated: "
                               f"{' '.join(self.log) or 'no message'}") from None

    def var(self, name):
        try:
            return self.vars[name]
        except KeyError:
            raise ArtibusError(f"{self.path}: {self.md.modelName} has no variable '{name}'") from None

    def set_values(self, values):
        for name, value in values.items():
            v = self.var(name)
            vr = [v.valueReference]
            if v.type == "Real":
                self.slave.setReal(vr, [float(value)])
            elif v.type in ("Integer", "Enumeration"):
                self.slave.setInteger(vr, [int(value)])
            elif v.type == "Boolean":
                self.slave.setBoolean(vr, [value in (True, 1, "true", "1")])
            else:
                self.slave.setString(vr, [str(value)])

    def get(self, *names):
        reals = [self.var(n).valueReference for n in names]
        return self.slave.getReal(reals)

    def initialize(self, values, start_time=0.0):
        """setupExperiment, the values set in initialisation mode, exit it:
        the instance is ready to step from start_time. Returns self."""
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

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def simulate(path, parameters=None, inputs=None, stop_time=None, step=None,
             outputs=None, start_time=0.0):
    """Simulate one FMU.

    parameters: {name: value} set in initialization mode.
    inputs: {name: f(t)} evaluated at each communication point (held over the step).
    outputs: names to record (default: every output).
    Returns a Result; raises SimulationError (with the partial Result) on failure.
    """
    parameters = parameters or {}
    inputs = inputs or {}
    with Fmu(path) as fmu:
        de = fmu.md.defaultExperiment
        stop_time = stop_time if stop_time is not None else float(de.stopTime)
        step = step if step is not None else float(de.stepSize)
        if not step > 0:
            raise ArtibusError(f"{path}: step = {step} must be > 0")
        if outputs is None:
            outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"]
        result = Result(["time"] + list(outputs))
        vrs = [fmu.var(n).valueReference for n in outputs]
        t = start_time
        try:
            fmu.slave.setupExperiment(startTime=start_time)
            fmu.slave.enterInitializationMode()
            fmu.set_values(parameters)
            fmu.set_values({n: f(t) for n, f in inputs.items()})
            fmu.slave.exitInitializationMode()
            result.rows.append([t] + fmu.slave.getReal(vrs))
            n = int(round((stop_time - start_time) / step))
            for i in range(n):
                fmu.slave.doStep(t, step)
                t = start_time + (i + 1) * step
                result.rows.append([t] + fmu.slave.getReal(vrs))
                fmu.set_values({n_: f(t) for n_, f in inputs.items()})
        except FMICallException:
            # keep the state the FMU stopped in (getters are allowed in the error state)
            try:
                t_fail = fmu.slave.getRealStatus(2)  # fmi2LastSuccessfulTime
                if t_fail > result.rows[-1][0] if result.rows else True:
                    result.rows.append([t_fail] + fmu.slave.getReal(vrs))
                    t = t_fail
            except Exception:
                pass
            last = fmu.log[-1] if fmu.log else "no message"
            raise SimulationError(f"{path}: {fmu.md.modelName} failed at t = {t:g} s: {last}",
                                  result, list(fmu.log)) from None
        return result
