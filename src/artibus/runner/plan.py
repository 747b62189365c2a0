"""The step plan: the order of the components (Gauss-Seidel, from the
connection graph and the FMUs' direct feedthrough: ``gauss_seidel_order``)
and which components start and end their communication step at each base
step (``_Plan``, multi-rate).

Direct feedthrough is read from each output's ``dependencies`` (FMI 2.0
2.2.8 "Definition of the Model Structure", FMI 3.0 2.4.8 "Model Structure"):
an output that lists an input depends on it (declared); an output without
the attribute "must be assumed" to depend on every input (assumed: many
exporters write no dependencies at all, so a controller + plant loop of
such FMUs is the normal case). A loop of feedthrough that is declared all
around is an algebraic loop, an error under Gauss-Seidel; a loop through
at least one assumed feedthrough is broken at one of those connections,
which then carries its source's output of the previous step (one step of
delay), as other SSP masters run such files. Jacobi needs no order: every
connection carries the previous step's outputs (Simulation: no order, no
loop check)."""
import math
from dataclasses import dataclass

from artibus.base import ArtibusError


def feedthrough(md):
    """{(input name, output name): declared} of a model (artibus.fmu.model.Model): True where
    the output lists the input in its dependencies, False where the output has no
    dependencies attribute and so is assumed to depend on every input (FMI 2.0 2.2.8,
    FMI 3.0 2.4.8); an empty list: no feedthrough."""
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    out = {}
    for o in md.outputs:
        declared = o.dependencies is not None
        for d in o.dependencies if declared else inputs:
            if d.causality == "input":
                out[(d.name, o.variable.name)] = declared
    return out


@dataclass(frozen=True)
class Wire:
    """A connection as the order sees it: component paths and variable names; label names it
    in messages (the file and line of its Connection)."""
    src: str
    output: str
    dst: str
    input: str
    label: str = ""

    def text(self):
        return f"{self.src}.{self.output} -> {self.dst}.{self.input}"


def wire(where, c):
    """The Wire of a bench's Connection (artibus.bench.ssp.Connection), labelled with its file and line."""
    return Wire(c.start[0], c.start[1], c.end[0], c.end[1],
                f"{where}:{c.line}: Connection {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}")


@dataclass(frozen=True)
class Order:
    """gauss_seidel_order's answer: the component paths in stepping order; the connections
    broken (one step of delay), each with the loop it broke."""
    paths: list
    broken: list                 # [(Wire, [Wire of its loop])]


def _feed_edges(wires, feeds, cut):
    """(component, output) -> [((component, output), wire, declared)]: the output reaches
    the other output through the wire and the destination's feedthrough; wires in cut left out"""
    edges = {}
    for w in wires:
        if w in cut:
            continue
        for (i, o), declared in sorted(feeds.get(w.dst, {}).items()):
            if i == w.input:
                edges.setdefault((w.src, w.output), []).append(((w.dst, o), w, declared))
    return edges


def _a_cycle(edges):
    """The first cycle of the feedthrough graph (depth first, in the wires' order) as
    [(wire, declared)], or None."""
    state, stack = {}, []         # stack: [(node, the edge taken to it)]

    def visit(n, via):
        state[n] = 1
        stack.append((n, via))
        for m, w, declared in edges.get(n, []):
            if state.get(m) == 1:
                at = next(k for k, (node, _) in enumerate(stack) if node == m)
                return [e for _, e in stack[at + 1:]] + [(w, declared)]
            if state.get(m) is None:
                found = visit(m, (w, declared))
                if found:
                    return found
        stack.pop()
        state[n] = 2
        return None

    for n in list(edges):
        if state.get(n) is None:
            found = visit(n, None)
            if found:
                return found
    return None


def _break_loops(paths, wires, feeds, where):
    """[(wire, loop)]: one wire per loop of feedthrough, until none is left; the wire
    broken is a loop's connection into an assumed feedthrough whose destination comes
    first in the bench (paths' order), the connection's text breaking a tie. A loop
    declared all around is an algebraic loop: an error naming it."""
    rank = {p: k for k, p in enumerate(paths)}
    broken = []
    while True:
        cycle = _a_cycle(_feed_edges(wires, feeds, {w for w, _ in broken}))
        if cycle is None:
            return broken
        loop = [w for w, _ in cycle]
        assumed = [w for w, declared in cycle if not declared]
        if not assumed:
            raise ArtibusError(f"{where}: algebraic loop (direct feedthrough all around, declared by the "
                               f"outputs' dependencies): " + " -> ".join(
                                   [f"{w.src}.{w.output}" for w in loop] + [f"{loop[0].src}.{loop[0].output}"])
                               + f" ({loop[0].label}); Gauss-Seidel cannot order it (--algorithm jacobi "
                               f"runs it, every connection one step delayed)")
        broken.append((min(assumed, key=lambda w: (rank.get(w.dst, len(rank)), w.text())), loop))


