"""The co-simulation master: runs an SSP bench of FMI 2.0 co-simulation FMUs.

- parameters from the bench's bindings (.ssv inside the .ssp), then from
  ``--ssv`` files and ``--set comp.var=value`` given by the user;
- every value checked against the FMU's declared type (artibus.parameters.coerce);
- connections between component variables, through nested systems, with SSP
  linear transformations; without one, values are converted between the
  connected variables' units (FMI unit definitions, base units and factor/offset);
  Integer, Boolean, String and Enumeration connections join variables of one
  type, exactly, with SSP's mapping transformations (_TypedCalls, _typed_convert);
- initialisation: every FMU in initialization mode, connected inputs set from
  the outputs they are connected to, repeated to a fixed point (bounded);
- stepping: Gauss-Seidel in an order derived from the connection graph (an
  algebraic loop of direct feedthrough is an error naming it), or Jacobi;
  multi-rate: each component has its own communication step, a multiple of the
  base step; slower components hold their inputs;
- one batched getReal/setReal per component per step;
- recording of every connection (or a chosen list) at every base step, of any
  type (a Boolean as 0/1, a String's text in Result.strings);
- on a failure midway, the results so far are kept with the failing time and
  the FMU's log.
"""
import math
import os
import shutil
import sys
from ctypes import (CDLL, Structure, addressof, byref, c_double, c_int, c_long, c_longlong, c_size_t,
                    c_ubyte, c_uint, c_ulonglong, c_void_p, cast, memmove, sizeof, string_at)
import tempfile
import time as _time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from fmpy.fmi1 import FMICallException

from artibus.base import ROOT, ArtibusError
from artibus.bench.parameters import check_against
from artibus.fmu.instance import Fmu, Result, SimulationError
from artibus.bench import ssp as ssp_mod
from artibus.runner import tables

MAX_INIT_ITERATIONS = 50


@dataclass
class Link:
    """One connection, resolved to value references."""
    src: "Unit"
    src_index: int          # index into src.out_vrs
    dst: "Unit"
    dst_index: int          # index into dst.in_vrs
    factor: float
    offset: float
    name: str
    connection: object = None   # the bench's Connection (ssp.Connection)


@dataclass(eq=False)        # a unit is itself: compared by identity
class Unit:
    """A component while it runs."""
    path: str
    fmu: Fmu
    step: float
    ratio: int = 1                               # step / base step
    in_vrs: list = field(default_factory=list)   # Real inputs that are connected
    in_names: list = field(default_factory=list)
    out_vrs: list = field(default_factory=list)  # Real outputs that are read
    out_names: list = field(default_factory=list)
    out_values: list = field(default_factory=list)
    in_values: list = field(default_factory=list)
    feeds: set = field(default_factory=set)      # (input name, output name) direct feedthrough
    links_in: list = field(default_factory=list)  # the Links into its inputs
    sources: list = field(default_factory=list)   # the same Links as (input index, source
                                                  # output buffer, output index, factor, offset)
    stimuli: list = field(default_factory=list)   # (input index, f(t), base value or None)
    wall: float = 0.0
    raw: object = None                           # _RawCalls, once the variables are known
    # Integer, Boolean, String and Enumeration variables (artibus.runner._TypedCalls):
    tout: list = field(default_factory=list)     # outputs read: (name, type, value reference)
    tin: list = field(default_factory=list)      # connected inputs: (name, type, value reference)
    typed_sources: list = field(default_factory=list)  # (input index, source unit, output index, convert)

    def column(self, name):
        """The place of an output in raw.out (Real ones first, then the typed ones)."""
        if name in self.out_names:
            return self.out_names.index(name)
        return len(self.out_names) + [n for n, _, _ in self.tout].index(name)


class _RawCalls:
    """fmi2GetReal/SetReal/DoStep called through ctypes directly, with the value
    references and value buffers allocated once: one call per component and
    step, without FMPy's per-call wrapper (it logs and converts lists). The
    functions come from a handle of our own on the FMU's library (FMPy's are
    left as they are) and get ctypes objects made once, not Python values to
    convert at every call."""

    def __init__(self, unit):
        dll = CDLL(unit.fmu.slave.dll._name)      # the library FMPy loaded: the same instance
        self._get, self._set, self._do = dll.fmi2GetReal, dll.fmi2SetReal, dll.fmi2DoStep
        for f in (self._get, self._set, self._do):
            f.restype = c_int
        self.comp = c_void_p(unit.fmu.slave.component)
        self.n_out, self.n_in = len(unit.out_vrs), len(unit.in_vrs)
        self._n_out, self._n_in = c_size_t(self.n_out), c_size_t(self.n_in)
        self.out_vrs = (c_uint * self.n_out)(*unit.out_vrs)
        self.out = (c_double * self.n_out)()
        self.in_vrs = (c_uint * self.n_in)(*unit.in_vrs)
        self.inp = (c_double * self.n_in)()
        self.written = None       # the input values last set (bytes): unchanged ones are not set again
        self._true = c_int(1)     # noSetFMUStatePriorToCurrentPoint

    def read(self):
        if self.n_out:
            status = self._get(self.comp, self.out_vrs, self._n_out, self.out)
            if status > 1:  # fmi2Discard or worse
                raise FMICallException(function="fmi2GetReal", status=status)

    def write(self):
        if self.n_in:
            values = bytes(self.inp)
            if values == self.written:    # the FMU holds them already (FMI 2.0: inputs keep their values)
                return
            status = self._set(self.comp, self.in_vrs, self._n_in, self.inp)
            if status > 1:
                raise FMICallException(function="fmi2SetReal", status=status)
            self.written = values

    def step(self, t, h):
        status = self._do(self.comp, c_double(t), c_double(h), self._true)
        if status > 1:  # fmi2Discard or worse
            raise FMICallException(function="fmi2DoStep", status=status)


class _TypedCalls(_RawCalls):
    """_RawCalls of a unit with Integer, Boolean, String or Enumeration
    variables connected or recorded: those go through FMPy's calls (one per
    type), after the Real ones. Their values as read are in ``tout_values``
    (Python values) and, for the recording, as numbers after the Real outputs
    in ``out``: a Boolean as 0/1, an Integer or Enumeration as its value, a
    String as the number of its text in ``texts`` (the order in which each
    text was first seen). The inputs to set are in ``tin_values``; unchanged
    ones are not set again. The C stepping core does not run such a bench
    (Simulation.stepping says so)."""

    def __init__(self, unit):
        super().__init__(unit)
        self.slave = unit.fmu.slave
        n_real = self.n_out
        self.n_real, self.n_out = n_real, n_real + len(unit.tout)
        self.out = (c_double * self.n_out)()
        self.tout_values = [None] * len(unit.tout)
        self.tin_values = [None] * len(unit.tin)
        self.tin_written = None
        self.texts = {}
        self._get_groups = self._groups(unit.tout)
        self._set_groups = self._groups(unit.tin)
        self._string_out = [i for i, (_, t, _) in enumerate(unit.tout) if t == "String"]

    @staticmethod
    def _groups(variables):
        """[(FMI type of the call, [indices], [value references])] per type."""
        groups = {}
        for i, (_, t, vr) in enumerate(variables):
            g = groups.setdefault("Integer" if t == "Enumeration" else t, ([], []))
            g[0].append(i)
            g[1].append(vr)
        return [(t, idx, vrs) for t, (idx, vrs) in groups.items()]

    def read(self):
        if self.n_real:
            status = self._get(self.comp, self.out_vrs, self._n_out, self.out)
            if status > 1:  # fmi2Discard or worse
                raise FMICallException(function="fmi2GetReal", status=status)
        for t, idx, vrs in self._get_groups:
            values = getattr(self.slave, f"get{t}")(vrs)
            for i, x in zip(idx, values):
                if t == "String":
                    x = x.decode("utf-8", errors="replace") if x is not None else ""
                    self.out[self.n_real + i] = self.texts.setdefault(x, len(self.texts))
                else:
                    x = bool(x) if t == "Boolean" else int(x)
                    self.out[self.n_real + i] = x
                self.tout_values[i] = x

    def write(self):
        super().write()
        if self.tin_values and self.tin_values != self.tin_written:
            for t, idx, vrs in self._set_groups:
                getattr(self.slave, f"set{t}")(vrs, [self.tin_values[i] for i in idx])
            self.tin_written = list(self.tin_values)

    def text(self, number):
        """The String whose number (see above) a recorded column holds."""
        if not hasattr(self, "_by_number") or len(self._by_number) != len(self.texts):
            self._by_number = {k: x for x, k in self.texts.items()}
        return self._by_number.get(number, "")


