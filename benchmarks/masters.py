"""Benchmark (prints, not a test; issue 30): our runner against ecos and libcosim
on the same portable packs (artibus pack --portable; the guide's "Other SSP
masters"), in-process and as commands, with the results compared.

1. In-process: every master in a process of its own (benchmarks/masters_timed.py,
   ours too), its Python interface imported before the timing, then REPEAT times
   set-up (reading the SSP, unpacking, loading the FMUs, instantiating, the
   recording configured) + run (initialisation, every step, and every recorded
   output of every step read back into Python), timed inside that process; the
   best of REPEAT (set-up + run) is the figure. Each master records in its own
   fastest way: ours the C core's table, ecos its C++ CSV writer with the
   variables registered (read back with NumPy), libcosim a buffered time-series
   observer (read back into NumPy); --python-reads adds the way
   tests/masters_run.py drives them (a value read from Python after each step:
   "ecos-py", "libcosim-py"). Ours is run stepped as each master steps (libcosim:
   Jacobi, each component at its own step; ecos: every component at the base
   step, the nearest of our algorithms Jacobi; tests/test_masters.STEPPING) and
   compared with that master: the speed ratio (theirs / ours) against the target
   1.5 x, and the bench's KPIs (our KPI code on their results) against ours,
   the largest difference relative to ours (under the tests' floor of each unit,
   tests/test_masters.ABS, the floor), "equal" within the tests' tolerance (2 %,
   libcosim 0.1 %). Our default run (Gauss-Seidel, multi-rate: what `artibus
   run` does) is printed beside.
2. As commands (a new process each, best and median of REPEAT): `artibus run
   PACK -o x.csv`, ecos's own command-line program (`ecos simulate`, shipped in
   ecospy's wheel, its CSV restricted to the same variables) and a Python process
   driving ecospy, a Python process driving libcosimpy (libcosim's command-line
   program is not on PyPI), each writing the recorded outputs to a CSV; beside
   them `artibus --version` and the floor (`python -c pass`), with issue 30's
   targets.

The machine's load average is printed at the start and the end: on this shared
2-core machine the wall times rise with it.

usage: .venv/bin/python benchmarks/masters.py [--repeat N] [--python-reads] [--no-commands] [BENCH[:VARIANT] ...]
       (default: Urbino18_Circle Bus36m_Circle Scania18m_Damping MultiAxle_StepSteer, REPEAT 5)

figures(cases, repeat) returns the in-process rows and commands(...) the command
rows as dicts; table(rows) the lines of the summary (benchmarks/suite.py prints it).
"""
import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TIMED = HERE / "masters_timed.py"
sys.path.insert(0, str(ROOT / "tests"))

CASES = [("Urbino18_Circle", ()), ("Bus36m_Circle", ()), ("Scania18m_Damping", ()), ("MultiAxle_StepSteer", ())]
MASTERS = ["ecos", "libcosim"]
TARGET = 1.5            # issue 30: in-process set-up + run at least 1.5 x faster than each
COMMAND_TARGETS = {"artibus --version": 0.15, "artibus run Scania18m_Damping -o x.csv (the bench)": 0.35}


def _stepping(master):
    from test_masters import STEPPING
    return STEPPING[master.removesuffix("-py")]


def _kpis(bench, names, rows):
    import numpy as np
    from artibus.bench import script
    from artibus.fmu import Result
    r = Result.from_array(names, np.array(rows, dtype=float))
    return {k.name: (k.value, k.unit) for k in script.kpis(bench, r)
            if isinstance(k.value, (int, float)) and not isinstance(k.value, bool)}


def _compare(ours, theirs, master):
    """(largest difference relative to ours -- or to the unit's floor --, equal within the
    tests' tolerance of that master, the KPI of the largest with both values)."""
    from test_masters import ABS, REL, TIGHT
    master = master.removesuffix("-py")
    worst, equal, which = 0.0, True, ""
    for name, (v, unit) in ours.items():
        w = theirs.get(name, (math.nan, unit))[0]
        if not (math.isfinite(v) and math.isfinite(w)):
            if math.isfinite(v) != math.isfinite(w):
                return math.inf, False, name
            continue
        floor = ABS.get(unit, 0.0)
        d = abs(w - v) / max(abs(v), floor / REL, 1e-12)
        rel = TIGHT.get(master, REL)
        equal &= abs(w - v) <= max(rel * abs(v), floor * rel / REL)
        if d > worst:
            worst, which = d, f"{name}: ours {v:.6g} {unit}, theirs {w:.6g}"
    return worst, equal, which


