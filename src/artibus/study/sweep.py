"""Sweeps: many runs of one bench, each case a Dask task (issue 13).

The cases come from a grid (``--grid Bus.mu[3]=0.2,0.5,1.0 Driver.vSet=10:30:5``,
``--variant a,b`` as an axis), from a design file (CSV: one case a row; YAML:
a grid, a Latin hypercube or Monte Carlo with distributions and a seed), or
from Python::

    import artibus
    table = artibus.sweep("Bus36m_Circle", grid={"Driver.vSet": [2, 3, 4]}, out="sweep-out")

The cases run as tasks on dask.distributed: a local cluster with one worker
process per core (one thread each, Dask's periodic work made rare: QUIET), or
an existing scheduler (``scheduler=``, ``--scheduler ADDRESS``), so the same
command runs on a cluster. A task holds one case or several (_Chunks: about
0.1 to 2 s of work, fewer towards the end), so Dask's cost per task (~10 ms of
CPU in the client and scheduler and ~9 ms in the worker, on the cores the
workers need) is spread over its cases. A worker unpacks the bench once and
reuses its FMU instances across cases (fmi2Reset, then the case's parameters
and a new initialisation; the same results as a fresh instance,
tests/test_sweep.py); a case that fails drops them. On a client the caller
gives (``client=``), the workers keep them, and the bench's copy, for the next
sweep of the same bench (``client.run(artibus.sweep.release)`` frees them); a
sweep's own cluster or ``scheduler=`` client frees them at its end. The worker
also makes each case's row and Parquet files; the client only writes them, and
makes the table once, at the end.

Results, in the output folder:
  cases/<key>.parquet    one row per case (its parameters, every KPI of the
                         bench, status, error, wall time), written atomically
                         as its task comes back;
  series/<key>.parquet   the case's time series (keep_series);
  results.parquet        the table of every case of this sweep, in case order,
                         assembled at the end (and on resume);
  study.png, worst.txt   the study plot and the worst cases with the command
                         that re-runs each alone (artibus.sweep.study).
A case's key is a hash of the bench's content (its .ssd, FMUs, parameter sets,
the .ssv of the case's variants, its bench.py), the run's settings and the
case's values: a rerun skips finished cases, a changed FMU or .ssv reruns the
cases it touches, an interrupted sweep resumes.
"""
import atexit
import collections
import csv
import hashlib
import json
import logging
import math
import os
import shlex
import sys
import tempfile
import threading
import time
import types
import weakref
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError

CASES_DIR, SERIES_DIR = "cases", "series"
TABLE, MANIFEST, WORST, PLOT = "results.parquet", "sweep.json", "worst.txt", "study.png"
MAX_CASES = 1_000_000
STATUS_OK, STATUS_FAILED = "ok", "failed"


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
    from artibus.bench import script as benches, ssp as ssp_mod
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
    bf = benches.bench_file(name)
    if bf.is_file():
        common.update(b"bench.py\0" + bf.read_bytes())
    return BenchInfo(name, path, dict(variables), sorted(var_hash), list(components), common.hexdigest(),
                     dict(var_hash), data, ssp_hash)


def _ssp_info(path, data):
    """(name, variables, components, the hash input of the entries but the variants, variant hashes) of an .ssp."""
    import io

    from fmpy import read_model_description
    from artibus.bench import ssp as ssp_mod
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
            md = read_model_description(str(f))
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
        if v.type == "Real":
            if isinstance(text, bool):
                raise ValueError
            return float(text)
        if v.type in ("Integer", "Enumeration"):
            if isinstance(text, bool):
                raise ValueError
            x = float(text)
            if not x == int(x):
                raise ValueError
            return int(x)
        if v.type == "Boolean":
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
            a, b, s = (float(p) for p in parts)
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
            lo, hi = float(spec["low"]), float(spec["high"])
            if not hi > lo:
                raise ValueError("high must be above low")
            return stats.uniform(loc=lo, scale=hi - lo)
        if kind == "normal":
            return stats.norm(loc=float(spec["mean"]), scale=float(spec["std"]))
        if kind == "lognormal":       # the logarithm's mean and std
            return stats.lognorm(s=float(spec["std"]), scale=math.exp(float(spec["mean"])))
        if kind == "truncnormal":
            m, s = float(spec["mean"]), float(spec["std"])
            lo, hi = float(spec["low"]), float(spec["high"])
            return stats.truncnorm((lo - m) / s, (hi - m) / s, loc=m, scale=s)
        if kind == "triangular":
            lo, mode, hi = float(spec["low"]), float(spec["mode"]), float(spec["high"])
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
    if p.suffix.lower() == ".csv":
        with p.open(newline="") as f:
            rows = list(csv.reader(f))
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
        spec = yaml.safe_load(p.read_text())
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
        n = int(spec.get("n"))
        seed = int(spec.get("seed"))
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


