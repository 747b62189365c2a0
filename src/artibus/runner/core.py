"""The one stepping loop (issues 13, 37): a bench's run in the C core.

Simulation.run's loop over the base steps (the networks' ticks; propagate, set, step,
get as the plan says; record) done by <build>/lib/libartibus_core.so
(src/runner_core/core.c) through the FMUs' own fmi2SetReal/fmi2DoStep/fmi2GetReal (an
FMI 3.0 FMU's fmi3SetFloat64/fmi3DoStep/fmi3GetFloat64), on _RawCalls' buffers; the
initialisation's rounds to the fixed point of the connected inputs too
(_CoreStepper.settle), and an FMU's own end of the run (the base step finished by the
others, recorded: AC_ENDED). Python sets the bench up, builds the plan (artibus.runner.plan)
and the structs (from the library's own layout, artibus.runner.corelib), and turns the
core's failures into errors. There is no other loop.

What the core does not do in C it calls back for (_Hooks, core.h's ac_hook): a unit's
Integer, Boolean, String and Enumeration variables (FMPy's calls, _TypedCalls), stimuli
(Python functions of time: artibus bode's sine), and a network that ticks in Python: a CAN
network with faults, a tamper function, a real interface or signals the C codec does not
encode (Network.core_support), an FMI-LS-BUS network the C master does not take
(LsBusSteering.core_support). Otherwise the networks tick in C too: CAN (_CanCore,
artibus.can.Network.tick's frames, codec, E2E, counts, bits and since series) and
FMI-LS-BUS (_LsBusCore, src/runner_core/lsbus.c: lsbus.Network.advance on FMPy's
instances). run(core=False) (or ARTIBUS_CORE=0) ticks every network in Python, its
reference implementation (tests/test_can_core.py, tests/test_lsbus_core.py hold the C
networks to them); Simulation.stepping says what ran where.
"""
import os
import sys
from ctypes import CFUNCTYPE, addressof, byref, c_double, c_int, c_long, c_void_p, cast, memmove, sizeof

from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
from artibus.fmu import Result, SimulationError, Termination
from artibus.runner import corelib, tables
from artibus.runner.can_core import _CanCore
from artibus.runner.corelib import struct
from artibus.runner.markers import mark
from artibus.runner.unit import _last_message

CORE_PIECE = 5000                  # base steps per call into the core (without the progress bar)
# core.h's failures: the function that failed, or what stopped the core
_AC_DO_STEP, _AC_GET_REAL, _AC_SET_REAL, _AC_CAN, _AC_UNSETTLED, _AC_EXIT_INIT = 1, 2, 3, 4, 5, 6
_AC_LSBUS, _AC_HOOK, _AC_ENDED = 7, 8, 9
# core.h's ac_hook calls
_HOOK_PROPAGATE, _HOOK_READ, _HOOK_WRITE, _HOOK_TICK, _HOOK_SETTLE, _HOOK_SNAPSHOT, _HOOK_SETTLED = \
    1, 2, 4, 8, 16, 32, 64
_HOOK_TYPE = CFUNCTYPE(c_int, c_int, c_int, c_long, c_double)


def _core_stepper(sim, plan, core=None):
    """The C core set up for this run of ``sim``; sim.stepping says what runs in C and
    what in Python, and why. core: None (the networks in C where C has them, unless
    ARTIBUS_CORE=0), True (the same), False (every network in Python: its reference
    implementation). An unbuilt or foreign library is an error naming it."""
    if core is None:
        core = os.environ.get("ARTIBUS_CORE", "1").strip() not in ("0", "")
        off = None if core else "switched off (ARTIBUS_CORE=0)"
    else:
        off = None if core else "switched off (core=False)"
    lib, why = corelib.load()
    if lib is None:
        raise ArtibusError(f"{sim.bench.file}: the C stepping core: {why} (scripts/setup.sh builds it)")
    python_net = _python_network(sim, off)
    lsbus_c = python_net is None and sim.lsbus is not None
    c_stimuli = _lsbus_stimuli(sim) if lsbus_c else None
    if lsbus_c and c_stimuli is None:      # a stimulus of another origin on the plant: the network in Python
        python_net = "a stimulus of the user's own on the plant"
    in_python = []
    if python_net is not None:
        in_python.append(f"the network, {python_net}")
    if any(u.stimuli for u in sim.units) and c_stimuli is None:
        in_python.append("stimuli (Python functions of time)")
    if any(u.tout or u.tin for u in sim.units):
        in_python.append("Integer, Boolean, String or Enumeration variables")
    sim.stepping = "C core" + ("; in Python: " + "; ".join(in_python) if in_python else "")
    return _CoreStepper(sim, lib, plan, python_net is not None, c_stimuli)


