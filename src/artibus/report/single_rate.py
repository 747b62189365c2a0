"""How far a single-rate run of a bench is from ours, for its page.

Our benches step some components more slowly than others (the
org.artibus.simulation annotation's stepSize, artibus-specific); another SSP
master (ecos, libcosim, FMPy's) steps every component at one rate. The bench's
page says which steps it has and, measured, how far its KPIs move when every
component steps at the shortest of them: one more run of the bench
(``Simulation(single_rate=True)``) and the bench's own KPIs (bench.py's
``kpis(result)``) of both runs; a bench without a bench.py is compared on its
recorded signals (the largest difference relative to the signal's range). A
bench already single-rate needs no run: the deviation is 0.
"""
import html
import math
import time
from dataclasses import dataclass, field

from artibus import runner
from artibus.base import ArtibusError
from artibus.bench import script


@dataclass
class SingleRate:
    steps: dict                      # component -> its step, s
    step: float                      # the one step of the single-rate run, s
    deviation: float                 # the largest KPI deviation, % (0: the same)
    worst: str = ""                  # the KPI (or signal) it is on
    rows: list = field(default_factory=list)    # (KPI, unit, multi-rate, single-rate, deviation %)
    wall: float = 0.0                # the extra run's wall time, s

    @property
    def multi_rate(self):
        return len(set(self.steps.values())) > 1

    def html(self):
        rates = ", ".join(f"{html.escape(p)} {s:g} s" for p, s in self.steps.items())
        if not self.multi_rate:
            return (f"<h2>Single-rate masters</h2><p>Every component steps at {self.step:g} s: the bench is "
                    f"single-rate, a master without multi-rate steps runs it as we do "
                    f"(single-rate KPI deviation: <span class=srdev>{self.deviation:g}</span> %).</p>")
        rows = "".join(f"<tr><td>{html.escape(k)}</td><td class=n>{a:.6g}</td><td class=n>{b:.6g}</td>"
                       f"<td>{html.escape(u)}</td><td class=n>{d:.3g}</td></tr>" for k, u, a, b, d in self.rows)
        return (f"<h2>Single-rate masters</h2><p>Multi-rate steps (org.artibus.simulation, artibus-specific): "
                f"{rates}. A master that steps every component at one rate (ecos, libcosim, FMPy) at "
                f"{self.step:g} s differs from this run by at most "
                f"<span class=srdev>{self.deviation:.3g}</span> % (on {html.escape(self.worst)}; measured: "
                f"the bench run once more with <code>--single-rate</code>, {self.wall:.1f} s).</p>"
                f"<table><tr><th>KPI</th><th>multi-rate</th><th>single-rate</th><th>unit</th>"
                f"<th>deviation, %</th></tr>{rows}</table>")


def _relative(a, b):
    """|a - b| relative to the larger of the two, %; 0 where both are 0."""
    scale = max(abs(a), abs(b))
    return 0.0 if scale == 0 else 100.0 * abs(a - b) / scale


def _numbers(kpis):
    return {k.name: (k.value, k.unit) for k in kpis if isinstance(k.value, (int, float))
            and not isinstance(k.value, bool) and math.isfinite(k.value)}


def measure(sim, result, run_again):
    """SingleRate of a bench's run: ``sim`` the Simulation it ran in (its
    components' steps), ``result`` its result, ``run_again()`` the same run
    single-rate (a Result), called only for a multi-rate bench."""
    steps = {u.path: u.step for u in sim.units}
    h = min(steps.values())
    if len(set(steps.values())) <= 1:
        return SingleRate(steps, h, 0.0)
    t0 = time.perf_counter()
    other = run_again()
    wall = time.perf_counter() - t0
    mod = script.load(sim.bench.name)
    rows = []
    if mod is not None and callable(getattr(mod, "kpis", None)):
        try:
            a, b = _numbers(mod.kpis(result)), _numbers(mod.kpis(other))
        except (ArtibusError, ValueError, ArithmeticError, IndexError):   # a run too short for its KPIs
            # (--stop-time shorter than the bench): then its recorded signals
            a, b = {}, {}
        rows = [(k, a[k][1], a[k][0], b[k][0], _relative(a[k][0], b[k][0])) for k in a if k in b]
    if not rows:                       # no KPIs: the recorded signals, relative to their range
        import numpy as np
        n = min(len(result.time), len(other.time))
        for name in result.names[1:]:
            if name not in other.names:
                continue
            x, y = np.asarray(result[name][:n], float), np.asarray(other[name][:n], float)
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                continue
            span = float(np.max(x) - np.min(x))
            d = float(np.max(np.abs(x - y)))
            rows.append((f"signal {name} (largest difference / range)", "", span, d,
                         0.0 if d == 0 else 100.0 * d / span if span > 0 else 100.0))
    worst = max(rows, key=lambda r: r[4]) if rows else ("", "", 0, 0, 0.0)
    return SingleRate(steps, h, worst[4], worst[0], rows, wall)


def run_single_rate(bench, overrides, stop_time, step=None, record=None, algorithm="gauss-seidel", can=None,
                    fmi=None, **more):
    """The bench run with every component at one step (a Result; fmi: its FMUs' build, as Simulation's;
    ``more``: the run's other settings, as Simulation takes them: fmi_type, input_file, ...)."""
    with runner.Simulation(bench, step=step, overrides=overrides, record=record, algorithm=algorithm,
                           can=can, single_rate=True, fmi=fmi, **more) as sim:
        return sim.run(stop_time=stop_time)