# --- on a worker -------------------------------------------------------------------

#: FMU instances reused across cases (fmi2Reset and a new initialisation); False: a fresh Simulation each case
REUSE = os.environ.get("ARTIBUS_SWEEP_REUSE", "1") != "0"
_LOCK = threading.Lock()
_SIMS = {}          # (thread, .ssp, step) -> (a Simulation not in use, the .ssp's content hash), kept for
                    # the thread's next case (of this sweep, or of the next one on the same cluster)
_SSPS = {}          # (bench, content) -> (the .ssp's path on this worker, its stat where not this worker's copy)
_DIRS = []          # folders this worker made for .ssp files


def _worker_ssp(bench_name, content_hash, ssp_path, ssp_bytes):
    """The bench's .ssp on this worker: the path where it exists with the same
    content, else the bytes written once to a local file. content_hash: the
    hash of the bytes (BenchInfo.ssp_hash, computed once by the client)."""
    key = (bench_name, content_hash if ssp_bytes else ssp_path)
    with _LOCK:
        got = _SSPS.get(key)
        if got is not None and got[1] is not None and got[1] != _stat(got[0]):
            got = None                  # the file at the path changed since (the cache outlives a sweep)
        if got is None:
            p, sig = Path(ssp_path), None
            if ssp_bytes and not (p.is_file() and p.read_bytes() == ssp_bytes):
                d = Path(tempfile.mkdtemp(prefix="artibus-sweep-worker-"))
                _DIRS.append(d)
                p = d / f"{bench_name}.ssp"
                p.write_bytes(ssp_bytes)
            else:
                sig = _stat(p)
            got = _SSPS[key] = (str(p), sig)
        return got[0]


def _stat(path):
    try:
        st = os.stat(path)
    except OSError:
        return False
    return st.st_ino, st.st_size, st.st_mtime_ns


def release():
    """Close the instances this process keeps and remove its .ssp copies (a
    sweep on its own cluster or scheduler= client calls it on every worker at its
    end; on a client= the workers keep them for the next sweep:
    client.run(release) frees them; also at exit). Returns how many."""
    import shutil
    with _LOCK:
        sims = [sim for sim, _ in _SIMS.values()]
        _SIMS.clear()
        _SSPS.clear()
        dirs = list(_DIRS)
        _DIRS.clear()
    for sim in sims:
        try:
            sim.close()
        except Exception:
            pass
    for d in dirs:
        shutil.rmtree(d, ignore_errors=True)
    return len(sims)


atexit.register(release)


def _parameters(sim, overrides):
    """The parameters a fresh Simulation would set: the bench's bindings, then
    the case's overrides (as Simulation._setup does). The bench's own, resolved
    and checked, are kept with the Simulation (the same every case: ~0.7 ms a
    case checked again); each case's overrides are checked."""
    from artibus.bench.parameters import check_against
    from artibus.runner.simulation import resolve_resources
    where = sim.bench.file
    units = {u.path: u for u in sim.units}
    base = getattr(sim, "_sweep_bench_parameters", None)
    if base is None:
        base = {p: dict(c.parameters) for p, c in sim.bench.components.items()}
        for path, values in base.items():
            resolve_resources(sim._tmp, where, values)
            check_against(values, units[path].fmu.md, where, prefix=f"{path}.")
        sim._sweep_bench_parameters = base
    params = {p: dict(values) for p, values in base.items()}
    changed = {}
    for full, value in overrides.items():
        comp, _, var = full.rpartition(".")
        if comp not in params:
            raise ArtibusError(f"--set {full}={value}: no component '{comp}' in {where}")
        params[comp][var] = value
        changed.setdefault(comp, {})[var] = value
    for path, values in changed.items():
        resolve_resources(sim._tmp, where, values)
        check_against(values, units[path].fmu.md, where, prefix=f"{path}.")
        params[path].update(values)
    return params


