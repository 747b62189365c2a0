"""The linear model of a bench (`artibus linearize BENCH`, issue 43): its Model Exchange plants
linearised (artibus.linear.fmu: directional derivatives where the FMU provides them, else central
differences) with everything else in the loop as the linear map it is at the operating point:

    plants:      der(x) = A x + B u_p,    y_p = C x + D u_p
    the loop:    u_p = K_y y_p + K_r r     (the controllers, the static ME parts, the connections)
    closed:      y_p = L^-1 (C x + D K_r r),  L = I - D K_y
                 der(x) = (A + B K_y L^-1 C) x + B (K_y L^-1 D + I) K_r r

r the bench's open inputs (an input connected to nothing, or to a component left out with
``exclude``: then named by that component's output). K_y, K_r are the Jacobian of the loop's
map from the plants' outputs (and r) to the plants' inputs, by central differences: each
controller (a Co-Simulation FMU, sampled) stepped once, one sample, from its state at the
operating point saved and restored (fmi2/fmi3Get/SetFMUstate: FMI 2.0.4 2.1.8, FMI 3.0 2.2.6.4)
for every difference: its sampling is ignored (continuous equivalent: a static gain), its own
filters' states held (their response to r is not in B; the feedback through the plants' outputs
is what A_cl needs). A Model Exchange component without dynamic states (a damper whose states
only integrate its energy) is a static map of its inputs (its outputs read in Continuous-Time
Mode, FMI 2.0.4 3.2.1, FMI 3.0 3.2.1). The operating point: the bench's start values (each
component initialised with its bound parameters, each controller stepped one sample with the
loop's values propagated to it, PASSES passes), or (``steady``) the plants integrated with the loop's values held until their dynamic
states rest, the loop updated, twice; or (``at``, open_run) the bench's state at a time of its run: the
components' own instances as the run left them there."""
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from artibus.linear import fmu as lz
from artibus.base import ArtibusError

#: the loop's central differences: each plant output and open input moved by +-STEP x its nominal
STEP = 1e-6
#: passes through the loop's static elements per evaluation (algebraic loops among them:
#: the damping controller needs the damper's Mmax, the damper its pct)
PASSES = 3


@dataclass
class Element:
    """A component of the bench: ``role`` "plant" (ME with dynamic states), "static" (ME without
    them) or "controller" (Co-Simulation, stepped one ``step`` from its saved ``state``)."""
    name: str
    inst: object
    role: str
    step: float = 0.0
    inputs: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    state: object = None
    t: float = 0.0                 # the time of the saved state
    lin: object = None


