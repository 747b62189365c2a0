"""The linear model of one Model Exchange FMU at an operating point (`artibus linearize`, issue 43):

    der(x) = A dx + B du,    y = C dx + D du       (dx = x - x0, du = u - u0, y - y0)

x the FMU's continuous states in the order of its ModelStructure's derivatives (FMI 2.0.4 2.2.8
<Derivatives>, FMI 3.0 2.4.8 <ContinuousStateDerivative>: "the order defines the state vector"),
u the inputs chosen, y the outputs chosen (a state may be named as an output). The operating point:
the FMU initialised with the values given (FMI 2.0.4 3.2.2, FMI 3.0 3.2), then, if asked, integrated
as Model Exchange (artibus.fmu.me, CVODE) with the inputs held to a time, or until its dynamic
states are steady. The matrices come

- from fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative (FMI 2.0.4 2.1.9, FMI 3.0
  2.2.12 "Getting Partial Derivatives") where the FMU says providesDirectionalDerivative(s)="true";
- else by central finite differences, each state and input moved by +-h x its nominal (the
  FMU's fmi2/fmi3GetNominalsOfContinuousStates, an input's nominal attribute): error O(h^2),
  exact to rounding for a model linear in them.

``Linear.modes()``: each eigenvalue of A as a mode (natural and damped frequency, damping ratio,
time constant, the state that dominates its eigenvector scaled by the nominals);
``Linear.frequency_response(input, output, w)``: C (jwI - A)^-1 B + D.
A bench's ME plants with their controllers in the loop: artibus.linear.bench (on ``linear_at``)."""
import math
from dataclasses import dataclass, field

import numpy as np

from artibus.base import ArtibusError

#: central finite differences: each state or input moved by +-STEP x its nominal
STEP = 1e-5
#: --steady: the dynamic states' derivatives below this x their nominal per second
STEADY_TOL = 1e-6
#: --steady: give up after this long in simulated time, s
STEADY_LIMIT = 600.0
#: an operating point whose articulation angle (artAngle[i], the bus models') is beyond this has
#: jack-knifed: the sections fold onto each other, a linear model of it means nothing
JACKKNIFE = math.radians(90.0)


@dataclass
class Signal:
    """A state, input or output of the linear model: its name, unit, nominal, value at the point."""
    name: str
    unit: str
    nominal: float
    value: float


@dataclass
class Mode:
    """One eigenvalue of A (a complex pair once, Im > 0): ``wn`` natural frequency |lambda| (rad/s),
    ``wd`` damped frequency |Im lambda| (rad/s), ``zeta`` damping ratio -Re/|lambda|, ``tau`` the
    time constant -1/Re of a real mode (None for an integrator, lambda ~ 0), ``dominant`` the state
    with the largest |component| of its eigenvector, each component divided by the state's nominal."""
    eigenvalue: complex
    wn: float
    wd: float
    zeta: float
    tau: float
    dominant: str
    next: tuple = None            # (the state second in the eigenvector, its size relative to the first)

    @property
    def kind(self):
        if self.wd > 0:
            return "oscillatory"
        return "integrator" if self.tau is None else "real"