def _simulate(ssp, overrides, stop_time, step, content=None):
    """A Result; the Simulation kept for this thread's next case where it may
    be reused (one a thread: another bench's is closed; content: the .ssp's
    hash, a kept one of other content is closed)."""
    from artibus import runner
    me = threading.get_ident()
    key = (me, ssp, step)
    with _LOCK:
        sim, kept = _SIMS.pop(key, (None, None))
        others = [k for k in _SIMS if k[0] == me]
        stale = [_SIMS.pop(k)[0] for k in others]
    if sim is not None and kept != content:
        stale.append(sim)
        sim = None
    for old in stale:
        old.close()
    if sim is not None:
        try:
            for u in sim.units:
                u.fmu.slave.reset()
            sim.parameters = _parameters(sim, overrides)
        except BaseException:
            sim.close()
            raise
    else:
        sim = runner.Simulation(ssp, step=step, overrides=overrides)
    ok = False
    try:
        r = sim.run(stop_time=stop_time)
        ok = True
        return r
    finally:
        if ok and REUSE and sim.can is None:
            with _LOCK:
                _SIMS[key] = (sim, content)
        else:
            sim.close()


def run_case(bench_name, content_hash, ssp_path, ssp_bytes, case, fixed, stop_time, step, keep_series):
    """One case on a worker: (row, series or None). A failure is a row with its error."""
    from artibus.bench import script as benches, ssp as ssp_mod
    t0 = time.perf_counter()
    row = {"status": STATUS_OK, "error": ""}
    series = None
    try:
        ssp = _worker_ssp(bench_name, content_hash, ssp_path, ssp_bytes)
        variants = _variant_list(case.get("variant"))
        overrides = {**(ssp_mod.variant_overrides(ssp, variants) if variants else {}), **fixed,
                     **{k: v for k, v in case.items() if k != "variant"}}
        stop = stop_time if stop_time is not None else (ssp_mod.variant_stop_time(ssp, variants) if variants else None)
        r = _simulate(ssp, overrides, stop, step, content_hash)
        try:
            for k in benches.kpis(bench_name, r):
                v = k.value
                row[f"{k.name} [{k.unit}]"] = float(v) if v is not None else math.nan
        except Exception as e:
            raise ArtibusError(f"KPI: {type(e).__name__}: {e}") from None
        if keep_series:
            series = {n: r[n] for n in r.names}
    except KeyboardInterrupt:
        raise
    except Exception as e:
        row["status"] = STATUS_FAILED
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        row["error"] = msg[:1000]
    row["wall_s"] = time.perf_counter() - t0
    return row, series


def run_cases(bench_name, content_hash, ssp_path, ssp_bytes, cases, fixed, stop_time, step, keep_series):
    """A task: several cases [(key, index, case)] in turn on one worker (run_case
    each). For each its table row (_case_row), its case file's bytes and its time
    series' (or None), both Parquet made here (the client only writes them), and
    the CPU time it took (s)."""
    out = []
    for key, index, case in cases:
        cpu = time.thread_time()
        row, series = run_case(bench_name, content_hash, ssp_path, ssp_bytes, case, fixed, stop_time, step,
                               keep_series)
        row = _case_row(key, index, case, row)
        out.append((row, _parquet_bytes(_table([row])),
                    _parquet_bytes(_series_table(series)) if series is not None else None,
                    time.thread_time() - cpu))
    return out


# --- the sweep ---------------------------------------------------------------------

def _write_parquet(table, path):
    import pyarrow.parquet as pq
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    pq.write_table(table, tmp)
    os.replace(tmp, path)


def _parquet_bytes(table):
    import pyarrow as pa
    import pyarrow.parquet as pq
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


def _write_bytes(data, path):
    """data into the file path, atomically (a hidden .part file renamed); plain os
    calls: pathlib's open costs more system calls, paid a case in the client."""
    path = os.fspath(path)
    head, name = os.path.split(path)
    tmp = os.path.join(head, f".{name}.{os.getpid()}.part")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)
    os.replace(tmp, path)


def _case_row(key, index, case, row):
    """A case's row of the table: key, case (its index), its values, status, error, wall_s, the KPIs."""
    cols = {"key": key, "case": index}
    cols.update(case)
    for k in ("status", "error", "wall_s"):
        cols[k] = row[k]
    for k, v in row.items():
        if k not in cols:
            cols[k] = v
    return cols


def _table(rows):
    """The rows as one table: the columns in the order they first appear (a
    failed case has no KPIs: null there), each column's type from its values."""
    import pyarrow as pa
    names = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    return pa.table({n: [r.get(n) for r in rows] for n in names}) if rows else pa.table({})


def _series_table(series):
    import pyarrow as pa
    return pa.table({k: np.asarray(v) for k, v in series.items()})


_SCATTERED = weakref.WeakKeyDictionary()     # a client -> (.ssp hash, the future of its bytes on the workers)


