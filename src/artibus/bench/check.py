"""`artibus check VEHICLE.ssv`: is a vehicle's parameter set consistent?
(`artibus check BENCH`: what of a bench the runner does not apply and what is
artibus-specific, see check_bench.)

For a BusDynamics set (nModules, nAxles, m[i], Jz[i], lHf/lHr, axleModule,
xA, C, mu, lFront/lRear, width; see ssp/parameters/Template.ssv and
docs/geometry.png for the conventions) and a BusKinematics set (N, L0, L[i],
Lh[i]) it checks:

- the counts against the arrays: every module's, hinge's and axle's entries
  given, none beyond nModules / nModules - 1 / nAxles (N for the kinematic model);
- masses, inertias, cornering stiffnesses, friction, widths and body lengths
  positive; static loads Fz0 positive when FzFromMasses is false;
- each axle on a module that exists and within its body (-lRear <= xA <= lFront);
  every module carrying an axle or resting on a hinge;
- each hinge within reach of both bodies it joins (at most GANGWAY m beyond
  the front body's rear and the rear body's front, the gangway between them);
- the centre of mass between the module's supports (its axles and the hinge
  in front of it), otherwise a static axle load comes out negative;
- the yaw inertia plausible for the module's mass and body length L: between
  m L^2/20 and m L^2/8. A uniform box has m (L^2 + w^2)/12 (about m L^2/11 for a
  bus body); mass towards the ends (engine, axles, doors) raises it, towards the
  middle lowers it; the band is that factor of about 1.5 either way (the
  project's sets: Scania 18 m 0.089 and 0.095, 36 m bus 0.087);
- names the FMU does not have (with the nearest name).

Every problem names the file, the parameter and its value; `artibus check`
exits with 1 when there is one.
"""
import difflib
import math
from dataclasses import dataclass
from pathlib import Path

from artibus.base import ArtibusError

GANGWAY = 1.0            # m: how far a hinge may lie beyond a body's end (the gangway between bodies)
J_BAND = (1 / 20, 1 / 8)  # J / (m L^2)


@dataclass
class Problem:
    parameter: str
    value: object
    what: str

    def text(self, file):
        v = "" if self.value is None else f" = {self.value:g}" if isinstance(self.value, float) else \
            f" = {self.value}"
        return f"{file}: {self.parameter}{v}: {self.what}"


def _model(values):
    if "nModules" in values or any(k.startswith(("xA[", "lHf[", "axleModule[")) for k in values):
        return "BusDynamics"
    if "N" in values or "L0" in values or any(k.startswith("Lh[") for k in values):
        return "BusKinematics"
    return None


def _fmu_defaults(model):
    """{name: start value} of the built FMU's parameters, or None when it is not built."""
    from artibus.base import fmu_path
    try:
        path = fmu_path(model)
    except ArtibusError:
        return None
    from fmpy import read_model_description

    from artibus.fmu.model import model_of
    md = model_of(read_model_description(str(path)))
    out = {}
    for v in md.modelVariables:
        if v.causality == "parameter" and not v.shape:
            s = v.start
            if v.kind == "Real":
                s = float(s) if s is not None else None
            elif v.kind in ("Integer", "Enumeration"):
                s = int(s) if s is not None else None
            elif v.kind == "Boolean":
                s = s in (True, "true", "1", 1) if s is not None else None
            out[v.name] = s
    return out


def _indices(values, name):
    out = {}
    for k, v in values.items():
        if k.startswith(name + "[") and k.endswith("]"):
            try:
                out[int(k[len(name) + 1:-1])] = v
            except ValueError:
                pass
    return out


def check_values(values, model=None, defaults=None):
    """[Problem] of a parameter set {name: value} for ``model`` (BusDynamics or
    BusKinematics, guessed from the names when None); ``defaults``: the FMU's
    start values, used where a value is not given and to spot unknown names."""
    model = model or _model(values)
    if model is None:
        return [Problem("(file)", None, "neither a BusDynamics set (nModules, xA[i], ...) nor a BusKinematics "
                                        "set (N, L0, ...): nothing to check")]
    probs = []
    if defaults:
        for k, v in values.items():
            if k not in defaults:
                near = difflib.get_close_matches(k, list(defaults), n=1)
                probs.append(Problem(k, v, f"{model} has no parameter of that name"
                                           + (f" (did you mean {near[0]}?)" if near else "")))
    get = dict(defaults or {})
    get.update(values)
    check = _dynamics if model == "BusDynamics" else _kinematics
    return probs + check(values, get)


