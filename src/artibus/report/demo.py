"""``artibus demo``, the main job (for now): the Urbino 18 Electric (seed 003,
Table I) pushed at 3 m/s through an S-curve (25 deg left, 25 deg right,
straight), BusKinematics alone; its results, bird's-eye view and signals."""
import math

import numpy as np

from artibus.base import fmu_path
from artibus.bench.parameters import read_parameters
from artibus.fmu import simulate
from artibus.report.plots import birds_eye, signals
from artibus.runner import save


def s_curve(out, csv):
    """The S-curve run: its results saved as ``csv`` and its plots written into
    the folder ``out``. Returns (the plot's path, max |beta[1]| in rad)."""
    fmu = fmu_path("BusKinematics")
    params = read_parameters("Urbino18", fmu)
    params["testSteerAmp"] = 0.0
    amp, period = math.radians(25.0), 24.0

    def gammaF(t):
        return amp * math.sin(2 * math.pi * t / period) if t < period else 0.0

    result = simulate(fmu, parameters=params, inputs={"gammaF": gammaF, "v": lambda t: 3.0},
                      stop_time=40.0, step=0.05)
    png = out / "BusKinematics_Urbino18_SCurve.png"
    save(result, csv)
    theta0 = result["theta[0]"]
    front = (result["x[0]"] + params["L0"] * np.cos(theta0), result["y[0]"] + params["L0"] * np.sin(theta0))
    birds_eye(png, {"front axle": front, "tractor rear axle P0": (result["x[0]"], result["y[0]"]),
                    "wagon axle P1": (result["x[1]"], result["y[1]"])},
              title="Urbino 18 pusher, S-curve at 3 m/s (seed 003 model)")
    signals(out / "BusKinematics_Urbino18_SCurve_signals.png", result.time,
            [("steering gammaF [deg]", {"gammaF": np.degrees([gammaF(t) for t in result.time])}),
             ("joint angle [deg]", {"beta[1]": np.degrees(result["beta[1]"])})], title="S-curve")
    return png, max(abs(result["beta[1]"]))
