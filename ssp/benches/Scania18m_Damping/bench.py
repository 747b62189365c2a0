"""Scania18m_Damping: seed 001's articulation damping study (artibus.damping).
The KPIs of one run (a function of the result alone: its driving case, one of
the variants lc25_50, lc60_100, lc200_100, lc60_130, is told by the run's
speed and where the front axle crosses half the lane offset); the report is a
study: every damping function side by side as the thesis's Figs. 5.9-5.21
(artibus.benches)."""
import math

import numpy as np

from artibus.report import Kpi
from artibus.study import damping


def case_of(r):
    """The driving case nearest to the run's initial speed and the lane change's length."""
    v_kmh = float(r["Bus.vx[1]"][0]) * 3.6
    y, x = r["Bus.yAxle[1]"], r["Bus.xAxle[1]"]
    half = y > damping.OFFSET / 2
    length = 2 * (float(x[np.argmax(half)]) - damping.ROAD_BEFORE) if half.any() else math.inf
    return min(damping.CASES, key=lambda c: (abs(damping.CASES[c].speed_kmh - v_kmh) / 10
                                             + abs(damping.CASES[c].length - length) / 20))


def kpis(r):
    case = case_of(r)
    k = damping.kpis(r, case)
    src = "seed 001, 5.2.4 (the thesis's (4)-(6))"
    return [
        Kpi("rear axle overshoot beyond the 3.25 m offset after the lane change", k.overshoot, "m", "", src),
        Kpi("max |articulation angle| after the lane change", k.peak_angle, "deg", "", src),
        Kpi("max |articulation rate| after the lane change", k.peak_rate, "deg/s", "", src),
        Kpi(f"oscillations above {damping.OSCILLATION_DEG:g} deg after the lane change", k.oscillations, "-"),
        Kpi(f"settling below {damping.SETTLED_DEG:g} deg after the lane change (no thesis claim)", k.settling, "s"),
        Kpi("max damping request", k.peak_pct, "%", "within 3.5-34", "seed 001, 5.1.1",
            (3.5 - 1e-9 <= k.min_pct and k.peak_pct <= 34 + 1e-9) if k.peak_pct > 0 else None, bound=34.0,
            ungraded="" if k.peak_pct > 0 else "no damping (variant none): the damper is off, the bound is a "
                                               "damping function's",
            explain="The floor (pctFloor 3.5 %) and the cap (pctMax 34 %) bound every request of the controller "
                    "and the baseline by construction: a value outside them is a bug."),
        Kpi("min damping request", k.min_pct, "%"),
        Kpi("energy the damper took out", k.energy / 1e3, "kJ"),
    ]


def figures(r, out):
    from artibus import report
    DEG = damping.DEG
    report.signals(out / "signals.png", r.time, [
        ("articulation [deg]", {"hinge": r["Bus.artAngle[1]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge": r["Bus.artRate[1]"] * DEG}),
        ("damping request [%]", {"pct": r["Controller.pct"]}),
    ], title="Scania18m_Damping, this run", bounds=[(2, 34.0, "pctMax 34 % (seed 001, 5.1.1)"),
                                                    (2, 3.5, "floor 3.5 % (seed 001, 5.1.1)")])
    return [("signals.png", "Articulation angle and rate, damping request of this run.")]


def study(r, out):
    return damping.report(r, out)