@dataclass
class Linear:
    """A, B, C, D with the states', inputs' and outputs' names and units (Signal), the FMU, the
    time of the point and how the derivatives were found (``method``); ``notes``: what to know
    about the point (a singular A on the dynamic states, ...)."""
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list
    inputs: list
    outputs: list
    fmu: str = ""
    time: float = 0.0
    method: str = ""
    dynamic: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def modes(self, tiny=1e-9):
        """Every eigenvalue of A as a Mode, a complex pair once; sorted by |lambda|."""
        lam, vec = np.linalg.eig(self.A)
        nominal = np.array([s.nominal for s in self.states])
        scale = max(1.0, float(np.max(np.abs(lam)))) if len(lam) else 1.0
        modes = []
        for k, z in enumerate(lam):
            if z.imag < -tiny * scale:
                continue                           # the pair's other half
            shape = np.abs(vec[:, k]) / nominal
            order = np.argsort(-shape)
            nxt = ((self.states[int(order[1])].name, float(shape[order[1]] / shape[order[0]]))
                   if len(order) > 1 and shape[order[0]] > 0 else None)
            wn = abs(z)
            tau = None if wn <= tiny * scale else (-1.0 / z.real if z.real != 0 else math.inf)
            wd = abs(z.imag) if abs(z.imag) > tiny * scale else 0.0
            modes.append(Mode(complex(z), wn, wd, -z.real / wn if wn > tiny * scale else 0.0,
                              tau if wd == 0 else None, self.states[int(order[0])].name, nxt))
        return sorted(modes, key=lambda m: m.wn)

    def _index(self, name, signals, what):
        names = [s.name for s in signals]
        if name in names:
            return names.index(name)
        from artibus.bench.parameters import suggest
        raise ArtibusError(f"{self.fmu}: '{name}' is no {what} of this linear model "
                           f"(its {what}s: {', '.join(names)}){suggest(name, names)}")

    def frequency_response(self, input, output, w):
        """G(jw) = C (jwI - A)^-1 B + D from ``input`` to ``output`` (an output or a state by name)
        at the angular frequencies ``w`` (rad/s): complex, as an array like w."""
        j = self._index(input, self.inputs, "input")
        if output in [s.name for s in self.outputs] or output not in [s.name for s in self.states]:
            i = self._index(output, self.outputs, "output")
            c, d = self.C[i], self.D[i, j]
        else:
            i = self._index(output, self.states, "state")
            c, d = np.eye(len(self.states))[i], 0.0
        w = np.atleast_1d(np.asarray(w, dtype=float))
        n = len(self.states)
        g = np.array([c @ np.linalg.solve(1j * x * np.eye(n) - self.A, self.B[:, j]) + d for x in w])
        return g


# --- the FMU's equations as functions of the states and inputs ------------------------------

def _state_of(fmu, der, derivatives):
    """The state whose derivative ``der`` is (its derivative attribute: FMI 2.0.4 2.2.7, FMI 3.0
    2.4.7.5); where that names no possible state (the independent variable, or a derivative
    itself: the fmi-sys build of the Reference-FMUs' FMI 2.0 descriptions has the index off by
    one) the variable the name der(<name>) names."""
    target = getattr(der, "derivative", None)
    v = fmu.vars.get(target.name) if target is not None else None
    if (v is None or v.name in derivatives) and der.name.startswith("der(") and der.name.endswith(")"):
        v = fmu.vars.get(der.name[4:-1])
    return v


class Equations:
    """f(x, u) and g(x, u) of an initialised ME FMU (FMPy's FMU2Model / FMU3Model ``slave``):
    the states set with fmi2/fmi3SetContinuousStates, the inputs with SetReal/SetFloat64,
    the derivatives and outputs read back (FMI 2.0.4 3.2.1, FMI 3.0 3.2.1: Continuous-Time Mode)."""

    def __init__(self, fmu, inputs, outputs):
        from ctypes import c_double
        self.fmu, self.slave, self.fmi = fmu, fmu.slave, fmu.fmi
        md = fmu.md
        self.nx = len(md.derivatives)
        self._buf = (c_double * max(self.nx, 1))()
        self.der_vrs = [d.variable.valueReference for d in md.derivatives]
        ders = {d.variable.name for d in md.derivatives}
        self.state_vars = [_state_of(fmu, d.variable, ders) for d in md.derivatives]
        self.in_vrs = [v.valueReference for v in inputs]
        self.out_vrs = [v.valueReference for v in outputs]
        self.out_state = [None] * len(outputs)

    def _get(self, vrs):
        if not vrs:
            return np.zeros(0)
        get = self.slave.getFloat64 if self.fmi == 3 else self.slave.getReal
        return np.array(get(vrs), dtype=float)

    def _set(self, vrs, values):
        if vrs:
            (self.slave.setFloat64 if self.fmi == 3 else self.slave.setReal)(vrs, [float(x) for x in values])

    def states(self):
        self.slave.getContinuousStates(self._buf, self.nx)
        return np.array(self._buf[:self.nx])

    def nominals(self):
        self.slave.getNominalsOfContinuousStates(self._buf, self.nx)
        return np.array([x if x > 0 and math.isfinite(x) else 1.0 for x in self._buf[:self.nx]])

    def set_states(self, x):
        for k, v in enumerate(x):
            self._buf[k] = float(v)
        self.slave.setContinuousStates(self._buf, self.nx)

    def inputs(self):
        return self._get(self.in_vrs)

    def __call__(self, x, u):
        """(f, g) at x, u"""
        self.set_states(x)
        self._set(self.in_vrs, u)
        if self.fmi == 3:
            self.slave.getContinuousStateDerivatives(self._buf, self.nx)
        else:
            self.slave.getDerivatives(self._buf, self.nx)
        return np.array(self._buf[:self.nx]), self._get(self.out_vrs)