class Opened:
    """The bench's components instantiated and initialised (``elements``), the signals' values at
    the operating point (``values``: (component, variable) -> value), the open inputs (``open``:
    external name -> the (component, variable) ends it feeds); closed by ``close``. ``run``: a
    Simulation run to time ``at`` whose instances are taken as they are (open_run), else None."""

    def __init__(self, bench, ssp_file, exclude, overrides, run=None, at=None):
        self.bench, self.ssp_file = bench, ssp_file
        self.elements, self.values, self.t0 = {}, {}, float(bench.start_time or 0.0)
        self.run, self.at = run, at
        if run is not None:
            self.t0 = float(at)
        self.feeds = {}                       # (comp, var) input -> ((comp, var) source, factor, offset)
        self.open = {}                        # external input name -> [(comp, var), ...]
        self._dirs = []
        self.notes = []                       # what the closed loop's report says of the point
        try:
            self._check_exclude(exclude)
            if run is None:
                self._instantiate(exclude, overrides)
            else:
                self._adopt(exclude)
        except BaseException:
            self.close()
            raise

    def _check_exclude(self, exclude):
        unknown = [n for n in exclude if n not in self.bench.components]
        if unknown:
            from artibus.bench.parameters import suggest
            raise ArtibusError(f"{self.bench.file}: --exclude {unknown[0]}: no such component (its components: "
                               f"{', '.join(self.bench.components)}){suggest(unknown[0], self.bench.components)}")

    def _adopt(self, exclude):
        """The run's instances as the elements, in the states the run left them at ``at``: a Model
        Exchange one a plant (the run integrated it as ME; _classify makes one without dynamic
        states static), a Co-Simulation one a controller (its step the run's)."""
        for u in self.run.units:
            if u.path in exclude:
                continue
            role = "plant" if u.fmu.interface == "me" else "controller"
            self.elements[u.path] = Element(u.path, u.fmu, role, step=float(u.step))
        self._wire(exclude)

    def _instantiate(self, exclude, overrides):
        from artibus import cache
        from artibus.fmu.instance import Fmu, read_model
        d, temporary = cache.unpacked(self.ssp_file)
        if temporary:
            self._dirs.append(d)
        for name, c in self.bench.components.items():
            if name in exclude:
                continue
            path = Path(d) / c.source
            md = read_model(path)
            me = md.modelExchange is not None and len(md.derivatives) > 0
            inst = Fmu(path, instance_name=name, interface="me" if me else "cs")
            el = Element(name, inst, "plant" if me else "controller")
            self.elements[name] = el
            values = {k: v for k, v in c.parameters.items()}
            values.update({k.split(".", 1)[1]: v for k, v in overrides.items() if k.split(".", 1)[0] == name})
            el.step = float(c.step or getattr(md.defaultExperiment, "stepSize", None) or 0.01)
            try:
                inst.initialize(values, start_time=self.t0)
            except ArtibusError as e:
                raise ArtibusError(f"{self.bench.name}: {name}: {e}") from None
            except Exception as e:
                raise ArtibusError(f"{self.bench.name}: {name} ({md.modelName}) refused its values at "
                                   f"initialisation: {' '.join(inst.log) or e}") from None
        self._wire(exclude)

    def _wire(self, exclude):
        """The connections between the elements kept; an input fed by an excluded component is
        open, named by that component's output; an input fed by nothing is open under its own name."""
        for c in self.bench.connections:
            if c.end[0] not in self.elements:
                continue
            if c.start[0] in exclude:
                self.open.setdefault(".".join(c.start), []).append(c.end)
            else:
                self.feeds[c.end] = (c.start, c.factor, c.offset)
        for name, el in self.elements.items():
            md = el.inst.md
            el.inputs = [v.name for v in md.modelVariables if v.causality == "input" and v.kind == "Real"
                         and not v.shape]
            el.outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.kind == "Real"
                          and not v.shape]
            for n in el.inputs:
                if (name, n) not in self.feeds and not any((name, n) in e for e in self.open.values()):
                    self.open[f"{name}.{n}"] = [(name, n)]
            for n, x in zip(el.inputs + el.outputs, el.inst.get_values(el.inputs + el.outputs)):
                self.values[(name, n)] = float(x)
        for ext, ends in self.open.items():
            self.values[("", ext)] = self.values[ends[0]]

    # --- the loop's values ---------------------------------------------------------------------

    def _input_value(self, end):
        if end in self.feeds:
            src, factor, offset = self.feeds[end]
            return factor * self.values[src] + offset
        ext = next(k for k, ends in self.open.items() if end in ends)
        return self.values[("", ext)]

    def _evaluate(self, el):
        """One element's outputs from its inputs' present values: a controller stepped one sample
        from its saved state (restored after), a static ME part read."""
        ins = {n: self._input_value((el.name, n)) for n in el.inputs}
        try:
            if el.role == "controller":
                el.inst.slave.setFMUState(el.state)
                el.inst.set_values(ins)
                el.inst.do_step(el.t, el.step)
            else:
                el.inst.set_values(ins)
            got = el.inst.get_values(el.outputs)
        except ArtibusError:
            raise
        except Exception as e:
            inputs = ", ".join(f"{n} = {x:g}" for n, x in ins.items())
            raise ArtibusError(f"{self.bench.file}: {el.name} ({el.inst.md.modelName}) failed at the operating "
                               f"point with {inputs}: {' '.join(el.inst.log[-2:]) or e}") from None
        for n, x in zip(el.outputs, got):
            self.values[(el.name, n)] = float(x)

    def _passes(self, passes=PASSES):
        """The loop's elements (all but the plants) evaluated ``passes`` times in order."""
        for _ in range(passes):
            for el in self.elements.values():
                if el.role != "plant":
                    self._evaluate(el)

    def propagate(self, passes=PASSES):
        """The loop's elements evaluated ``passes`` times in order; the plants' inputs set."""
        self._passes(passes)
        for el in self.plants():
            ins = {n: self._input_value((el.name, n)) for n in el.inputs}
            el.inst.set_values(ins)
            for n, x in zip(el.outputs, el.inst.get_values(el.outputs)):
                self.values[(el.name, n)] = float(x)

    def plants(self):
        return [e for e in self.elements.values() if e.role == "plant"]

    def close(self):
        import shutil
        for el in self.elements.values():
            if el.state is not None:
                try:
                    el.inst.slave.freeFMUState(el.state)
                except Exception:                 # an instance that failed: freed with it below
                    pass
            el.inst.close()
        for d in self._dirs:
            shutil.rmtree(d, ignore_errors=True)
        if self.run is not None:              # the run's instances (closed above) and its files
            self.run.close()

    # --- the loop as a map from the plants' outputs and the open inputs to the plants' inputs ----

    def loop(self, yp, r):
        """u_p of y_p (every plant output, in ``plant_outputs`` order) and r (``open`` order): the
        static elements evaluated, the plants left as they are."""
        for (key, x) in zip(self.plant_outputs(), yp):
            self.values[key] = float(x)
        for ext, x in zip(self.open, r):
            self.values[("", ext)] = float(x)
        self._passes()
        return np.array([self._input_value(k) for k in self.plant_inputs()])

    def plant_outputs(self):
        return [(e.name, n) for e in self.plants() for n in e.outputs]

    def plant_inputs(self):
        return [(e.name, n) for e in self.plants() for n in e.inputs]

    def operating_point(self):
        """(y_p, r) at the operating point"""
        return (np.array([self.values[k] for k in self.plant_outputs()]),
                np.array([self.values[("", k)] for k in self.open]))


