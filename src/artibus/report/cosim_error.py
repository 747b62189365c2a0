"""Each KPI's co-simulation error (issue 44): how far a bench's KPIs at its
communication steps are from the continuous solution of its model.

A bench couples its continuous components (the plants, the damper: those that
offer Model Exchange) through a sample-and-hold at their communication step;
the sampled controllers, ECUs and the CAN cycle are discrete by nature and
their periods are part of the model, not of the stepping. The error of a KPI
is measured in one of two ways, the first that can run:

- ``REFERENCE``: the difference between the default run and the bench's
  monolithic reference (``Simulation(reference=True)``: the continuous
  components integrated together in one solver, the sampled ones as they are);
- else the estimate the issue gives "where no reference can run": the larger of
  ``HALVED``, 2 |K(h) - K(h/2)| (the continuous components' steps halved, the
  sampled ones kept; a zero-order hold's coupling error is first order in h, so
  K(h) - K(h/2) is half of K(h)'s error: Richardson's estimate for order 1), and
  ``ALGORITHMS``, |K(Gauss-Seidel) - K(Jacobi)| (the other algorithm at h).

The KPIs of the other runs are the page's own: bench.py's ``kpis`` on the other
run, or for a study (a page whose KPIs come from runs of its own) the study
again, every run it makes in the other configuration (``runs_as``).
"""
import inspect
import math
import tempfile
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from artibus import runner
from artibus.base import ArtibusError

REFERENCE = "against the reference"
HALVED = "h against h/2"
ALGORITHMS = "Gauss-Seidel against Jacobi"
MARK_PCT = 2.0        # issue 44: a graded KPI whose error exceeds 2 % is marked


def reference_available():
    """Whether the runner has the monolithic reference (Simulation's ``reference``)."""
    from artibus.runner.simulation import Simulation
    return "reference" in inspect.signature(Simulation.__init__).parameters


def continuous(unit):
    """A component whose communication step is stepping, not model: one that offers
    Model Exchange (a plant, the damper). The others (controllers, ECUs, the driver)
    are sampled systems whose period is part of the model."""
    return unit.fmu.md.modelExchange is not None


def _configured(kind):
    """The Simulation class that runs a bench in the configuration ``kind``:
    HALVED (the continuous components at half their step), ALGORITHMS (Jacobi)
    or REFERENCE (the monolithic reference)."""
    from artibus.runner.simulation import Simulation

    class Configured(Simulation):
        def __init__(self, *args, **kw):
            if kind == HALVED and kw.get("step") is not None:
                kw["step"] = kw["step"] / 2
            elif kind == ALGORITHMS:
                kw["algorithm"] = "jacobi" if kw.get("algorithm", "gauss-seidel") == "gauss-seidel" else "gauss-seidel"
            elif kind == REFERENCE:
                kw["reference"] = True
            super().__init__(*args, **kw)

        def _units(self, step, where):
            units = super()._units(step, where)
            if kind == HALVED and step is None:
                # the continuous components' step halved as --step does it (runner.setup: a
                # sampled component keeps its period and the delay of its output, plan.stated_timing)
                h = min((u.step for u in self.units if continuous(u)), default=None)
                if h is not None:
                    for u in self.units:
                        u.fmu.close()
                    units = super()._units(h / 2, where)
            return units

    Configured.__name__ = Configured.__qualname__ = f"Simulation[{kind}]"
    return Configured


@contextmanager
def runs_as(kind):
    """Every bench run made inside (runner.run, runner.Simulation: a study's own
    runs) in the configuration ``kind``. The report is single-threaded; the names
    are restored on the way out."""
    from artibus.runner import simulation as sim_mod
    cls, saved = _configured(kind), (runner.Simulation, sim_mod.Simulation)
    runner.Simulation = sim_mod.Simulation = cls
    try:
        yield cls
    finally:
        runner.Simulation, sim_mod.Simulation = saved


@dataclass
class Estimate:
    """The other runs' KPIs of a page, to measure each KPI's co-simulation error
    by: ``others`` [(how: REFERENCE, HALVED or ALGORITHMS, {KPI name: value})];
    ``why``: why there are none; ``wall``: the extra runs' time, s."""
    others: list = field(default_factory=list)
    why: str = ""
    wall: float = 0.0

    @property
    def methods(self):
        return tuple(how for how, _ in self.others)

    def apply(self, kpis):
        """Each KPI given its error (Kpi.error, Kpi.error_how, Kpi.margin_error: combine);
        returns the KPIs."""
        errors = combine(_values(kpis), self.others)
        for k in kpis:
            if k.name in errors:
                k.error, k.error_how, k.margin_error = errors[k.name]
        return kpis

    def said(self):
        """How the errors were measured, in one phrase (for the printout and the page)."""
        if self.why:
            return f"not measured ({self.why})"
        if REFERENCE in self.methods:
            return "the difference from the bench's monolithic reference run (Simulation(reference=True))"
        return ("estimated where no reference can run: the larger of 2 |K(h) - K(h/2)| (the continuous "
                "components' steps halved, the sampled controllers at their periods) and "
                "|K(Gauss-Seidel) - K(Jacobi)| at h")


