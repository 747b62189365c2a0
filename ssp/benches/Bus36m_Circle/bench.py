"""Bus36m_Circle: seed 000's 17.5 m circle, 36 m bus, kinetic model, A3..A6
unsteered. Its KPIs (a function of the result alone), figures and text
(artibus.benches); the steered circle benches (Bus36m_Circle_Guided,
_GuidedAll, _GuidedForceMin, _CAN) use the functions here with their own
label, the paper's values and pass rule."""
import math

import numpy as np

from artibus import kpi, report
from artibus.benchkit import DEG, circle_road, outlines
from artibus.report import Kpi

#: this bench: what is steered, the paper's deviation and force, the force's pass rule
LABEL = "A3..A6 unsteered"
PAPER_DEV = "about 6 (unsteered)"
PAPER_F = "> 20 with wrong A3/A5 angles"
STEERED = False

TEXT = ("The paper gives no geometry or masses for its bus: ours are estimates from public "
        "data (ssp/parameters/Bus36m.ssv), so the figures differ. Speed 3 m/s (the paper gives none).")


def F_ok(F):
    return F > 20


def _axles(r):
    # traces every 5th sample (15 cm apart at 3 m/s: the chord error on the
    # circle is below 0.3 mm)
    return {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}


def circle_kpis(r, steered, paper_dev, paper_F, F_ok):
    """steered: the pass rule deviation < 1.0 m applies (None where unsteered)."""
    ax = _axles(r)
    d4 = kpi.trace_deviation(*ax[2], *ax[4])
    d6 = kpi.trace_deviation(*ax[2], *ax[6])
    # on the circle, entry and exit transients left out (the driver's progress
    # between 40 % and 90 % of the circle)
    arc = 2 * math.pi * 17.5
    s5 = r["Driver.s"][::5]
    on_circle = (s5 > 25 + 0.4 * arc) & (s5 < 25 + 0.9 * arc)
    steady = {}
    for a in (4, 6):
        dev, inside = kpi.lateral_distance(*ax[2], *ax[a])
        sel = inside & on_circle
        steady[a] = float(np.max(np.abs(dev[sel]))) if sel.any() else float("nan")
    # the hinge forces' peaks while the bus moves (kpi.peak_while_moving: |v| > 0.1 m/s)
    F1 = kpi.peak_while_moving(r["Bus.FjointY[1]"], r["Bus.v"]) / 1e3
    F2 = kpi.peak_while_moving(r["Bus.FjointY[2]"], r["Bus.v"]) / 1e3
    outl = outlines(r, 3)
    front = ((outl[:, 1, 0]), (outl[:, 1, 1]))   # the right front corner of the tractor
    swept = kpi.swept_path_width(front[0][::20], front[1][::20], outl[::20], bin_length=0.5, samples_per_edge=4)
    return [
        Kpi("max deviation of A4 from the A2 trace", d4, "m", paper_dev, "seed 000, Fig. 9",
            d4 < 1.0 if steered else None),
        Kpi("max deviation of A6 from the A2 trace", d6, "m", paper_dev, "seed 000, Fig. 9",
            d6 < 1.0 if steered else None),
        Kpi("deviation of A4 on the circle (transients left out)", steady[4], "m",
            paper_dev if steered else "", "seed 000, Fig. 9", steady[4] < 1.0 if steered else None),
        Kpi("deviation of A6 on the circle (transients left out)", steady[6], "m",
            paper_dev if steered else "", "seed 000, Fig. 9", steady[6] < 1.0 if steered else None),
        Kpi("max |lateral force| hinge 1", F1, "kN", paper_F, "seed 000, Fig. 10", F_ok(F1)),
        Kpi("max |lateral force| hinge 2", F2, "kN", "", ""),
        Kpi("swept path width", swept, "m", "", "outermost front point on 17.5 m"),
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
    ]


def circle_figures(r, out, label):
    ax = _axles(r)
    outl = outlines(r, 3)
    images = []
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outl,
                     road=circle_road(), every=300,
                     title=f"36 m bus, {label}, 17.5 m circle at 3 m/s")
    images.append(("path.png", "Bird's-eye view: road (grey, followed by the outermost front point), "
                               "body outlines every 3 s, axle traces."))
    dev4, in4 = kpi.lateral_distance(*ax[2], *ax[4])
    dev6, in6 = kpi.lateral_distance(*ax[2], *ax[6])
    s = r["Driver.s"]
    report.signals(out / "deviation.png", r.time[::5], [
        ("deviation from A2 trace [m]", {"A4": np.where(in4, np.abs(dev4), np.nan),
                                         "A6": np.where(in6, np.abs(dev6), np.nan)}),
        ("road progress [m]", {"s": s[::5]}),
    ], title="Deviation of A4 and A6 from the trace of A2 (seed 000, Fig. 9)")
    images.append(("deviation.png", "Lateral distance of A4 and A6 from the trace of A2."))
    report.signals(out / "forces.png", r.time, [
        ("hinge lateral force [kN]", {"hinge 1": r["Bus.FjointY[1]"] / 1e3, "hinge 2": r["Bus.FjointY[2]"] / 1e3}),
        ("articulation [deg]", {"hinge 1": r["Bus.artAngle[1]"] * DEG, "hinge 2": r["Bus.artAngle[2]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge 1": r["Bus.artRate[1]"] * DEG, "hinge 2": r["Bus.artRate[2]"] * DEG}),
        ("steering A1 [deg]", {"driver": r["Driver.delta"] * DEG}),
    ], title="Hinge forces (seed 000, Fig. 10), articulation, steering")
    images.append(("forces.png", "Lateral hinge forces in the front module's frame, articulation angles and rates, steering."))
    return images


def kpis(r):
    return circle_kpis(r, STEERED, PAPER_DEV, PAPER_F, F_ok)


def figures(r, out):
    return circle_figures(r, out, LABEL)