def _python_network(sim, off):
    """Why the bench's network ticks in Python (None: it ticks in C, or there is none)."""
    if sim.network is None:
        return None
    return off if off is not None else sim.network.core_support()


def _lsbus_stimuli(sim):
    """{unit index: [core.h's ac_stimulus]} when every stimulus is an FMI-LS-BUS network's
    output onto the plant (artibus.runner.lsbus_core), else None"""
    if sim.lsbus is None:
        return None
    from artibus.runner.lsbus_core import core_stimuli
    return core_stimuli(sim.lsbus, sim)


class _Hooks:
    """core.h's ac_hook: the parts of the one loop the core calls back for (see the module's
    docstring), the same Python code the units' and networks' own methods are. An exception
    (an FMU call that failed, Ctrl-C, a network's error) is kept in ``error`` with the unit
    (``unit``, -1: the network) and the core stops (AC_HOOK); _CoreStepper raises it."""

    def __init__(self, sim, network, stimuli):
        self.sim, self.units, self.network, self.stimuli = sim, sim.units, network, stimuli
        self.typed = [u for u in sim.units if u.tin]
        self.error, self.unit, self.snapshot = None, -1, None
        self.c = _HOOK_TYPE(self)

    def flags(self, u):
        """The hooks a unit needs (core.h's ac_unit.hooks)."""
        return ((_HOOK_PROPAGATE if u.typed_sources or (u.stimuli and self.stimuli) else 0)
                | (_HOOK_READ if u.tout else 0) | (_HOOK_WRITE if u.tin else 0))

    def __call__(self, what, unit, k, t):
        try:
            if what == _HOOK_PROPAGATE:
                self.propagate(self.units[unit], t)
            elif what == _HOOK_READ:
                self.units[unit].raw.read_typed()
            elif what == _HOOK_WRITE:
                self.units[unit].raw.write_typed()
            elif what == _HOOK_TICK:
                self.network.tick(k, t)
            elif what == _HOOK_SETTLE:
                self.network.settle()
            elif what == _HOOK_SNAPSHOT:
                self.snapshot = [list(u.raw.tin_values) for u in self.typed]
            elif what == _HOOK_SETTLED:
                return int(self.snapshot != [list(u.raw.tin_values) for u in self.typed])
            return 0
        except BaseException as e:        # (nothing may unwind through C)
            self.error, self.unit = e, unit
            return -1

    def propagate(self, to, t):
        """Simulation._propagate's part in Python, after the core's sources: the typed
        sources, then the stimuli (added to the connection's value or the base value)."""
        for i, src, j, convert in to.typed_sources:
            x = src.raw.tout_values[j]
            to.raw.tin_values[i] = x if convert is None else convert(x)
        if self.stimuli:
            inp = to.in_values
            for i, f, base in to.stimuli:
                inp[i] = (inp[i] if base is None else base) + f(t)

    def raise_error(self):
        e, self.error = self.error, None
        raise e