def _scatter(client, info, again=False):
    """The bench's bytes on every worker (a future). On a client the caller gave,
    the copy is kept for the next sweep of the same bench, as the workers keep
    their instances (release() on the workers frees them: client.run(release))."""
    got = _SCATTERED.get(client)
    if again or got is None or got[0] != info.ssp_hash or got[1].status != "finished":
        got = (info.ssp_hash, client.scatter(info.ssp_bytes, broadcast=True, hash=False))
        try:
            _SCATTERED[client] = got
        except TypeError:
            pass
    return got[1]


def _client(scheduler, workers):
    from dask.distributed import Client, LocalCluster
    if scheduler:
        try:
            return Client(scheduler, timeout="5s"), None
        except (OSError, TimeoutError) as e:
            raise ArtibusError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({e})") from None
        except ValueError as e:
            raise ArtibusError(f"--scheduler {scheduler}: not a scheduler address ({e})") from None
    import dask
    n = workers or os.cpu_count() or 1
    with dask.config.set(QUIET):
        # no dashboard; the scheduler's HTTP server (health routes) on a free port of
        # 127.0.0.1, not on Dask's 8787 (taken by a user's own dashboard: a warning)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                               silence_logs=logging.CRITICAL)
    return Client(cluster), cluster


#: a local cluster's settings: Dask's periodic work off or rare (the workers' stack
#: sampling every 10 ms, the event loops' 20 ms health tick, the 100 ms memory and
#: 500 ms system monitors): idle, a cluster of two workers took ~15 % of a core with
#: the defaults (on the cores its workers run on), ~2 % with these
QUIET = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
         "distributed.worker.memory.monitor-interval": "1s", "distributed.admin.system-monitor.interval": "5s",
         "distributed.admin.system-monitor.gil.enabled": False}


class _Chunks:
    """The cases to run, handed out as tasks of several cases: a task's fixed
    cost (Dask's scheduler and client, ~10 ms of CPU a task on this 2-core
    machine, taken from the cores the workers run on) is then spread over its
    cases. The first tasks hold one case each (a case's time is not known yet),
    until one result a worker has come back (each such task costs ~20 ms of CPU
    more than its case);
    later ones a 1 / (2 workers) share of the cases left (so the workers finish
    together), but at least as many cases as run in MIN_S seconds and at most as
    many as in MAX_S seconds (by the median CPU time of the cases so far: an
    interrupted sweep loses about that much a worker). MIN_S is small: it sets
    the last tasks' size, and one worker waits up to that long for the other at
    the end (0.25 s cost 2 workers 10-25 % on a sweep of 60 cases of 20 ms; a
    task costs ~20 ms of CPU on this machine). IN_FLIGHT tasks a worker
    are submitted at once (one runs, the next waits on the worker). The cases
    of a task whose worker died go out again one a task (`alone`): only the
    case that kills its worker fails, not the others it shared a task with."""
    MIN_S, MAX_S = 0.1, 2.0
    IN_FLIGHT = 2

    def __init__(self, items, client):
        from collections import deque
        self.pending = deque(items)
        self.alone = deque()
        self.client = client
        self.cpu = []
        self.workers = 1
        self.asked = -math.inf

    def _workers(self):
        now = time.monotonic()
        if now - self.asked > 5.0:               # workers may join or leave an external cluster
            self.asked = now
            try:
                self.workers = max(1, sum(self.client.nthreads().values()))
            except Exception:
                pass
        return self.workers

    def in_flight(self):
        return self.IN_FLIGHT * self._workers()

    def took(self, cpu):
        if math.isfinite(cpu):
            self.cpu.append(cpu)
            del self.cpu[:-64]

    def left(self):
        return bool(self.pending or self.alone)

    def next(self):
        if self.alone:
            return [self.alone.popleft()]
        n = 1
        if len(self.cpu) >= self._workers():
            per_case = max(float(np.median(self.cpu)), 1e-6)
            share = math.ceil(len(self.pending) / (2 * self._workers()))
            n = max(1, int(self.MIN_S / per_case), min(share, int(self.MAX_S / per_case)))
        return [self.pending.popleft() for _ in range(min(n, len(self.pending)))]


class _Progress:
    def __init__(self, total, done_before, stream=sys.stderr):
        self.total, self.before, self.stream = total, done_before, stream
        self.done = self.failed = 0
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def update(self, failed, final=False):
        self.done += 1
        self.failed += failed
        now = time.perf_counter()
        if not final and not self.tty and now - self.last < 2.0 and self.done < self.total:
            return
        self.last = now
        rate = 60 * self.done / max(now - self.t0, 1e-9)
        left = self.total - self.done
        eta = f", {left / rate:.1f} min left" if rate > 0 and left else ""
        line = (f"sweep: {self.done + self.before}/{self.total + self.before} done "
                f"({self.before} before), {self.failed} failed, {rate:.1f} cases/min{eta}")
        self.stream.write(("\r" + line) if self.tty else line + "\n")
        if self.tty and self.done == self.total:
            self.stream.write("\n")
        self.stream.flush()