def _central(eq, x0, u0, xn, un, step):
    """A, B, C, D by central differences: column j of [A; C] is (f, g)(x0 + h_j e_j) minus
    (f, g)(x0 - h_j e_j) over 2 h_j, h_j = step x nominal_j; the same for the inputs."""
    cols_x, cols_u = [], []
    for j in range(len(x0)):
        e = np.zeros(len(x0))
        e[j] = step * xn[j]
        (fp, gp), (fm, gm) = eq(x0 + e, u0), eq(x0 - e, u0)
        cols_x.append(np.concatenate([fp - fm, gp - gm]) / (2 * e[j]))
    for j in range(len(u0)):
        e = np.zeros(len(u0))
        e[j] = step * un[j]
        (fp, gp), (fm, gm) = eq(x0, u0 + e), eq(x0, u0 - e)
        cols_u.append(np.concatenate([fp - fm, gp - gm]) / (2 * e[j]))
    eq(x0, u0)                                  # the point restored
    return _split(cols_x, cols_u, len(x0), len(eq.out_vrs), len(u0))


def _split(cols_x, cols_u, nx, ny, nu):
    X = np.array(cols_x).T if cols_x else np.zeros((nx + ny, 0))
    U = np.array(cols_u).T if cols_u else np.zeros((nx + ny, nu))
    return X[:nx], U[:nx], X[nx:], U[nx:]


def _directional(eq, x0, u0):
    """A, B, C, D column by column from fmi2/fmi3GetDirectionalDerivative: unknowns the
    derivatives and the outputs, knowns the states (their value references) and the inputs, the
    seed a unit vector (FMI 2.0.4 2.1.9, FMI 3.0 2.2.12)."""
    eq(x0, u0)
    unknowns = eq.der_vrs + eq.out_vrs
    state_vrs = [v.valueReference for v in eq.state_vars]
    dd = eq.slave.getDirectionalDerivative
    cols_x = [np.array(dd(unknowns, [vr], [1.0]), dtype=float) for vr in state_vrs]
    cols_u = [np.array(dd(unknowns, [vr], [1.0]), dtype=float) for vr in eq.in_vrs]
    return _split(cols_x, cols_u, len(x0), len(eq.out_vrs), len(u0))


def provides_derivatives(path):
    """providesDirectionalDerivative (FMI 2.0) or providesDirectionalDerivatives (FMI 3.0) of the
    FMU's <ModelExchange> (FMI 2.0.4 3.3.1, FMI 3.0 3.4.1), read from its modelDescription.xml
    (FMPy 0.3 keeps FMI 2.0's attribute only)."""
    import zipfile

    from lxml import etree
    with zipfile.ZipFile(str(path)) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    me = root.find("ModelExchange")
    return me is not None and any(me.get(a) in ("true", "1") for a in
                                  ("providesDirectionalDerivative", "providesDirectionalDerivatives"))


# --- the operating point ------------------------------------------------------------------------