def nominal_of(opened, key):
    v = opened.elements[key[0]].inst.vars.get(key[1]) if key[0] else None
    return lz.nominal_of(v)


def loop_gains(opened, step=STEP):
    """K_y = du_p/dy_p and K_r = du_p/dr by central differences of ``opened.loop`` around the
    operating point, each column's step ``step`` x the signal's nominal."""
    y0, r0 = opened.operating_point()
    ny = len(y0)
    z0 = np.concatenate([y0, r0])
    keys = opened.plant_outputs() + [("", k) for k in opened.open]
    cols = []
    for j, key in enumerate(keys):
        h = step * max(nominal_of(opened, key), abs(z0[j]) if key[0] == "" else 0.0, 1e-300)
        e = np.zeros(len(z0))
        e[j] = h
        zp, zm = z0 + e, z0 - e
        cols.append((opened.loop(zp[:ny], zp[ny:]) - opened.loop(zm[:ny], zm[ny:])) / (2 * h))
    opened.loop(y0, r0)
    K = np.array(cols).T if cols else np.zeros((len(opened.plant_inputs()), 0))
    return K[:, :ny], K[:, ny:]


def _plant_linear(el, step, derivatives, t0, states_only=False):
    """The element's Linear from all its Real inputs to all its Real outputs at its present point
    (``states_only``: A alone, no inputs or outputs: which states are dynamic; an input at a bound
    of its range, a damper's pct at 0, cannot be moved both ways)."""
    inst = el.inst
    ins = [] if states_only else [inst.vars[n] for n in el.inputs]
    outs = [] if states_only else [inst.vars[n] for n in el.outputs]
    return lz.linear_at(inst, ins, outs, t0, None, None, step, derivatives)


@dataclass
class BenchLinear:
    """The closed loop (``closed``: an artibus.linear.fmu.Linear over the plants' states, the open
    inputs, the plants' outputs), the plants' own (``plants``: name -> Linear), the loop's gains
    K_y (plant inputs by plant outputs) and K_r (by open inputs) and how each component was
    treated (``treated``: name -> a sentence)."""
    closed: object
    plants: dict
    Ky: np.ndarray
    Kr: np.ndarray
    treated: dict


def _blocks(lins):
    from scipy.linalg import block_diag
    pick = lambda m: block_diag(*[getattr(x, m) for x in lins]) if lins else np.zeros((0, 0))  # noqa: E731
    return pick("A"), pick("B"), pick("C"), pick("D")


