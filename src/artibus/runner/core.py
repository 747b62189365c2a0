"""The stepping core in C (issue 13).

Simulation.run's loop over the base steps (propagate, set, step, get, record)
done by <build>/lib/libartibus_core.so (src/runner_core/core.c) through the
FMUs' own fmi2SetReal/fmi2DoStep/fmi2GetReal (an FMI 3.0 FMU's
fmi3SetFloat64/fmi3DoStep/fmi3GetFloat64), on the same value buffers
(_RawCalls'), in the same order, with the same floating-point operations:
the results are the Python loop's, bit for bit (tests/test_runner_core.py).
Python keeps the set-up, the checks and the errors; of the initialisation the
core does the rounds to the fixed point of the connected inputs (_CoreStepper.settle:
artibus_core_settle, the same calls, order and test as Simulation._initialize's loop).
A bench that routes connections over CAN has its network ticked by the core
too (_CanCore: artibus.can.Network.tick's frames, codec, E2E, counts, bits and
since series in C, and the initialisation's settle: _CanCore.settle;
tests/test_can_core.py), unless it has faults, a
tamper function, a real interface or signals the core does not encode
(Network.core_support). A bench whose network is FMI-LS-BUS FMUs
(artibus.runner.lsbus_bench) has it ticked by the core as well (_LsBusCore:
src/runner_core/lsbus.c does lsbus.Network.advance on FMPy's instances, the
network's outputs reach the plant as its stimuli do in _propagate;
tests/test_lsbus_core.py). Today's Python loop runs instead when the core does
not apply (the reason is in Simulation.stepping): such a CAN network, a bench
with stimuli (Python functions of time), Integer/Boolean/String/Enumeration
variables, the library not built, or the core switched off (run(core=False)
or ARTIBUS_CORE=0).
"""
import os
import sys
from ctypes import (CDLL, Structure, addressof, byref, c_double, c_int, c_long, c_size_t, c_ulonglong, c_void_p,
                    cast, memmove, sizeof)
from pathlib import Path

from fmpy.fmi1 import FMICallException

from artibus.base import ROOT, ArtibusError
from artibus.fmu import Result, SimulationError
from artibus.runner import tables
from artibus.runner.can_core import _CanCore
from artibus.runner.unit import _last_message

CORE_ABI = 13                      # ARTIBUS_CORE_ABI in src/runner_core/core.h
CORE_PIECE = 5000                  # base steps per call into the core (without the progress bar)
_AC_PROPAGATE, _AC_WRITE, _AC_STEP = 0, 1, 2
_AC_DO_STEP = 1                    # core.h: fmi2DoStep failed (or returned fmi2Discard)
_AC_CAN = 4                        # core.h: a frame could not be encoded
_AC_LSBUS = 7                      # core.h: the FMI-LS-BUS network's tick failed
_AC_GET_REAL, _AC_SET_REAL, _AC_UNSETTLED, _AC_EXIT_INIT = 2, 3, 5, 6


class _AcSource(Structure):
    _fields_ = [("dst", c_void_p), ("src", c_void_p), ("factor", c_double), ("offset", c_double)]


class _AcUnit(Structure):
    _fields_ = [("component", c_void_p), ("fmi", c_int), ("doStep", c_void_p), ("getReal", c_void_p),
                ("setReal", c_void_p), ("doStep3", c_void_p), ("getFloat64", c_void_p), ("setFloat64", c_void_p),
                ("step", c_double), ("n_out", c_size_t), ("n_in", c_size_t),
                ("out_vrs", c_void_p), ("out", c_void_p), ("in_vrs", c_void_p), ("inp", c_void_p),
                ("written", c_void_p), ("has_written", c_int), ("n_sources", c_int),
                ("sources", c_void_p), ("wall", c_double), ("ticks", c_ulonglong),
                ("terminate", c_int), ("last_successful_time", c_double), ("n_stimuli", c_int),
                ("stimuli", c_void_p)]


class _AcSim(Structure):
    _fields_ = [("n_units", c_int), ("units", c_void_p), ("period", c_int), ("op_start", c_void_p),
                ("op_kind", c_void_p), ("op_unit", c_void_p), ("start", c_double), ("h", c_double),
                ("can", c_void_p), ("n_cols", c_int), ("n_runs", c_int), ("runs", c_void_p), ("table", c_void_p),
                ("fail_unit", c_int), ("fail_function", c_int), ("fail_status", c_int), ("fail_k", c_long),
                ("wall", c_double), ("lsbus", c_void_p)]