def _timed(spec, tmp):
    """masters_timed.py on SPEC in a new process: its JSON (ok, error, setup, run, names, rows)."""
    tag = f"{spec['master']}-{next(_COUNT)}"
    sp, out = Path(tmp) / f"{tag}.spec.json", Path(tmp) / f"{tag}.json"
    sp.write_text(json.dumps(spec))
    p = subprocess.run([sys.executable, str(TIMED), str(sp), str(out)], capture_output=True, text=True,
                       timeout=1800)
    if not out.is_file():
        return {"ok": False, "error": f"died (exit {p.returncode}): {p.stderr.strip()[-300:]}"}
    return json.loads(out.read_text())


_COUNT = iter(range(10**9))


def _best(got):
    """(set-up s, run s) of the repetition with the least set-up + run."""
    return min(zip(got["setup"], got["run"]), key=sum)


def figures(cases=CASES, repeat=5, python_reads=False, log=print):
    """[{bench, master, stepping, ok, error, setup, run, ours_setup, ours_run, ours_default,
    ratio, kpi_diff, kpi, equal}]: for each case and master, theirs against ours stepped as
    it steps (the module's docstring)."""
    from artibus.bench.portable import pack_portable
    from artibus.runner import Simulation
    from test_masters import one_rate
    masters = MASTERS + ([f"{m}-py" for m in MASTERS] if python_reads else [])
    rows = []
    with tempfile.TemporaryDirectory(prefix="artibus-masters-") as tmp:
        for bench, variants in cases:
            label = "_".join([bench, *variants])
            pack = pack_portable(bench, variants, out=Path(tmp) / f"{label}.portable.ssp")
            with Simulation(pack) as sim:
                r = sim.run()
                step, stop = sim.base_step, float(r.time[-1])
            names = [n for n in r.names if n != "time"]
            base = dict(pack=str(pack), step=step, stop=stop, repeat=repeat, names=names)
            packs = {False: str(pack), True: str(one_rate(pack, step, Path(tmp) / f"{label}.one-rate.ssp"))}
            ours = {}
            for algorithm, single in [("gauss-seidel", False), *(_stepping(m) for m in masters)]:
                if (algorithm, single) not in ours:
                    got = _timed({**base, "master": "artibus", "algorithm": algorithm, "pack": packs[single]}, tmp)
                    if not got["ok"]:
                        raise SystemExit(f"artibus on {label}: {got['error']}")
                    ours[algorithm, single] = (got, _kpis(bench, got["names"], got["rows"]))
            default = sum(_best(ours["gauss-seidel", False][0]))
            log(f"  {label}: ours (Gauss-Seidel, multi-rate, as `artibus run`) {1e3 * default:.1f} ms "
                f"set-up + run, best of {repeat}")
            for m in masters:
                mine, my_kpis = ours[_stepping(m)]
                got = _timed({**base, "master": m}, tmp)
                row = dict(bench=label, master=m, stepping=_describe(_stepping(m)), ok=got["ok"],
                           error=got.get("error", ""), ours_setup=_best(mine)[0], ours_run=_best(mine)[1],
                           ours_default=default, setup=math.nan, run=math.nan, ratio=math.nan,
                           kpi_diff=math.nan, kpi="", equal=False, repeat=repeat)
                if got["ok"]:
                    row["setup"], row["run"] = _best(got)
                    row["ratio"] = (row["setup"] + row["run"]) / (row["ours_setup"] + row["ours_run"])
                    try:
                        row["kpi_diff"], row["equal"], row["kpi"] = _compare(my_kpis, _kpis(bench, got["names"],
                                                                                             got["rows"]), m)
                    except Exception as e:       # the KPIs need what the master did not give
                        row["error"] = f"KPIs: {type(e).__name__}: {e}"
                rows.append(row)
                log(_line(row))
    return rows


