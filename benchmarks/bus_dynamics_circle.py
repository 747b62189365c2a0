"""Benchmark (prints, not a test): BusDynamics with the Bus36m parameter set,
60 s of a circle manoeuvre at a 10 ms communication step, the FMU alone driven
from Python (FMPy): seed 000's circle as in the Bus36m_Circle bench (tyreModel
1, the front axle at 0.40 rad: the outermost front corner on 17.5 m, A3..A6
straight), A2 pushing (without a drive the scrubbing trailers stop the bus
within seconds, and a standing bus is no benchmark). Prints the real-time
factor, the right-hand-side evaluations per simulated second and the speed at
the end, for three ways of driving it:

  held    ctypes fmi2DoStep only: the front axle at 0.40 rad and a constant
          drive force of 69 kN (what holds 3 m/s on this circle in
          equilibrium), set once: the integrator steps across communication
          points; the FMU's own cost. Open-loop the bus does not stay at
          3 m/s: it surges between ~3.8 and 6 m/s, its trailer axles sliding
          and gripping in turn (5.4 m/s at the end);
  raw     the steering turned in over the first 5 s and a PI speed governor
          holding 3 m/s, both sampled every 20 ms as the driver FMU does in
          the benches; fmi2SetReal and fmi2DoStep through ctypes directly, the
          inputs replayed from a run of the governor (the same trajectory,
          deterministic), outputs read at the end: the FMU's own cost plus
          the Python calls;
  fmpy    FMPy's wrappers, the governor closed in Python: getReal, setReal
          and doStep at every step, as a simple co-simulation master does.

Every changed input restarts the integrator (the FMI layer's rule; an
unchanged one does not): with BDF that is a new start at order 1, with the
explicit Runge-Kutta (solver 2) it goes on with its step size.

usage: .venv/bin/python benchmarks/bus_dynamics_circle.py [--solver 0|1|2] [--rtol R]
Target (issue 3): at least 5,000 times faster than real time.

The ctypes loops pass ctypes objects made before the clock starts (no
argtypes conversion at every call, as the bench runner does): a call from
Python then costs ~0.3-1 us instead of ~1.5 us. OpenBLAS's worker threads
(NumPy, SciPy) are kept from spinning on the second core.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse   # noqa: E402  (after the environment is set for NumPy)
import ctypes     # noqa: E402
import time       # noqa: E402

from artibus import fmu_path
from artibus.bench.parameters import read_parameters
from artibus.fmu import Fmu

STOP, H, SPEED, DELTA, FX_HELD = 60.0, 0.01, 3.0, 0.40, 69e3


def open_bus(solver, rtol):
    p = read_parameters("Bus36m", fmu_path("BusDynamics"))
    p.update(testSteerAmp=0.0, tyreModel=1, vx_start=SPEED, solver=solver)
    if rtol is not None:
        p.update(rtol=rtol, atol=rtol)
    return Fmu(fmu_path("BusDynamics")).initialize(p)


def governed(solver, rtol):
    """FMPy's wrappers, the governor closed in Python; returns the inputs it set."""
    with open_bus(solver, rtol) as fmu:
        vr_in = [fmu.var(n).valueReference for n in ("delta[1]", "Fx[2]")]
        vr_out = [fmu.var(n).valueReference for n in ("vx[1]", "nRhs")]
        integ, u, schedule = 0.0, [0.0, 0.0], []
        t0 = time.perf_counter()
        for i in range(int(round(STOP / H))):
            vx, _ = fmu.slave.getReal(vr_out)
            if i % 2 == 0:                         # a new sample every 20 ms
                integ += 5e4 * 2 * H * (SPEED - vx)
                u = [DELTA * min(1.0, i * H / 5.0), 1e5 * (SPEED - vx) + integ]
                fmu.slave.setReal(vr_in, u)
            schedule.append(list(u))
            fmu.slave.doStep(i * H, H)
        wall = time.perf_counter() - t0
        vx, nrhs = fmu.slave.getReal(vr_out)
    return wall, nrhs, vx, schedule


def raw_calls(fmu):
    """fmi2DoStep and fmi2SetReal from a handle of our own on the FMU's library
    (FMPy's function objects are left as they are), the component pointer,
    the step and the communication points as ctypes objects."""
    dll = ctypes.CDLL(fmu.slave.dll._name)
    comp = ctypes.c_void_p(fmu.slave.component)
    times = [ctypes.c_double(i * H) for i in range(int(round(STOP / H)))]
    return dll.fmi2DoStep, dll.fmi2SetReal, comp, times, ctypes.c_double(H), ctypes.c_int(1)


def held(solver, rtol):
    """ctypes fmi2DoStep only, the inputs set once."""
    with open_bus(solver, rtol) as fmu:
        fmu.set_values({"delta[1]": DELTA, "Fx[2]": FX_HELD})
        do_step, _, comp, times, h, true = raw_calls(fmu)
        t0 = time.perf_counter()
        for t in times:
            if do_step(comp, t, h, true) != 0:
                raise RuntimeError(f"failed at t = {t.value}: {fmu.log[-1:]}")
        wall = time.perf_counter() - t0
        vx, nrhs = fmu.get("vx[1]", "nRhs")
    return wall, nrhs, vx


def replayed(solver, rtol, schedule):
    """ctypes directly, the governor's inputs replayed."""
    with open_bus(solver, rtol) as fmu:
        do_step, set_real, comp, times, h, true = raw_calls(fmu)
        vrs = (ctypes.c_uint * 2)(*[fmu.var(n).valueReference for n in ("delta[1]", "Fx[2]")])
        n_vrs = ctypes.c_size_t(2)
        # the governor's samples as ready buffers; None where the input is unchanged
        bufs, last = [], None
        for u in schedule:
            bufs.append(None if u == last else (ctypes.c_double * 2)(*u))
            last = u
        t0 = time.perf_counter()
        for t, buf in zip(times, bufs):
            if (buf is not None and set_real(comp, vrs, n_vrs, buf) != 0) or do_step(comp, t, h, true) != 0:
                raise RuntimeError(f"failed at t = {t.value}: {fmu.log[-1:]}")
        wall = time.perf_counter() - t0
        vx, nrhs = fmu.get("vx[1]", "nRhs")
    return wall, nrhs, vx


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solver", type=int, default=0, help="0 BDF, 1 Adams, 2 explicit Runge-Kutta")
    ap.add_argument("--rtol", type=float, default=None, help="rtol = atol (default: the FMU's)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each; the best is printed")
    args = ap.parse_args()
    tol = args.rtol if args.rtol is not None else "default"
    name = ("BDF", "Adams", "ERK")[args.solver]
    runs = [governed(args.solver, args.rtol) for _ in range(args.repeat)]
    schedule = runs[0][3]
    for mode, results in (("held", [held(args.solver, args.rtol) for _ in range(args.repeat)]),
                          ("raw", [replayed(args.solver, args.rtol, schedule) for _ in range(args.repeat)]),
                          ("fmpy", [r[:3] for r in runs])):
        wall, nrhs, vx = min(results, key=lambda r: r[0])
        print(f"Bus36m circle, 60 s at 10 ms, {mode:4s}, solver {name}, rtol {tol}: best of {args.repeat} "
              f"{STOP / wall:6.0f} x real time ({wall:.3f} s wall), {nrhs / STOP:5.0f} RHS evaluations per "
              f"simulated second; vx[1] at the end {vx:.3f} m/s")


if __name__ == "__main__":
    main()
