"""A sweep's cases: the bench's parameters and variants, for checking the cases
before any runs (``bench_info``, ``typed_value``), grids (``parse_grid``),
design files (CSV, YAML: grid, Latin hypercube, Monte Carlo; ``read_design``),
the cases checked against the bench (``build_cases``) and each case's key
(``case_key``: the hash of the bench's content, the run's settings and its values)."""
import csv
import hashlib
import json
import math
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError, parse_integer, parse_real

MAX_CASES = 1_000_000


# --- the bench's parameters, for checking the cases before any runs -----------------

@dataclass
class BenchInfo:
    name: str
    ssp: Path
    variables: dict          # "Comp.var" -> fmpy ScalarVariable (parameters and inputs)
    variants: list
    components: list
    common_hash: str         # .ssd, FMUs, parameter sets (not the variants), bench.py
    variant_hash: dict       # variant name -> hash of its .ssv
    ssp_bytes: bytes = field(repr=False, default=b"")
    ssp_hash: str = ""       # hash of the whole .ssp (a worker's copy is known by it)


_INFO = {}          # sha256 of an .ssp's bytes -> what bench_info reads from them (a sweep after another)


def bench_info(bench):
    from artibus.bench import script, ssp as ssp_mod
    path = ssp_mod.ssp_path(bench)
    data = path.read_bytes()
    ssp_hash = hashlib.sha256(data).hexdigest()
    got = _INFO.get(ssp_hash)
    if got is None:                        # the .ssd and every FMU's model description: ~50 ms
        got = _INFO[ssp_hash] = _ssp_info(path, data)
        while len(_INFO) > 4:
            del _INFO[next(iter(_INFO))]
    name, variables, components, entries, var_hash = got
    common = hashlib.sha256(entries)
    bf = script.bench_file(name)
    if bf.is_file():
        common.update(b"bench.py\0" + bf.read_bytes())
    return BenchInfo(name, path, dict(variables), sorted(var_hash), list(components), common.hexdigest(),
                     dict(var_hash), data, ssp_hash)


def _ssp_info(path, data):
    """(name, variables, components, the hash input of the entries but the variants, variant hashes) of an .ssp."""
    import io

    from fmpy import read_model_description

    from artibus.bench import ssp as ssp_mod
    from artibus.fmu.model import model_of
    b = ssp_mod.read(path)
    variables, common, var_hash = {}, [], {}
    with zipfile.ZipFile(io.BytesIO(data)) as z, tempfile.TemporaryDirectory(prefix="artibus-sweep-") as tmp:
        for n in sorted(z.namelist()):
            content = z.read(n)
            h = hashlib.sha256(content).hexdigest()
            if n.startswith(f"{ssp_mod.VARIANT_DIR}/") and n.endswith(".ssv"):
                var_hash[Path(n).stem] = h
            else:
                common.append(f"{n}\0{h}\0".encode())
        for cpath, c in b.components.items():
            f = Path(tmp) / c.source
            if not f.is_file():
                f.parent.mkdir(parents=True, exist_ok=True)
                f.write_bytes(z.read(c.source))
            md = model_of(read_model_description(str(f)))
            for v in md.modelVariables:
                if v.causality in ("parameter", "input"):
                    variables[f"{cpath}.{v.name}"] = v
    return b.name, variables, list(b.components), b"".join(common), var_hash


def typed_value(info, name, value, where):
    """value (text or number) as the variable's type; errors name where, the parameter and the value."""
    v = info.variables.get(name)
    if v is None:
        comp = name.rpartition(".")[0]
        if comp not in info.components:
            raise ArtibusError(f"{where}: parameter '{name}': no component '{comp}' in {info.name} "
                               f"(components: {', '.join(info.components)})")
        raise ArtibusError(f"{where}: parameter '{name}': {info.name} has no parameter or input of that "
                           f"name in component '{comp}'")
    text = value.strip() if isinstance(value, str) else value
    try:
        if v.kind == "Real":
            if isinstance(text, bool):
                raise ValueError
            return parse_real(text)
        if v.kind in ("Integer", "Enumeration"):
            if isinstance(text, bool):
                raise ValueError
            x = parse_real(text)
            if not x == int(x):
                raise ValueError
            return int(x)
        if v.kind == "Boolean":
            if isinstance(text, (bool, np.bool_)):
                return bool(text)
            if str(text).lower() in ("true", "1", "1.0"):
                return True
            if str(text).lower() in ("false", "0", "0.0"):
                return False
            raise ValueError
        return str(text)
    except (TypeError, ValueError, OverflowError):
        article = "an" if v.type[0] in "AEIOU" else "a"
        raise ArtibusError(f"{where}: parameter '{name}' = {value!r}: not {article} {v.type} value") from None


# --- the cases ---------------------------------------------------------------------

