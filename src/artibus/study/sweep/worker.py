"""A sweep's cases on a worker: the bench's .ssp copied once (``_worker_ssp``),
its FMU instances reused across cases (fmi2Reset, then the case's parameters
and a new initialisation: ``_simulate``; ``release`` frees them), one case
(``run_case``) and a task of several (``run_cases``), each case's row and its
Parquet files made here (the client only writes them)."""
import atexit
import math
import os
import tempfile
import threading
import time
from pathlib import Path

from artibus.base import ArtibusError
from artibus.study.sweep.designs import _variant_list
from artibus.study.sweep.store import STATUS_FAILED, STATUS_OK, STATUS_TERMINATED, _case_row, _parquet_bytes, _series_table, _table


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
    from artibus.runner import resolve_resources
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
        if ok and REUSE and sim.network is None:
            with _LOCK:
                _SIMS[key] = (sim, content)
        else:
            sim.close()


def run_case(bench_name, content_hash, ssp_path, ssp_bytes, case, fixed, stop_time, step, keep_series, error=False):
    """One case on a worker: (row, series or None). A failure is a row with its error.
    ``error``: the case's KPIs' co-simulation error estimated too (error_columns)."""
    from artibus.bench import script, ssp as ssp_mod
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
        if r.terminated is not None:        # an FMU's own end: the case ran, ended early
            row["status"], row["error"] = STATUS_TERMINATED, str(r.terminated)
        try:
            for k in script.kpis(bench_name, r):
                v = k.value
                row[f"{k.name} [{k.unit}]"] = float(v) if v is not None else math.nan
        except Exception as e:
            raise ArtibusError(f"KPI: {type(e).__name__}: {e}") from None
        if error:
            row.update(error_columns(bench_name, ssp, overrides, stop, step, row))
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


def error_columns(bench_name, ssp, overrides, stop_time, step, row):
    """The co-simulation error of each KPI of a case's ``row`` (issue 44): the case run
    again with the continuous components' steps halved (artibus.report.cosim_error,
    HALVED: the sampled controllers at their periods), 2 |K(h) - K(h/2)|, a column
    "KPI [unit] cosim error" each (NaN where either run has no number)."""
    from artibus.bench import script
    from artibus.report import cosim_error
    with cosim_error._configured(cosim_error.HALVED)(ssp, step=step, overrides=overrides) as sim:
        half = {f"{k.name} [{k.unit}]": cosim_error.number(k.value)
                for k in script.kpis(bench_name, sim.run(stop_time=stop_time))}
    out = {}
    for col, h2 in half.items():
        v = cosim_error.number(row.get(col))
        out[f"{col} {ERROR_SUFFIX}"] = 2 * abs(v - h2) if v is not None and h2 is not None else math.nan
    return out


ERROR_SUFFIX = "cosim error"      # a KPI's column "NAME [unit]" and its error's "NAME [unit] cosim error"


def run_cases(bench_name, content_hash, ssp_path, ssp_bytes, cases, fixed, stop_time, step, keep_series,
              error_every=0):
    """A task: several cases [(key, index, case)] in turn on one worker (run_case
    each). For each its table row (_case_row), its case file's bytes and its time
    series' (or None), both Parquet made here (the client only writes them), and
    the CPU time it took (s). ``error_every``: every n-th case (by its index) with its
    KPIs' co-simulation errors (error_columns; 0: none)."""
    out = []
    for key, index, case in cases:
        cpu = time.thread_time()
        row, series = run_case(bench_name, content_hash, ssp_path, ssp_bytes, case, fixed, stop_time, step,
                               keep_series, error=bool(error_every) and index % error_every == 0)
        row = _case_row(key, index, case, row)
        out.append((row, _parquet_bytes(_table([row])),
                    _parquet_bytes(_series_table(series)) if series is not None else None,
                    time.thread_time() - cpu))
    return out