def number(v):
    """A KPI's value as a finite float, else None (a count, a flag, n/a)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _difference(how, a, b):
    """The error a run of kind ``how`` measures between the default's a and its b (None: either missing)."""
    if a is None or b is None:
        return None
    return abs(a - b) * (2.0 if how == HALVED else 1.0)


def combine(base, others):
    """{name: (error, how, margin error)}: base {name: (value, margin)} of the default
    run against others [(how, {name: (value, margin)})]: REFERENCE |K - K_ref|; HALVED
    2 |K(h) - K(h/2)|; ALGORITHMS |K_GS - K_J|; the largest of those there are (where
    a reference ran, it alone). The margin (the distance to the paper's bound, which
    for an ordering between two runs is the other run's value: it has its own error)
    the same way; None where the KPI has no bound."""
    out = {}
    ref = [o for o in others if o[0] == REFERENCE]
    for name, (v, m) in base.items():
        best, margin = None, None
        for how, vals in ref or others:
            w, wm = vals.get(name, (None, None))
            e = _difference(how, v, w)
            if e is not None and (best is None or e > best[0]):
                best = (e, how)
            em = _difference(how, m, wm)
            if em is not None and (margin is None or em > margin):
                margin = em
        if best is not None:
            out[name] = (*best, margin)
    return out


def _values(kpis):
    """{name: (value, distance to its bound)} of the numbers among the KPIs."""
    return {k.name: (number(k.value), k.margin) for k in kpis}


def page_kpis(bench, result, kind=None):
    """The page's KPIs of a run (artibus.report.pages._report without the page):
    bench.py's ``kpis``, or its ``study`` (its figures into a scratch folder), with
    every run the study makes in configuration ``kind`` (None: as they are)."""
    from artibus.bench import script
    mod = script.load(bench)
    if mod is None:
        return []
    if not callable(getattr(mod, "study", None)):
        return mod.kpis(result)
    with tempfile.TemporaryDirectory(prefix="artibus-error-") as tmp:
        if kind is None:
            return list(mod.study(result, Path(tmp)))[0]
        with runs_as(kind):
            return list(mod.study(result, Path(tmp)))[0]


def _run_as(kind, bench, overrides, stop_time, settings, like):
    """The bench's run in configuration ``kind`` (a Result carrying ``like``'s fmi and variants)."""
    with _configured(kind)(bench, overrides=overrides, **settings) as sim:
        r = sim.run(stop_time=stop_time)
    r.fmi, r.variants = getattr(like, "fmi", None), getattr(like, "variants", None)
    return r


def kinds(reference=None):
    """The configurations to run: the reference where the runner has one (and
    ``reference`` is not False), else h/2 and the other algorithm."""
    if reference is None:
        reference = reference_available()
    return (REFERENCE,) if reference else (HALVED, ALGORITHMS)


def measure(bench, result, overrides=None, stop_time=None, settings=None, reference=None):
    """Estimate of the page KPIs of ``result`` (the bench's run with ``overrides``,
    ``settings`` as Simulation takes them). A reference that cannot run (a bench
    without Model Exchange components, or one that fails) falls back to the
    estimate; a run of the estimate that fails is left out and said (Estimate.why
    where none ran), the report goes on; a KPI the other runs cannot compute (a
    run too short for it) gets no error."""
    settings = dict(settings or {})
    t0 = time.perf_counter()
    others, failed = [], []
    todo = list(kinds(reference))
    while todo:
        kind = todo.pop(0)
        try:
            other = _run_as(kind, bench, overrides, stop_time, settings, result)
            others.append((kind, _values(page_kpis(bench, other, kind))))
        except ArtibusError as e:              # (SimulationError too: the run failed midway)
            failed.append(f"{kind}: {str(e).splitlines()[0] if str(e) else type(e).__name__}")
            if kind == REFERENCE:
                todo = [HALVED, ALGORITHMS]        # no reference for this bench: the estimate
        except (ValueError, ArithmeticError, IndexError) as e:    # (a run too short for the page's KPIs)
            failed.append(f"{kind}: the KPIs: {type(e).__name__}: {e}")
    est = Estimate(others, wall=time.perf_counter() - t0)
    if not others:
        est.why = "; ".join(failed) or "no other run could compute the KPIs"
    return est