def _count(values, probs, name, n, what, given_needed=True):
    idx = _indices(values, name)
    for i in sorted(idx):
        if i < 1 or i > n:
            probs.append(Problem(f"{name}[{i}]", idx[i], f"beyond the {n} {what} (index 1..{n})"))
    if given_needed:
        missing = [i for i in range(1, n + 1) if i not in idx]
        if missing:
            probs.append(Problem(f"{name}[{','.join(map(str, missing))}]", None,
                                 f"missing: the set has {n} {what} but gives no value here (the FMU's "
                                 f"default, made for another vehicle, would apply)"))


def _positive(get, probs, name, what):
    v = get.get(name)
    if v is None:
        return False
    if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
        probs.append(Problem(name, v, f"{what} must be positive"))
        return False
    return True


def _dynamics(values, get):
    probs = []
    nm, na = get.get("nModules"), get.get("nAxles")
    if not (isinstance(nm, int) and 1 <= nm <= 4):
        return [Problem("nModules", nm, "must be an integer 1..4")]
    if not (isinstance(na, int) and 1 <= na <= 8):
        return [Problem("nAxles", na, "must be an integer 1..8")]
    for name, n, what in (("m", nm, "modules"), ("Jz", nm, "modules"), ("lFront", nm, "modules"),
                          ("lRear", nm, "modules"), ("width", nm, "modules"), ("lHf", nm - 1, "hinges"),
                          ("lHr", nm - 1, "hinges"), ("axleModule", na, "axles"), ("xA", na, "axles"),
                          ("C", na, "axles")):
        _count(values, probs, name, n, what)
    for name, n, what in (("mu", na, "axles"), ("Fz0", na, "axles"), ("psi_start", nm, "modules"),
                          ("r_start", nm, "modules")):
        _count(values, probs, name, n, what, given_needed=False)
    ok = {}
    for k in range(1, nm + 1):
        ok[k] = all([_positive(get, probs, f"m[{k}]", "a mass"),
                     _positive(get, probs, f"Jz[{k}]", "a yaw moment of inertia"),
                     _positive(get, probs, f"lFront[{k}]", "the body's length ahead of the centre of mass"),
                     _positive(get, probs, f"lRear[{k}]", "the body's length behind the centre of mass"),
                     _positive(get, probs, f"width[{k}]", "a body width")])
    for a in range(1, na + 1):
        _positive(get, probs, f"C[{a}]", "a cornering stiffness")
        if f"mu[{a}]" in get:
            _positive(get, probs, f"mu[{a}]", "a friction coefficient")
        if get.get("FzFromMasses") is False:
            _positive(get, probs, f"Fz0[{a}]", "a static axle load (FzFromMasses is false)")
    # axles on existing modules, within their bodies
    on = {k: [] for k in range(1, nm + 1)}
    for a in range(1, na + 1):
        k, x = get.get(f"axleModule[{a}]"), get.get(f"xA[{a}]")
        if not isinstance(k, int) or not 1 <= k <= nm:
            probs.append(Problem(f"axleModule[{a}]", k, f"no such module (nModules = {nm})"))
            continue
        if x is None:
            continue
        on[k].append(x)
        lf, lr = get.get(f"lFront[{k}]"), get.get(f"lRear[{k}]")
        if ok.get(k) and not (-lr <= x <= lf):
            probs.append(Problem(f"xA[{a}]", x, f"axle {a} lies outside module {k}'s body "
                                                f"(from -lRear[{k}] = {-lr:g} to lFront[{k}] = {lf:g} m)"))
    prev = [get.get(f"axleModule[{a}]") for a in range(1, na + 1)]
    if all(isinstance(k, int) for k in prev) and prev != sorted(prev):
        probs.append(Problem("axleModule", None, f"axles not numbered from the front to the rear module "
                                                 f"({', '.join(map(str, prev))})"))
    # hinges within reach of both bodies
    for h in range(1, nm):
        f, r = get.get(f"lHf[{h}]"), get.get(f"lHr[{h}]")
        if f is not None and ok.get(h):
            if not f > 0:
                probs.append(Problem(f"lHf[{h}]", f, f"hinge {h} must lie behind module {h}'s centre of mass (> 0)"))
            elif f > get[f"lRear[{h}]"] + GANGWAY:
                probs.append(Problem(f"lHf[{h}]", f, f"hinge {h} lies {f - get[f'lRear[{h}]']:.3g} m behind the rear "
                                                     f"of module {h}'s body (lRear[{h}] = {get[f'lRear[{h}]']:g}); "
                                                     f"more than a gangway ({GANGWAY:g} m)"))
        if r is not None and ok.get(h + 1):
            if not r > 0:
                probs.append(Problem(f"lHr[{h}]", r, f"hinge {h} must lie ahead of module {h + 1}'s centre of mass (> 0)"))
            elif r > get[f"lFront[{h + 1}]"] + GANGWAY:
                probs.append(Problem(f"lHr[{h}]", r, f"hinge {h} lies {r - get[f'lFront[{h + 1}]']:.3g} m ahead of "
                                                     f"the front of module {h + 1}'s body (lFront[{h + 1}] = "
                                                     f"{get[f'lFront[{h + 1}]']:g}); more than a gangway ({GANGWAY:g} m)"))
    _static_loads(get, probs, nm, na, ok, on)
    # yaw inertia against mass and body length
    for k in range(1, nm + 1):
        if not ok.get(k):
            continue
        m, J = get[f"m[{k}]"], get[f"Jz[{k}]"]
        L = get[f"lFront[{k}]"] + get[f"lRear[{k}]"]
        ratio = J / (m * L * L)
        if not J_BAND[0] <= ratio <= J_BAND[1]:
            probs.append(Problem(f"Jz[{k}]", J, f"implausible for m[{k}] = {m:g} kg and a body {L:g} m long: "
                                                f"J/(m L^2) = {ratio:.3g}, expected {J_BAND[0]:.3g}..{J_BAND[1]:.3g} "
                                                f"(a uniform box: about 1/12, m (L^2 + w^2)/12 = "
                                                f"{m * (L * L + get[f'width[{k}]'] ** 2) / 12:.4g} kg.m2)"))
    return probs


