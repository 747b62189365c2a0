"""Benchmark (prints, not a test): our runner against ecos, libcosim and
fmpy.ssp.simulate_ssp on the same portable packs (artibus pack --portable; the
guide's "Other SSP masters"), each master in a process of its own
(tests/masters_run.py, as tests/test_masters.py runs them).

For each bench and master: the wall time of the run (set-up -- reading,
unpacking, loading the FMUs --, initialisation, stepping and reading the
recorded values at every step, as each master's Python interface gives them:
ecos and libcosim one step at a time from Python, fmpy.ssp its whole run), the
real-time factor (simulated span / that wall time), and the largest relative
difference of the bench's KPIs (our KPI code on the master's results) from ours
on the same pack. Ours is timed the same way (Simulation set-up + run, in this
process).

usage: .venv/bin/python benchmarks/masters.py [BENCH[:VARIANT] ...]
       (default: the five benches of tests/test_masters.py)

figures(cases, masters) returns the rows as dicts, for other scripts
(benchmarks/suite.py may print them).
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
RUN = HERE.parent / "tests" / "masters_run.py"
CASES = [("Urbino18_Circle", ()), ("MultiAxle_StepSteer", ()), ("Scania18m_Damping", ()),
         ("Bus36m_Circle", ("guidedForceMin",)), ("Scania18m_LaneChange", ())]
MASTERS = ["ecos", "libcosim", "fmpy-ssp"]


def _kpis(bench, result):
    from artibus.bench import script
    return {k.name: k.value for k in script.kpis(bench, result)
            if isinstance(k.value, (int, float)) and not isinstance(k.value, bool)}


def _largest_difference(ours, theirs):
    worst = 0.0
    for name, v in ours.items():
        w = theirs.get(name, math.nan)
        if not (math.isfinite(v) and math.isfinite(w)):
            if math.isfinite(v) != math.isfinite(w):
                return math.inf
            continue
        worst = max(worst, abs(w - v) / max(abs(v), 1e-9))
    return worst


def figures(cases=CASES, masters=MASTERS, log=print):
    """[{bench, master, ok, error, wall_s, rtf, kpi_rel_diff}] for each case and master
    (ours first as master "artibus")."""
    import numpy as np
    from artibus.bench.portable import pack_portable
    from artibus.fmu import Result
    from artibus.runner import Simulation
    rows = []
    with tempfile.TemporaryDirectory(prefix="artibus-masters-") as tmp:
        for bench, variants in cases:
            label = "_".join([bench, *variants])
            pack = pack_portable(bench, variants, out=Path(tmp) / f"{label}.portable.ssp")
            t0 = time.perf_counter()
            with Simulation(pack) as sim:
                r = sim.run()
                step = sim.base_step
            wall = time.perf_counter() - t0
            span = float(r.time[-1] - r.time[0])
            ours = _kpis(bench, r)
            rows.append(dict(bench=label, master="artibus", ok=True, error="", wall_s=wall, rtf=span / wall,
                             kpi_rel_diff=0.0))
            log(_line(rows[-1]))
            names = [n for n in r.names if n != "time"]
            for m in masters:
                out = Path(tmp) / f"{label}-{m}.json"
                subprocess.run([sys.executable, str(RUN), m, str(pack), repr(step), repr(float(r.time[-1])),
                                str(out), *names], capture_output=True, text=True, timeout=1800)
                got = json.loads(out.read_text()) if out.is_file() else {"ok": False, "error": "died"}
                row = dict(bench=label, master=m, ok=got["ok"], error=got.get("error", ""),
                           wall_s=got.get("wall", math.nan), rtf=math.nan, kpi_rel_diff=math.nan)
                if got["ok"]:
                    row["rtf"] = span / got["wall"]
                    theirs = Result.from_array(got["names"], np.array(got["rows"], dtype=float))
                    try:
                        row["kpi_rel_diff"] = _largest_difference(ours, _kpis(bench, theirs))
                    except Exception as e:          # the KPIs need what the master did not give
                        row["error"] = f"KPIs: {type(e).__name__}: {e}"
                rows.append(row)
                log(_line(row))
    return rows


def _line(row):
    if not row["ok"]:
        return f"{row['bench']:34s} {row['master']:9s} cannot run it: {row['error'][:100]}"
    diff = f"{100 * row['kpi_rel_diff']:8.3f} %" if math.isfinite(row["kpi_rel_diff"]) else f"   ({row['error'][:60]})"
    return (f"{row['bench']:34s} {row['master']:9s} {row['wall_s']:8.2f} s  real-time x{row['rtf']:7.1f}  "
            f"KPIs off by at most {diff}")


def main(argv):
    cases = [(a.split(":")[0], tuple(a.split(":")[1:])) for a in argv] or CASES
    print(f"{'bench':34s} {'master':9s} {'wall':>10s}  {'':18s}  KPIs against ours")
    figures(cases)


if __name__ == "__main__":
    main(sys.argv[1:])
