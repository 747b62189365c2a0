"""The step plan: the order of the components (Gauss-Seidel, from the
connection graph and the FMUs' direct feedthrough; an algebraic loop is an
error naming it) and which components start and end their communication
step at each base step (``_Plan``, multi-rate)."""
import math

from artibus.base import ArtibusError


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
        ending = [u for u in self.order if (k + 1) % u.ratio == 0]
        gs = [(u, k % u.ratio == 0, (k + 1) % u.ratio == 0) for u in self.order
              if k % u.ratio == 0 or (k + 1) % u.ratio == 0]
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
        return ops

    def __getitem__(self, k):
        return self.table[k % self.period] if self.table is not None else self.entry(k)
