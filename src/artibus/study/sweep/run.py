"""``sweep``: the cases of a bench run as Dask tasks, resumable (see artibus.study.sweep)."""
import collections
import json
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from artibus.base import ArtibusError
from artibus.study.sweep.cluster import _Chunks, _client, _Progress, _scatter, lost_message, scheduler_lost
from artibus.study.sweep.designs import (Design, _product_lists, bench_info, build_cases, case_key, parse_values,
                                         read_design, typed_value)
from artibus.study.sweep.plots import study
from artibus.study.sweep.store import (CASES_DIR, MANIFEST, PLOT, SERIES_DIR, STATUS_FAILED, TABLE, WORST,
                                       FolderLock, _case_row,
                                       _parquet_bytes, _table, _write_bytes, _write_text, assemble, read_case)
from artibus.study.sweep.worker import release, run_cases


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


def _refuse_inputs(out, bench, design):
    """The output folder and the files a sweep writes in it, none of them an
    input of the sweep (its design file, the bench, the runner's packs and FMUs,
    ssp/: artibus.files.bench_inputs), checked by identity before anything runs."""
    from artibus.files import bench_inputs, check_not_input
    inputs = ([(Path(design), "the design file")] if design else []) + bench_inputs(bench)
    check_not_input(out, "-o", inputs)
    for name in (TABLE, MANIFEST, WORST, PLOT):
        check_not_input(out / name, "-o", inputs)


def sweep(bench, grid=None, variants=None, design=None, cases=None, out="sweep", stop_time=None, step=None,
          fixed=None, keep_series=False, scheduler=None, workers=None, client=None, kpi=None, plot=True,
          progress=sys.stderr, argv=None, retry_failed=False, fmi=None, error_every=0):
    """Run the cases of a bench as Dask tasks; returns a SweepResult (its table
    a pyarrow.Table). grid: {name: [values] or "start:stop:step"}; variants:
    [[names]] (each list an axis) or [names] (one axis); design: a design file;
    cases: [{name: value, 'variant': 'a+b'}]; fixed: {name: value} for every
    case (after its variants, before its own values); retry_failed: run the
    cases recorded as failed again (else a rerun skips them too). scheduler: an existing
    scheduler's address; client: a dask.distributed Client to use (else a
    local cluster of `workers` processes, default one per core). fmi: "2"
    or "3", every FMU's build of that FMI version (the bench's pack with them,
    artibus.bench.ssp.ssp_path: its cases are other cases, their keys hash the
    FMUs), None as the bench's .ssd names them. error_every: every n-th case (by its
    index; 0: none) run again with its continuous components' steps halved, each KPI's
    co-simulation error a column "KPI [unit] cosim error" (worker.error_columns, issue 44).
    See the module's docstring."""
    d, where = _design(grid, variants, design, cases)
    _check_settings(step, stop_time, error_every)
    if fmi is not None:
        from artibus.bench import ssp as ssp_mod
        bench = ssp_mod.ssp_path(bench, fmi)
    info = bench_info(bench)
    all_cases = build_cases(info, d, where)
    fixed = {k: typed_value(info, k, v, "--set") for k, v in (fixed or {}).items()}
    settings = {"stop_time": stop_time, "step": step, "fixed": fixed}
    if error_every:           # (a case with its error estimate is another case; without, the keys as before)
        settings["error_every"] = error_every
    keys = [case_key(info, c, settings) for c in all_cases]
    out = Path(out)
    _refuse_inputs(out, bench, design)
    (out / CASES_DIR).mkdir(parents=True, exist_ok=True)
    if keep_series:
        (out / SERIES_DIR).mkdir(exist_ok=True)

    with FolderLock(out):                             # one sweep at a time in a folder
        todo = [i for i, k in enumerate(keys) if not _finished(out, k, keep_series, retry_failed, progress)]
        unique = _first_of_each(keys, todo)
        _write_text(out / MANIFEST, json.dumps(_manifest(info, bench, d, all_cases, keys, fixed, stop_time, step,
                                                         error_every, argv), indent=1, default=str))
        skipped = len(keys) - len(unique)
        t0 = time.perf_counter()
        rows = {}                                         # key -> its row, of the cases run now
        failed = 0
        if unique:
            job = _Job(info, keys, all_cases, fixed, stop_time, step, keep_series, error_every, out)
            failed = _run_on_dask(job, unique, skipped, rows, client, scheduler, workers, progress)
        wall = time.perf_counter() - t0
        table = assemble(out, keys, rows)
        res = SweepResult(table, out, len(unique), skipped, failed, wall)
        if plot:
            study(out, kpi=kpi, log=(lambda line: print(f"sweep: {line}", file=progress)) if progress else None)
        return res