def parse_values(text, where):
    """'0.2,0.5,1.0' -> the texts; 'start:stop:step' -> numbers (stop included)."""
    text = text.strip()
    if not text:
        raise ArtibusError(f"{where}: no values")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ArtibusError(f"{where}: malformed range {text!r} (expected START:STOP:STEP)")
        try:
            a, b, s = (parse_real(p) for p in parts)
        except ValueError:
            raise ArtibusError(f"{where}: malformed range {text!r} (START, STOP, STEP must be numbers)") from None
        if not all(math.isfinite(x) for x in (a, b, s)) or not s > 0 or b < a:
            raise ArtibusError(f"{where}: malformed range {text!r} (needs STEP > 0 and STOP >= START)")
        n = int(math.floor((b - a) / s + 1e-9)) + 1
        if n > MAX_CASES:
            raise ArtibusError(f"{where}: range {text!r} has {n} values (at most {MAX_CASES})")
        return [float(f"{a + k * s:.12g}") for k in range(n)]
    values = [p.strip() for p in text.split(",")]
    if any(not p for p in values):
        raise ArtibusError(f"{where}: malformed list {text!r} (an empty value)")
    return values


def parse_grid(items):
    """['Bus.mu[3]=0.2,0.5', 'Driver.vSet=10:30:5'] -> {name: [values]}."""
    grid = {}
    for item in items or []:
        name, sep, values = item.partition("=")
        if not sep or not name.strip():
            raise ArtibusError(f"--grid {item}: expected NAME=V1,V2,... or NAME=START:STOP:STEP")
        grid[name.strip()] = parse_values(values, f"--grid {item}")
    return grid


def _product(axes):
    """[(name, values)] -> [{name: value}] (the last axis fastest)."""
    cases = [{}]
    for name, values in axes:
        cases = [{**c, name: v} for c in cases for v in values]
    return cases


@dataclass
class Design:
    method: str = "grid"           # grid, cases (CSV or Python), lhs, montecarlo
    axes: list = field(default_factory=list)     # [(name, values)] of a grid
    cases: list = field(default_factory=list)    # [{name: value}] ("variant": "a+b")
    seed: int | None = None


DISTRIBUTIONS = ("uniform", "normal", "lognormal", "truncnormal", "triangular")


def _distribution(name, spec, where):
    from scipy import stats
    if not isinstance(spec, dict):
        raise ArtibusError(f"{where}: parameter '{name}': expected a mapping such as "
                           f"{{distribution: uniform, low: 0.2, high: 1.0}}, got {spec!r}")
    kind = spec.get("distribution", "uniform")
    try:
        if kind == "uniform":
            lo, hi = parse_real(spec["low"]), parse_real(spec["high"])
            if not hi > lo:
                raise ValueError("high must be above low")
            return stats.uniform(loc=lo, scale=hi - lo)
        if kind == "normal":
            return stats.norm(loc=parse_real(spec["mean"]), scale=parse_real(spec["std"]))
        if kind == "lognormal":       # the logarithm's mean and std
            return stats.lognorm(s=parse_real(spec["std"]), scale=math.exp(parse_real(spec["mean"])))
        if kind == "truncnormal":
            m, s = parse_real(spec["mean"]), parse_real(spec["std"])
            lo, hi = parse_real(spec["low"]), parse_real(spec["high"])
            return stats.truncnorm((lo - m) / s, (hi - m) / s, loc=m, scale=s)
        if kind == "triangular":
            lo, mode, hi = parse_real(spec["low"]), parse_real(spec["mode"]), parse_real(spec["high"])
            return stats.triang(c=(mode - lo) / (hi - lo), loc=lo, scale=hi - lo)
    except KeyError as e:
        raise ArtibusError(f"{where}: parameter '{name}': distribution {kind} needs {e.args[0]}") from None
    except (TypeError, ValueError, ZeroDivisionError) as e:
        raise ArtibusError(f"{where}: parameter '{name}': distribution {kind}: {e}") from None
    raise ArtibusError(f"{where}: parameter '{name}': unknown distribution {kind!r} "
                       f"(known: {', '.join(DISTRIBUTIONS)})")