def gauss_seidel_order(paths, wires, feeds, where):
    """The Order of components ``paths`` (the bench's order) joined by ``wires`` (Wire), with
    ``feeds`` {path: feedthrough(md)}: a component whose output reaches another's input
    directly (through that one's feedthrough) goes first; each loop broken (_break_loops),
    an algebraic loop an error."""
    broken = _break_loops(paths, wires, feeds, where)
    cut = {w for w, _ in broken}
    deps = {p: set() for p in paths}
    for w in wires:
        if w not in cut and w.src != w.dst and any(i == w.input for i, _ in feeds.get(w.dst, {})):
            deps[w.dst].add(w.src)
    ordered, done = [], set()
    while len(ordered) < len(paths):
        ready = [p for p in paths if p not in done and deps[p] <= done]
        if not ready:  # a loop of components, none of variables (A.y1 -> B -> A.u2, u2 not feeding y1)
            ready = [next(p for p in paths if p not in done)]
        for p in ready:
            ordered.append(p)
            done.add(p)
    return Order(ordered, broken)


def loop_warning(where, wire, loop):
    """The warning of a loop broken at ``wire`` (gauss_seidel_order)."""
    path = " -> ".join([f"{w.src}.{w.output}" for w in loop] + [f"{loop[0].src}.{loop[0].output}"])
    return (f"{where}: loop {path} through outputs that declare no dependencies (FMI 2.0 2.2.8, FMI 3.0 "
            f"2.4.8: assumed to depend on every input): Gauss-Seidel breaks it at {wire.label or wire.text()}, "
            f"one step of delay there")


def _steps_at(u, k):
    """Whether the plan steps unit u in base step k: in the last base step of its period, or
    ``u.early`` base steps before it (a sampled unit's stated timing: stated_timing)."""
    return (k + 1 + getattr(u, "early", 0)) % u.ratio == 0


def stated_timing(units, default_base, base):
    """Each sampled unit's ``early`` (core.h's ac_unit.early): a sampled unit (a controller, the
    driver, an ECU: one whose period the bench states and that offers no Model Exchange) samples
    its inputs at the start of its period and its output is seen by the others from the base step
    in which the plan steps it. At the bench's default base step ``default_base`` that is the last
    base step of its period: its output holds from (period - default_base) after the sample (0
    for a unit at the base step; the Gauss-Seidel order puts such a controller, without direct
    feedthrough, before the plants, so it reads their outputs at the sample instant). That delay
    is the bench's model, not its stepping (issue 44): at another base step ``base`` (--step,
    the plants' steps halved, the reference) the unit is stepped where its output is seen the
    same delay after its sample, when that is a whole number of base steps (else in its period's
    last one, as before)."""
    for u in units:
        u.early = 0
        if not getattr(u, "sampled", False) or u.ratio == 1 or default_base is None:
            continue
        offset = (u.step - default_base) / base        # base steps from its sample to its output
        if abs(offset - round(offset)) < 1e-9 and 0 <= round(offset) <= u.ratio - 1:
            u.early = u.ratio - 1 - int(round(offset))


AC_PROPAGATE, AC_WRITE, AC_STEP = 0, 1, 2     # core.h's operations (the plan as data: _Plan.ops)
PLAN_TABLE = 4096       # base steps of the plan's period tabulated at most (see _Plan)


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
        ending = [u for u in self.order if _steps_at(u, k)]
        gs = [(u, k % u.ratio == 0, _steps_at(u, k)) for u in self.order
              if k % u.ratio == 0 or _steps_at(u, k)]
        return starting, ending, gs

    def ops(self, k, jacobi=False):
        """Base step k's operations in the order the stepping core does them, as data:
        [(kind, unit)], kind core.h's AC_PROPAGATE (the unit's inputs from its sources),
        AC_WRITE (set them), AC_STEP (its step, then its outputs read). Gauss-Seidel: per
        unit of the order, propagate and write when its step starts, step when it ends;
        Jacobi: every starting unit propagated, then written, then every ending unit stepped."""
        starting, ending, gs = self[k]
        if jacobi:
            return ([(AC_PROPAGATE, u) for u in starting] + [(AC_WRITE, u) for u in starting]
                    + [(AC_STEP, u) for u in ending])
        ops = []
        for u, starts, ends in gs:
            if starts:
                ops += [(AC_PROPAGATE, u), (AC_WRITE, u)]
            if ends:
                ops.append((AC_STEP, u))
        return _grouped(ops)

    def __getitem__(self, k):
        return self.table[k % self.period] if self.table is not None else self.entry(k)


def _grouped(ops):
    """Gauss-Seidel's operations with a Model Exchange group (the monolithic reference, issue 44:
    artibus.runner.reference; units with ``group`` set): the group integrates all its members at
    the first member's step, so every member's inputs are propagated and written before that step
    (moved there, in their order); without a group, ops as they are."""
    first = next((i for i, (kind, u) in enumerate(ops)
                  if kind == AC_STEP and getattr(u, "group", None) is not None), None)
    if first is None:
        return ops
    group = ops[first][1].group
    late = [i for i, (kind, u) in enumerate(ops)
            if i > first and kind != AC_STEP and getattr(u, "group", None) is group]
    moved = [ops[i] for i in late]
    rest = [op for i, op in enumerate(ops) if i not in set(late)]
    return rest[:first] + moved + rest[first:]