def _typed_convert(label, a, va, b, vb, mapping):
    """The conversion of a connection's value from the Integer, Boolean,
    String or Enumeration output va to the input vb: the types must be the
    same (an error naming both ends otherwise); an Enumeration to one of other
    items needs a mapping (SSP 1.0's EnumerationMappingTransformation by item
    names, or IntegerMappingTransformation by values); a mapping (SSP 1.0's
    Boolean-, Integer- or EnumerationMappingTransformation) maps the values
    it lists, the others pass unchanged."""
    ends = (f"{a.path}.{va.name} is {va.type}{' ' + va.declaredType.name if va.declaredType else ''}, "
            f"{b.path}.{vb.name} is {vb.type}{' ' + vb.declaredType.name if vb.declaredType else ''}")
    if va.type != vb.type:
        raise ArtibusError(f"{label}: the types differ ({ends}): a connection joins variables of one type")
    kind, table = mapping if mapping else (None, None)
    expect = {"Boolean": ("Boolean",), "Integer": ("Integer",), "Enumeration": ("Integer", "Enumeration")}
    if kind is not None and kind not in expect.get(va.type, ()):
        raise ArtibusError(f"{label}: a {kind}MappingTransformation does not apply to {ends}")
    if va.type == "Enumeration":
        items_a = {i.name: int(i.value) for i in va.declaredType.items}
        items_b = {i.name: int(i.value) for i in vb.declaredType.items}
        if kind == "Enumeration":
            for src, dst in table.items():
                if src not in items_a or dst not in items_b:
                    raise ArtibusError(f"{label}: EnumerationMappingTransformation {src} -> {dst}: "
                                       f"items of {va.declaredType.name}: {', '.join(items_a)}; "
                                       f"of {vb.declaredType.name}: {', '.join(items_b)}")
            names_a = {k: n for n, k in items_a.items()}
            table = {k: items_b[table.get(name, name)] for k, name in names_a.items()
                     if table.get(name, name) in items_b}
            kind = "Integer"
        elif kind is None and items_a != items_b:
            raise ArtibusError(f"{label}: the enumerations differ ({ends}: items "
                               f"{', '.join(f'{n}={k}' for n, k in items_a.items())} against "
                               f"{', '.join(f'{n}={k}' for n, k in items_b.items())}); "
                               f"an EnumerationMappingTransformation maps them")
    if kind is None:
        return None
    return lambda x: table.get(x, x)


def _last_message(log):
    """The FMU's last error message, else its last message."""
    errors = [m for m in log if m.startswith(("[Error]", "[Fatal]"))]
    return errors[-1] if errors else log[-1] if log else "no message"


def _suggest(name, known):
    from artibus.bench.parameters import suggest
    return suggest(name, known)


def _unit_conversion(md_a, var_a, md_b, var_b, where):
    """factor, offset taking a value in var_a's unit to var_b's unit."""
    ua, ub = _unit_of(md_a, var_a), _unit_of(md_b, var_b)
    if ua is None or ub is None or ua == ub:
        return 1.0, 0.0
    da = {u.name: u for u in md_a.unitDefinitions}.get(ua)
    db = {u.name: u for u in md_b.unitDefinitions}.get(ub)
    if da is None or db is None or da.baseUnit is None or db.baseUnit is None:
        raise ArtibusError(f"{where}: units '{ua}' and '{ub}' differ and one has no base-unit definition")
    dims = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
    if any(getattr(da.baseUnit, d) != getattr(db.baseUnit, d) for d in dims):
        raise ArtibusError(f"{where}: cannot convert '{ua}' to '{ub}': different dimensions")
    fa, oa = da.baseUnit.factor, da.baseUnit.offset
    fb, ob = db.baseUnit.factor, db.baseUnit.offset
    # base = fa*x + oa ; y = (base - ob) / fb
    return fa / fb, (oa - ob) / fb


def _unit_of(md, var):
    if var.unit:
        return var.unit
    if var.declaredType is not None and getattr(var.declaredType, "unit", None):
        return var.declaredType.unit
    return None