def read_design(path):
    """A design file: .csv (a header of parameter names, and 'variant' for
    variants joined by '+'; one case a row) or .yaml/.yml:

        method: grid | lhs | montecarlo
        seed: 1                       # lhs, montecarlo
        n: 100                        # lhs, montecarlo: the number of cases
        parameters:
          Bus.mu[3]: [0.2, 0.5, 1.0]  # grid: values, or "0.2:1.0:0.1"
          Driver.vSet: {distribution: uniform, low: 10, high: 30}    # lhs, montecarlo
        variants: [a, b]              # grid: an axis of the bench's variants
    """
    p = Path(path)
    where = str(p)
    if not p.is_file():
        raise ArtibusError(f"{where}: no such design file")
    try:
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ArtibusError(f"{where}: not a text file (UTF-8): byte {e.start}: {e.reason}") from None
    if p.suffix.lower() == ".csv":
        import io
        try:
            rows = list(csv.reader(io.StringIO(text, newline="")))
        except csv.Error as e:
            raise ArtibusError(f"{where}: not a valid CSV file: {e}") from None
        rows = [r for r in rows if r and any(c.strip() for c in r)]
        if len(rows) < 2:
            raise ArtibusError(f"{where}: a header of parameter names and at least one case expected")
        head = [h.strip() for h in rows[0]]
        cases = []
        for i, r in enumerate(rows[1:], start=2):
            if len(r) != len(head):
                raise ArtibusError(f"{where}:{i}: {len(r)} values for {len(head)} columns")
            cases.append({h: v.strip() for h, v in zip(head, r)})
        return Design("cases", cases=cases)
    if p.suffix.lower() not in (".yaml", ".yml"):
        raise ArtibusError(f"{where}: a design file is .csv or .yaml")
    import yaml
    try:
        spec = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise ArtibusError(f"{where}: not valid YAML: {e}") from None
    if not isinstance(spec, dict):
        raise ArtibusError(f"{where}: expected a mapping with method and parameters")
    unknown = set(spec) - {"method", "seed", "n", "parameters", "variants"}
    if unknown:
        raise ArtibusError(f"{where}: unknown key(s) {', '.join(sorted(unknown))} "
                           f"(known: method, seed, n, parameters, variants)")
    method = str(spec.get("method", "grid")).lower().replace(" ", "")
    aliases = {"grid": "grid", "lhs": "lhs", "latinhypercube": "lhs", "montecarlo": "montecarlo", "mc": "montecarlo"}
    if method not in aliases:
        raise ArtibusError(f"{where}: method {spec.get('method')!r}: expected grid, lhs or montecarlo")
    method = aliases[method]
    params = spec.get("parameters") or {}
    if not isinstance(params, dict):
        raise ArtibusError(f"{where}: parameters: expected a mapping NAME: values")
    variants = spec.get("variants")
    if method == "grid":
        axes = []
        for name, values in params.items():
            if isinstance(values, str):
                values = parse_values(values, f"{where}: parameter '{name}'")
            elif not isinstance(values, list) or not values:
                raise ArtibusError(f"{where}: parameter '{name}': a grid needs a list of values or START:STOP:STEP")
            axes.append((str(name), values))
        if variants:
            axes.append(("variant", [str(v) for v in (variants if isinstance(variants, list) else [variants])]))
        return Design("grid", axes=axes)
    if variants:
        raise ArtibusError(f"{where}: variants: an axis of a grid only (for {method}, run one sweep per variant)")
    try:
        n = parse_integer(spec.get("n"))
        seed = parse_integer(spec.get("seed"))
    except (TypeError, ValueError):
        raise ArtibusError(f"{where}: {method} needs n (the number of cases) and seed (integers)") from None
    if not 0 < n <= MAX_CASES:
        raise ArtibusError(f"{where}: n = {n}: expected 1..{MAX_CASES}")
    if not params:
        raise ArtibusError(f"{where}: {method}: no parameters")
    names = [str(k) for k in params]
    dists = [_distribution(k, params[k], where) for k in params]
    if method == "lhs":
        from scipy.stats import qmc
        u = qmc.LatinHypercube(d=len(names), seed=np.random.default_rng(seed)).random(n)
    else:
        u = np.random.default_rng(seed).random((n, len(names)))
    values = np.column_stack([d.ppf(u[:, j]) for j, d in enumerate(dists)])
    cases = [{k: float(values[i, j]) for j, k in enumerate(names)} for i in range(n)]
    return Design(method, cases=cases, seed=seed)


def _variant_list(text):
    return [v for v in str(text).split("+") if v] if text not in (None, "") else []


def build_cases(info, design, where="the design"):
    """[{name: typed value, 'variant': 'a+b' or absent}] checked against the bench."""
    raw = _product(design.axes) if design.method == "grid" else design.cases
    if not raw:
        raise ArtibusError(f"{where}: no cases")
    if len(raw) > MAX_CASES:
        raise ArtibusError(f"{where}: {len(raw)} cases (at most {MAX_CASES})")
    cases = []
    for i, c in enumerate(raw):
        typed = {}
        for name, value in c.items():
            if name == "variant":
                for v in _variant_list(value):
                    if v not in info.variants:
                        raise ArtibusError(f"{where}: variant {v!r}: {info.name} has no such variant "
                                           f"(known: {', '.join(info.variants) or 'none'})")
                if value not in (None, ""):
                    typed["variant"] = str(value)
            else:
                typed[name] = typed_value(info, name, value, where)
        cases.append(typed)
    return cases


def case_key(info, case, settings):
    """The hash of the bench's content, the run's settings and the case's values."""
    h = hashlib.sha256()
    h.update(info.common_hash.encode())
    for v in _variant_list(case.get("variant")):
        h.update(f"\0variant {v} {info.variant_hash[v]}".encode())
    h.update(json.dumps({"settings": settings, "case": case}, sort_keys=True, default=str).encode())
    return h.hexdigest()[:20]


def _product_lists(lists):
    combos = [[]]
    for values in lists:
        combos = [c + [v] for c in combos for v in values]
    return combos