@dataclass
class SweepResult:
    table: object                  # pyarrow.Table, one row per case in case order
    out: Path
    ran: int
    skipped: int
    failed: int
    wall: float

    @property
    def rate(self):
        return 60 * self.ran / self.wall if self.wall > 0 else math.nan


def sweep(bench, grid=None, variants=None, design=None, cases=None, out="sweep", stop_time=None, step=None,
          fixed=None, keep_series=False, scheduler=None, workers=None, client=None, kpi=None, plot=True,
          progress=sys.stderr, argv=None, retry_failed=False):
    """Run the cases of a bench as Dask tasks; returns a SweepResult (its table
    a pyarrow.Table). grid: {name: [values] or "start:stop:step"}; variants:
    [[names]] (each list an axis) or [names] (one axis); design: a design file;
    cases: [{name: value, 'variant': 'a+b'}]; fixed: {name: value} for every
    case (after its variants, before its own values); retry_failed: run the
    cases recorded as failed again (else a rerun skips them too). scheduler: an existing
    scheduler's address; client: a dask.distributed Client to use (else a
    local cluster of `workers` processes, default one per core). See the
    module's docstring."""
    axes = []
    for name, values in (grid or {}).items():
        if isinstance(values, str):
            values = parse_values(values, f"grid {name}")
        axes.append((name, list(values)))
    if variants:
        lists = variants if isinstance(variants[0], (list, tuple)) else [variants]
        if len(lists) == 1:
            axes.append(("variant", [str(v) for v in lists[0]]))
        else:
            axes.append(("variant", ["+".join(c) for c in _product_lists(lists)]))
    sources = [x for x in (axes, design, cases) if x]
    if len(sources) != 1:
        raise ArtibusError("give the cases one way: a grid (with variants), a design file, or a list of cases")
    if design:
        d = read_design(design)
        where = str(design)
    elif cases:
        d, where = Design("cases", cases=[dict(c) for c in cases]), "cases"
    else:
        d, where = Design("grid", axes=axes), "--grid"
    if step is not None and not step > 0:
        raise ArtibusError(f"--step {step}: must be > 0")
    if stop_time is not None and not stop_time > 0:
        raise ArtibusError(f"--stop-time {stop_time}: must be > 0")
    info = bench_info(bench)
    all_cases = build_cases(info, d, where)
    fixed = {k: typed_value(info, k, v, "--set") for k, v in (fixed or {}).items()}
    settings = {"stop_time": stop_time, "step": step, "fixed": fixed}
    keys = [case_key(info, c, settings) for c in all_cases]
    out = Path(out)
    (out / CASES_DIR).mkdir(parents=True, exist_ok=True)
    if keep_series:
        (out / SERIES_DIR).mkdir(exist_ok=True)

    def finished(k):
        f = out / CASES_DIR / f"{k}.parquet"
        if not f.is_file():
            return False
        has_series = not keep_series or (out / SERIES_DIR / f"{k}.parquet").is_file()
        if has_series and not retry_failed:
            return True
        import pyarrow.parquet as pq
        failed = pq.read_table(f, columns=["status"])["status"][0].as_py() != STATUS_OK
        if retry_failed:
            return not failed and has_series
        return failed                         # a failed case has no series

    todo = [i for i, k in enumerate(keys) if not finished(k)]
    seen, unique = set(), []
    for i in todo:                                    # the same values twice: run once
        if keys[i] not in seen:
            seen.add(keys[i])
            unique.append(i)
    manifest = {"bench": info.name, "run": str(bench), "method": d.method, "seed": d.seed, "stop_time": stop_time, "step": step,
                "fixed": fixed,
                "axes": [[n, [str(v) for v in vs]] for n, vs in d.axes] if d.method == "grid" else [],
                "parameters": sorted({k for c in all_cases for k in c}), "keys": keys,
                "argv": argv}
    _write_text(out / MANIFEST, json.dumps(manifest, indent=1, default=str))
    skipped = len(keys) - len(unique)
    t0 = time.perf_counter()
    failed = 0
    rows = {}                                         # key -> its row, of the cases run now
    if unique:
        cluster = None
        own = client is None
        if own:
            client, cluster = _client(scheduler, workers)
        try:
            data = _scatter(client, info)
            cases_dir, series_dir = os.fspath(out / CASES_DIR), os.fspath(out / SERIES_DIR)
            bar = _Progress(len(unique), skipped, progress) if progress else None
            chunks = _Chunks(unique, client)
            running = {}
            tries = collections.Counter()             # a case's tasks lost with a dead worker
            lost = collections.Counter()              # of them, cancelled: the bench's copy lost

            def submit():
                items = chunks.next()
                f = client.submit(run_cases, info.name, info.ssp_hash, str(info.ssp), data,
                                  [(keys[i], i, all_cases[i]) for i in items], fixed, stop_time, step, keep_series,
                                  key=f"artibus-cases-{keys[items[0]]}-{len(items)}-{tries[items[0]]}", pure=False, retries=0)
                running[f] = items
                return f

            from dask.distributed import as_completed
            done = as_completed([submit() for _ in range(min(chunks.in_flight(), len(unique)))])
            for f in done:
                items = running.pop(f)
                try:
                    results = f.result()
                except Exception as e:       # the worker died (not an error of a case)
                    if data.status != "finished":        # the bench's copies died with the workers
                        data = _scatter(client, info, again=True)
                    # a task of several: which case killed it? each again alone. A case alone:
                    # again up to 3 times after its worker died (it may have waited on a worker
                    # another case killed), up to 10 after its bench copy was lost with one
                    killed = type(e).__name__ == "KilledWorker"
                    if len(items) > 1 or (tries[items[0]] < 3 if killed else lost[items[0]] < 10):
                        for i in items:
                            tries[i] += 1
                            lost[i] += not killed
                        chunks.alone.extend(items)
                        items, results = [], []
                    else:
                        results = [(_case_row(keys[i], i, all_cases[i],
                                              {"status": STATUS_FAILED, "error": f"worker: {type(e).__name__}: {e}",
                                               "wall_s": math.nan}), None, None, math.nan) for i in items]
                for *_, cpu in results:
                    chunks.took(cpu)
                while chunks.left() and len(running) < chunks.in_flight():
                    done.add(submit())       # the next task before this one's files: no worker waits
                for i, (row, case_file, series_file, _) in zip(items, results):
                    bad = row["status"] != STATUS_OK
                    failed += bad
                    if series_file is not None:
                        _write_bytes(series_file, os.path.join(series_dir, f"{keys[i]}.parquet"))
                    _write_bytes(case_file if case_file is not None else _parquet_bytes(_table([row])),
                                 os.path.join(cases_dir, f"{keys[i]}.parquet"))
                    rows[keys[i]] = row
                    if bar:
                        bar.update(bad)
        finally:
            if own:
                try:
                    client.run(release)          # the workers' instances and .ssp copies
                except Exception:
                    pass
                client.close()
                if cluster is not None:
                    cluster.close()
    wall = time.perf_counter() - t0
    table = assemble(out, keys, rows)
    res = SweepResult(table, out, len(unique), skipped, failed, wall)
    if plot:
        study(out, kpi=kpi)
    return res