def close_loop(A, B, C, D, Ky, Kr):
    """(A_cl, B_cl, C_cl, D_cl) of the plants (A, B, C, D) with u_p = K_y y_p + K_r r; an algebraic
    loop through the plants' feedthrough that has no solution (I - D K_y singular) is an error."""
    L = np.eye(len(C)) - D @ Ky
    try:          # (its condition number says nothing: D's entries in N and K's in rad/N differ by 1e6)
        LC, LDK = np.linalg.solve(L, C), np.linalg.solve(L, D @ Kr)
    except np.linalg.LinAlgError:
        LC = None
    if LC is None or not (np.all(np.isfinite(LC)) and np.all(np.isfinite(LDK))):
        raise ArtibusError("the loop through the plants' feedthrough D and the controllers' gains has no "
                           "unique solution (I - D K_y is singular): an algebraic loop without a solution")
    return A + B @ Ky @ LC, B @ (Ky @ LDK + Kr), LC, LDK


def _treatment(el):
    if el.role == "controller":
        return (f"Co-Simulation, sampled every {el.step:g} s: its response over one sample from its saved "
                "state taken as a static gain (sampling ignored: continuous equivalent; its own states, "
                "filters, held at the operating point)")
    if el.role == "static":
        return (f"Model Exchange without dynamic states ({', '.join(s.name for s in el.lin.states) or 'none'} "
                "only integrate): a static map of its inputs")
    return f"Model Exchange plant, {el.lin.method}"


def _save_controllers(opened):
    """Each controller's state saved at the start, the loop's values propagated, then each stepped
    one sample with them (a controller's first sample may reset its filters to the measured values,
    as DampingController's reference model does) and its state saved there: every evaluation of the
    loop starts from it. At a time of a run (``opened.at``) the state the run left is the one
    saved: it has had its samples."""
    for el in opened.elements.values():
        if el.role == "controller":
            if not getattr(el.inst.md.coSimulation, "canGetAndSetFMUstate", False):
                raise ArtibusError(f"{opened.bench.file}: {el.name} ({el.inst.md.modelName}) cannot save and "
                                   "restore its state (canGetAndSetFMUstate is not true): its response around "
                                   "the operating point cannot be measured; leave it out with --exclude "
                                   f"{el.name} (what it drives becomes an open input)")
            el.state, el.t = el.inst.slave.getFMUState(), opened.t0
    opened.propagate()
    if opened.at is not None:
        return
    for el in opened.elements.values():
        if el.role == "controller":
            opened._evaluate(el)
            first = el.state
            el.state, el.t = el.inst.slave.getFMUState(), el.t + el.step
            el.inst.slave.freeFMUState(first)


def _settle(opened, limit):
    """--steady for a bench: each plant integrated with its inputs held until its dynamic states
    rest (artibus.linear.fmu), the loop's values updated, twice."""
    times = {}
    for _ in range(2):
        for el in opened.plants():
            eq = lz.Equations(el.inst, [el.inst.vars[n] for n in el.inputs], [])
            t, _ = lz.steady_point(el.inst, eq, times.get(el.name, opened.t0), eq.inputs(), eq.nominals(), limit=limit)
            times[el.name] = t
        opened.propagate()
    return times


def _classify(opened, step, derivatives):
    """Each ME element linearised at the point; one without dynamic states becomes static."""
    for el in list(opened.plants()):
        try:
            el.lin = _plant_linear(el, step, derivatives, opened.t0, states_only=True)
        except ArtibusError as e:           # named by the component, not by where its FMU was unpacked
            text = str(e).replace(f"{el.inst.path}: ", "")
            raise ArtibusError(f"{opened.bench.file}: {el.name}: {text}") from None
        if not el.lin.dynamic:
            el.role = "static"
    if not opened.plants():
        kinds = ", ".join(f"{n} ({'Model Exchange, no dynamic states' if e.role == 'static' else 'Co-Simulation only'})"
                          for n, e in opened.elements.items())
        raise ArtibusError(f"{opened.bench.file}: {opened.bench.name} has no Model Exchange plant with dynamic "
                           f"states to linearise (its components: {kinds}); a Co-Simulation FMU lets nobody "
                           "set its states or read its derivatives")


def _read(bench, variants, sets):
    """(path, bench, overrides) of the bench (a name or an .ssp): its variants' values and
    ``sets`` ({"Component.variable": value}), each set's component checked."""
    from artibus.bench import ssp
    path = ssp.ssp_path(bench)
    b = ssp.read(path)
    overrides = dict(ssp.variant_overrides(path, list(variants)))
    for k, v in (sets or {}).items():
        comp, dot, var = k.partition(".")
        if not dot or comp not in b.components:
            from artibus.bench.parameters import suggest
            raise ArtibusError(f"--set {k}={v}: expected Component.variable, a component of {b.name} "
                               f"({', '.join(b.components)}){suggest(comp, b.components)}")
        overrides[k] = v
    return path, b, overrides


