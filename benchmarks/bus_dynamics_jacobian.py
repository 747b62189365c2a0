"""What one Jacobian of BusDynamics (FMI 2.0, Model Exchange) costs the two ways CVODE can get it:
a benchmark, not a test (issue 43).

    .venv/bin/python benchmarks/bus_dynamics_jacobian.py [--fmu fmus/BusDynamics.fmu] [--jacobians N]

benchmarks/jacobian_timer.c (compiled with cc when this runs: no Python between the calls) times
CVODE's difference quotients (per state a right-hand side: fmi2SetContinuousStates and
fmi2GetDerivatives) against the FMU's directional derivatives (per state one
fmi2GetDirectionalDerivative with the unit seed, as artibus' ME facade asks them: me.c, jac), each
Jacobian at a new point, at the FMU's start values (an 18 m articulated bus: two modules); the
fastest block of Jacobians counts. BusDynamics answers the first column at a point with one
forward pass on vector dual numbers for all of them (dyn_eval_jacobian) and the others from it.
"""
import argparse
import shutil
import subprocess
import tempfile
from pathlib import Path

from fmpy import extract, read_model_description

ROOT = Path(__file__).resolve().parents[1]


def jacobian_ns(fmu, jacobians=20000):
    """(ns per Jacobian by difference quotients, ns per Jacobian by directional derivatives, states)"""
    md = read_model_description(str(fmu))
    work = Path(tempfile.mkdtemp(prefix="jacbench-"))
    try:
        exe = work / "jacobian_timer"
        subprocess.run(["cc", "-O2", "-std=gnu11", f"-I{ROOT / 'include/fmi2'}",
                        str(ROOT / "benchmarks/jacobian_timer.c"), "-o", str(exe), "-ldl"], check=True)
        unzip = Path(extract(str(fmu), str(work / "fmu")))
        binary = unzip / "binaries/linux64" / f"{md.modelExchange.modelIdentifier}.so"
        xs = ",".join(str(d.variable.derivative.valueReference) for d in md.derivatives)
        dxs = ",".join(str(d.variable.valueReference) for d in md.derivatives)
        out = subprocess.run([str(exe), str(binary), md.guid, (unzip / "resources").as_uri(), str(jacobians),
                              xs, dxs], capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"{fmu}: {out.stderr.strip()}")
        dq, dd, nx = out.stdout.split()
        return float(dq), float(dd), int(nx)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmus" / "BusDynamics.fmu"))
    ap.add_argument("--jacobians", type=int, default=20000)
    args = ap.parse_args()
    dq, dd, nx = jacobian_ns(args.fmu, args.jacobians)
    print(f"BusDynamics ME, one Jacobian of its {nx} states (the fastest block of 200):")
    print(f"  by difference quotients ({nx} right-hand sides):      {dq / 1e3:7.2f} us")
    print(f"  by its directional derivatives ({nx} calls):          {dd / 1e3:7.2f} us  ({dd / dq:.2f} x)")


if __name__ == "__main__":
    main()
