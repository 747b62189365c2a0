"""BusDynamics as Model Exchange in FMPy's CVode (BDF, Newton with a dense linear solver), with
and without the FMU's Jacobian (issue 43): a benchmark, not a test.

    .venv/bin/python benchmarks/bus_dynamics_cvode_jacobian.py [--fmu fmus/BusDynamics.fmu] [--repeat 5]

FMPy 0.3.x does not use fmi2GetDirectionalDerivative: its CVodeSolver leaves CVODE's Jacobian to
CVODE's own difference quotients (one right-hand side per state and Jacobian), whatever the FMU
provides. "With the Jacobian" here is FMPy's CVodeSolver with CVodeSetJacFn set to a function
that fills the dense Jacobian d(der(x))/dx column by column from the FMU's
fmi2GetDirectionalDerivative (a unit seed per state, SUNDIALS' CVLsJacFn); all else is
fmpy.simulate_fmu(..., fmi_type='ModelExchange', solver='CVode') as is. Prints the wall time
(best of --repeat), CVODE's counts (steps, right-hand sides, Jacobians) and the largest
difference of the two results over every output, relative to the output's range.
"""
import argparse
import ctypes
import gc
import time
from pathlib import Path

import numpy as np
import fmpy.sundials
from fmpy import read_model_description, simulate_fmu
from fmpy.sundials import CVodeSolver
from fmpy.sundials.libraries import sundials_cvode, sundials_sunmatrixdense
from fmpy.sundials.nvector_serial import NV_DATA_S
from fmpy.sundials.sundials_nvector import N_Vector

ROOT = Path(__file__).resolve().parents[1]
START = {"testSteerAmp": 0.05, "testSteerPeriod": 4.0, "vx_start": 15.0}   # a lane change at 54 km/h
STOP, RTOL, INTERVAL = 20.0, 1e-6, 0.01

# int (*CVLsJacFn)(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *user, N_Vector tmp1..3)
CVLsJacFn = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, N_Vector, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
CVodeSetJacFn = sundials_cvode.CVodeSetJacFn
CVodeSetJacFn.argtypes, CVodeSetJacFn.restype = [ctypes.c_void_p, CVLsJacFn], ctypes.c_int
SUNDenseMatrix_Data = sundials_sunmatrixdense.SUNDenseMatrix_Data
SUNDenseMatrix_Data.argtypes, SUNDenseMatrix_Data.restype = [ctypes.c_void_p], ctypes.POINTER(ctypes.c_double)
COUNTS = ("CVodeGetNumSteps", "CVodeGetNumRhsEvals", "CVodeGetNumJacEvals", "CVodeGetNumLinRhsEvals")
for _name in COUNTS:
    getattr(sundials_cvode, _name).argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_long)]

STATS = {}


class Solver(CVodeSolver):
    """FMPy's CVodeSolver; with_jacobian: CVODE's Jacobian from the FMU's directional derivatives"""
    with_jacobian = False
    md = None

    def __init__(self, **kw):
        super().__init__(**kw)
        fmu = kw["get_nominals"].__self__
        ders = [d.variable.valueReference for d in self.md.derivatives]
        states = [d.variable.derivative.valueReference for d in self.md.derivatives]
        nx = len(states)

        def jac(t, y, fy, J, user, t1, t2, t3):
            try:
                fmu.setTime(t)
                fmu.setContinuousStates(NV_DATA_S(y), nx)
                data = SUNDenseMatrix_Data(J)               # column-major, leading dimension nx
                for j in range(nx):
                    col = fmu.getDirectionalDerivative(ders, [states[j]], [1.0])
                    for i in range(nx):
                        data[j * nx + i] = col[i]
                return 0
            except Exception as e:              # CVODE says the setup failed; say why
                print(f"Jacobian: {e!r}")
                return -1

        if self.with_jacobian:
            self.jac_ = CVLsJacFn(jac)
            assert CVodeSetJacFn(self.cvode_mem, self.jac_) == 0

    def __del__(self):
        for name in COUNTS:
            n = ctypes.c_long()
            getattr(sundials_cvode, name)(self.cvode_mem, ctypes.byref(n))
            STATS[name[len("CVodeGetNum"):]] = n.value
        super().__del__()


def run(fmu, with_jacobian):
    Solver.with_jacobian = with_jacobian
    fmpy.sundials.CVodeSolver = Solver             # simulate_fmu imports it from there
    t = time.perf_counter()
    res = simulate_fmu(str(fmu), fmi_type="ModelExchange", solver="CVode", start_values=START,
                       stop_time=STOP, relative_tolerance=RTOL, output_interval=INTERVAL)
    elapsed = time.perf_counter() - t
    gc.collect()                                    # the solver's counts (Solver.__del__)
    return res, elapsed, dict(STATS)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", type=Path, default=ROOT / "fmus" / "BusDynamics.fmu")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    Solver.md = read_model_description(str(args.fmu))
    out = {}
    for jac in (False, True, False, True):          # interleaved: the machine's load hits both alike
        for _ in range(args.repeat // 2 + 1):
            res, dt, stats = run(args.fmu, jac)
            best = out.get(jac)
            if best is None or dt < best[1]:
                out[jac] = (res, dt, stats)
    (r0, t0, s0), (r1, t1, s1) = out[False], out[True]
    names = [n for n in r0.dtype.names if n != "time"]
    diff = max(np.abs(r0[n] - r1[n]).max() / max(np.ptp(r0[n]), 1e-300) for n in names if np.ptp(r0[n]) > 0)
    print(f"BusDynamics ME, FMPy CVode (BDF), rtol {RTOL:g}, {STOP:g} s lane change, {len(r0)} rows")
    print(f"  without the Jacobian (CVODE's difference quotients): {t0 * 1e3:8.1f} ms  {s0}")
    print(f"  with the FMU's directional derivatives:               {t1 * 1e3:8.1f} ms  {s1}")
    print(f"  largest difference of the {len(names)} outputs: {diff:.2e} of the output's range")


if __name__ == "__main__":
    main()