def _order(units, links, where):
    """links: (source unit, output name, destination unit, input name) of
    every connection. Gauss-Seidel order: a component whose outputs feed another's inputs
    directly (through feedthrough) goes first. A cycle made only of direct
    feedthrough is an algebraic loop."""
    # graph on (unit, output) -> (unit, input) -> (unit, output via feedthrough)
    feed_edges = {}
    for src, src_out, dst, dst_in in links:      # (source unit, output, destination unit, input)
        for (i, o) in dst.feeds:
            if i == dst_in:
                feed_edges.setdefault((src.path, src_out), []).append(
                    ((dst.path, o), f"{src.path}.{src_out} -> {dst.path}.{dst_in}"))
    # cycle detection on the feedthrough graph
    state, stack = {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m, label in feed_edges.get(n, []):
            if state.get(m) == 1:
                cycle = stack[stack.index(m):] + [m]
                raise ArtibusError(f"{where}: algebraic loop (direct feedthrough all around): "
                                   + " -> ".join(f"{c}.{v}" for c, v in cycle))
            if state.get(m) is None:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in list(feed_edges):
        if state.get(n) is None:
            visit(n)
    # order components: Kahn on "A feeds B through B's feedthrough", then the rest
    deps = {u.path: set() for u in units}
    for src, _, dst, dst_in in links:
        if any(i == dst_in for i, _ in dst.feeds) and src is not dst:
            deps[dst.path].add(src.path)
    ordered, done = [], set()
    while len(ordered) < len(units):
        ready = [u for u in units if u.path not in done and deps[u.path] <= done]
        if not ready:  # cannot happen without an algebraic loop
            ready = [next(u for u in units if u.path not in done)]
        for u in ready:
            ordered.append(u)
            done.add(u.path)
    return ordered


PLAN_TABLE = 4096       # base steps of the plan's period tabulated at most (see _Plan)


def resolve_resources(tmp, where, values, origins=None):
    """A String parameter "resources/<file>" names a file inside the .ssp: its
    value in ``values`` becomes that file's path in the unpacked copy ``tmp``.
    An error names the bench (``where``) and where the value is from
    (``origins[var]``: the parameter file and its element, or --set) where given."""
    for var, value in values.items():
        if isinstance(value, str) and value.startswith("resources/"):
            f = Path(tmp) / value
            if not f.is_file():
                origin = (origins or {}).get(var)
                raise ArtibusError(f"{where}: parameter '{var}' = {value!r}"
                                   + (f" (from {origin})" if origin else "") + ": no such file in the .ssp")
            values[var] = str(f)


def _settled(before, now, tol=1e-12):
    """np.allclose(before, now, rtol=tol, atol=tol), without NumPy's cost on a few
    values: |b - x| <= tol + tol * |x| for each pair, NaN never settled, an infinity
    settled only on itself."""
    return len(before) == len(now) and all(
        b == x or (math.isfinite(x) and abs(b - x) <= tol + tol * abs(x)) for b, x in zip(before, now))


def _available_memory():
    """MemAvailable (bytes) from /proc/meminfo, or None where there is none."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _check_room(rows, cols, where, available=None):
    """The results are a table of rows x cols doubles in memory (every base
    step, every recorded signal): a run whose table would take more than half
    the memory available is refused before it starts, saying what to change,
    rather than ending in a MemoryError or the OOM killer hours later."""
    need = rows * cols * 8
    available = _available_memory() if available is None else available
    if available is not None and need > available // 2:
        raise ArtibusError(f"{where}: {rows} base steps x {cols} columns of results would take "
                           f"{need / 1e9:.3g} GB, more than half the memory available "
                           f"({available / 1e9:.3g} GB): give a larger --step, a shorter --stop-time, "
                           f"or fewer signals with --record")


class _Plan:
    """Which components start and which end their communication step at base
    step k. A component with step H = ratio * h takes its inputs at the start of
    its interval (k % ratio == 0) and publishes its outputs at the end, when the
    others get there ((k + 1) % ratio == 0). The pattern repeats with the period
    lcm(ratios): up to PLAN_TABLE base steps (and never more than the run's n)
    it is tabulated once; beyond (a slow component on a tiny base step: with
    --step 1e-8 a 0.01 s component's period is 10^6 base steps) each step's
    entry is computed when it is asked for, so memory does not grow with the
    period. plan[k] = (starting, ending, gs): gs for Gauss-Seidel, per base
    step in the order, (unit, starts, ends) of those that do either."""

    def __init__(self, order, n):
        self.order = order
        self.period = math.lcm(*(u.ratio for u in order))
        self.table = ([self.entry(k) for k in range(self.period)]
                      if self.period <= min(PLAN_TABLE, max(n, 1)) else None)

    def entry(self, k):
        starting = [u for u in self.order if k % u.ratio == 0]
        ending = [u for u in self.order if (k + 1) % u.ratio == 0]
        gs = [(u, k % u.ratio == 0, (k + 1) % u.ratio == 0) for u in self.order
              if k % u.ratio == 0 or (k + 1) % u.ratio == 0]
        return starting, ending, gs

    def __getitem__(self, k):
        return self.table[k % self.period] if self.table is not None else self.entry(k)


class Simulation:
    """A bench, set up and ready to run."""

    def __init__(self, ssp, step=None, overrides=None, record=None, algorithm="gauss-seidel",
                 stimuli=None, can=None, can_log=None, can_faults=None, cut=None):
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
        row."""
        self.can = None
        if algorithm not in ("gauss-seidel", "jacobi"):
            raise ArtibusError(f"algorithm '{algorithm}': expected gauss-seidel or jacobi")
        self.algorithm = algorithm
        self.ssp = ssp_mod.ssp_path(ssp)
        self.bench = ssp_mod.read(self.ssp)
        where = self.bench.file
        if step is not None and not step > 0:
            raise ArtibusError(f"--step {step}: the communication step must be > 0")
        self._tmp = tempfile.mkdtemp(prefix="artibus-")
        try:
            with zipfile.ZipFile(self.ssp) as z:
                z.extractall(self._tmp)
            self._setup(step, overrides or {}, record, where, stimuli or {}, can, can_log, can_faults,
                        set(cut or ()))
        except BaseException:
            self.close()
            raise

    def _setup(self, step, overrides, record, where, stimuli, can_interface=None, can_log=None, can_faults=None,
               cut=frozenset()):
        units = {}
        for path, c in self.bench.components.items():
            try:
                fmu = Fmu(Path(self._tmp) / c.source, instance_name=path)
            except ArtibusError as e:    # a corrupt or missing FMU: named as the bench names it
                raise ArtibusError(f"{where}:{c.line}: Component '{path}' source=\"{c.source}\": "
                                   + str(e).replace(f"{Path(self._tmp) / c.source}: ", "")) from None
            de = fmu.md.defaultExperiment
            h = c.step or (step if step is not None else
                           float(de.stepSize) if de is not None and de.stepSize else None)
            units[path] = Unit(path=path, fmu=fmu, step=h)
            self.units = list(units.values())     # (closed by close() if a later one fails)
        # a component without a step (its FMU's default experiment has no stepSize, FMI 2.0
        # allows it; no annotation, no --step): the others' shortest, else the bench's
        # span / DEFAULT_STEPS
        from artibus.fmu.instance import DEFAULT_STEPS
        known = [u.step for u in units.values() if u.step is not None]
        for u in units.values():
            if u.step is None:
                if known:
                    u.step = min(known)
                elif self.bench.stop_time is not None and self.bench.stop_time > self.bench.start_time:
                    u.step = (self.bench.stop_time - self.bench.start_time) / DEFAULT_STEPS
                else:
                    c = self.bench.components[u.path]
                    raise ArtibusError(f"{where}:{c.line}: Component '{u.path}': no communication step "
                                       f"(give --step or a stepSize annotation)")
        self.units = list(units.values())
        self.base_step = step if step is not None else min(u.step for u in self.units)
        for u in self.units:
            r = u.step / self.base_step
            if abs(r - round(r)) > 1e-9 or round(r) < 1:
                raise ArtibusError(f"{where}: Component '{u.path}': step {u.step} s is not a "
                                   f"multiple of the base step {self.base_step} s")
            u.ratio = int(round(r))

        # parameters: bindings, then the user's overrides ("comp.var" -> value)
        self.parameters = {p: dict(c.parameters) for p, c in self.bench.components.items()}
        origins = {p: dict(c.origins) for p, c in self.bench.components.items()}
        from artibus.bench.names import expand_all      # Bus.mu[*], Bus.mu[1:6]: each element

        def variables_of(full):
            comp = full.split("[", 1)[0].rpartition(".")[0]
            return (comp + ".", list(units[comp].fmu.vars)) if comp in units else None
        overrides = expand_all(overrides, variables_of)
        for full, value in overrides.items():
            comp, _, var = full.rpartition(".")
            if comp not in self.parameters:
                raise ArtibusError(f"--set {full}={value}: no component '{comp}' in {where}"
                                   f"{_suggest(comp, self.parameters)} (components: {', '.join(self.parameters)})")
            self.parameters[comp][var] = value
            origins.setdefault(comp, {})[var] = "--set/--ssv/--variant"
        for path, values in self.parameters.items():
            resolve_resources(self._tmp, where, values, origins.get(path))
        for path, values in self.parameters.items():
            check_against(values, units[path].fmu.md, where, prefix=f"{path}.", origins=origins.get(path))

        # connections (those into a cut input left out)
        connected = {f"{c.end[0]}.{c.end[1]}" for c in self.bench.connections}
        for name in sorted(cut):
            comp, _, var = name.rpartition(".")
            v = units[comp].fmu.vars.get(var) if comp in units else None
            if v is None or v.causality != "input":
                raise ArtibusError(f"cut {name}: not an input of a component of {where}")
            if name not in connected:
                raise ArtibusError(f"cut {name}: the input is not connected in {where}")
        self.cut = sorted(cut)
        routed_before = any(c.can is not None for c in self.bench.connections)
        self.links = []
        for c in self.bench.connections:
            if f"{c.end[0]}.{c.end[1]}" in cut:
                continue
            label = f"{where}:{c.line}: Connection {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}"
            a, b = units[c.start[0]], units[c.end[0]]
            va, vb = a.fmu.vars.get(c.start[1]), b.fmu.vars.get(c.end[1])
            if va is None or vb is None:
                from artibus.bench.parameters import no_variable
                u, var = (a, c.start[1]) if va is None else (b, c.end[1])
                raise ArtibusError(f"{label}: no variable '{u.path}.{var}' ({no_variable(u.fmu.md, var)})")
            if va.type != vb.type:
                raise ArtibusError(f"{label}: types {va.type} -> {vb.type} ({c.start[0]}.{c.start[1]} is "
                                   f"{va.type}, {c.end[0]}.{c.end[1]} is {vb.type}): a connection joins "
                                   f"variables of one type")
            if va.causality not in ("output", "parameter", "calculatedParameter") or vb.causality != "input":
                raise ArtibusError(f"{label}: connects a {va.causality} to a {vb.causality} "
                                   f"(expected output -> input)")
            if va.type != "Real" or vb.type != "Real":
                self._typed_link(c, label, a, va, b, vb)
                continue
            if c.mapping is not None:
                raise ArtibusError(f"{label}: a {c.mapping[0]}MappingTransformation on Real variables "
                                   f"(a LinearTransformation applies to them)")
            if c.factor != 1.0 or c.offset != 0.0:
                f, o = c.factor, c.offset
            else:
                f, o = _unit_conversion(a.fmu.md, va, b.fmu.md, vb, label)
            if c.start[1] not in a.out_names:
                a.out_names.append(c.start[1])
                a.out_vrs.append(va.valueReference)
            if c.end[1] in b.in_names:
                raise ArtibusError(f"{label}: input {c.end[0]}.{c.end[1]} is connected twice")
            b.in_names.append(c.end[1])
            b.in_vrs.append(vb.valueReference)
            self.links.append(Link(a, a.out_names.index(c.start[1]), b, len(b.in_names) - 1,
                                   f, o, f"{c.end[0]}.{c.end[1]}", c))
            if c.can is None:                 # a connection routed over CAN goes through self.can
                b.links_in.append(self.links[-1])
        self._setup_can(where, can_interface, can_log, can_faults, routed_before)
        # direct feedthrough from the model descriptions
        for u in self.units:
            inputs = [v for v in u.fmu.md.modelVariables if v.causality == "input"]
            for o in u.fmu.md.outputs:
                deps = o.dependencies if o.dependencies is not None else inputs
                for d in deps:
                    if d.causality == "input":
                        u.feeds.add((d.name, o.variable.name))
        self.order = _order(self.units, [(l.src, l.src.out_names[l.src_index], l.dst, l.dst.in_names[l.dst_index])
                                         for l in self.links if l.connection.can is None]
                            + [(src, src.tout[j][0], u, u.tin[i][0])
                               for u in self.units for i, src, j, _ in u.typed_sources], where)

        # recording: every connection's source, plus what was asked for
        self.record = []
        for name in record or []:
            comp, _, var = name.rpartition(".")
            if comp not in units:
                raise ArtibusError(f"--record {name}: no component '{comp}' in {where}"
                                   f"{_suggest(comp, units)} (components: {', '.join(units)})")
            if var not in units[comp].fmu.vars:
                from artibus.bench.parameters import no_variable
                raise ArtibusError(f"--record {name}: {comp}: {no_variable(units[comp].fmu.md, var)}")
            self.record.append((units[comp], var))
        if not record:   # every output connector the bench declares, and every connected output
            for u in self.units:
                for n in dict.fromkeys(self.bench.components[u.path].outputs + u.out_names
                                       + [n for n, _, _ in u.tout]):
                    if n not in u.fmu.vars:
                        raise ArtibusError(f"{where}: Component '{u.path}': connector '{n}' is "
                                           f"not a variable of {u.fmu.md.modelName}")
                    self.record.append((u, n))
        for u, n in self.record:
            v = u.fmu.var(n)
            if v.type != "Real":
                if n not in [m for m, _, _ in u.tout]:
                    u.tout.append((n, v.type, v.valueReference))
            elif n not in u.out_names:
                u.out_names.append(n)
                u.out_vrs.append(v.valueReference)
        for name, f in stimuli.items():       # added to the input: f(t) + its connection or base value
            comp, _, var = name.rpartition(".")
            v = units[comp].fmu.vars.get(var) if comp in units else None
            if v is None or v.causality != "input" or v.type != "Real":
                raise ArtibusError(f"stimulus {name}: not a Real input of a component of {where}")
            u = units[comp]
            if self.can is not None and any(l.dst is u and l.name == name for l in self.can_links):
                raise ArtibusError(f"stimulus {name}: the input is routed over CAN in {where}")
            if var in u.in_names:
                u.stimuli.append((u.in_names.index(var), f, None))
            else:
                u.in_names.append(var)
                u.in_vrs.append(v.valueReference)
                base = float(self.parameters[comp].get(var, v.start))
                u.stimuli.append((len(u.in_names) - 1, f, base))
        for u in self.units:
            u.raw = (_TypedCalls if u.tout or u.tin else _RawCalls)(u)
            u.out_values = u.raw.out      # read and written in place
            u.in_values = u.raw.inp
        for u in self.units:
            u.sources = [(l.dst_index, l.src.raw.out, l.src_index, l.factor, l.offset) for l in u.links_in]
        if self.can is not None:
            self.can.bind()
        self.names = ["time"] + [f"{u.path}.{n}" for u, n in self.record]
        self._col_units = {"time": "s", **{f"{u.path}.{n}": _unit_of(u.fmu.md, u.fmu.vars[n]) or ""
                                           for u, n in self.record}}
        # recording: per component, which of its outputs go to which columns
        self._rec = []
        for u in self.units:
            cols = [k + 1 for k, (v, _) in enumerate(self.record) if v is u]
            idx = [u.column(n) for v, n in self.record if v is u]
            if cols:
                self._rec.append((u, np.array(idx), np.array(cols)))
        # String columns: the recorded numbers turned into their texts (_with_texts)
        self._text_cols = {f"{u.path}.{n}": u for u, n in self.record if u.fmu.vars[n].type == "String"}

    def _typed_link(self, c, label, a, va, b, vb):
        """A connection of Integer, Boolean, String or Enumeration variables (see
        _typed_convert): read and set in Python (_TypedCalls), exact values."""
        convert = _typed_convert(label, a, va, b, vb, c.mapping)
        if c.factor != 1.0 or c.offset != 0.0:
            raise ArtibusError(f"{label}: a LinearTransformation on {va.type} variables "
                               f"(SSP 1.0: it applies to Real ones)")
        if c.can is not None:
            raise ArtibusError(f"{label}: routed over CAN: the runner routes Real variables only")
        if c.end[1] in [n for n, _, _ in b.tin] or c.end[1] in b.in_names:
            raise ArtibusError(f"{label}: input {c.end[0]}.{c.end[1]} is connected twice")
        names = [n for n, _, _ in a.tout]
        if c.start[1] not in names:
            a.tout.append((c.start[1], va.type, va.valueReference))
            names.append(c.start[1])
        b.tin.append((c.end[1], vb.type, vb.valueReference))
        b.typed_sources.append((len(b.tin) - 1, a, names.index(c.start[1]), convert))

    def _with_texts(self, result):
        """A String column's numbers (see _TypedCalls) as Result.strings; the
        columns' units (Result.units: the recorded variables' units from their
        model descriptions, "s" for time, "" for none and the CAN columns)."""
        if result is None:
            return result
        result.units = {n: self._col_units.get(n, "") for n in result.names}
        if not self._text_cols:
            return result
        table = result.array()
        for name, u in self._text_cols.items():
            j = result.names.index(name)
            result.strings[name] = [u.raw.text(int(x)) if np.isfinite(x) else "" for x in table[:, j]]
            table[:, j] = np.nan
        return result

    def _setup_can(self, where, interface, log, faults=None, routed=True):
        """The CAN network of a bench that routes connections over CAN (see artibus.can);
        none when every route was cut (routed: the bench routes some)."""
        self.can_links = [l for l in self.links if l.connection.can is not None]
        spec = self.bench.can
        if spec is not None and routed and not self.can_links:
            if interface is not None or log is not None or faults:
                raise ArtibusError(f"--can/--can-log/--can-fault: every connection {where} routes over CAN "
                                   f"is cut: the run has no network")
            return
        if spec is None:
            if self.can_links:
                c = self.can_links[0].connection
                raise ArtibusError(f"{where}:{c.can['line']}: Connection {c.start[0]}.{c.start[1]} -> "
                                   f"{c.end[0]}.{c.end[1]} is routed over CAN but the System has no "
                                   f"org.artibus.can annotation naming the DBC")
            if interface is not None or log is not None or faults:
                raise ArtibusError(f"--can/--can-log/--can-fault: {where} routes no connection over CAN")
            return
        from artibus import can as can_mod
        self.can = can_mod.Network(self.bench, can_mod.dbc_in(self._tmp, spec), self.can_links,
                                   interface or "virtual", log, faults)
        r = self.can.period / self.base_step
        if abs(r - round(r)) > 1e-9 or round(r) < 1:
            raise ArtibusError(f"{where}:{spec['line']}: the CAN tick {self.can.period} s is not a "
                               f"multiple of the base step {self.base_step} s")
        self.can_ratio = int(round(r))

    # --- the algorithm ---------------------------------------------------------------

    def _step(self, u, t0):
        w = _time.perf_counter()
        raw = u.raw
        raw.step(t0, u.step)
        raw.read()
        u.wall += _time.perf_counter() - w

    def _propagate(self, to=None, t=0.0):
        if to is None:
            for u in self.units:
                self._propagate(u, t)
            return
        inp = to.in_values
        for i, out, j, factor, offset in to.sources:
            inp[i] = factor * out[j] + offset
        for i, src, j, convert in to.typed_sources:
            x = src.raw.tout_values[j]
            to.raw.tin_values[i] = x if convert is None else convert(x)
        for i, f, base in to.stimuli:
            inp[i] = (inp[i] if base is None else base) + f(t)

    def _initialize(self, start):
        for u in self.units:
            self._busy = u            # the unit being called: a failure names it
            s = u.fmu.slave
            s.setupExperiment(startTime=start)
            s.enterInitializationMode()
            u.fmu.set_values(self.parameters[u.path])
            u.raw.written = None      # every connected input is set at least once
        settle, self._settle_core = getattr(self, "_settle_core", None), None   # (no cycle: it refers to self)
        if settle is not None:           # the C core does the rounds, the same, bit for bit (_CoreStepper.settle),
            exited = settle.settle()      # and the exits below unless FMPy logs the calls
        else:
            self._settle(start)
            exited = False
        for u in () if exited else self.units:
            self._busy = u
            u.fmu.slave.exitInitializationMode()
            u.raw.read()
        self._busy = None

    def _settle(self, start):
        """The initialisation's rounds to the fixed point of the connected inputs:
        the inputs of the units that have some (the others are settled as they are);
        _propagate leaves a unit without sources or stimuli as it is."""
        watched = [u for u in self.units if len(u.in_values) or getattr(u.raw, "tin_values", None)]
        fed = [(u, bool(u.sources or u.typed_sources or u.stimuli), bool(u.raw.n_in or u.tin))
               for u in self.order]
        gauss_seidel = self.algorithm == "gauss-seidel"
        for _ in range(MAX_INIT_ITERATIONS):
            before = [(list(u.in_values), list(getattr(u.raw, "tin_values", ()))) for u in watched]
            for u, f, _ in fed:
                self._busy = u
                u.raw.read()
                if not gauss_seidel:
                    self._propagate(None, start)
                elif f:
                    self._propagate(u, start)
            if self.can is not None:     # the core's codec when the core ticks the network (_CanCore.settle)
                (getattr(self, "_core_can", None) or self.can).settle()
            for u, f, w in fed:
                self._busy = u
                if f:
                    self._propagate(u, start)
                if w:                    # (without inputs, write sets nothing)
                    u.raw.write()
            for u in self.units:
                self._busy = u
                u.raw.read()
            if all(_settled(b, u.in_values)
                   and tb == list(getattr(u.raw, "tin_values", ()))
                   for (b, tb), u in zip(before, watched)):
                return
        raise ArtibusError(f"{self.bench.file}: initialisation did not settle in "
                           f"{MAX_INIT_ITERATIONS} iterations of the connected inputs")

    class _Recorder:
        """At every base step a copy of each recorded component's output buffer
        (one memcpy), sorted into the result's columns when it is asked for."""

        def __init__(self, names, rec):
            self.names, self.rec, self.times = names, rec, []
            self.buffers = [(u.raw.out, []) for u, _, _ in rec]

        def take(self, t):
            self.times.append(t)
            for out, copies in self.buffers:
                copies.append(bytes(out))

        def result(self):
            # rows taken whole (an interrupt may have stopped take() midway)
            n = min([len(self.times)] + [len(copies) for _, copies in self.buffers])
            table = np.empty((n, len(self.names)))
            table[:, 0] = self.times[:n]
            for (u, idx, cols), (_, copies) in zip(self.rec, self.buffers):
                values = np.frombuffer(b"".join(copies[:n]), dtype=np.float64).reshape(n, u.raw.n_out)
                table[:, cols] = values[:, idx]
            return Result.from_array(self.names, table)

    def run(self, stop_time=None, start_time=None, progress=False, core=None):
        """Run from the start to the stop time (the bench's DefaultExperiment's
        unless given): the Result, with String columns in Result.strings; the
        results up to a failure or an interrupt go with the exception (its
        ``result``). See _run."""
        from artibus.fmu.instance import check_times, claim_logger_proxy
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
        """core: the stepping core in C where it applies (None, the default, unless
        ARTIBUS_CORE=0), True (it must), False (the Python loop below); see
        _core_stepper. self.stepping says which ran."""
        start = self.bench.start_time if start_time is None else start_time
        stop = stop_time if stop_time is not None else self.bench.stop_time
        if stop is None:
            raise ArtibusError(f"{self.bench.file}: no DefaultExperiment stopTime; give --stop-time")
        if not stop > start:
            raise ArtibusError(f"stop time {stop} must be after the start time {start}")
        rec = self._Recorder(self.names, self._rec)
        h = self.base_step
        n = int(round((stop - start) / h))
        _check_room(n + 1, len(self.names), self.bench.file)
        t = start
        current = None
        plan = _Plan(self.order, n)
        stepper = _core_stepper(self, plan, None, core)
        if stepper is not None:
            stepper.allocate(n)      # (the recorder's, as rec above)
        self._core_can = stepper.can if stepper is not None else None
        self._settle_core = stepper
        wall0 = _time.perf_counter()
        try:
            self._initialize(start)
            if self.can is not None:
                self.can.start(start)
            if stepper is not None:      # the C core does the loop below, the same, bit for bit
                result = stepper.run(start, h, n, progress)
                self.wall = _time.perf_counter() - wall0
                if self.can is not None:
                    self.can.finish()
                    return self._with_can_columns(result, stepper.table)
                return result
            rec.take(t)
            for k in range(n):
                t = start + k * h
                if self.can is not None and k % self.can_ratio == 0:
                    self.can.tick(k // self.can_ratio, t)
                starting, ending, gs = plan[k]
                if self.algorithm == "jacobi":
                    for u in starting:
                        self._propagate(u, t)
                    for u in starting:
                        current = u
                        u.raw.write()
                    for u in ending:
                        current = u
                        self._step(u, t + h - u.step)
                else:
                    for u, starts, ends in gs:
                        if starts:
                            self._propagate(u, t)
                            current = u
                            u.raw.write()
                        if ends:
                            current = u
                            self._step(u, t + h - u.step)
                current = None
                t = start + (k + 1) * h
                rec.take(t)
                if progress and k % max(1, n // 50) == 0:
                    sys.stderr.write(f"\r{self.bench.name}: t = {t:8.2f} s  [{'#' * (50 * (k + 1) // n):50s}]")
            if progress:
                sys.stderr.write("\n")
        except KeyboardInterrupt as e:   # Ctrl-C or SIGTERM (artibus.cli): the results so far go with it
            if progress:
                sys.stderr.write("\n")
            if stepper is None:          # (the core attached its own)
                e.result = rec.result()
            raise
        except FMICallException:
            current = current or getattr(self, "_busy", None)    # (in the initialisation)
            who = current.path if current else "?"
            log = current.fmu.log if current else [m for u in self.units for m in u.fmu.log]
            raise SimulationError(f"{self.ssp}: component '{who}' failed at t = {t:g} s: "
                                  f"{_last_message(log)}", rec.result(), list(log)) from None
        self.wall = _time.perf_counter() - wall0
        if self.can is not None:
            self.can.finish()
            return self._with_can_columns(rec.result())
        return rec.result()

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

    def close(self):
        if getattr(self, "can", None) is not None:
            self.can.close()
        for u in getattr(self, "units", []):
            u.fmu.close()
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# --- the stepping core in C (issue 13) ---------------------------------------------
#
# Simulation.run's loop over the base steps (propagate, set, step, get, record)
# done by <build>/lib/libartibus_core.so (src/runner_core/core.c) through the
# FMUs' own fmi2SetReal/fmi2DoStep/fmi2GetReal, on the same value buffers
# (_RawCalls'), in the same order, with the same floating-point operations:
# the results are the Python loop's, bit for bit (tests/test_runner_core.py).
# Python keeps the set-up, the checks and the errors; of the initialisation the
# core does the rounds to the fixed point of the connected inputs (_CoreStepper.settle:
# artibus_core_settle, the same calls, order and test as Simulation._initialize's loop).
# A bench that routes connections over CAN has its network ticked by the core
# too (_CanCore: artibus.can.Network.tick's frames, codec, E2E, counts, bits and
# since series in C, and the initialisation's settle: _CanCore.settle;
# tests/test_can_core.py), unless it has faults, a
# tamper function, a real interface or signals the core does not encode
# (Network.core_support). Today's Python loop runs instead when the core does
# not apply (the reason is in Simulation.stepping): such a CAN network, a bench
# with stimuli (Python functions of time), Integer/Boolean/String/Enumeration
# variables, the library not built, or the core switched off (run(core=False)
# or ARTIBUS_CORE=0).

CORE_ABI = 10                      # ARTIBUS_CORE_ABI in src/runner_core/core.h
CORE_PIECE = 5000                  # base steps per call into the core (without the progress bar)
_AC_PROPAGATE, _AC_WRITE, _AC_STEP = 0, 1, 2
_AC_CAN = 4                        # core.h: a frame could not be encoded
_AC_GET_REAL, _AC_SET_REAL, _AC_UNSETTLED, _AC_EXIT_INIT = 2, 3, 5, 6


class _AcSource(Structure):
    _fields_ = [("dst", c_void_p), ("src", c_void_p), ("factor", c_double), ("offset", c_double)]


class _AcUnit(Structure):
    _fields_ = [("component", c_void_p), ("doStep", c_void_p), ("getReal", c_void_p),
                ("setReal", c_void_p), ("step", c_double), ("n_out", c_size_t), ("n_in", c_size_t),
                ("out_vrs", c_void_p), ("out", c_void_p), ("in_vrs", c_void_p), ("inp", c_void_p),
                ("written", c_void_p), ("has_written", c_int), ("n_sources", c_int),
                ("sources", c_void_p), ("wall", c_double), ("ticks", c_ulonglong)]


class _AcSim(Structure):
    _fields_ = [("n_units", c_int), ("units", c_void_p), ("period", c_int), ("op_start", c_void_p),
                ("op_kind", c_void_p), ("op_unit", c_void_p), ("start", c_double), ("h", c_double),
                ("can", c_void_p), ("n_cols", c_int), ("n_runs", c_int), ("runs", c_void_p), ("table", c_void_p),
                ("fail_unit", c_int), ("fail_function", c_int), ("fail_status", c_int), ("fail_k", c_long),
                ("wall", c_double)]


class _AcSettle(Structure):
    _fields_ = [("order", c_void_p), ("n_order", c_int), ("gauss_seidel", c_int), ("max_iter", c_int),
                ("can", c_void_p), ("before", c_void_p), ("exit_init", c_void_p), ("fmu_wall", c_double),
                ("rounds", c_int),
                ("can_settles", c_long)]


class _AcCanReceiver(Structure):
    _fields_ = [("dst", c_void_p), ("factor", c_double)]


class _AcCanSignal(Structure):
    _fields_ = [("src", c_void_p), ("factor", c_double), ("minimum", c_double), ("maximum", c_double),
                ("scale", c_double), ("offset", c_double), ("integer", c_int), ("iscale", c_longlong),
                ("ioffset", c_longlong), ("start", c_int), ("length", c_int), ("big_endian", c_int),
                ("is_signed", c_int), ("n_receivers", c_int), ("receivers", c_void_p)]


class _AcCanMessage(Structure):
    _fields_ = [("id", c_uint), ("dlc", c_int), ("ratio", c_int), ("data_id", c_uint),
                ("fixed", c_ubyte * 8), ("n_signals", c_int), ("signals", c_void_p),
                ("counter", c_int), ("last_counter", c_int), ("good_tick", c_long),
                ("produced", c_long), ("sent", c_long), ("rejected", c_long), ("rejected_crc", c_long),
                ("rejected_repeated", c_long), ("rejected_sequence", c_long), ("bits", c_longlong),
                ("end_bits", c_longlong), ("since", c_void_p), ("head_crc", c_uint), ("head_state", c_int),
                ("head_stuffed", c_int), ("seen", c_ulonglong * 16), ("seen_bits", c_int * 16),
                ("seen_crc", c_ubyte * 16)]


class _AcCan(Structure):
    _fields_ = [("n_messages", c_int), ("messages", c_void_p), ("ratio", c_int), ("tau", c_double),
                ("ticks", c_long), ("frames", c_long), ("frame_cap", c_long), ("frame_tick", c_void_p),
                ("frame_stamp", c_void_p), ("frame_data", c_void_p), ("stamps", c_ulonglong), ("wall", c_double)]


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
        elif any(u.stimuli for u in sim.units):
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
            s.component = raw.comp.value
            s.doStep, s.getReal, s.setReal = (cast(f, c_void_p).value for f in (raw._do, raw._get, raw._set))
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
        self.can = _CanCore(sim, lib) if sim.can is not None else None
        self.extra = len(sim.can.messages) if sim.can is not None else 0
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
        # fmi2ExitInitializationMode (FMPy's call, without its call logger when none is set)
        order = (c_int * max(1, len(sim.order)))(*(index[id(u)] for u in sim.order))
        before = (c_double * max(1, sum(u.raw.n_in for u in units)))()
        exits = None
        if all(u.fmu.slave.fmiCallLogger is None for u in units):
            exits = (c_void_p * len(units))(
                *(cast(u.fmu.slave.dll.fmi2ExitInitializationMode, c_void_p).value for u in units))
        self._keep += [order, before, exits]
        self.settling = _AcSettle(order=addressof(order), n_order=len(sim.order),
                                  gauss_seidel=sim.algorithm == "gauss-seidel", before=addressof(before),
                                  can=addressof(self.can.c) if self.can is not None else None,
                                  exit_init=addressof(exits) if exits is not None else None)
        self._settle_refs = (self._struct_ref, byref(self.settling))
        self._inputs = [(a, raw, written) for a, _, raw, written in self._each if raw.n_in]

    def settle(self):
        """Simulation._initialize's rounds to the fixed point of the connected inputs
        (artibus_core_settle): the same reads, propagations, writes and network settles
        in the same order on the same buffers, the same test (_settled), the same
        errors (self.sim._busy the failing unit); then, unless an FMU has FMPy's call
        logger, each unit's fmi2ExitInitializationMode and read: True if so. The time
        inside the FMUs' calls there is added to sim.settle_wall (seconds)."""
        sim, s, z = self.sim, self.struct, self.settling
        if self.can is not None:           # (_CanCore.settle: the counters in)
            for a, m in zip(self.can.messages, self.can.net.messages):
                a.counter = m.counter
        z.max_iter, z.fmu_wall = MAX_INIT_ITERATIONS, 0.0
        try:
            failed = self.lib.artibus_core_settle(*self._settle_refs)
        finally:
            sim.settle_wall = getattr(sim, "settle_wall", 0.0) + z.fmu_wall
            for a, raw, written in self._inputs:
                raw.written = bytes(written) if a.has_written else None
        if self.can is not None:           # the messages settled: all once the network settled once
            ms = self.can.net.messages
            for m in ms if z.can_settles > 0 else ms[:s.fail_unit] if failed == _AC_CAN else ():
                m.last_counter = None
                m.good_tick = -m.ratio
        if failed == _AC_CAN:              # Network._encode raises its error (t = nan in the initialisation)
            self.can.refused(s.fail_unit, float("nan"))
        if failed == _AC_UNSETTLED:
            raise ArtibusError(f"{sim.bench.file}: initialisation did not settle in "
                               f"{MAX_INIT_ITERATIONS} iterations of the connected inputs")
        if failed:
            sim._busy = sim.units[s.fail_unit]
            raise FMICallException(function={_AC_GET_REAL: "fmi2GetReal", _AC_SET_REAL: "fmi2SetReal",
                                             _AC_EXIT_INIT: "fmi2ExitInitializationMode"}[failed],
                                   status=s.fail_status)
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
        memory recycled from tables no longer referred to (artibus.tables: no page faults
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
        if self.can is not None:
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
        if failed == _AC_CAN:          # a frame the encoder refused: artibus.can says why, as in the Python loop
            self.can.refused(s.fail_unit, start + s.fail_k * h)
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


def can_signal(s, q=None):
    """core.h's ac_can_signal of a cantools Signal (its range, conversion and
    place; no source, no receivers): q filled, or a new one."""
    q = _AcCanSignal() if q is None else q
    conv = getattr(s.conversion, "_conversion", s.conversion)   # NamedSignalConversion's own
    q.minimum, q.maximum = s.minimum, s.maximum
    q.scale, q.offset = conv.scale, conv.offset
    q.integer = type(conv).__name__ in ("IdentityConversion", "LinearIntegerConversion")
    if q.integer:
        q.iscale, q.ioffset = int(conv.scale), int(conv.offset)
    q.start, q.length = s.start, s.length
    q.big_endian, q.is_signed = s.byte_order == "big_endian", bool(s.is_signed)
    return q


class _CanCore:
    """The CAN network (artibus.can.Network) as core.h's ac_can: its messages in
    identifier order, each routed signal with cantools' conversion and place in
    the frame, pointing into the senders' output and the receivers' input
    buffers; the network's state goes in before the run and comes back after
    (counters, the receivers' E2E state, counts, bits, the since series), so
    Network.report, summary and since_series read as after the Python loop."""

    def __init__(self, sim, lib):
        from artibus.can.network import COUNTER_SIGNAL
        net = self.net = sim.can
        double = sizeof(c_double)
        self._keep = []
        self.messages = (_AcCanMessage * len(net.messages))()
        for a, m in zip(self.messages, net.messages):
            sigs = (_AcCanSignal * max(1, len(m.routes)))()
            for q, r in zip(sigs, m.routes):
                s = r.signal
                rcs = (_AcCanReceiver * max(1, len(r.receivers)))(
                    *((addressof(rc.unit.raw.inp) + double * rc.index, rc.factor) for rc in r.receivers))
                self._keep.append(rcs)
                can_signal(s, q)
                q.src = None if s.name == COUNTER_SIGNAL else addressof(r.unit.raw.out) + double * r.index
                q.factor = r.factor
                q.n_receivers, q.receivers = len(r.receivers), addressof(rcs)
            self._keep.append(sigs)
            a.id, a.dlc, a.ratio, a.data_id = m.msg.frame_id, m.msg.length, m.ratio, m.data_id
            a.fixed[:m.msg.length] = net.fixed_frame(m)
            a.n_signals, a.signals = len(m.routes), addressof(sigs)
        self.c = _AcCan(n_messages=len(net.messages), messages=addressof(self.messages), ratio=sim.can_ratio,
                        tau=1.0 / net.bitrate)
        self.ratio = sim.can_ratio
        self.lib = lib

    def settle(self):
        """Network.settle through the core's codec (artibus_core_can_settle), the
        same frames, receivers' inputs and E2E state."""
        net = self.net
        for a, m in zip(self.messages, net.messages):
            a.counter = m.counter
        bad = self.lib.artibus_core_can_settle(addressof(self.c))
        for m in net.messages[:bad] if bad >= 0 else net.messages:    # the messages it settled
            m.last_counter = None
            m.good_tick = -m.ratio
        if bad >= 0:                   # Network._encode raises its error (t = nan in the initialisation)
            self.refused(bad, float("nan"))

    def begin(self, n):
        """Before the run of n base steps: the network's state in."""
        ticks = -(-n // self.ratio)
        self.since = np.zeros((len(self.net.messages), max(1, ticks)))
        for i, (a, m) in enumerate(zip(self.messages, self.net.messages)):
            a.counter = m.counter
            a.last_counter = -1 if m.last_counter is None else m.last_counter
            a.good_tick = m.good_tick
            a.produced = a.sent = a.rejected = a.rejected_crc = a.rejected_repeated = a.rejected_sequence = 0
            a.bits, a.end_bits = 0, -1
            a.since = self.since[i].ctypes.data
        self.c.ticks = self.c.frames = 0
        self.c.wall = 0.0
        if self.net.writer is not None:     # every frame recorded, for the log (Network.log_frames)
            cap = sum(-(-ticks // m.ratio) for m in self.net.messages)
            self.frame_tick = np.zeros(cap, dtype=np.int64)      # (c_long: LP64)
            self.frame_stamp = np.zeros(cap)
            self.frame_data = np.zeros((cap, 16), dtype=np.uint8)
            self.c.frame_cap, self.c.frame_tick = cap, self.frame_tick.ctypes.data
            self.c.frame_stamp, self.c.frame_data = self.frame_stamp.ctypes.data, self.frame_data.ctypes.data
        return addressof(self.c)

    def end(self, start, h):
        """After the run (or its failure, or an interrupt): the state back into the network."""
        net, ticks = self.net, self.c.ticks
        for i, (a, m) in enumerate(zip(self.messages, net.messages)):
            m.counter = a.counter
            m.last_counter = None if a.last_counter < 0 else a.last_counter
            m.good_tick = a.good_tick
            m.produced += a.produced
            m.sent += a.sent
            m.rejected += a.rejected
            for why, count in (("crc", a.rejected_crc), ("repeated", a.rejected_repeated),
                               ("sequence", a.rejected_sequence)):
                m.why[why] += count
            m.bits += a.bits
            if a.end_bits >= 0:
                fid = m.msg.frame_id
                net.observed[fid] = max(net.observed.get(fid, 0.0), a.end_bits * (1.0 / net.bitrate))
            since = self.since[i, :ticks]
            net.add_since(m, since)
            if ticks and since.max() > m.longest:      # Network.tick: the first tick reaching the longest run
                j = int(np.argmax(since))
                m.longest, m.longest_at = int(since[j]), start + ((net.ticks + j) * self.ratio) * h
        net.frames += self.c.frames
        net.ticks += ticks
        net.wall += self.c.wall
        if self.c.frame_cap:
            n = min(self.c.frames, self.c.frame_cap)
            ids = self.frame_data[:n, 0].astype(int) | (self.frame_data[:n, 1].astype(int) << 8)
            net.log_frames((float(t), int(i), bytearray(f[8:8 + f[4]]))
                           for t, i, f in zip(self.frame_stamp[:n], ids, self.frame_data[:n]))

    def refused(self, index, t):
        """The core could not encode message index's frame at t: Network._encode's error."""
        m = self.net.messages[index]
        self.net._encode(m, t)
        raise ArtibusError(f"{self.net.dbc_label}: message {m.msg.name}: the stepping core refused its frame "
                           f"at t = {t:g} s, artibus.can's encoder did not (a defect: run with ARTIBUS_CORE=0)")


def run(ssp, stop_time=None, step=None, overrides=None, record=None,
        algorithm="gauss-seidel", progress=False, stimuli=None):
    """Run a bench (name or .ssp path); returns the Result."""
    with Simulation(ssp, step=step, overrides=overrides, record=record, algorithm=algorithm,
                    stimuli=stimuli) as sim:
        return sim.run(stop_time=stop_time, progress=progress)


def save(result, path):
    """CSV, or MATLAB .mat (one variable per signal, names made MATLAB-safe),
    written to a temporary name beside ``path`` and renamed (artibus.files):
    ``path`` is the complete file or is left as it was, never torn by a
    Ctrl-C, a SIGTERM or a full disk.

    Units (Result.units): a CSV keeps its one header line of names; the units go
    to the sidecar ``units_path(path)`` (``out.csv`` -> ``out.units.csv``: a CSV
    with the columns ``name,unit``, a row per column of the results in their
    order, "" for none), written after the results (an interrupt in between
    leaves the results without their units, never units without results). A .mat holds a struct
    ``units`` with a field per signal (the signal's MATLAB-safe name) holding its
    unit; a signal whose safe name is ``units`` is saved as ``units_``."""
    import csv
    from artibus.files import atomic_path
    path = Path(path)
    units = getattr(result, "units", None) or {}
    with atomic_path(path) as tmp:
        if path.suffix == ".mat":
            from scipy.io import savemat
            data = result.array()
            safe, safe_units = {}, {}
            for i, n in enumerate(result.names):
                key = "".join(ch if ch.isalnum() else "_" for ch in n).strip("_")[:63] or f"v{i}"
                key = "units_" if key == "units" else key
                safe[key] = (np.array(result.strings[n], dtype=object) if n in result.strings  # a cell array
                             else data[:, i])
                safe_units[key] = units.get(n, "")
            safe["units"] = safe_units
            savemat(str(tmp), safe)
        else:
            result.to_csv(tmp)
    if path.suffix != ".mat":
        with atomic_path(units_path(path)) as tmp:
            with open(tmp, "w", newline="") as f:
                w = csv.writer(f, quoting=csv.QUOTE_NONNUMERIC)
                w.writerow(["name", "unit"])
                w.writerows([n, units.get(n, "")] for n in result.names)
    return path


def units_path(path):
    """The units' sidecar of a CSV of results: ``out.csv`` -> ``out.units.csv``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.units.csv")


def read_units(path):
    """{name: unit} of a CSV of results (its sidecar, see save)."""
    import csv
    with open(units_path(path), newline="") as f:
        rows = list(csv.reader(f))
    return {n: u for n, u in rows[1:]}


def partial_path(path):
    """Where the results of a run that stopped midway go: ``out.csv`` ->
    ``out.partial.csv`` (``.mat`` likewise), never the final name."""
    path = Path(path)
    return path.with_name(f"{path.stem}.partial{path.suffix or '.csv'}")