class _AcSettle(Structure):
    _fields_ = [("order", c_void_p), ("n_order", c_int), ("gauss_seidel", c_int), ("max_iter", c_int),
                ("can", c_void_p), ("before", c_void_p), ("exit_init", c_void_p), ("fmu_wall", c_double),
                ("rounds", c_int),
                ("can_settles", c_long)]


class _AcRecRun(Structure):
    _fields_ = [("src", c_void_p), ("col", c_int), ("n", c_int)]


_core_libs = {}


def core_library_path():
    """$ARTIBUS_CORE_LIB, else the build next to the FMUs in use: with
    $ARTIBUS_FMU_DIR = <build>/fmus (the sanitizer build's FMUs) its
    <build>/lib/libartibus_core.so when built, else build/lib's."""
    if os.environ.get("ARTIBUS_CORE_LIB"):
        return Path(os.environ["ARTIBUS_CORE_LIB"])
    name = "libartibus_core.so"
    fmus = os.environ.get("ARTIBUS_FMU_DIR")
    if fmus and (Path(fmus).parent / "lib" / name).is_file():
        return Path(fmus).parent / "lib" / name
    return ROOT / "build" / "lib" / name


def _core_library():
    """(the loaded core library, None) or (None, why not)."""
    path = core_library_path()
    if path in _core_libs:
        return _core_libs[path]
    if not path.is_file():
        return None, f"{path} is not built"
    try:
        lib = CDLL(str(path))
    except OSError as e:
        return None, f"{path}: {e}"
    lib.artibus_core_abi.restype = c_int
    if lib.artibus_core_abi() != CORE_ABI:
        got = None, f"{path} is of another version (ABI {lib.artibus_core_abi()}, expected {CORE_ABI})"
    else:
        lib.artibus_core_record_start.argtypes = [c_void_p]
        lib.artibus_core_record_start.restype = None
        lib.artibus_core_run.argtypes = [c_void_p, c_long, c_long]
        lib.artibus_core_run.restype = c_int
        lib.artibus_core_can_settle.argtypes = [c_void_p]
        lib.artibus_core_can_settle.restype = c_int
        lib.artibus_core_settle.argtypes = [c_void_p, c_void_p]
        lib.artibus_core_settle.restype = c_int
        got = lib, None
    _core_libs[path] = got
    return got


def _core_stepper(sim, plan, plan_gs=None, core=None):
    """The C core set up for this run of ``sim``, or None where it does not
    apply: then today's Python loop runs. ``sim.stepping`` says which, and
    why. core: None (use it where it applies, unless ARTIBUS_CORE=0), True
    (it must apply: ArtibusError otherwise), False (the Python loop)."""
    if core is None:
        core = os.environ.get("ARTIBUS_CORE", "1").strip() not in ("0", "")
        why = None if core else "switched off (ARTIBUS_CORE=0)"
        forced = False
    else:
        why = None if core else "switched off (core=False)"
        forced = bool(core)
    lib = None
    if why is None:
        if sim.can is not None and sim.can.core_support() is not None:
            why = f"connections routed over CAN with {sim.can.core_support()} (the network ticks in Python)"
        elif any(u.stimuli for u in sim.units) and _lsbus_stimuli(sim) is None:
            why = "stimuli (Python functions of time)"
        elif any(u.tout or u.tin for u in sim.units):
            why = "Integer, Boolean, String or Enumeration variables connected or recorded (the core does Real)"
        else:
            lib, why = _core_library()
    if why is not None:
        sim.stepping = f"Python loop: {why}"
        if forced:
            raise ArtibusError(f"{sim.bench.file}: the C stepping core does not apply: {why}")
        return None
    sim.stepping = "C core"
    return _CoreStepper(sim, lib, plan)


def _lsbus_stimuli(sim):
    """{unit index: [core.h's ac_stimulus]} when every stimulus is an FMI-LS-BUS network's
    output onto the plant (artibus.runner.lsbus_core), else None"""
    if getattr(sim.can, "core_values", None) is None:
        return None
    from artibus.runner.lsbus_core import core_stimuli
    return core_stimuli(sim.can, sim)