def dynamic_states(A, nominal, rel=1e-12):
    """The states the dynamics need: those on a loop of the dependency graph (i depends on j where
    A[i, j] != 0: a self-loop or a cycle) and every state such a state depends on. The rest (a
    position along the road, a heading that only turns the path) are ignorable coordinates
    (Lagrangian mechanics): they may move forever in a steady motion. A boolean list."""
    n = len(A)
    if n == 0:
        return []
    S = np.abs(A) * nominal[None, :] / nominal[:, None]
    R = S > rel * max(float(S.max()), 1e-300)
    for k in range(n):                          # Warshall: R[i, j] = a path i -> ... -> j
        R = R | (R[:, [k]] & R[[k], :])
    on_loop = np.diag(R).copy()
    return list(on_loop | R[on_loop].any(axis=0))


def _check_point(fmu, eq, x0, f0, y0, outputs):
    """A NaN or Inf state, derivative or output, or a jack-knifed articulation: an error naming
    the FMU and the variable."""
    md = fmu.md
    for k, (x, f) in enumerate(zip(x0, f0)):
        if not (math.isfinite(x) and math.isfinite(f)):
            name = eq.state_vars[k].name if eq.state_vars[k] is not None else f"state {k + 1}"
            raise ArtibusError(f"{fmu.path}: {md.modelName}'s state {name} = {x!r}, its derivative "
                               f"{f!r} at the operating point: not a finite number, no linear model")
    for v, y in zip(outputs, y0):
        if not math.isfinite(y):
            raise ArtibusError(f"{fmu.path}: {md.modelName}'s output {v.name} = {y!r} at the operating "
                               "point: not a finite number, no linear model")
    arts = [n for n in fmu.vars if n.startswith("artAngle")]
    for n, a in zip(arts, fmu.get(*arts) if arts else ()):
        if abs(a) >= JACKKNIFE:
            raise ArtibusError(f"{fmu.path}: {md.modelName} has jack-knifed at the operating point: "
                               f"{n} = {math.degrees(a):.1f} deg (|{n}| >= {math.degrees(JACKKNIFE):g} deg): "
                               "no linear model of a folded bus")


def _simulate_to(fmu, t0, t1):
    """Integrate the ME FMU with its inputs held from t0 to t1 (artibus.fmu.me: CVODE); a failure
    is an error naming the FMU and its message."""
    from fmpy.fmi1 import FMICallException
    if t1 <= t0:
        return
    try:
        ended = fmu.do_step(t0, t1 - t0)
    except FMICallException as e:
        raise ArtibusError(f"{fmu.path}: {fmu.md.modelName} failed on the way to the operating point "
                           f"(t = {fmu.last_successful_time():g} s): {fmu.calls.facade.message() or e}") from None
    if ended is not None:
        raise ArtibusError(f"{fmu.path}: {fmu.md.modelName} ended the simulation at t = {ended:g} s, "
                           f"before the operating point t = {t1:g} s")


def steady_point(fmu, eq, t0, u0, xn, tol=STEADY_TOL, limit=STEADY_LIMIT):
    """Integrate until the derivatives of the dynamic states are below tol x their nominals (per
    second); returns (time, dynamic mask). Never steady within ``limit`` s: an error naming the
    state still moving most."""
    x = eq.states()
    f, _ = eq(x, u0)
    A = _central(eq, x, u0, xn, np.ones(len(u0)), STEP)[0]
    dyn = np.array(dynamic_states(A, xn), dtype=bool)
    t, h = t0, 0.1
    while True:
        x = eq.states()
        f, _ = eq(x, u0)
        r = np.where(dyn, np.abs(f) / xn, 0.0)
        if not np.all(np.isfinite(r)):
            break                               # a NaN: _check_point names the variable
        if r.max() <= tol:
            return t, dyn
        if t - t0 >= limit:
            k = int(np.argmax(r))
            name = eq.state_vars[k].name if eq.state_vars[k] is not None else f"state {k + 1}"
            raise ArtibusError(f"{fmu.path}: {fmu.md.modelName} is not steady after {limit:g} s: the "
                               f"derivative of {name} is still {f[k]:.3g} (|der|/nominal > {tol:g}/s): "
                               "no steady state with these inputs (use --at TIME for a point of a run)")
        _simulate_to(fmu, t, t + h)
        t, h = t + h, min(2 * h, 20.0)
    return t, dyn


# --- the linear model ---------------------------------------------------------------------------

