"""The co-simulation master: runs an SSP bench of FMI 2.0 or 3.0 co-simulation
FMUs (``fmi``: the bench's choice, or every FMU's FMI 2.0 or 3.0 build,
artibus.bench.fmi).

- parameters from the bench's bindings (.ssv inside the .ssp), then from
  ``--ssv`` files and ``--set comp.var=value`` given by the user;
- every value checked against the FMU's declared type (artibus.bench.parameters.coerce);
- connections between component variables, through nested systems, with SSP
  linear transformations; without one, values are converted between the
  connected variables' units (FMI unit definitions, base units and factor/offset);
  Integer, Boolean, String and Enumeration connections join variables of one
  type, exactly, with SSP's mapping transformations (_TypedCalls, _typed_convert);
- initialisation: every FMU in initialization mode, connected inputs set from
  the outputs they are connected to, repeated to a fixed point (bounded);
- stepping in the one loop, the C core (artibus.runner.core): Gauss-Seidel in an
  order derived from the connection graph (an algebraic loop of direct feedthrough
  is an error naming it), or Jacobi;
  multi-rate: each component has its own communication step, a multiple of the
  base step; slower components hold their inputs;
- one batched getReal/setReal per component per step;
- recording of every connection (or a chosen list) at every base step, of any
  type (a Boolean as 0/1, a String's text in Result.strings);
- on a failure midway, the results so far are kept with the failing time and
  the FMU's log;
- an FMU that ends the simulation itself (fmi2DoStep's fmi2Discard with
  fmi2Terminated, fmi3DoStep's terminateSimulation) ends the run as a normal end: the base step it ended in is
  finished by the others, recorded, and the run returns its Result with
  ``terminated`` (artibus.fmu.Termination: which component, when).
"""
import shutil
import time as _time
from pathlib import Path

import numpy as np
from fmpy.fmi1 import FMICallException

from artibus import cache
from artibus.base import ArtibusError
from artibus.bench import ssp as ssp_mod
from artibus.fmu import Result, SimulationError
from artibus.runner.core import _core_stepper
from artibus.runner.plan import _Plan, stated_timing
from artibus.runner.results import check_room
from artibus.runner.setup import _Setup
from artibus.runner.unit import _last_message

MAX_INIT_ITERATIONS = 50


def _read_bench(path):
    """artibus.bench.ssp.read(path), once per content of the .ssp (its .ssd and
    parameter files parsed and validated against the XSDs once): kept in the
    .ssp's cache entry (artibus.cache.stored), under the path it was read as
    (its messages name it) and the code that reads it (artibus.bench.ssp and
    .parameters, .units: every module of artibus.bench; FMPy's version), so an
    edit of any reads it again."""
    if cache.root() is None:
        return ssp_mod.read(path)
    try:
        entry, temporary = cache.unpacked(path)
    except Exception:                 # not a zip, a broken member: read names it
        return ssp_mod.read(path)
    if temporary:
        shutil.rmtree(entry, ignore_errors=True)
        return ssp_mod.read(path)
    return cache.stored(entry, f"bench-{_reader_key(path)}", lambda: ssp_mod.read(path))


def _reader_key(path):
    import hashlib
    import fmpy
    h = hashlib.sha256(f"{path}\0{fmpy.__version__}".encode())
    for module in sorted(Path(ssp_mod.__file__).parent.glob("*.py")):   # the whole reader: ssp, parameters, units, ...
        h.update(module.read_bytes())
    return h.hexdigest()[:24]