def _static_loads(get, probs, nm, na, ok, on):
    """the static axle loads as BusDynamics computes them (dyn_static_loads): module by
    module from the rear, each module's axles and, with fewer than two axles, its front
    hinge carry its weight and what its rear hinge passes on; a negative load, or a module
    on fewer than two supports, is a Problem in ``probs`` (``ok``: {module: its masses and
    lengths valid}; ``on``: {module: the xA of its axles})"""
    if all(ok.get(k) for k in on) and all(get.get(f"lHf[{h}]") is not None and get.get(f"lHr[{h}]") is not None
                                        for h in range(1, nm)):
        import numpy as np
        g = 9.81
        passed = 0.0                                      # vertical load of the rear hinge on module k, N (down)
        for k in range(nm, 0, -1):
            axles = [a for a in range(1, na + 1) if get.get(f"axleModule[{a}]") == k and f"xA[{a}]" in get]
            xs = [get[f"xA[{a}]"] for a in axles]
            hinge = k > 1 and len(axles) < 2
            if hinge:
                xs.append(get[f"lHr[{k - 1}]"])
            if len(xs) < 2 or max(xs) - min(xs) < 1e-9:
                probs.append(Problem(f"axleModule (module {k})", None,
                                     f"module {k} rests on fewer than two supports (its axles"
                                     + (f" and hinge {k - 1}" if k > 1 else "") + "): no static loads"))
                break
            xr = -get[f"lHf[{k}]"] if k < nm else 0.0
            A = np.array([np.ones(len(xs)), xs])
            rhs = np.array([get[f"m[{k}]"] * g + passed, xr * passed])
            F = np.linalg.lstsq(A, rhs, rcond=None)[0]
            for a, Fa in zip(axles, F):
                if Fa < 0:
                    probs.append(Problem(f"xA[{a}]", get[f"xA[{a}]"],
                                         f"the static load of axle {a} would be {Fa:.4g} N (negative): module "
                                         f"{k}'s weight" + (f" and the {passed:.4g} N hinge {k} passes on "
                                                            f"(from module {k + 1})" if passed else "")
                                         + " do not rest between its supports"))
            passed = float(F[-1]) if hinge else 0.0


