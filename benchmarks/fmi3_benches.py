"""Benchmark (prints, not a test): the real-time factor of every bench with the FMI 2.0
builds of its FMUs (fmus/<Bench>.ssp) and with their FMI 3.0 builds (fmus/fmi3/<Bench>.ssp,
`artibus run BENCH --fmi 3`), issue 23.

Each bench runs REPEAT times per build, FMI 2.0 and 3.0 in turn (a busy moment of the
shared machine hits both), in one process (the packs and the FMUs' unpacked copies made
before the first timed run); the wall time is Simulation.wall (initialisation and stepping,
not the set-up), the stepping as Simulation.stepping says (the one loop, the C core; with
--python a bench's network ticked in Python, run(core=False)). Printed: the simulated span, the median real-time factor
of each build (span / wall), the best, and FMI 3.0's median wall over FMI 2.0's; the
machine's load average before and after (the figures are this machine's at that load).

usage: .venv/bin/python benchmarks/fmi3_benches.py [--repeat R] [--python] [BENCH...]
"""
import argparse
import os
import statistics

from artibus import runner
from artibus.bench import ssp


def timed(bench, fmi, core):
    """(wall s, span s, stepping) of one run of the bench's default experiment"""
    with runner.Simulation(bench, fmi=fmi) as sim:
        r = sim.run(core=core)
        return sim.wall, r.time[-1] - r.time[0], sim.stepping


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--python", action="store_true",
                    help="the networks ticked in Python (run(core=False)), not in C")
    ap.add_argument("benches", nargs="*")
    a = ap.parse_args(argv)
    core = False if a.python else None
    benches = a.benches or ssp.bench_names()
    load0 = os.getloadavg()
    print(f"load average before: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f} ({os.cpu_count()} cores)")
    print(f"{'bench':28s} {'span s':>7s} {'RTF FMI 2':>10s} {'RTF FMI 3':>10s} {'best 2':>8s} {'best 3':>8s} "
          f"{'wall 3/2':>8s}  stepping")
    for bench in benches:
        for fmi in ("2", "3"):               # packed and unpacked once, untimed
            timed(bench, fmi, core)
        walls = {"2": [], "3": []}
        for _ in range(a.repeat):
            for fmi in ("2", "3"):
                w, span, stepping = timed(bench, fmi, core)
                walls[fmi].append(w)
        m2, m3 = statistics.median(walls["2"]), statistics.median(walls["3"])
        print(f"{bench:28s} {span:7.1f} {span / m2:10.0f} {span / m3:10.0f} {span / min(walls['2']):8.0f} "
              f"{span / min(walls['3']):8.0f} {m3 / m2:8.3f}  {stepping}")
    load1 = os.getloadavg()
    print(f"load average after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")


if __name__ == "__main__":
    main()
