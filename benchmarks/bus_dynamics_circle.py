"""Benchmark (prints, not a test): BusDynamics with the Bus36m parameter set,
60 s of a circle manoeuvre at a 10 ms communication step, the FMU alone driven
from Python (FMPy). Prints the real-time factor and the right-hand-side
evaluations per simulated second, for three ways of driving it:

  raw     fmi2DoStep called through ctypes directly, inputs set once, outputs
          read at the end: the FMU's own cost plus one Python call a step;
  held    FMPy's wrappers, doStep and getReal at every step, inputs set once:
          CVODE continues its history across steps (and past them);
  ramp    as held, and the steering is set at every step, ramping into the
          circle over the first 5 s and held after it, as in a co-simulation:
          every changed value restarts the integrator (the FMI layer's rule;
          an unchanged value does not), which costs more while it changes.

usage: .venv/bin/python benchmarks/bus_dynamics_circle.py [--solver 0|1|2] [--rtol R]
Target (issue 3): at least 5,000 times faster than real time.
"""
import argparse
import ctypes
import time

from artibus import fmu_path
from artibus.parameters import read_parameters
from artibus.simulation import Fmu


def run(mode, solver, rtol=None, stop=60.0, h=0.01, speed=5.0, delta=0.1):
    p = read_parameters("Bus36m", fmu_path("BusDynamics"))
    p.update(testSteerAmp=0.0, vx_start=speed, solver=solver)
    if rtol is not None:
        p.update(rtol=rtol, atol=rtol)
    with Fmu(fmu_path("BusDynamics")) as fmu:
        fmu.slave.setupExperiment(startTime=0.0)
        fmu.slave.enterInitializationMode()
        fmu.set_values(p)
        fmu.set_values({"delta[1]": 0.0 if mode == "ramp" else delta})
        fmu.slave.exitInitializationMode()
        vr_delta = [fmu.var("delta[1]").valueReference]
        vr_out = [fmu.var(n).valueReference for n in ("x[1]", "y[1]", "FjointY[1]", "nRhs")]
        n = int(round(stop / h))
        if mode == "raw":
            do_step = fmu.slave.dll.fmi2DoStep
            do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
            do_step.restype = ctypes.c_int
            comp = fmu.slave.component
            t0 = time.perf_counter()
            for i in range(n):
                if do_step(comp, i * h, h, 1) != 0:
                    raise RuntimeError(f"fmi2DoStep failed at t = {i * h}: {fmu.log[-1:]}")
            wall = time.perf_counter() - t0
            out = fmu.slave.getReal(vr_out)
            return stop / wall, out[3] / stop, wall
        t0 = time.perf_counter()
        t = 0.0
        for i in range(n):
            if mode == "ramp":
                fmu.slave.setReal(vr_delta, [delta * min(1.0, t / 5.0)])
            fmu.slave.doStep(t, h)
            t = (i + 1) * h
            out = fmu.slave.getReal(vr_out)
        wall = time.perf_counter() - t0
    return stop / wall, out[3] / stop, wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solver", type=int, default=0, help="0 BDF, 1 Adams, 2 explicit Runge-Kutta")
    ap.add_argument("--rtol", type=float, default=None, help="rtol = atol (default: the FMU's)")
    args = ap.parse_args()
    tol = args.rtol if args.rtol is not None else "default"
    for mode in ("raw", "held", "ramp"):
        rtf, rhs, wall = run(mode, args.solver, args.rtol)
        print(f"Bus36m circle, 60 s at 10 ms, inputs {mode:4s}, solver {('BDF', 'Adams', 'ERK')[args.solver]}, "
              f"rtol {tol}: "
              f"{rtf:8.0f} x real time ({wall:.3f} s wall), {rhs:7.0f} RHS evaluations per simulated second")


if __name__ == "__main__":
    main()