def open_bench(bench, variants=(), sets=None, exclude=(), at=None):
    """The bench (a name or an .ssp) opened at its start values, variants and ``sets``
    ({"Component.variable": value}) applied, or (``at``) at that time of its run (open_run): an
    Opened (close it)."""
    if at is not None:
        return open_run(bench, at, variants, sets, exclude)
    path, b, overrides = _read(bench, variants, sets)
    return Opened(b, str(path), tuple(exclude), overrides)


def _check_at(b, at):
    """--at: a finite time from the bench's start to its stop time."""
    import math
    start, stop = float(b.start_time or 0.0), b.stop_time
    if not math.isfinite(at):
        raise ArtibusError(f"{b.file}: --at {at!r}: a finite time from {b.name}'s start {start:g} s "
                           f"to its stop time{f' {float(stop):g} s' if stop is not None else ''}")
    if at < start:
        raise ArtibusError(f"{b.file}: --at {at:g} s is before {b.name}'s start time {start:g} s")
    if stop is not None and at > float(stop) + 1e-9 * max(1.0, abs(float(stop))):
        raise ArtibusError(f"{b.file}: --at {at:g} s is after {b.name}'s stop time {float(stop):g} s "
                           "(its run ends there)")


def open_run(bench, at, variants=(), sets=None, exclude=()):
    """The bench run by artibus's runner from its start to time ``at`` (artibus.runner.Simulation,
    as `artibus run --fmi-type me` runs it, the variants and ``sets`` applied) and opened there: an
    Opened whose elements are the run's own instances (close it: the run goes with it).

    Why the run's instances and not fresh ones set from the run's FMU states: the plants' continuous
    states, every controller's internal state (filters, reference model, integrators) and the inputs
    each was last given are then exactly the run's, and nothing is copied between instances (which
    would need each FMU to serialise its state: canSerializeFMUstate, FMI 2.0.4 2.1.8, FMI 3.0
    "Getting and Setting the Complete FMU State"; the controllers' states are still saved and
    restored in their own instance for the loop's differences, _save_controllers). The plants run as
    Model Exchange (FMI 2.0.4 3, FMI 3.0 3): their continuous states are what the linearisation sets
    and moves, which a Co-Simulation build (its solver inside) does not expose; the runner's ME
    integration gives the same KPIs (artibus.fmu.me.BENCH_TOLERANCE). The point's time is the run's communication point nearest
    ``at`` (a bench steps on a fixed base step), said in ``notes`` when it is not ``at``."""
    from artibus.runner.simulation import Simulation
    path, b, overrides = _read(bench, variants, sets)
    _check_at(b, float(at))
    start = float(b.start_time or 0.0)
    sim = Simulation(path, overrides=overrides, fmi_type="me")
    try:
        if round((float(at) - start) / sim.base_step) < 1:       # the start itself: no step to run
            sim.close()
            opened = open_bench(bench, variants, sets, exclude)
            if float(at) != start:
                opened.notes.append(f"--at {float(at):g} s: the run's nearest communication point is its "
                                    f"start t = {start:g} s (its base step {sim.base_step:g} s)")
            return opened
        t_end = _run_to(sim, b, float(at))
        opened = Opened(sim.bench, str(sim.ssp), tuple(exclude), overrides, run=sim, at=t_end)
    except BaseException:
        sim.close()
        raise
    if abs(t_end - float(at)) > 1e-9 * max(1.0, abs(t_end)):
        opened.notes.append(f"--at {float(at):g} s: the run's nearest communication point t = {t_end:g} s "
                            f"(its base step {sim.base_step:g} s)")
    return opened


def _run_to(sim, b, at):
    """The Simulation run to ``at``: the time it reached (its last communication point); a run
    that a component ended before is an error naming it."""
    result = sim.run(stop_time=at)
    t_end = float(result.array()[-1, 0])
    end = getattr(result, "terminated", None)
    if end is not None:
        raise ArtibusError(f"{b.file}: {end.component} ended the run at t = {end.time:g} s ({end.how}), "
                           f"before the operating point --at {at:g} s")
    return t_end