def _chosen(fmu, names, causality):
    """The inputs or outputs named (each checked: an unknown name says the close ones), or all of
    the FMU's Real ones of that causality."""
    if names is None:
        return [v for v in fmu.md.modelVariables if v.causality == causality and v.kind == "Real"
                and not v.shape and v.variability == "continuous"]
    chosen = []
    for n in names:
        v = fmu.var(n)
        if v.causality != causality or v.kind != "Real":
            raise ArtibusError(f"{fmu.path}: {n} is no Real {causality} of {fmu.md.modelName} "
                               f"(its causality is {v.causality}, its type {v.type})")
        chosen.append(v)
    return chosen


def unit_of(v):
    return (v.unit if v is not None else None) or "-"


def nominal_of(v):
    x = getattr(v, "nominal", None) if v is not None else None
    try:
        x = float(x)
    except (TypeError, ValueError):
        return 1.0
    return x if x > 0 and math.isfinite(x) else 1.0


def _open(path):
    """The ME instance of the FMU at ``path`` (a path, or the name of a built FMU); an FMU without
    Model Exchange is refused: a Co-Simulation FMU lets nobody set its states or read its derivatives."""
    from pathlib import Path

    from artibus.base import fmu_path
    from artibus.fmu.instance import Fmu, read_model
    p = Path(str(path))
    p = p if p.suffix == ".fmu" or p.is_file() else fmu_path(str(path))
    md = read_model(p)
    if md.modelExchange is None:
        raise ArtibusError(f"{p}: {md.modelName} has no Model Exchange interface: a linear model needs "
                           "its states set and its derivatives read, which Co-Simulation does not "
                           "offer (finite differences on a Co-Simulation FMU are not possible)")
    return Fmu(p, instance_name="linearize", interface="me")


def linearize(fmu, at=None, steady=False, parameters=None, inputs=None, outputs=None, step=STEP,
              derivatives="auto", steady_limit=STEADY_LIMIT):
    """The Linear model of the ME FMU ``fmu`` (a path or a built FMU's name) with ``parameters``
    {name: value} (parameters and inputs' held values) at its start, at time ``at``, or (``steady``)
    where its dynamic states have come to rest; ``inputs``/``outputs``: names (default: all the
    continuous Real ones); ``derivatives``: "auto" (directional derivatives where the FMU provides
    them), "fd" (finite differences, step ``step`` x nominal) or "exact"; ``steady_limit``: how long
    (s, simulated) --steady waits for the states to come to rest."""
    if at is not None and steady:
        raise ArtibusError("linearize: --at TIME or --steady, not both")
    if at is not None and not (math.isfinite(at) and at >= 0):
        raise ArtibusError(f"linearize: --at {at!r}: a finite time >= 0 s")
    if not (step > 0 and math.isfinite(step)):
        raise ArtibusError(f"linearize: step {step!r}: a finite number > 0")
    inst = _open(fmu)
    try:
        ins, outs = _chosen(inst, inputs, "input"), _chosen(inst, outputs, "output")
        for n in parameters or {}:
            inst.var(n)                         # an unknown name says the close ones
        t0 = float(getattr(inst.md.defaultExperiment, "startTime", None) or 0.0)
        inst.initialize(dict(parameters or {}), start_time=t0)
        return linear_at(inst, ins, outs, t0, at, steady_limit if steady else None, step, derivatives)
    finally:
        inst.close()