def _kinematics(values, get):
    probs = []
    N = get.get("N")
    if not (isinstance(N, int) and 1 <= N <= 4):
        return [Problem("N", N, "number of wagons must be an integer 1..4")]
    _count(values, probs, "L", N, "wagons")
    _count(values, probs, "Lh", N, "joints")
    _positive(get, probs, "L0", "the tractor's wheelbase")
    for i in range(1, N + 1):
        _positive(get, probs, f"L[{i}]", f"wagon {i}'s length from joint {i} to its axle")
        lh = get.get(f"Lh[{i}]")
        if isinstance(lh, (int, float)) and not math.isfinite(lh):
            probs.append(Problem(f"Lh[{i}]", lh, "not a finite length"))
        # Lh < 0 (joint ahead of the axle) is a tractor-trailer's hitch, allowed by the model (seed 003, sec. II)
    for key in ("k", "j"):
        v = get.get(key)
        if isinstance(v, int) and not 0 <= v <= N:
            probs.append(Problem(key, v, f"segment {v} does not exist (0..N = 0..{N})"))
    return probs


def check_file(path, model=None, converted=None, units=None):
    """(model, [Problem]) of an .ssv file. A value given with a unit is checked
    in the unit of the FMU's variable (artibus.bench.units; ``converted``:
    filled with {name: (value, unit, converted value, the variable's unit)};
    ``units``: with {unit: its definition, the file's, else the FMU's, or None}
    of the units the file's values are given in)."""
    from artibus.bench.parameters import read_parameters
    from artibus.bench.units import Quantity, fmu_units
    values = read_parameters(path, keep_units=True)
    model = model or _model({k: getattr(v, "value", v) for k, v in values.items()})
    if any(isinstance(v, Quantity) for v in values.values()):
        md = _fmu_md(model) if model else None
        fmu_defs = fmu_units(md) if md is not None else {}
        for v in values.values():
            if isinstance(v, Quantity) and units is not None:
                units.setdefault(v.unit, v.definitions.get(v.unit) or fmu_defs.get(v.unit))
        if md is not None:
            from artibus.bench.units import convert
            variables = {v.name: v for v in md.modelVariables}
            for k, v in values.items():
                if isinstance(v, Quantity) and k in variables and variables[k].kind == "Real":
                    values[k] = convert(v, variables[k], md, k)
                    if converted is not None and values[k] is not v.value:
                        from artibus.bench.units import declared_unit
                        converted[k] = (v.value, v.unit, values[k], declared_unit(variables[k]))
        values = {k: getattr(v, "value", v) for k, v in values.items()}
    defaults = _fmu_defaults(model) if model else None
    return model, check_values(values, model, defaults)


def _fmu_md(model):
    from artibus.base import fmu_path
    try:
        path = fmu_path(model)
    except ArtibusError:
        return None
    from artibus.fmu.model import model_of, read_description
    return model_of(read_description(str(path)))


def check_bench(bench, out=print):
    """``artibus check BENCH``: what of the bench the runner does not apply, what
    is artibus-specific (with what another master does instead), the units its
    values are given in (their factors) and the values converted from the unit
    their file gives to the FMU's. 0: the bench reads (its values convert, its
    bindings resolve, each of its variable's type and range, each input with one
    source: artibus.bench.rules, as `artibus run` checks them), else an ArtibusError."""
    from artibus.bench import ssp as ssp_mod
    from artibus.bench.portability import artibus_specific, not_applied
    path = ssp_mod.ssp_path(bench)
    b = ssp_mod.read(path)
    notices = not_applied(path)
    out(f"{b.name}: {b.file if b.file != f'{path}/SystemStructure.ssd' else path}")   # an unpacked SSP: its .ssd
    out(f"  not applied by the artibus runner ({len(notices)}):" if notices else
        "  everything in it is applied by the artibus runner")
    for n in notices:
        out(f"    {n.text()}")
    specific = artibus_specific(path, b)
    out(f"  artibus-specific ({len(specific)}):" if specific else "  nothing artibus-specific")
    for what, other in specific:
        out(f"    {what}")
        out(f"      another master: {other}")
    if b.read_as != b.version:
        out(f"  SystemStructure.ssd says version=\"{b.version}\" but holds SSP {b.read_as} content only (no connector "
            f"of an SSP 2.0 type, no FMI-LS-BUS network): read as SSP {b.read_as}")
    for name, value in b.system_values.items():
        out(f"  system connector {name} = {value!r}: bound, connected to no FMU variable (the value stays the "
            f"connector's)")
    _loops(path, b, out)
    _masters(bench, b, out)
    if b.read_as == "2.0":       # its FMI-LS-BUS network, read and checked as the runner reads it
        from artibus.bench.ssp2 import network_lines
        for line in network_lines(path):
            out(f"  {line}")
    _print_units(b.units, "  ", out, "  ")
    conv = [(p, k, v) for p, c in b.components.items() for k, v in c.converted.items()]
    if conv:
        out(f"  values converted to the FMU's units ({len(conv)}):")
        for p, k, (raw, unit, x, target) in conv:
            out(f"    {p}.{k} = {raw:g} {unit} -> {x:.10g} {target} (from {b.components[p].origins.get(k, '?')})")
    return 0