def _product_lists(lists):
    combos = [[]]
    for values in lists:
        combos = [c + [v] for c in combos for v in values]
    return combos


def _write_text(path, text):
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    tmp.write_text(text)
    os.replace(tmp, path)


def assemble(out, keys=None, rows=None):
    """results.parquet from the cases of this sweep (its manifest's keys), in case
    order: each case's row from rows (key -> row, the cases just run) or else read
    from its case file; the table made once, at the end."""
    import pyarrow.parquet as pq
    out = Path(out)
    if keys is None:
        keys = json.loads((out / MANIFEST).read_text())["keys"]
    rows = rows or {}
    table, done = [], set()
    for i, k in enumerate(keys):
        if k in done:
            continue
        row = rows.get(k)
        if row is None:
            f = out / CASES_DIR / f"{k}.parquet"
            if not f.is_file():
                continue
            row = pq.read_table(f).to_pylist()[0]
        done.add(k)
        table.append({**row, "case": i})
    table = _table(table)
    _write_parquet(table, out / TABLE)
    return table


# --- study plots -------------------------------------------------------------------

def kpi_columns(table):
    return [n for n in table.column_names if n.endswith("]") and " [" in n]


def _pick_kpi(table, kpi):
    cols = kpi_columns(table)
    if not cols:
        return None
    if kpi is None:
        return cols[0]
    hits = [c for c in cols if c == kpi] or [c for c in cols if kpi.lower() in c.lower()]
    if not hits:
        raise ArtibusError(f"--kpi {kpi}: no such KPI (known: {'; '.join(cols)})")
    return hits[0]


