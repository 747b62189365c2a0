"""Urbino18_Circle: seed 003 bus on seed 000's 17.5 m circle, kinematic model.
Its KPIs (a function of the result alone), figures and text (artibus.benches)."""
import math

import numpy as np

from artibus import report
from artibus.report import Kpi
from artibus.report.benchkit import DEG, circle_road, fit_radius
from artibus.study import kpi

Lh1, L1, L0, R = 1.789, 4.211, 5.9, 17.5

TEXT = ("The steady radii of the kinematic model satisfy R1^2 = R0^2 + Lh1^2 - L1^2 "
        "(exact for a single-axle wagon).")


def kpis(r):
    s = r["Driver.s"]
    arc = 2 * math.pi * R
    steady = (s > 25 + 0.6 * arc) & (s < 25 + arc - 5)
    R0 = fit_radius(r["Bus.x[0]"][steady], r["Bus.y[0]"][steady])
    R1 = fit_radius(r["Bus.x[1]"][steady], r["Bus.y[1]"][steady])
    r1_sq = R0 ** 2 + Lh1 ** 2 - L1 ** 2           # negative (or NaN) only from a run too short for the fit
    R1_kin = math.sqrt(r1_sq) if r1_sq >= 0 else math.nan
    on_circle = (s > 30) & (s < 25 + arc)
    return [
        Kpi("front axle: max |lateral error| on the circle", kpi.peak(r["Driver.eLat"][on_circle]), "m"),
        Kpi("rear axle P0: steady radius", R0, "m", f"sqrt(R^2 - L0^2) = {math.sqrt(R**2 - L0**2):.3f}",
            "geometry, front axle on R = 17.5 m"),
        Kpi("wagon axle P1: steady radius", R1, "m", f"sqrt(R0^2 + Lh1^2 - L1^2) = {R1_kin:.3f}",
            "seed 003 kinematics, steady state", abs(R1 - R1_kin) < 0.01, bound=(R1_kin - 0.01, R1_kin + 0.01),
            explain="A closed form of the kinematic model: a failure is a bug of BusKinematics, or a run too short "
                    "to reach the steady state on the circle (the fit uses 60 % to 100 % of the circle)."),
        Kpi("max |joint angle beta1|", kpi.peak(r["Bus.beta[1]"]) * DEG, "deg", "< 54 (mechanical limit)",
            "seed 003 Table I", kpi.peak(r["Bus.beta[1]"]) * DEG < 54, bound=54.0,
            explain="The joint's mechanical limit: beyond it the bus would jack-knife; on this circle it depends on "
                    "the radius (17.5 m) and the Urbino's geometry (Table I)."),
    ]


def figures(r, out):
    fx = r["Bus.x[0]"] + L0 * np.cos(r["Bus.theta[0]"])
    fy = r["Bus.y[0]"] + L0 * np.sin(r["Bus.theta[0]"])
    images = []
    report.birds_eye(out / "path.png", {"front axle": (fx, fy), "rear axle P0": (r["Bus.x[0]"], r["Bus.y[0]"]),
                                        "wagon axle P1": (r["Bus.x[1]"], r["Bus.y[1]"])},
                     road=circle_road(R), title="Urbino 18 on the 17.5 m circle, 3 m/s (kinematic)")
    images.append(("path.png", "Bird's-eye view: the road (grey) and the axle traces."))
    report.signals(out / "signals.png", r.time, [
        ("steering [deg]", {"gammaF (driver)": r["Driver.delta"] * DEG}),
        ("joint [deg]", {"beta1": r["Bus.beta[1]"] * DEG}),
        ("lateral error [m]", {"front axle eLat": r["Driver.eLat"]}),
    ], title="Urbino18_Circle", bounds=[(1, 54.0, "paper: < 54 deg, the joint's limit (seed 003, Table I)"),
                                        (1, -54.0, "paper: < 54 deg, the joint's limit (seed 003, Table I)")])
    images.append(("signals.png", "Steering, joint angle and the driver's lateral error over time."))
    return images