class _CoreStepper:
    """The plan and the units as core.h's plain structs, over _RawCalls' buffers."""

    def __init__(self, sim, lib, plan, python_net=False, c_stimuli=None):
        """python_net: the bench's network ticks in Python (_Hooks); c_stimuli: the
        FMI-LS-BUS network's outputs onto the plant in C ({unit index: [ac_stimulus]}),
        None: every stimulus in Python."""
        self.sim, self.lib, self.plan = sim, lib, plan
        self._keep = []                                  # ctypes objects the structs point into
        self._index = {id(u): i for i, u in enumerate(sim.units)}
        self.hooks = _Hooks(sim, sim.network if python_net else None, c_stimuli is None)
        self._units(c_stimuli or {})
        # the plan as the loop walks it: per base step of the period, (op, unit); a plan
        # too long to tabulate (_Plan.table None) is given to the core a window of
        # CORE_PIECE base steps at a time (see _window)
        if plan.table is not None:
            self._ops(range(plan.period), plan.period)
        self._network(python_net, c_stimuli is not None)
        self._sim_struct(python_net)
        self._settle_struct(python_net)

    def _units(self, c_stimuli):
        """core.h's ac_unit of each unit: its FMU's functions, buffers, sources, C stimuli, hooks."""
        units, double = self.sim.units, sizeof(c_double)
        self.units = (struct("ac_unit") * len(units))()
        self.written, self.sources = [], []
        for j, (s, u) in enumerate(zip(self.units, units)):
            raw = u.raw
            if j in c_stimuli:                       # the FMI-LS-BUS network's outputs onto the plant
                arr = (type(c_stimuli[j][0]) * len(c_stimuli[j]))(*c_stimuli[j])
                self._keep.append(arr)
                s.n_stimuli, s.stimuli = len(c_stimuli[j]), addressof(arr)
            sources = (struct("ac_source") * max(1, len(u.sources)))()
            self.sources.append(sources)
            for q, (i, out, jj, factor, offset) in zip(sources, u.sources):
                q.dst = addressof(raw.inp) + double * i
                q.src = addressof(out) + double * jj
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
                s.getBooleanStatus, s.getRealStatus = raw.status_functions
            s.step, s.n_out, s.n_in = u.step, getattr(raw, "n_real", raw.n_out), raw.n_in
            s.out_vrs, s.out = addressof(raw.out_vrs), addressof(raw.out)
            s.in_vrs, s.inp = addressof(raw.in_vrs), addressof(raw.inp)
            s.written, s.n_sources, s.sources = addressof(written), len(u.sources), addressof(sources)
            s.hooks = self.hooks.flags(u)
            s.early = getattr(u, "early", 0)        # (a sampled unit's stated timing: runner.plan)
        self._each = [(a, u, u.raw, written) for a, u, written in zip(self.units, units, self.written)]

    def _network(self, python_net, lsbus):
        """The bench's network in C (_CanCore, _LsBusCore), or None (none, or in Python);
        with a CAN network, a column per message after the recorded ones for its
        sinceGood, filled by Simulation._with_can_columns after the run (no copy of
        the table to add them; the core leaves them)."""
        sim = self.sim
        self.lsbus = lsbus
        if python_net or sim.network is None:
            self.can = None
        elif lsbus:                                      # an FMI-LS-BUS network: ticked by the core too
            from artibus.runner.lsbus_core import _LsBusCore
            self.can = _LsBusCore(sim, self.lib)
        else:
            self.can = _CanCore(sim, self.lib)
        self.extra = len(sim.can.messages) if sim.can is not None else 0

    def _sim_struct(self, python_net):
        """core.h's ac_sim of the run: all but the start, the step and the table (run sets
        those); recording: each column a place in an output buffer, as runs of
        consecutive outputs."""
        sim, double = self.sim, sizeof(c_double)
        runs = []                                        # [address, first column, length]
        for col, (u, n) in enumerate(sim.record, start=1):
            a = addressof(u.raw.out) + double * u.column(n)
            if runs and runs[-1][0] + double * runs[-1][2] == a:
                runs[-1][2] += 1
            else:
                runs.append([a, col, 1])
        self.runs = (struct("ac_rec_run") * max(1, len(runs)))(*(tuple(r) for r in runs))
        self.struct = s = struct("ac_sim")(n_units=len(sim.units), units=addressof(self.units),
                                           n_cols=len(sim.names) + self.extra, n_runs=len(runs),
                                           runs=addressof(self.runs))
        if self.plan.table is not None:
            s.period, s.op_start = self.period, addressof(self.op_start)
            s.op_kind, s.op_unit = addressof(self.op_kind), addressof(self.op_unit)
        needed = python_net or any(a.hooks for a in self.units)
        s.hook = cast(self.hooks.c, c_void_p).value if needed else None     # (no call into Python)
        s.hook_ratio = sim.network_ratio if python_net else 0
        self._struct_ref = byref(s)

    def _settle_struct(self, python_net):
        """core.h's ac_settle of the initialisation (settle): the order, the algorithm, the
        network, a scratch for the inputs before each round, and the FMUs'
        fmi2/fmi3ExitInitializationMode (FMPy's call, without its call logger when none is set)."""
        sim, units = self.sim, self.sim.units
        order = (c_int * max(1, len(sim.order)))(*(self._index[id(u)] for u in sim.order))
        before = (c_double * max(1, sum(u.raw.n_in for u in units)))()
        exits = None
        if all(u.fmu.slave.fmiCallLogger is None for u in units):
            exits = (c_void_p * len(units))(     # (a Model Exchange unit: its ME facade's, artibus.fmu.me)
                *(u.fmu.calls.facade.exit_function if getattr(u.fmu.calls, "facade", None) is not None else
                  cast(getattr(u.fmu.slave.dll, f"fmi{u.fmu.fmi}ExitInitializationMode"), c_void_p).value
                  for u in units))
        self._keep += [order, before, exits]
        self.settling = struct("ac_settle")(
            order=addressof(order), n_order=len(sim.order), gauss_seidel=sim.algorithm == "gauss-seidel",
            before=addressof(before), hook_settle=bool(python_net),
            can=addressof(self.can.c) if self.can is not None and not self.lsbus else None,
            exit_init=addressof(exits) if exits is not None else None)
        self._settle_refs = (self._struct_ref, byref(self.settling))
        self._inputs = [(a, raw, written) for a, _, raw, written in self._each if raw.n_in]

    def _hold_broken(self):
        """The connections Gauss-Seidel breaks (sim.broken) held at one value through the
        initialisation's rounds, as each carries one value into every step (its source's output
        of the step before): its source's output before the exchange (read once here), so a loop
        through it is not iterated to a fixed point it may not have (gain >= 1). [(the core's
        ac_source, its own src, the held double)], pointed at the held value; settle restores
        them. (A connection of the Python part, an Integer or Boolean one, is iterated still.)"""
        sim = self.sim
        cut = {(w.src, w.output, w.dst, w.input) for w, _ in getattr(sim, "broken", ())}
        held = []
        for u, sources in zip(sim.units, self.sources):
            for k, link in enumerate(u.links_in):
                c = link.connection
                if c is None or (*c.start, *c.end) not in cut:
                    continue
                link.src.raw.read()
                value = c_double(link.src.raw.out[link.src_index])
                q = sources[k]
                held.append((q, q.src, value))
                q.src = addressof(value)
        self._keep += [v for *_, v in held]
        return held

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
        held = self._hold_broken()
        try:
            failed = self.lib.artibus_core_settle(*self._settle_refs)
        finally:
            for q, src, _ in held:
                q.src = src
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
        if failed == _AC_HOOK:             # the exception of the part in Python, its unit the failing one
            sim._busy = sim.units[self.hooks.unit] if self.hooks.unit >= 0 else None
            self.hooks.raise_error()
        if failed:
            sim._busy = u = sim.units[s.fail_unit]
            function = {_AC_GET_REAL: "GetReal", _AC_SET_REAL: "SetReal", _AC_EXIT_INIT: "ExitInitializationMode"}
            name = function[failed].replace("Real", "Float64") if u.fmu.fmi == 3 else function[failed]
            raise FMICallException(function=f"fmi{u.fmu.fmi}{name}", status=s.fail_status)
        return z.exit_init is not None

    def _ops(self, steps, period):
        """op_start/op_kind/op_unit for the core: entry p (0 <= p < period) does base
        step steps[p]'s operations (the core does those of entry k % period at step k)."""
        index, jacobi = self._index, self.sim.algorithm == "jacobi"
        kinds, who, start = [], [], [0]
        for k in steps:
            ops = self.plan.ops(k, jacobi) if k is not None else []
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
        CAN columns) and its Result, in the run's set-up:
        memory recycled from tables no longer referred to (artibus.runner.tables: no page faults
        on memory in use already); the core fills it."""
        m = len(self.sim.names)
        self.table, self.struct.table = tables.take(n + 1, m + self.extra)
        self.result = Result.from_array(self.sim.names, self.table[:, :m] if self.extra else self.table)

    def run(self, start, h, n, progress):
        """Base steps 0 .. n - 1 from the initialised state into the table of
        allocate(n): the Result, or SimulationError with the results up to the
        failure."""
        sim, s = self.sim, self.struct
        m = len(sim.names)
        table = self.table
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
        # a callback); with the progress bar every 2 % of the run
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
                if k1 < n:                   # for the tests: where the run is (artibus.runner.markers)
                    mark(f"t={start + k1 * h!r}")
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
        return self._outcome(failed, start, h, progress)

    def _outcome(self, failed, start, h, progress):
        """The run's Result after artibus_core_run returned ``failed``: the whole table, or
        up to the FMU's own end (Result.terminated), or the error of the failure."""
        sim, s, table, m = self.sim, self.struct, self.table, len(self.sim.names)
        k = s.fail_k
        if failed == _AC_LSBUS:        # the network's tick failed: the Python master's error
            raise self.can.failure(start + k * h)
        if failed == _AC_CAN:          # a frame the encoder refused: artibus.can says why
            self.can.refused(s.fail_unit, start + k * h)
        if failed == _AC_HOOK:         # the part in Python failed: its exception, with the rows done
            return self._hook_failed(start, h, k, m)
        if failed == _AC_ENDED:        # an FMU ended the run: a normal end, the step finished and recorded
            a, u = self.units[s.fail_unit], sim.units[s.fail_unit]
            u.raw.terminate, u.raw.last_successful_time = bool(a.terminate), a.last_successful_time
            t_end = a.last_successful_time
            result = Result.from_array(sim.names, table[:k + 2, :m])
            result.terminated = Termination(u.path, t_end if t_end == t_end else (start + k * h) + h,
                                            "terminateSimulation" if u.raw.fmi == 3 else "fmi2Terminated")
            if progress:
                sys.stderr.write("\n")
            return result
        if failed:
            u, t = sim.units[s.fail_unit], start + k * h
            getattr(u.fmu.calls, "explain", lambda: None)()    # (Model Exchange: the facade's own words)
            after = (f" (after '{sim.units[s.ended_unit].path}' ended the simulation)" if s.ended_unit >= 0
                     else "")
            partial = None if after else Result.from_array(sim.names, table[:k + 1, :m].copy())
            raise SimulationError(f"{sim.ssp}: component '{u.path}' failed at t = {t:g} s{after}: "
                                  f"{_last_message(u.fmu.log)}", partial, list(u.fmu.log))
        if progress:
            sys.stderr.write("\n")
        return self.result

    def _hook_failed(self, start, h, k, m):
        """The exception the part in Python raised in base step k (rows 0 .. k done): Ctrl-C
        with those rows (as between pieces), an FMU call that failed as a SimulationError
        naming its unit, anything else as it is."""
        sim, hooks = self.sim, self.hooks
        e, who = hooks.error, hooks.unit
        rows = Result.from_array(sim.names, self.table[:k + 1, :m].copy())
        if isinstance(e, KeyboardInterrupt):
            e.result = rows
            hooks.raise_error()
        if isinstance(e, FMICallException) and who >= 0:
            u = sim.units[who]
            raise SimulationError(f"{sim.ssp}: component '{u.path}' failed at t = {start + k * h:g} s: "
                                  f"{_last_message(u.fmu.log)}", rows, list(u.fmu.log)) from None
        hooks.raise_error()