def linear_at(inst, ins, outs, t0, at, steady, step, derivatives):
    """The operating point reached (at: a time; steady: None, or how long to wait for rest, s)
    and the matrices there."""
    eq = Equations(inst, ins, outs)
    xn = eq.nominals()
    un = np.array([nominal_of(v) for v in ins])
    u0 = eq.inputs()
    t, dyn = t0, None
    if at is not None:
        if at < t0:
            raise ArtibusError(f"{inst.path}: --at {at:g} s is before {inst.md.modelName}'s start time {t0:g} s")
        _simulate_to(inst, t0, float(at))
        t = float(at)
    elif steady is not None:
        t, dyn = steady_point(inst, eq, t0, u0, xn, limit=steady)
    x0 = eq.states()
    f0, y0 = eq(x0, u0)
    _check_point(inst, eq, x0, f0, y0, outs)
    exact = provides_derivatives(inst.path)
    if derivatives == "exact" and not exact:
        raise ArtibusError(f"{inst.path}: {inst.md.modelName} provides no directional derivatives "
                           "(providesDirectionalDerivative is not true): use finite differences")
    if exact and None in eq.state_vars:         # a state without its variable: no known to seed
        exact = False
        if derivatives == "exact":
            raise ArtibusError(f"{inst.path}: {inst.md.modelName}: a state's variable is not named by its "
                               "derivative: no directional derivative with respect to it")
    if exact and derivatives != "fd":
        A, B, C, D = _directional(eq, x0, u0)
        method = f"directional derivatives (fmi{inst.fmi}GetDirectionalDerivative)"
    else:
        A, B, C, D = _central(eq, x0, u0, xn, un, step)
        method = f"finite differences (central), step h = {step:g} x each state's and input's nominal"
    states = [Signal(v.name if v is not None else f"x{k + 1}", unit_of(v), xn[k], x0[k])
              for k, v in enumerate(eq.state_vars)]
    lin = Linear(A, B, C, D, states, [Signal(v.name, unit_of(v), n, x) for v, n, x in zip(ins, un, u0)],
                 [Signal(v.name, unit_of(v), nominal_of(v), y) for v, y in zip(outs, y0)],
                 fmu=str(inst.path), time=t, method=method)
    dyn = np.array(dynamic_states(A, xn), dtype=bool) if dyn is None else dyn
    lin.dynamic = [s.name for s, d in zip(states, dyn) if d]
    _note_singular(lin, dyn, steady is not None)
    return lin


def _note_singular(lin, dyn, steady):
    """A singular A on the dynamic states (a steady state that is not isolated: a free rigid-body
    motion, a neutral direction) noted."""
    idx = np.flatnonzero(dyn)
    if len(idx) == 0:
        return
    sub = lin.A[np.ix_(idx, idx)]
    sv = np.linalg.svd(sub, compute_uv=False)
    if sv[-1] <= 1e-10 * max(sv[0], 1e-300):
        what = "steady state" if steady else "operating point"
        lin.notes.append(f"A is singular on the dynamic states ({', '.join(lin.dynamic)}): the "
                         f"{what} is not isolated (a neutral direction: an eigenvalue 0)")


# --- output -------------------------------------------------------------------------------------

def modes_table(lin):
    """The printed table of the modes: eigenvalue, natural frequency (rad/s, Hz), damped frequency,
    damping ratio, or the time constant of a real mode; the dominant state."""
    rows = [f"{'eigenvalue':>24}  {'wn [rad/s]':>10} {'fn [Hz]':>8} {'wd [rad/s]':>10} {'zeta':>7}  "
            f"{'time constant':>14}  dominant state"]
    for m in lin.modes():
        z = m.eigenvalue
        ev = f"{z.real:.5g} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.5g}j" if m.wd else f"{z.real:.5g}"
        if m.kind == "oscillatory":
            rows.append(f"{ev:>24}  {m.wn:10.4g} {m.wn / (2 * math.pi):8.4g} {m.wd:10.4g} {m.zeta:7.4f}  "
                        f"{'':>14}  {m.dominant}" + (f" (next {m.next[0]}: {m.next[1]:.2f})" if m.next else ""))
        else:
            tc = "integrator" if m.kind == "integrator" else (
                f"{m.tau:.4g} s" if m.tau > 0 else f"unstable {-m.tau:.4g} s")
            rows.append(f"{ev:>24}  {'':>10} {'':>8} {'':>10} {'':>7}  {tc:>14}  {m.dominant}")
    return rows


def _labels(signals, prefix=""):
    return [f"{prefix}{s.name} [{s.unit}]" for s in signals]