def rerun_command(manifest, row):
    """The command that runs one case alone, with its report."""
    parts = ["artibus", "run", manifest.get("run", manifest["bench"])]
    for v in _variant_list(row.get("variant")):
        parts += ["--variant", v]
    def text(v):
        return str(v).lower() if isinstance(v, bool) else repr(v) if isinstance(v, float) else str(v)
    for name, val in (manifest.get("fixed") or {}).items():
        if name not in row:
            parts += ["--set", f"{name}={text(val)}"]
    for name in manifest["parameters"]:
        if name != "variant" and row.get(name) is not None:
            parts += ["--set", f"{name}={text(row[name])}"]
    if manifest.get("stop_time") is not None:
        parts += ["--stop-time", f"{manifest['stop_time']:g}"]
    if manifest.get("step") is not None:
        parts += ["--step", f"{manifest['step']:g}"]
    parts += ["--report", f"case-{row['key']}"]
    return " ".join(shlex.quote(p) for p in parts)


def study(out, kpi=None, worst=10, largest=True):
    """study.png (a KPI over two swept parameters, a panel per value of a
    third; or its distribution for Latin hypercube / Monte Carlo) and
    worst.txt (the cases with the largest KPI, and every failed case, each
    with the command that re-runs it alone). Returns the files written."""
    import pyarrow.parquet as pq
    out = Path(out)
    manifest = json.loads((out / MANIFEST).read_text())
    table = pq.read_table(out / TABLE)
    rows = table.to_pylist()
    col = _pick_kpi(table, kpi)
    written = []
    lines = [f"Sweep of {manifest['bench']}: {len(rows)} cases, "
             f"{sum(r['status'] != STATUS_OK for r in rows)} failed ({out / TABLE})", ""]
    if col is not None:
        ok = [r for r in rows if r["status"] == STATUS_OK and r.get(col) is not None and math.isfinite(r[col])]
        ok.sort(key=lambda r: r[col], reverse=largest)
        lines.append(f"The {min(worst, len(ok))} cases with the {'largest' if largest else 'smallest'} {col}:")
        for r in ok[:worst]:
            lines.append(f"  {col} = {r[col]:.6g}   {rerun_command(manifest, r)}")
        lines.append("")
        if _plot(out / PLOT, manifest, rows, col):
            written.append(out / PLOT)
    bad = [r for r in rows if r["status"] != STATUS_OK]
    if bad:
        lines.append(f"Failed cases ({len(bad)}):")
        for r in bad:
            lines.append(f"  {r['error']}\n    {rerun_command(manifest, r)}")
    _write_text(out / WORST, "\n".join(lines) + "\n")
    written.append(out / WORST)
    return written


def _plot(path, manifest, rows, col):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ok = [r for r in rows if r["status"] == STATUS_OK and r.get(col) is not None]
    if not ok:
        return False
    axes = [(n, vs) for n, vs in manifest["axes"] if len(vs) > 1]
    if manifest["method"] == "grid" and len(axes) >= 2:
        (xn, _), (yn, _) = axes[0], axes[1]
        third = axes[2][0] if len(axes) > 2 else None
        panels = sorted({str(r.get(third)) for r in ok}, key=_num_key) if third else [None]
        fig, axs = plt.subplots(1, len(panels), figsize=(4.6 * len(panels) + 1, 4.2), squeeze=False)
        xs = sorted({r[xn] for r in ok}, key=_num_key)
        ys = sorted({r[yn] for r in ok}, key=_num_key)
        vals = [r[col] for r in ok if math.isfinite(r[col])]
        vmin, vmax = (min(vals), max(vals)) if vals else (0, 1)
        im = None
        for ax, pv in zip(axs[0], panels):
            z = np.full((len(ys), len(xs)), np.nan)
            for r in ok:
                if third is None or str(r.get(third)) == pv:
                    z[ys.index(r[yn]), xs.index(r[xn])] = r[col]
            im = ax.imshow(z, origin="lower", aspect="auto", cmap="viridis", vmin=vmin, vmax=vmax,
                           extent=None)
            ax.set_xticks(range(len(xs)), [f"{x:g}" if isinstance(x, float) else str(x) for x in xs],
                          rotation=90 if len(xs) > 8 else 0, fontsize=7)
            ax.set_yticks(range(len(ys)), [f"{y:g}" if isinstance(y, float) else str(y) for y in ys], fontsize=7)
            ax.set_xlabel(xn)
            ax.set_ylabel(yn)
            ax.set_title(f"{third} = {pv}" if third else manifest["bench"], fontsize=9)
        fig.colorbar(im, ax=axs[0].tolist(), label=col)
        fig.suptitle(f"{manifest['bench']}: {col}", fontsize=10)
    elif manifest["method"] == "grid" and len(axes) == 1:
        n = axes[0][0]
        pts = sorted(((r[n], r[col]) for r in ok), key=lambda p: _num_key(p[0]))
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.plot([str(p[0]) if not isinstance(p[0], (int, float)) else p[0] for p in pts], [p[1] for p in pts], "o-")
        ax.set_xlabel(n)
        ax.set_ylabel(col)
        ax.grid(True, alpha=0.3)
        ax.set_title(manifest["bench"])
    else:
        v = np.array([r[col] for r in ok], dtype=float)
        v = v[np.isfinite(v)]
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.hist(v, bins=max(5, min(50, int(math.sqrt(len(v))) + 1)), color="#4477aa", edgecolor="white")
        if len(v):
            for q, ls in ((0.5, "-"), (0.95, "--")):
                x = float(np.quantile(v, q))
                ax.axvline(x, color="k", ls=ls, lw=1, label=f"{int(q * 100)} % quantile {x:.4g}")
            ax.legend(fontsize=8)
        ax.set_xlabel(col)
        ax.set_ylabel("cases")
        ax.set_title(f"{manifest['bench']}: {manifest['method']}, {len(v)} cases"
                     + (f", seed {manifest['seed']}" if manifest.get("seed") is not None else ""), fontsize=9)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return True


