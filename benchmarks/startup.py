"""The command as fast as the run (issue 30): wall times of `artibus` as a
command, and of a run's set-up in-process, with the targets.

1. `artibus --version` and `artibus run Scania18m_Damping -o x.csv`, each a
   new process (the console script, as a user or a CI job starts it), best
   and median of REPEAT, wall clock and CPU time (user + system of the child).
   The run three ways: with the cache of unpacked benches and FMUs warm (the
   usual case: artibus.cache), cold (an empty cache each time: the first run
   after a rebuild), and without it (ARTIBUS_CACHE_MB=0: a temporary copy per
   run, as before the cache).
2. In-process, per bench: the set-up (Simulation(...): reading the .ssp,
   unpacking, model descriptions, instantiation, the connections) and the run
   (Simulation.run, the initialisation included), best of REPEAT, cache warm.
3. With --profile: cProfile of one command's work in-process (cache warm,
   imports done, as the second half of the command's wall time), the 25
   functions with the most cumulative time.

The machine's load (os.getloadavg) is printed first: on a shared machine the
wall times rise with it; the CPU times less so. Beside the commands, the floor
no artibus command goes below: a process that imports only what every run
needs from other packages (NumPy, FMPy, lxml), and one that imports nothing.

The commands run as a default Python runs them, with their bytecode written
and read (__pycache__): without PYTHONDONTWRITEBYTECODE, which some
environments set (then every start compiles artibus's modules again, ~0.03 s
here); --as-is keeps the environment as it is.

usage: .venv/bin/python benchmarks/startup.py [--repeat N] [--profile] [--as-is]
"""
import argparse
import cProfile
import io
import os
import pstats
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARTIBUS = [str(Path(sys.executable).with_name("artibus"))]
BENCHES = ["Scania18m_Damping", "Urbino18_Circle", "MultiAxle_StepSteer", "Bus36m_Circle"]
TARGETS = {"artibus --version": 0.15, "artibus run Scania18m_Damping -o x.csv (cache warm)": 0.35}


BASE_ENV = dict(os.environ)


def command(args, env=None, cwd=None, argv=None):
    """(wall s, CPU s) of one process running `artibus ARGS` (or argv)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(argv or ARTIBUS + args, cwd=cwd, env={**BASE_ENV, **(env or {})},
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        raise SystemExit(f"artibus {' '.join(args)}: exit {r.returncode}: {r.stderr.strip()}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def timed(label, repeat, args, env=None, cwd=None, before_each=None, argv=None):
    walls, cpus = [], []
    for _ in range(repeat):
        if before_each is not None:
            env = {**(env or {}), **before_each()}
        w, c = command(args, env, cwd, argv)
        walls.append(w)
        cpus.append(c)
    target = TARGETS.get(label)
    verdict = "" if target is None else (f"  target <= {target:.2f} s: "
                                         + ("met" if min(walls) <= target else "MISSED"))
    print(f"  {label:58s} wall best {min(walls):6.3f} s  median {statistics.median(walls):6.3f} s"
          f"   CPU best {min(cpus):6.3f} s{verdict}")
    return min(walls)


def in_process(repeat):
    from artibus.runner import Simulation
    print(f"\nin-process, best of {repeat} (cache warm): set-up = Simulation(bench), run = Simulation.run")
    print(f"  {'bench':24s} {'set-up ms':>10s} {'run ms':>10s} {'total ms':>10s}")
    for bench in BENCHES:
        with Simulation(bench) as sim:       # warm: packed, unpacked, described
            sim.run()
        setups, runs, totals = [], [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            with Simulation(bench) as sim:
                t1 = time.perf_counter()
                sim.run()
                t2 = time.perf_counter()
            setups.append(t1 - t0)
            runs.append(t2 - t1)
            totals.append(t2 - t0)
        print(f"  {bench:24s} {1e3 * min(setups):10.1f} {1e3 * min(runs):10.1f} {1e3 * min(totals):10.1f}")


def profile(out_dir):
    from artibus.cli import main
    main(["run", "Scania18m_Damping", "-o", str(out_dir / "warm.csv")])    # warm and imported
    pr = cProfile.Profile()
    pr.enable()
    main(["run", "Scania18m_Damping", "-o", str(out_dir / "x.csv")])
    pr.disable()
    s = io.StringIO()
    pstats.Stats(pr, stream=s).sort_stats("cumulative").print_stats(25)
    print("\ncProfile of `artibus run Scania18m_Damping -o x.csv` in-process (imports done, cache warm):")
    print("\n".join(s.getvalue().splitlines()[:60]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--as-is", action="store_true", help="keep PYTHONDONTWRITEBYTECODE if set")
    args = ap.parse_args()
    if not args.as_is and BASE_ENV.pop("PYTHONDONTWRITEBYTECODE", None) is not None:
        print("(PYTHONDONTWRITEBYTECODE left out of the commands' environment: bytecode written and read)")
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} cores; "
          f"best and median of {args.repeat}")
    with tempfile.TemporaryDirectory(prefix="artibus-startup-") as tmp:
        tmp = Path(tmp)
        out = ["run", "Scania18m_Damping", "-o", str(tmp / "x.csv")]
        command(["--version"])
        command(out)                                  # packed, cached, byte-compiled
        print("\nas a command (a new process each time):")
        python = str(Path(sys.executable))
        timed("floor: python -c pass", args.repeat, [], argv=[python, "-c", "pass"])
        timed("floor: python -c 'import numpy, fmpy, lxml.etree'", args.repeat, [],
              argv=[python, "-c", "import numpy, fmpy, lxml.etree"])
        timed("artibus --version", args.repeat, ["--version"])
        timed("artibus run Scania18m_Damping -o x.csv (cache warm)", args.repeat, out, cwd=tmp)
        n = iter(range(10**6))

        def empty_cache():
            d = tmp / f"cache-{next(n)}"
            return {"ARTIBUS_CACHE": str(d)}
        timed("artibus run Scania18m_Damping -o x.csv (cache cold)", args.repeat, out, cwd=tmp,
              before_each=empty_cache)
        timed("artibus run Scania18m_Damping -o x.csv (no cache)", args.repeat, out, cwd=tmp,
              env={"ARTIBUS_CACHE_MB": "0"})
        shutil.rmtree(tmp / "cache-0", ignore_errors=True)
        in_process(args.repeat)
        if args.profile:
            profile(tmp)


if __name__ == "__main__":
    main()