def write_csv(lin, path):
    """One block per matrix: its name and the column names, then a row per row name (A: rows
    der(state), columns states; B: der(state) by inputs; C: outputs by states; D: outputs by
    inputs), blocks separated by a blank line; written under a temporary name and renamed."""
    from artibus.files import atomic_write
    import csv
    blocks = [("A", lin.A, _labels(lin.states, "der "), _labels(lin.states)),
              ("B", lin.B, _labels(lin.states, "der "), _labels(lin.inputs)),
              ("C", lin.C, _labels(lin.outputs), _labels(lin.states)),
              ("D", lin.D, _labels(lin.outputs), _labels(lin.inputs))]
    with atomic_write(path, newline="") as f:
        w = csv.writer(f)
        w.writerow([f"# {lin.fmu} at t = {lin.time:g} s: {lin.method}"])
        for name, M, rows, cols in blocks:
            w.writerow([])
            w.writerow([name] + cols)
            for r, row in zip(rows, M):
                w.writerow([r] + [repr(float(x)) for x in row])
    return path


def write_mat(lin, path):
    """A, B, C, D, the names and units of the states, inputs and outputs (cell arrays), their
    values at the point (x0, u0, y0), the time and the method, as a MATLAB file (scipy.io.savemat)."""
    from scipy.io import savemat

    from artibus.files import atomic_path

    def cells(signals, what):
        return np.array([getattr(s, what) for s in signals], dtype=object)
    data = {"A": lin.A, "B": lin.B, "C": lin.C, "D": lin.D, "time": lin.time, "method": lin.method,
            "fmu": lin.fmu, "x0": np.array([s.value for s in lin.states]),
            "u0": np.array([s.value for s in lin.inputs]), "y0": np.array([s.value for s in lin.outputs])}
    for key, signals in (("states", lin.states), ("inputs", lin.inputs), ("outputs", lin.outputs)):
        data[key] = cells(signals, "name")
        data[key[:-1] + "_units"] = cells(signals, "unit")
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            savemat(f, data)
    return path


def bode_plot(lin, input, output, path, w=None):
    """The linear model's Bode plot from ``input`` to ``output`` (gain and phase over 0.01..100
    rad/s, or ``w``), each lightly damped mode's natural frequency marked; returns the path."""
    from artibus.study import bode
    if w is None:
        w = np.geomspace(1e-2, 1e2, 400)
    g = lin.frequency_response(input, output, w)
    f = w / (2 * math.pi)
    pts = [bode.Point(float(x), float(abs(z)), float(np.angle(z))) for x, z in zip(f, g)]
    units = {s.name: s.unit for s in lin.outputs + lin.states}
    in_unit = {s.name: s.unit for s in lin.inputs}.get(input, "")
    marks = [(m.wn / (2 * math.pi), f"mode {m.wn:.3g} rad/s, zeta {m.zeta:.2f} ({m.dominant})")
             for m in lin.modes() if m.kind == "oscillatory" and m.zeta < 0.7 and f[0] <= m.wn / (2 * math.pi) <= f[-1]]
    return bode.plot(path, {output: {f"linear model ({lin.method.split(',')[0]})": pts}},
                     f"{lin.fmu}: {output} / {input} at t = {lin.time:g} s", units={output: units.get(output, "")},
                     input_unit=in_unit, marks=marks)


def report(lin):
    """The lines `artibus linearize` prints: the point, the method, the sizes, the modes."""
    lines = [f"{lin.fmu} at t = {lin.time:g} s: {len(lin.states)} states, {len(lin.inputs)} inputs, "
             f"{len(lin.outputs)} outputs; {lin.method}",
             "states: " + ", ".join(f"{s.name} = {s.value:.6g} {s.unit}" for s in lin.states)]
    if lin.dynamic and len(lin.dynamic) < len(lin.states):
        lines.append("free states (on no feedback loop of A: positions, a heading that only turns the path, "
                     "a speed nothing brakes): "
                     + ", ".join(s.name for s in lin.states if s.name not in lin.dynamic))
    lines += [f"note: {n}" for n in lin.notes]
    lines.append("modes (wn natural frequency |lambda|, wd damped frequency |Im lambda|, zeta = -Re/|lambda|):")
    return lines + ["  " + r for r in modes_table(lin)]