class _CoreStepper:
    """The plan and the units as core.h's plain structs, over _RawCalls' buffers."""

    def __init__(self, sim, lib, plan):
        self.sim, self.lib, self.plan = sim, lib, plan
        units = sim.units
        index = {id(u): i for i, u in enumerate(units)}
        double = sizeof(c_double)
        self._keep = []                                  # ctypes objects the structs point into
        self.units = (_AcUnit * len(units))()
        self.written = []
        lsbus = getattr(sim.can, "core_values", None) is not None
        stimuli = _lsbus_stimuli(sim) if lsbus else {}
        for j, s in enumerate(self.units):           # the FMI-LS-BUS network's outputs onto the plant
            if j in stimuli:
                arr = (type(stimuli[j][0]) * len(stimuli[j]))(*stimuli[j])
                self._keep.append(arr)
                s.n_stimuli, s.stimuli = len(stimuli[j]), addressof(arr)
        for s, u in zip(self.units, units):
            raw = u.raw
            sources = (_AcSource * max(1, len(u.sources)))()
            for q, (i, out, j, factor, offset) in zip(sources, u.sources):
                q.dst = addressof(raw.inp) + double * i
                q.src = addressof(out) + double * j
                q.factor, q.offset = factor, offset
            written = (c_double * max(1, raw.n_in))()
            self._keep += [sources, written]
            self.written.append(written)
            s.component, s.fmi = raw.comp.value, raw.fmi
            calls = [cast(f, c_void_p).value for f in (raw._do, raw._get, raw._set)]
            if raw.fmi == 3:
                s.doStep3, s.getFloat64, s.setFloat64 = calls
            else:
                s.doStep, s.getReal, s.setReal = calls
            s.step, s.n_out, s.n_in = u.step, raw.n_out, raw.n_in
            s.out_vrs, s.out = addressof(raw.out_vrs), addressof(raw.out)
            s.in_vrs, s.inp = addressof(raw.in_vrs), addressof(raw.inp)
            s.written, s.n_sources, s.sources = addressof(written), len(u.sources), addressof(sources)
        self._index = index
        # the plan as Simulation.run's loop walks it: per base step of the period, (op, unit);
        # a plan too long to tabulate (_Plan.table None) is given to the core a window
        # of CORE_PIECE base steps at a time (see _window)
        if plan.table is not None:
            self._ops(range(plan.period), plan.period)
        # recording: the Recorder's columns, each a place in an output buffer, as runs
        # of consecutive outputs; with a CAN network, a column per message after them
        # for its sinceGood, filled by Simulation._with_can_columns after the run (no
        # copy of the table to add them; the core leaves them)
        if lsbus:                                        # an FMI-LS-BUS network: ticked by the core too
            from artibus.runner.lsbus_core import _LsBusCore
            self.can = _LsBusCore(sim, lib)
        else:
            self.can = _CanCore(sim, lib) if sim.can is not None else None
        self.lsbus = lsbus
        self.extra = len(sim.can.messages) if sim.can is not None and not lsbus else 0
        runs = []                                        # [address, first column, length]
        for col, (u, n) in enumerate(sim.record, start=1):
            a = addressof(u.raw.out) + double * u.out_names.index(n)
            if runs and runs[-1][0] + double * runs[-1][2] == a:
                runs[-1][2] += 1
            else:
                runs.append([a, col, 1])
        self.runs = (_AcRecRun * max(1, len(runs)))(*(tuple(r) for r in runs))
        # core.h's ac_sim of the run: all but the start, the step and the table (run sets those)
        self.struct = s = _AcSim(n_units=len(units), units=addressof(self.units), n_cols=len(sim.names) + self.extra,
                                 n_runs=len(runs), runs=addressof(self.runs))
        if plan.table is not None:
            s.period, s.op_start = self.period, addressof(self.op_start)
            s.op_kind, s.op_unit = addressof(self.op_kind), addressof(self.op_unit)
        self._struct_ref = byref(s)
        self._each = [(a, u, u.raw, written) for a, u, written in zip(self.units, units, self.written)]
        # core.h's ac_settle of the initialisation (settle): the order, the algorithm,
        # the network, a scratch for the inputs before each round, and the FMUs'
        # fmi2/fmi3ExitInitializationMode (FMPy's call, without its call logger when none is set)
        order = (c_int * max(1, len(sim.order)))(*(index[id(u)] for u in sim.order))
        before = (c_double * max(1, sum(u.raw.n_in for u in units)))()
        exits = None
        if all(u.fmu.slave.fmiCallLogger is None for u in units):
            exits = (c_void_p * len(units))(
                *(cast(getattr(u.fmu.slave.dll, f"fmi{u.fmu.fmi}ExitInitializationMode"), c_void_p).value
                  for u in units))
        self._keep += [order, before, exits]
        self.settling = _AcSettle(order=addressof(order), n_order=len(sim.order),
                                  gauss_seidel=sim.algorithm == "gauss-seidel", before=addressof(before),
                                  can=addressof(self.can.c) if self.can is not None and not lsbus else None,
                                  exit_init=addressof(exits) if exits is not None else None)
        self._settle_refs = (self._struct_ref, byref(self.settling))
        self._inputs = [(a, raw, written) for a, _, raw, written in self._each if raw.n_in]

    def settle(self, max_iter):
        """Simulation._initialize's rounds to the fixed point of the connected inputs
        (artibus_core_settle): the same reads, propagations, writes and network settles
        in the same order on the same buffers, the same test (_settled), the same
        errors (self.sim._busy the failing unit); then, unless an FMU has FMPy's call
        logger, each unit's fmi2ExitInitializationMode and read: True if so. At most
        max_iter rounds (Simulation's MAX_INIT_ITERATIONS). The time inside the FMUs'
        calls there is added to sim.settle_wall (seconds)."""
        sim, s, z = self.sim, self.struct, self.settling
        if self.can is not None and not self.lsbus:    # (_CanCore.settle: the counters in)
            for a, m in zip(self.can.messages, self.can.net.messages):
                a.counter = m.counter
        z.max_iter, z.fmu_wall = max_iter, 0.0
        try:
            failed = self.lib.artibus_core_settle(*self._settle_refs)
        finally:
            sim.settle_wall = getattr(sim, "settle_wall", 0.0) + z.fmu_wall
            for a, raw, written in self._inputs:
                raw.written = bytes(written) if a.has_written else None
        if self.can is not None and not self.lsbus:    # the messages settled: all once the network settled once
            ms = self.can.net.messages
            for m in ms if z.can_settles > 0 else ms[:s.fail_unit] if failed == _AC_CAN else ():
                m.last_counter = None
                m.good_tick = -m.ratio
        if failed == _AC_CAN:              # Network._encode raises its error (t = nan in the initialisation)
            self.can.refused(s.fail_unit, float("nan"))
        if failed == _AC_UNSETTLED:
            raise ArtibusError(f"{sim.bench.file}: initialisation did not settle in "
                               f"{max_iter} iterations of the connected inputs")
        if failed:
            sim._busy = u = sim.units[s.fail_unit]
            function = {_AC_GET_REAL: "GetReal", _AC_SET_REAL: "SetReal", _AC_EXIT_INIT: "ExitInitializationMode"}
            name = function[failed].replace("Real", "Float64") if u.fmu.fmi == 3 else function[failed]
            raise FMICallException(function=f"fmi{u.fmu.fmi}{name}", status=s.fail_status)
        return z.exit_init is not None

    def _ops(self, steps, period):
        """op_start/op_kind/op_unit for the core: entry p (0 <= p < period) does base
        step steps[p]'s operations (the core does those of entry k % period at step k)."""
        sim, index = self.sim, self._index
        kinds, who, start = [], [], [0]
        for k in steps:
            starting, ending, gs = self.plan[k] if k is not None else ((), (), ())
            if sim.algorithm == "jacobi":
                ops = ([(_AC_PROPAGATE, u) for u in starting] + [(_AC_WRITE, u) for u in starting]
                       + [(_AC_STEP, u) for u in ending])
            else:
                ops = []
                for u, starts, ends in gs:
                    if starts:
                        ops += [(_AC_PROPAGATE, u), (_AC_WRITE, u)]
                    if ends:
                        ops.append((_AC_STEP, u))
            kinds += [k for k, _ in ops]
            who += [index[id(u)] for _, u in ops]
            start.append(len(kinds))
        self.op_start = (c_int * len(start))(*start)
        self.op_kind = (c_int * max(1, len(kinds)))(*kinds)
        self.op_unit = (c_int * max(1, len(who)))(*who)
        self.period = period

    def _window(self, s, k0, k1):
        """The plan of base steps k0 .. k1 - 1 (k1 - k0 <= CORE_PIECE) as a period of
        CORE_PIECE entries: step k is entry k % CORE_PIECE, distinct for the steps of
        one window. Memory bounded whatever the plan's period."""
        w = CORE_PIECE
        steps = [None] * w
        for k in range(k0, k1):
            steps[k % w] = k
        self._ops(steps, w)
        s.period, s.op_start = self.period, addressof(self.op_start)
        s.op_kind, s.op_unit = addressof(self.op_kind), addressof(self.op_unit)

    def allocate(self, n):
        """The run's preallocated table for n base steps (n + 1 rows; see __init__: the
        CAN columns) and its Result, in the run's set-up (as the Python loop's recorder):
        memory recycled from tables no longer referred to (artibus.runner.tables: no page faults
        on memory in use already); the core fills it."""
        m = len(self.sim.names)
        self.table, self.struct.table = tables.take(n + 1, m + self.extra)
        self.result = Result.from_array(self.sim.names, self.table[:, :m] if self.extra else self.table)

    def run(self, start, h, n, progress):
        """Base steps 0 .. n - 1 from the initialised state into the table of
        allocate(n): the Result, or SimulationError with the results up to the
        failure, as the Python loop."""
        sim, s = self.sim, self.struct
        m = len(sim.names)
        table, result = self.table, self.result
        assert len(table) == n + 1, "allocate(n) first"
        windowed = self.plan.table is None
        s.start, s.h, s.wall = start, h, 0.0
        if self.lsbus:
            s.lsbus = self.can.begin(n)
        elif self.can is not None:
            s.can = self.can.begin(n)
        for a, _, raw, written in self._each:    # (the structs are new: a stepper per run)
            if raw.written is not None:
                a.has_written = 1
                memmove(written, raw.written, len(raw.written))
        lib, ref = self.lib, self._struct_ref
        lib.artibus_core_record_start(ref)
        every = max(1, n // 50)
        # in pieces, so that Ctrl-C is seen between them (KeyboardInterrupt, as in
        # the Python loop); with the progress bar ending where the Python loop draws it
        ends = [k + 1 for k in range(0, n, every)] if progress else list(range(CORE_PIECE, n, CORE_PIECE))
        ends.append(n)
        if windowed:                 # no piece longer than a window of the plan
            ends = sorted(set(ends) | set(range(CORE_PIECE, n, CORE_PIECE)))
        k0, failed = 0, 0
        try:
            for k1 in ends:
                if k1 <= k0:
                    continue
                if windowed:
                    self._window(s, k0, k1)
                failed = lib.artibus_core_run(ref, k0, k1)
                if failed:
                    break
                k0 = k1
                if progress and (k1 - 1) % every == 0:
                    t = start + k1 * h
                    sys.stderr.write(f"\r{sim.bench.name}: t = {t:8.2f} s  [{'#' * (50 * k1 // n):50s}]")
        except KeyboardInterrupt as e:     # Ctrl-C or SIGTERM (artibus.cli): the rows done go with it
            e.result = Result.from_array(sim.names, table[:k0 + 1, :m].copy())
            raise
        finally:
            # s inside artibus_core_run (the FMUs' calls and the network's ticks too), added as their walls are
            sim.core_wall = getattr(sim, "core_wall", 0.0) + s.wall
            for a, u, raw, written in self._each:
                u.wall += a.wall
                if a.has_written:            # (n_in >= 1 doubles)
                    raw.written = bytes(written)
            if self.can is not None:
                self.can.end(start, h)
        if failed == _AC_LSBUS:        # the network's tick failed: the Python master's error
            raise self.can.failure(start + s.fail_k * h)
        if failed == _AC_CAN:          # a frame the encoder refused: artibus.can says why, as in the Python loop
            self.can.refused(s.fail_unit, start + s.fail_k * h)
        if failed == _AC_DO_STEP:      # fmi2Discard with fmi2Terminated: the FMU's own end, as the Python loop
            k = s.fail_k
            a, raw = self.units[s.fail_unit], sim.units[s.fail_unit].raw    # (FMI 3.0: terminateSimulation)
            raw.terminate, raw.last_successful_time = bool(a.terminate), a.last_successful_time
            end = sim._end_of(sim.units[s.fail_unit], s.fail_status, self.plan, k, start + k * h, h)
            if end is not None:
                row = table[k + 1]
                row[0] = start + (k + 1) * h
                for col, (u, name) in enumerate(sim.record, start=1):
                    row[col] = u.raw.out[u.out_names.index(name)]
                if progress:
                    sys.stderr.write("\n")
                result = Result.from_array(sim.names, table[:k + 2, :m])
                result.terminated = end
                return result
        if failed:
            k = s.fail_k
            u = sim.units[s.fail_unit]
            t = start + k * h
            log = u.fmu.log
            raise SimulationError(f"{sim.ssp}: component '{u.path}' failed at t = {t:g} s: "
                                  f"{_last_message(log)}",
                                  Result.from_array(sim.names, table[:k + 1, :m].copy()), list(log))
        if progress:
            sys.stderr.write("\n")
        return result