def _masters(bench, b, out):
    """What ecos, libcosim and fmpy.ssp make of the bench's portable pack, as measured
    (artibus.bench.masters): each master outside its tolerance of our runner, per variant."""
    from pathlib import Path

    from artibus.bench.masters import TOLERANCE, all_differences
    if b.read_as != "1.0" or b.can is not None or any(c.can for c in b.connections):
        return                                 # no portable pack (artibus_specific says why)
    name = Path(str(bench)).stem if str(bench).endswith(".ssp") else str(bench)
    found = all_differences(name)
    tolerances = ", ".join(f"{m} {t:.1%}".replace(".0%", "%") for m, t in TOLERANCE.items())
    out(f"  its portable pack in other masters (measured; KPIs within {tolerances} of ours stepped as each steps"
        + (f" except {len(found)}):" if found else ")"))
    for variants, d in found:
        out(f"    {'--variant ' + ' '.join(variants) if variants else 'the bench'}: {d.text()}")


def _loops(path, b, out):
    """The loops Gauss-Seidel breaks, each at one connection with one step of delay, as `artibus
    run` breaks them (artibus.runner.plan.gauss_seidel_order over the FMUs' declared
    dependencies); an algebraic loop is its ArtibusError, as the run's."""
    from artibus.bench.ssd import model_description
    from artibus.runner.plan import feedthrough, gauss_seidel_order, wire
    feeds = {p: feedthrough(model_description(path, c.source)) for p, c in b.components.items()}
    wires = [wire(b.file, c) for c in b.connections if c.can is None]
    broken = gauss_seidel_order(list(b.components), wires, feeds, b.file).broken
    if broken:
        out(f"  loops through outputs that declare no dependencies, broken under Gauss-Seidel ({len(broken)}; "
            f"--algorithm jacobi delays every connection one step):")
    for w, loop in broken:
        cycle = " -> ".join([f"{x.src}.{x.output}" for x in loop] + [f"{loop[0].src}.{loop[0].output}"])
        out(f"    {cycle}: broken at {w.label}, one step of delay")


def _print_units(units, head, out, indent=""):
    """the table of the units values are given in (artibus.bench.units.unit_table), if any"""
    if units:
        from artibus.bench.units import unit_table
        out(f"{head}units the values are given in ({len(units)}), in the SI base units:")
        for line in unit_table(units):
            out(f"{indent}  {line}")


def _is_bench(name):
    from artibus.bench import ssp as ssp_mod
    p = Path(str(name))
    return (p.suffix.lower() in (".ssp", ".ssd") or (p.is_dir() and (p / "SystemStructure.ssd").is_file())
            or str(name) in ssp_mod.bench_names())


def main(paths, model=None, out=print):
    """Check each file (a parameter set, or a bench: check_bench); print what
    is wrong; 1 when anything is, else 0."""
    bad = 0
    for p in paths:
        if _is_bench(p):
            bad += check_bench(p, out)
            continue
        converted, units = {}, {}
        m, probs = check_file(p, model, converted, units)
        name = Path(p)
        for k, (raw, unit, x, target) in converted.items():
            out(f"{name}: {k} = {raw:g} {unit}: converted to {x:.10g} {target}")
        _print_units(units, f"{name}: ", out)
        for pr in probs:
            out(pr.text(name))
        if probs:
            bad += 1
            out(f"{name}: {len(probs)} problem{'s' if len(probs) > 1 else ''} ({m or 'unknown model'})")
        else:
            out(f"{name}: {m} parameter set consistent")
    return 1 if bad else 0