def _num_key(x):
    try:
        return (0, float(x), "")
    except (TypeError, ValueError):
        return (1, 0.0, str(x))


# --- the command line (artibus sweep) ----------------------------------------------

def add_parser(sub):
    s = sub.add_parser("sweep", help="run many cases of a bench on Dask (grid, design file), resumable")
    s.add_argument("bench", help="a bench name (see `artibus list`) or the path of an .ssp")
    s.add_argument("--grid", nargs="+", action="extend", metavar="COMP.VAR=VALUES",
                   help="an axis: COMP.VAR=V1,V2,... or COMP.VAR=START:STOP:STEP (stop included)")
    s.add_argument("--variant", action="append", metavar="A,B,...",
                   help="an axis of the bench's variants (repeatable: each one more axis)")
    s.add_argument("--design", metavar="FILE", help="the cases from a .csv (a case a row) or .yaml "
                                                    "(grid, lhs or montecarlo with a seed)")
    s.add_argument("-o", "--out", default=None, help="output folder (default: sweep-<BENCH>)")
    s.add_argument("--stop-time", type=float, help="every case's stop time (default: the bench's)")
    s.add_argument("--step", type=float, help="base communication step, s")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE", help="a parameter of every case")
    s.add_argument("--keep-series", action="store_true", help="keep each case's time series (series/<key>.parquet)")
    s.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler (tcp://host:8786)")
    s.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    s.add_argument("--retry-failed", action="store_true", help="run the cases recorded as failed again")
    s.add_argument("--kpi", help="the KPI of the study plot and the worst cases (default: the bench's first)")
    s.set_defaults(func=main)
    return s


def main(args):
    from artibus.cli import _parse_set          # --set as artibus run reads it
    variants = [v.split(",") for v in args.variant] if args.variant else None
    if variants and any(not x.strip() for vs in variants for x in vs):
        raise ArtibusError(f"--variant {','.join(args.variant)}: an empty variant name")
    if args.workers is not None and args.workers < 1:
        raise ArtibusError(f"--workers {args.workers}: at least 1")
    out = args.out or f"sweep-{Path(args.bench).stem}"
    res = sweep(args.bench, grid=parse_grid(args.grid) if args.grid else None, variants=variants,
                design=args.design, out=out, stop_time=args.stop_time, step=args.step,
                fixed=_parse_set(args.set),
                keep_series=args.keep_series, scheduler=args.scheduler, workers=args.workers, kpi=args.kpi,
                retry_failed=args.retry_failed,
                argv=sys.argv)
    n = res.table.num_rows
    print(f"sweep {Path(args.bench).stem}: {n} cases, {res.ran} run now ({res.failed} failed), "
          f"{res.skipped} done before" + (f"; {res.rate:.1f} cases/min" if res.ran else ""))
    for f in (TABLE, PLOT, WORST):
        if (Path(out) / f).is_file():
            print(f"    {Path(out) / f}")
    return 0


class _CallableModule(types.ModuleType):
    """``artibus.sweep(...)`` runs a sweep (the module is callable)."""

    def __call__(self, *args, **kwargs):
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