def _describe(stepping):
    algorithm, single = stepping
    return f"{algorithm.capitalize()}, {'one rate' if single else 'multi-rate'}"


def _line(row):
    if not row["ok"]:
        return f"    {row['master']:12s} cannot run it: {row['error'][:200]}"
    return (f"    {row['master']:12s} {1e3 * row['setup']:7.1f} + {1e3 * row['run']:7.1f} ms   ours as it steps "
            f"({row['stepping']}) {1e3 * row['ours_setup']:6.1f} + {1e3 * row['ours_run']:6.1f} ms   "
            f"x{row['ratio']:5.2f}   KPIs off by at most {100 * row['kpi_diff']:.3g} % "
            f"({'equal' if row['equal'] else 'NOT equal'} within the tests' tolerance; {row['kpi'] or '-'})")


def table(rows):
    """The summary, one line per bench and master, as a Markdown table."""
    out = ["| bench | master | stepping (ours as it) | ours ms (set-up + run) | theirs ms (set-up + run) "
           "| theirs / ours | KPIs: largest difference | 1.5 x |",
           "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        if not r["ok"]:
            out.append(f"| {r['bench']} | {r['master']} | | | cannot run it: {r['error'][:80]} | | | |")
            continue
        ours, theirs = r["ours_setup"] + r["ours_run"], r["setup"] + r["run"]
        out.append(f"| {r['bench']} | {r['master']} | {r['stepping']} | {1e3 * ours:.1f} "
                   f"({1e3 * r['ours_setup']:.1f} + {1e3 * r['ours_run']:.1f}) | {1e3 * theirs:.1f} "
                   f"({1e3 * r['setup']:.1f} + {1e3 * r['run']:.1f}) | {r['ratio']:.2f} | "
                   f"{100 * r['kpi_diff']:.2g} %{'' if r['equal'] else ' (not equal)'} | "
                   f"{'met' if r['ratio'] >= TARGET else 'MISSED'} |")
    return out


# --- 2. as commands ------------------------------------------------------------------

def _ecos_program(tmp):
    """ecospy's wheel ships ecos's command-line program without the executable bit: a copy with it."""
    import ecospy
    src = Path(ecospy.__file__).parent / "binaries" / "ecos"
    dst = Path(tmp) / "ecos"
    shutil.copy(src, dst)
    dst.chmod(0o755)
    return dst


def _ecos_csv_config(names, path):
    """ecos's CSV configuration (ecos:CsvConfig, csv_writer.cpp's reader): these variables only."""
    from xml.sax.saxutils import quoteattr
    comps = {}
    for n in names:
        c, _, v = n.partition(".")
        comps.setdefault(c, []).append(v)
    body = "".join(f"<ecos:component name={quoteattr(c)}>"
                   + "".join(f"<ecos:variable name={quoteattr(v)}/>" for v in vs) + "</ecos:component>"
                   for c, vs in comps.items())
    path.write_text(f'<ecos:CsvConfig xmlns:ecos="https://github.com/Ecos-platform/ecos">'
                    f"<ecos:components>{body}</ecos:components></ecos:CsvConfig>")
    return path


def _wall(argv, cwd, repeat):
    walls = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        p = subprocess.run(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        walls.append(time.perf_counter() - t0)
        if p.returncode != 0:
            return None, f"exit {p.returncode}: {p.stderr.strip()[-200:]}"
    return walls, ""


def commands(cases=CASES, repeat=5, log=print):
    """[{bench, command, ok, error, best, median}]: each a new process, REPEAT times."""
    from artibus.bench.portable import pack_portable
    from artibus.runner import Simulation
    python = sys.executable
    artibus = str(Path(python).with_name("artibus"))
    rows = []
    with tempfile.TemporaryDirectory(prefix="artibus-commands-") as tmp:
        tmp = Path(tmp)
        ecos = _ecos_program(tmp)

        def add(bench, what, argv):
            walls, err = _wall(argv, tmp, repeat)
            row = dict(bench=bench, command=what, ok=walls is not None, error=err,
                       best=min(walls) if walls else math.nan, median=statistics.median(walls) if walls else math.nan)
            target = COMMAND_TARGETS.get(what)
            row["target"] = target
            rows.append(row)
            log(f"  {what:58s} " + (f"wall best {row['best']:6.3f} s  median {row['median']:6.3f} s"
                                    + (f"   target <= {target:.2f} s: {'met' if row['best'] <= target else 'MISSED'}"
                                       if target else "") if row["ok"] else f"failed: {err}"))
        add("", "floor: python -c pass", [python, "-c", "pass"])
        _wall([artibus, "--version"], tmp, 1)                   # byte-compiled
        add("", "artibus --version", [artibus, "--version"])
        by_name = [artibus, "run", "Scania18m_Damping", "-o", "x.csv"]
        _wall(by_name, tmp, 1)                                  # packed, cached
        add("", "artibus run Scania18m_Damping -o x.csv (the bench)", by_name)
        for bench, variants in cases:
            label = "_".join([bench, *variants])
            pack = pack_portable(bench, variants, out=tmp / f"{label}.portable.ssp")
            with Simulation(pack) as sim:
                r = sim.run()
                step, stop = sim.base_step, float(r.time[-1])
            names = [n for n in r.names if n != "time"]
            _wall([artibus, "run", str(pack), "-o", "x.csv"], tmp, 1)      # cached
            add(label, f"artibus run {pack.name} -o x.csv", [artibus, "run", str(pack), "-o", "x.csv"])
            cfg = _ecos_csv_config(names, tmp / f"{label}.csv-config.xml")
            add(label, "ecos simulate (its program, CSV of the same variables)",
                [str(ecos), "simulate", "--path", str(pack), "--stepSize", repr(step), "--stopTime", repr(stop),
                 "--parameterSet", "bench", "--csvConfig", str(cfg), "-l", "err"])
            for m in MASTERS:
                spec = tmp / f"{label}-{m}.spec.json"
                spec.write_text(json.dumps(dict(master=m, pack=str(pack), step=step, stop=stop, repeat=1,
                                                names=names, csv=str(tmp / f"{m}.csv"))))
                add(label, f"python + {m}py (set-up, run, CSV of the same variables)",
                    [python, str(TIMED), str(spec), str(tmp / f"{m}.json")])
    return rows


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", metavar="BENCH[:VARIANT]")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--python-reads", action="store_true",
                    help="also ecos and libcosim with a value read from Python after each step")
    ap.add_argument("--no-commands", action="store_true")
    args = ap.parse_args(argv)
    cases = [(a.split(":")[0], tuple(a.split(":")[1:])) for a in args.cases] or CASES
    t0 = time.time()
    load = os.getloadavg()
    print(f"artibus against ecos and libcosim: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{os.cpu_count()} cores, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} at the start")
    print(f"\n1. In-process: set-up + run in ms, best of {args.repeat}, each master in a process of its own; "
          "ours stepped as each master steps; KPIs: our KPI code on their results against ours")
    rows = figures(cases, args.repeat, args.python_reads)
    print()
    print("\n".join(table(rows)))
    missed = [r for r in rows if not r["ok"] or r["ratio"] < TARGET]
    print(f"\n   [{'met' if not missed else 'MISSED'}] in-process set-up + run >= {TARGET} x faster than "
          + " and ".join(MASTERS) + " on " + ", ".join("_".join([b, *v]) for b, v in cases)
          + (f" (least: x{min(r['ratio'] for r in rows if r['ok']):.2f})" if any(r["ok"] for r in rows) else "")
          + ("; missed: " + ", ".join(f"{r['bench']} {r['master']}" for r in missed) if missed else ""))
    if not args.no_commands:
        print(f"\n2. As commands: a new process each, wall time best and median of {args.repeat}")
        commands(cases, args.repeat)
    load = os.getloadavg()
    print(f"\nload average {load[0]:.2f} (1 min) at the end, {time.time() - t0:.0f} s in all")


if __name__ == "__main__":
    main(sys.argv[1:])
