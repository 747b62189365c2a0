"""Benchmark (prints, not a test): microseconds per fmi3DoStep against fmi2DoStep for every
FMU, the FMI 3.0 build (fmus/fmi3/<Name>.fmu) against the FMI 2.0 one (fmus/<Name>.fmu):
the same model code on the two layers (src/fmi/fmi2Functions.c, fmi3Functions.c over
fmu_core.c).

Each FMU's binary is loaded by a small C program (benchmarks/dostep_timer.c, compiled with
cc when this runs: no Python between the calls), instantiated, initialised at its start
values, then stepped with its default experiment's step size STEPS times, timed around the
loop; REPEAT fresh processes per version, FMI 2.0 and 3.0 in turn (so a busy moment of the
machine hits both); the fastest (best) of the repeats is printed with the ratio FMI 3.0 /
FMI 2.0 (target of issue 23: within 5 %), beside the medians' ratio: the best is the FMU's
own cost, what the other processes of a busy machine add shows in the median. The inputs stay at their start values: each FMU's own
cost per step with nothing changing.

usage: .venv/bin/python benchmarks/fmi3_dostep.py [--steps N] [--repeat R] [NAME...]
"""
import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from fmpy import extract, read_model_description

from artibus import fmu_dir

ROOT = Path(__file__).resolve().parents[1]


def _timer():
    """benchmarks/dostep_timer.c compiled once per run (cc, the repository's FMI headers)"""
    exe = Path(tempfile.mkdtemp(prefix="fmi3bench-")) / "dostep_timer"
    subprocess.run(["cc", "-O2", "-std=gnu11", f"-I{ROOT / 'include/fmi2'}", f"-I{ROOT / 'include/fmi3'}",
                    str(ROOT / "benchmarks/dostep_timer.c"), "-o", str(exe), "-ldl"], check=True)
    return exe


def per_step_us(timer, path, version, steps):
    """one instance, initialised at its start values, stepped `steps` times with its default
    experiment's step size by the C timer: microseconds per step"""
    md = read_model_description(str(path))
    h = float((md.defaultExperiment and md.defaultExperiment.stepSize) or 0.01)
    unzip = Path(extract(str(path), tempfile.mkdtemp(prefix="fmi3bench-")))
    try:
        ident = md.coSimulation.modelIdentifier
        if version == 2:
            binary, token = unzip / "binaries/linux64" / f"{ident}.so", md.guid
            resources = (unzip / "resources").as_uri()
        else:
            binary, token = unzip / "binaries/x86_64-linux" / f"{ident}.so", md.instantiationToken
            resources = str(unzip / "resources") + "/"
        out = subprocess.run([str(timer), str(version), str(binary), token, resources, repr(h), str(steps)],
                             capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"{path}: {out.stderr.strip()}")
        return float(out.stdout) / steps / 1e3
    finally:
        shutil.rmtree(unzip, ignore_errors=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=20000, help="a multiple of 1000")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("names", nargs="*")
    a = ap.parse_args(argv)
    # the FMUs built in both versions (CanBus and the LS-BUS nodes are FMI 3.0 only: nothing to compare)
    names = a.names or sorted(p.stem for p in (fmu_dir() / "fmi3").glob("*.fmu")
                              if (fmu_dir() / p.name).exists())
    if not names:
        sys.exit(f"no FMI 3.0 FMUs in {fmu_dir() / 'fmi3'}: build them first")
    timer = _timer()
    print(f"{'FMU':22s} {'fmi2DoStep us':>14s} {'fmi3DoStep us':>14s} {'3/2 best':>9s} {'3/2 median':>11s}")
    for name in names:
        t2, t3 = [], []
        for _ in range(a.repeat):      # interleaved, so a slow moment hits both
            t2.append(per_step_us(timer, fmu_dir() / f"{name}.fmu", 2, a.steps))
            t3.append(per_step_us(timer, fmu_dir() / "fmi3" / f"{name}.fmu", 3, a.steps))
        b2, b3 = min(t2), min(t3)
        m2, m3 = statistics.median(t2), statistics.median(t3)
        print(f"{name:22s} {b2:14.3f} {b3:14.3f} {b3 / b2:9.3f} {m3 / m2:11.3f}")


if __name__ == "__main__":
    main()