def _design(grid, variants, design, cases):
    """(the Design, where it comes from for the messages): the grid's axes (a variants axis last),
    a design file, or a list of cases; exactly one of them."""
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
    return d, where


def _check_settings(step, stop_time, error_every):
    """--step, --stop-time and --error-every refused in one line where out of range."""
    if step is not None and not step > 0:
        raise ArtibusError(f"--step {step}: must be > 0")
    if stop_time is not None and not stop_time > 0:
        raise ArtibusError(f"--stop-time {stop_time}: must be > 0")
    if isinstance(error_every, bool) or not isinstance(error_every, int) or error_every < 0:
        raise ArtibusError(f"--error-every {error_every}: a whole number >= 0 (every n-th case; 0: none)")


def _finished(out, k, keep_series, retry_failed, progress):
    """Whether case ``k`` is done in ``out`` already (its row readable, its series where kept; a
    failed case is done unless retry_failed)."""
    f = out / CASES_DIR / f"{k}.parquet"
    if not f.is_file():
        return False
    row = read_case(f)
    if row is None:                       # torn or corrupt: run again
        if progress:
            print(f"sweep: {f}: cannot be read; the case is run again", file=progress)
        return False
    has_series = not keep_series or (out / SERIES_DIR / f"{k}.parquet").is_file()
    if has_series and not retry_failed:
        return True
    failed = row["status"] == STATUS_FAILED
    if retry_failed:
        return not failed and has_series
    return failed                         # a failed case has no series


def _first_of_each(keys, todo):
    """The cases of ``todo`` to run: the first of each key (the same values twice: run once)."""
    seen, unique = set(), []
    for i in todo:
        if keys[i] not in seen:
            seen.add(keys[i])
            unique.append(i)
    return unique


def _manifest(info, bench, d, all_cases, keys, fixed, stop_time, step, error_every, argv):
    """The sweep's manifest.json: what was run, how, its cases' keys and command line."""
    return {"bench": info.name, "run": str(bench), "method": d.method, "seed": d.seed, "stop_time": stop_time,
            "step": step, "error_every": error_every, "fixed": fixed,
            "axes": [[n, [str(v) for v in vs]] for n, vs in d.axes] if d.method == "grid" else [],
            "parameters": sorted({k for c in all_cases for k in c}), "keys": keys, "argv": argv}


@dataclass
class _Job:
    """What every case of a sweep shares: the bench, the cases and their keys, the settings, the folder."""
    info: object
    keys: list
    all_cases: list
    fixed: dict
    stop_time: object
    step: object
    keep_series: bool
    error_every: int
    out: Path


def _run_on_dask(job, unique, skipped, rows, client, scheduler, workers, progress):
    """The cases ``unique`` run as Dask tasks (a chunk of cases a task, the next submitted before
    a finished one's files are written), each case's row and series written as it comes and put
    in ``rows``; a task lost with its worker run again case by case. Returns the number failed.
    A lost scheduler: an ArtibusError saying what is on disk."""
    info, keys, all_cases, fixed, out = job.info, job.keys, job.all_cases, job.fixed, job.out
    stop_time, step, keep_series, error_every = job.stop_time, job.step, job.keep_series, job.error_every
    failed = 0
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
                              error_every,
                              key=f"artibus-cases-{keys[items[0]]}-{len(items)}-{tries[items[0]]}", pure=False, retries=0)
            running[f] = items
            return f

        from dask.distributed import as_completed
        from artibus.runner.markers import mark
        done = as_completed([submit() for _ in range(min(chunks.in_flight(), len(unique)))])
        for f in done:
            items = running.pop(f)
            try:
                results = f.result()
            except Exception as e:       # the worker died (not an error of a case)
                if scheduler_lost(client):   # (or the scheduler: said below)
                    raise
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
                bad = row["status"] == STATUS_FAILED     # (a terminated case ran: not counted)
                failed += bad
                if series_file is not None:
                    _write_bytes(series_file, os.path.join(series_dir, f"{keys[i]}.parquet"))
                _write_bytes(case_file if case_file is not None else _parquet_bytes(_table([row])),
                             os.path.join(cases_dir, f"{keys[i]}.parquet"))
                mark(f"case {keys[i]}")            # for the tests (artibus.runner.markers)
                rows[keys[i]] = row
                if bar:
                    bar.update(bad)
    except Exception as e:                # the scheduler lost (killed): each case done is on disk
        if not scheduler_lost(client):
            raise
        raise ArtibusError(lost_message(client, scheduler, out, len(rows), e)) from None
    finally:
        if own:
            try:
                client.run(release)          # the workers' instances and .ssp copies
            except Exception:
                pass
            client.close()
            if cluster is not None:
                cluster.close()
    return failed