class Simulation(_Setup):
    """A bench, set up and ready to run (the set-up: artibus.runner.setup)."""

    def __init__(self, ssp, step=None, overrides=None, record=None, algorithm="gauss-seidel",
                 stimuli=None, can=None, can_log=None, can_faults=None, cut=None, single_rate=False, fmi=None,
                 lsbus_wire_time=None, fmi_type=None, relative_tolerance=None, me_method="bdf", me_jacobian=False, input_file=None,
                 reference=False):
        """stimuli: {"comp.input": f(t)} added to the input (to its connection's
        value, or to its start value when it is not connected), sampled at
        the start of each of the component's steps. cut: inputs ("comp.input")
        whose connection the run leaves out, a direct one or a route over
        CAN (for a replay: a stimulus then feeds them alone, on their start
        value or an override); when every route over CAN is cut, the run has
        no network. can: the interface of a
        bench that routes connections over CAN ("virtual", the default, or
        "INTERFACE:CHANNEL"), can_log: a .blf or .asc file for its traffic,
        can_faults: faults injected into it (artibus.can.Fault or their text
        forms, see artibus.can.parse_fault). A CAN bench's result has a column
        ``can.<message>.sinceGood`` per message: the cycles since the
        receivers last accepted a frame of it, as of the inputs in the same
        row. single_rate: every component at the one step (--step, else the
        shortest of the bench's), as a master without multi-rate steps runs
        the bench. What the bench holds that the runner does not apply is
        printed as warnings, once (artibus.bench.portability). fmi: None (the
        builds the bench's .ssd names), "2" or "3" (every FMU's build of that
        FMI version: a bench of ssp/benches by name, artibus.bench.ssp.ssp_path).
        An SSP 2.0 bench with FMI-LS-BUS components runs their network
        (artibus.runner.lsbus_bench) in place of a CAN network; lsbus_wire_time:
        its bus's wireTime (None: the bench's binding). fmi_type: None or "cs" (Co-Simulation),
        "me" (every FMU that has Model Exchange runs as ME, integrated by the stepping core's ME
        facade, artibus.fmu.me; the others in Co-Simulation), or {component: "cs" | "me"};
        relative_tolerance: the ME units' (default: their default experiment's, else
        artibus.fmu.me.BENCH_TOLERANCE); me_method: their CVODE's, "bdf" or "adams"; me_jacobian:
        CVODE's Jacobian from the directional derivatives of the ME units that provide them (else
        its difference quotients; artibus.fmu.me.Facade.use_jacobian). input_file: a
        CSV driving the bench's free inputs, columns COMPONENT.VARIABLE (--input-file, as `simulate`
        reads one: artibus.fmu.inputs; _Setup._input_file). reference: the bench's monolithic reference
        (--reference, issue 44: artibus.runner.reference): every component that offers Model Exchange
        as ME, all of them integrated together in one CVODE (relative tolerance: the one given, else
        artibus.runner.reference.REFERENCE_TOLERANCE), the others as they are; the same Result."""
        self.can = self.lsbus = None     # the bench's network: a CAN one, or an FMI-LS-BUS one (network)
        self.single_rate = single_rate
        self.reference, self._group = bool(reference), None
        if reference:                    # every ME component as ME, in one group (artibus.runner.reference)
            from artibus.runner.reference import REFERENCE_TOLERANCE
            fmi_type = "me"
            relative_tolerance = REFERENCE_TOLERANCE if relative_tolerance is None else relative_tolerance
        self.fmi_type, self.relative_tolerance, self.me_method = fmi_type, relative_tolerance, me_method
        self.me_jacobian = bool(me_jacobian)
        if algorithm not in ("gauss-seidel", "jacobi"):
            raise ArtibusError(f"algorithm '{algorithm}': expected gauss-seidel or jacobi")
        self.algorithm = algorithm
        self.ssp = ssp_mod.ssp_path(ssp, fmi)
        self.bench = _read_bench(self.ssp)
        from artibus.bench.portability import warn
        warn(self.ssp)                   # what the runner does not apply: once a process, not cached
        where = self.bench.file
        if step is not None and not step > 0:
            raise ArtibusError(f"--step {step}: the communication step must be > 0")
        self._tmp, self._tmp_owned = None, False
        try:
            # unpacked once per content and kept (artibus.cache), or into a temporary directory
            self._tmp, self._tmp_owned = cache.unpacked(self.ssp)
            # an SSP 2.0 bench, which may have an FMI-LS-BUS network (artibus.bench.ssp2): only then
            # its modules (FMPy's FMI 3.0 classes) and a second reading of the .ssd; every SSP 1.0
            # bench's run pays nothing
            ssd = Path(self._tmp) / "SystemStructure.ssd"
            steering = None
            if self.bench.version == "2.0":
                from artibus.runner.lsbus_bench import LsBusSteering, read_spec
                if read_spec(ssd, where) is not None:
                    steering = LsBusSteering(where, self._tmp, lsbus_wire_time)
            if steering is not None:      # the network's outputs onto the plant's inputs; its frames' log
                stimuli = {**steering.stimuli(), **(stimuli or {})}
                steering.log, can_log = can_log, None
                steering.set_faults(can_faults)       # (injected by its bus simulation FMU)
                can_faults = None
            self._setup(step, overrides or {}, record, where, stimuli or {}, can, can_log, can_faults,
                        set(cut or ()), input_file)
            if reference:
                from artibus.runner import reference as reference_mod
                self._group = reference_mod.set_up(self, where)
            if steering is not None:
                steering.bind(self)
        except BaseException:
            self.close()
            raise

    def _with_texts(self, result):
        """A String column's numbers (see _TypedCalls) as Result.strings; the
        columns' units (Result.units: the recorded variables' units from their
        model descriptions, "s" for time, "" for none and the CAN columns)."""
        if result is None:
            return result
        result.units = {n: self._col_units.get(n, "") for n in result.names}
        result.descriptions = {n: self._col_descriptions.get(n, "") for n in result.names}
        if not self._text_cols:
            return result
        table = result.array()
        for name, u in self._text_cols.items():
            j = result.names.index(name)
            result.strings[name] = [u.raw.text(int(x)) if np.isfinite(x) else "" for x in table[:, j]]
            table[:, j] = np.nan
        return result

    def _initialize(self, start, stepper):
        """Every FMU in Initialization Mode with its parameters, the rounds to the fixed point
        of the connected inputs and the exits (the core's: _CoreStepper.settle; the exits
        here when FMPy logs the calls). A failure's unit is self._busy."""
        for u in self.units:
            self._busy = u            # the unit being called: a failure names it
            if getattr(u.fmu.calls, "facade", None) is not None:      # Model Exchange: its integrator's tolerance
                from artibus.fmu.me import bench_tolerance
                u.fmu.calls.facade.use_method(self.me_method)
                if self.me_jacobian and u.fmu.calls.facade.jacobian_available:
                    u.fmu.calls.facade.use_jacobian()
                u.fmu.enter_initialization_mode(start, bench_tolerance(u.fmu.md, self.relative_tolerance))
            else:
                u.fmu.enter_initialization_mode(start)
            u.fmu.set_values(self.parameters[u.path])
            u.raw.written = None      # every connected input is set at least once
        exited = stepper.settle(MAX_INIT_ITERATIONS)
        for u in () if exited else self.units:
            self._busy = u
            me = getattr(u.fmu.calls, "facade", None) is not None     # Model Exchange: the facade exits
            u.fmu.calls.exit_initialization() if me else u.fmu.slave.exitInitializationMode()
            u.raw.read()
        self._busy = None

    def run(self, stop_time=None, start_time=None, progress=False, core=None):
        """Run from the start to the stop time (the bench's DefaultExperiment's
        unless given): the Result, with String columns in Result.strings; the
        results up to a failure or an interrupt go with the exception (its
        ``result``). See _run."""
        from artibus.fmu import check_times, claim_logger_proxy
        claim_logger_proxy()
        start = self.bench.start_time if start_time is None else start_time
        stop = stop_time if stop_time is not None else self.bench.stop_time
        if stop is not None:
            check_times(start, stop, None, self.bench.file)
        try:
            return self._with_texts(self._run(stop_time, start_time, progress, core))
        except (SimulationError, KeyboardInterrupt) as e:
            if getattr(e, "result", None) is not None:
                e.result = self._with_texts(e.result)
            raise

    def _run(self, stop_time=None, start_time=None, progress=False, core=None):
        """The run in the one stepping loop (artibus.runner.core); core: None or True (the
        networks in C where C has them), False (every network in Python, its reference
        implementation). self.stepping says what ran where."""
        start = self.bench.start_time if start_time is None else start_time
        stop = stop_time if stop_time is not None else self.bench.stop_time
        if stop is None:
            raise ArtibusError(f"{self.bench.file}: no DefaultExperiment stopTime; give --stop-time")
        if not stop > start:
            raise ArtibusError(f"stop time {stop} must be after the start time {start}")
        h = self.base_step
        n = int(round((stop - start) / h))
        check_room(n + 1, len(self.names), self.bench.file)
        # the sampled units' timing at this run's steps (as set up, or changed since: the reference's group)
        stated_timing(self.units, getattr(self, "default_base", None), h)
        stepper = _core_stepper(self, _Plan(self.order, n), core)
        stepper.allocate(n)
        wall0 = _time.perf_counter()
        try:
            self._initialize(start, stepper)
        except FMICallException:
            who = getattr(self, "_busy", None)
            log = who.fmu.log if who else [m for u in self.units for m in u.fmu.log]
            raise SimulationError(f"{self.ssp}: component '{who.path if who else '?'}' failed at t = {start:g} s: "
                                  f"{_last_message(log)}", Result.from_array(self.names, np.empty((0, len(self.names)))),
                                  list(log)) from None
        if self.network is not None:
            self.network.start(start)
        result = stepper.run(start, h, n, progress)
        self.wall = _time.perf_counter() - wall0
        if self.network is not None:
            self.network.finish()
        if self.can is not None:
            end = result.terminated
            result = self._with_can_columns(result, stepper.table)
            result.terminated = end
        return result

    def _with_can_columns(self, result, wide=None):
        """can.<message>.sinceGood: row i > 0 holds the value after the last tick
        before it (the one whose frames the inputs recorded in row i got).
        wide: the stepping core's table, the result's columns and then one
        per message, filled here in place (no copy of the table)."""
        table = result.array()
        n = len(table)
        tick = np.maximum(np.arange(n) - 1, 0) // self.can_ratio
        cols, names = [], []
        for name, series in self.can.since_series().items():
            col = series[np.minimum(tick, len(series) - 1)] if len(series) else np.zeros(n)
            col[0] = 0.0
            cols.append(col)
            names.append(f"can.{name}.sinceGood")
        m = table.shape[1]
        if wide is not None and wide.shape == (n, m + len(cols)):
            for j, col in enumerate(cols):
                wide[:, m + j] = col
            return Result.from_array(result.names + names, wide)
        return Result.from_array(result.names + names, np.column_stack([table] + cols))

    @property
    def network(self):
        """The bench's network, CAN (self.can: artibus.can.Network) or FMI-LS-BUS
        (self.lsbus: artibus.runner.lsbus_bench.LsBusSteering), or None."""
        return self.can if getattr(self, "can", None) is not None else getattr(self, "lsbus", None)

    @property
    def network_ratio(self):
        """Base steps per tick of the bench's network."""
        return self.can_ratio if self.can is not None else self.lsbus_ratio

    def close(self):
        if self.network is not None:
            self.network.close()
        if getattr(self, "_group", None) is not None:       # (the reference's CVODE; the FMUs below)
            self._group.free()
        for u in getattr(self, "units", []):
            u.fmu.close()
        if getattr(self, "_tmp_owned", False):     # (a cache entry stays: artibus.cache)
            shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc):
        self.close()
        failed = getattr(self.network, "log_error", None)
        if exc_type is None and failed:     # the --can-log that failed (a full disk): said after the results
            raise ArtibusError(failed)


def run(ssp, stop_time=None, step=None, overrides=None, record=None,
        algorithm="gauss-seidel", progress=False, stimuli=None, fmi=None):
    """Run a bench (name or .ssp path); returns the Result."""
    with Simulation(ssp, step=step, overrides=overrides, record=record, algorithm=algorithm,
                    stimuli=stimuli, fmi=fmi) as sim:
        return sim.run(stop_time=stop_time, progress=progress)