def linearize_bench(bench, variants=(), sets=None, exclude=(), steady=False, inputs=None, outputs=None,
                    step=lz.STEP, derivatives="auto", steady_limit=lz.STEADY_LIMIT, at=None):
    """The closed-loop linear model of the bench (a BenchLinear) at its start, at time ``at`` of its
    run (open_run) or ``steady``: ``inputs``/``outputs``: names "Component.variable" of open inputs
    and plant outputs (default all)."""
    if at is not None and steady:
        raise ArtibusError("linearize: --at TIME or --steady, not both")
    opened = open_bench(bench, variants, sets, exclude, at)
    try:
        return linear_of(opened, steady, inputs, outputs, step, derivatives, steady_limit)
    finally:
        opened.close()


def linear_of(opened, steady=False, inputs=None, outputs=None, step=lz.STEP, derivatives="auto",
              steady_limit=lz.STEADY_LIMIT):
    """BenchLinear of an Opened bench (see linearize_bench)."""
    _save_controllers(opened)
    opened.propagate()
    times = _settle(opened, steady_limit) if steady else {}
    _classify(opened, step, derivatives)
    opened.propagate()
    for el in opened.plants():                # the point moved with the loop's values
        el.lin = _plant_linear(el, step, derivatives, opened.t0)
    Ky, Kr = loop_gains(opened)
    lins = [e.lin for e in opened.plants()]
    A_cl, B_cl, C_cl, D_cl = close_loop(*_blocks(lins), Ky, Kr)
    states = _prefixed(opened, "states")
    outs = _prefixed(opened, "outputs")
    ins = [_open_signal(opened, k) for k in opened.open]
    lin = lz.Linear(A_cl, B_cl, C_cl, D_cl, states, ins, outs, fmu=opened.bench.name, time=opened.t0,
                    method="closed loop A + B K C (artibus.linear.bench)")
    lin.dynamic = [f"{e.name}.{n}" for e in opened.plants() for n in e.lin.dynamic]
    if opened.at is not None:
        lin.notes.append(f"at t = {opened.t0:g} s of the bench's run (artibus.runner, its ME components as "
                         "Model Exchange): every plant's states and every controller's state the run's there")
    lin.notes += opened.notes
    if times:
        lin.notes.append("steady: each plant integrated with the loop's values held until its dynamic states "
                         "rest (" + ", ".join(f"{n} to t = {t:g} s" for n, t in times.items()) + "), twice")
    lin = _select(lin, inputs, outputs)
    treated = {n: _treatment(e) for n, e in opened.elements.items()}
    return BenchLinear(lin, {e.name: e.lin for e in opened.plants()}, Ky, Kr, treated)


def _prefixed(opened, what):
    """Every plant's states or outputs (Signal), named Component.variable"""
    return [lz.Signal(f"{e.name}.{s.name}", s.unit, s.nominal, s.value)
            for e in opened.plants() for s in getattr(e.lin, what)]


def _open_signal(opened, ext):
    comp, _, var = ext.partition(".")
    el = opened.elements.get(comp)
    if el is None:                            # an excluded component's output: the unit of what it feeds
        comp, var = opened.open[ext][0]
        el = opened.elements[comp]
    v = el.inst.vars[var]
    return lz.Signal(ext, lz.unit_of(v), lz.nominal_of(v), opened.values[("", ext)])


def _select(lin, inputs, outputs):
    """The open inputs and plant outputs named (each checked: an unknown one says the close ones)."""
    if inputs is not None:
        j = [lin._index(n, lin.inputs, "input") for n in inputs]
        lin.B, lin.D, lin.inputs = lin.B[:, j], lin.D[:, j], [lin.inputs[k] for k in j]
    if outputs is not None:
        i = [lin._index(n, lin.outputs, "output") for n in outputs]
        lin.C, lin.D, lin.outputs = lin.C[i], lin.D[i], [lin.outputs[k] for k in i]
    return lin


def report(bl):
    """The lines `artibus linearize BENCH` prints: how each component was treated, then the
    closed loop's report (artibus.linear.fmu.report)."""
    lines = [f"{n}: {t}" for n, t in bl.treated.items()]
    return lines + lz.report(bl.closed)
