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

The parts: ``designs`` (grids, design files, the cases checked against the
bench, their keys), ``worker`` (a case on a worker, the instances it keeps),
``cluster`` (Dask: the cluster, the tasks), ``store`` (the output folder,
resume), ``plots`` (the study plot and the worst cases), ``run`` (``sweep``
itself). This package is callable: ``artibus.study.sweep(...)`` (and
``artibus.sweep(...)``) is ``sweep(...)``.
"""
import sys
import types

from artibus.study.sweep.designs import (DISTRIBUTIONS, MAX_CASES, BenchInfo, Design, bench_info,  # noqa: F401
                                         build_cases, case_key, parse_grid, parse_values, read_design,
                                         typed_value)
from artibus.study.sweep.plots import kpi_columns, rerun_command, study                    # noqa: F401
from artibus.study.sweep.run import SweepResult, sweep                                      # noqa: F401
from artibus.study.sweep.store import (CASES_DIR, MANIFEST, PLOT, SERIES_DIR, STATUS_FAILED,  # noqa: F401
                                       STATUS_OK, STATUS_TERMINATED, TABLE, WORST, assemble)
from artibus.study.sweep.worker import release, run_case, run_cases                        # noqa: F401


class _CallableModule(types.ModuleType):
    """``artibus.study.sweep(...)`` runs a sweep (the package is callable)."""

    def __call__(self, *args, **kwargs):
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
