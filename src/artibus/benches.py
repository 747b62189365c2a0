"""What each bench's report shows: its KPIs next to the papers' values, and
its plots. A bench without an entry here gets the generic report (every
recorded signal over time)."""
import math
from pathlib import Path

import numpy as np

from artibus import kpi, report
from artibus.report import Kpi

DEG = 180 / math.pi


def _circle_road(R=17.5, before=25.0, after=50.0):
    from artibus import roads
    x, y = roads.generate(roads.CIRCLE, R=R, before=before, after=after)
    return x, y


def _lane_change_road(length, offset, before=25.0, after=50.0):
    from artibus import roads
    x, y = roads.generate(roads.LANE_CHANGE, laneLength=length, laneOffset=offset, before=before, after=after)
    return x, y


def _fit_radius(x, y):
    A = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    (cx, cy, c), *_ = np.linalg.lstsq(A, x ** 2 + y ** 2, rcond=None)
    return math.sqrt(c + cx ** 2 + cy ** 2)


def _outlines(r, n_modules):
    cols = []
    for c in range(1, 4 * n_modules + 1):
        cols.append(np.column_stack([r[f"Bus.xCorner[{c}]"], r[f"Bus.yCorner[{c}]"]]))
    return np.stack(cols, axis=1)


def urbino18_circle(r, out):
    """seed 003 bus on seed 000's 17.5 m circle, kinematic model."""
    Lh1, L1, L0, R = 1.789, 4.211, 5.9, 17.5
    s = r["Driver.s"]
    arc = 2 * math.pi * R
    steady = (s > 25 + 0.6 * arc) & (s < 25 + arc - 5)
    R0 = _fit_radius(r["Bus.x[0]"][steady], r["Bus.y[0]"][steady])
    R1 = _fit_radius(r["Bus.x[1]"][steady], r["Bus.y[1]"][steady])
    R1_kin = math.sqrt(R0 ** 2 + Lh1 ** 2 - L1 ** 2)
    on_circle = (s > 30) & (s < 25 + arc)
    kpis = [
        Kpi("front axle: max |lateral error| on the circle", kpi.peak(r["Driver.eLat"][on_circle]), "m"),
        Kpi("rear axle P0: steady radius", R0, "m", f"sqrt(R^2 - L0^2) = {math.sqrt(R**2 - L0**2):.3f}",
            "geometry, front axle on R = 17.5 m"),
        Kpi("wagon axle P1: steady radius", R1, "m", f"sqrt(R0^2 + Lh1^2 - L1^2) = {R1_kin:.3f}",
            "seed 003 kinematics, steady state", abs(R1 - R1_kin) < 0.01),
        Kpi("max |joint angle beta1|", kpi.peak(r["Bus.beta[1]"]) * DEG, "deg", "< 54 (mechanical limit)",
            "seed 003 Table I", kpi.peak(r["Bus.beta[1]"]) * DEG < 54),
    ]
    fx = r["Bus.x[0]"] + L0 * np.cos(r["Bus.theta[0]"])
    fy = r["Bus.y[0]"] + L0 * np.sin(r["Bus.theta[0]"])
    images = []
    report.birds_eye(out / "path.png", {"front axle": (fx, fy), "rear axle P0": (r["Bus.x[0]"], r["Bus.y[0]"]),
                                        "wagon axle P1": (r["Bus.x[1]"], r["Bus.y[1]"])},
                     road=_circle_road(R), title="Urbino 18 on the 17.5 m circle, 3 m/s (kinematic)")
    images.append(("path.png", "Bird's-eye view: the road (grey) and the axle traces."))
    report.signals(out / "signals.png", r.time, [
        ("steering [deg]", {"gammaF (driver)": r["Driver.delta"] * DEG}),
        ("joint [deg]", {"beta1": r["Bus.beta[1]"] * DEG}),
        ("lateral error [m]", {"front axle eLat": r["Driver.eLat"]}),
    ], title="Urbino18_Circle")
    images.append(("signals.png", "Steering, joint angle and the driver's lateral error over time."))
    return kpis, images, ("The steady radii of the kinematic model satisfy R1^2 = R0^2 + Lh1^2 - L1^2 "
                          "(exact for a single-axle wagon).")


VARIANTS = {
    "unsteered": ("A3..A6 unsteered", "about 6 (unsteered)", "> 20 with wrong A3/A5 angles", None),
    "guided": ("A4, A6 guided (Task 1), A3, A5 straight", "< 1.0 (steered)", "> 20 with wrong A3/A5 angles",
               lambda F: F > 20),
    "guided+forcemin": ("A4, A6 guided (Task 1), A3, A5 force-minimising (Task 2)", "< 1.0 (steered)",
                        "< 4 (steered)", lambda F: F < 4),
}


def bus36m_circle(r, out, variant="unsteered"):
    """seed 000's 17.5 m circle, 36 m bus, kinetic model."""
    label, paper_dev, paper_F, F_ok = VARIANTS[variant]
    # traces every 5th sample (15 cm apart at 3 m/s: the chord error on the
    # circle is below 0.3 mm)
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}
    d4 = kpi.trace_deviation(*ax[2], *ax[4])
    d6 = kpi.trace_deviation(*ax[2], *ax[6])
    F1 = kpi.peak(r["Bus.FjointY[1]"]) / 1e3
    F2 = kpi.peak(r["Bus.FjointY[2]"]) / 1e3
    outl = _outlines(r, 3)
    front = ((outl[:, 1, 0]), (outl[:, 1, 1]))   # the right front corner of the tractor
    swept = kpi.swept_path_width(front[0][::20], front[1][::20], outl[::20], bin_length=0.5, samples_per_edge=4)
    kpis = [
        Kpi("max deviation of A4 from the A2 trace", d4, "m", paper_dev, "seed 000, Fig. 9",
            None if variant == "unsteered" else d4 < 1.0),
        Kpi("max deviation of A6 from the A2 trace", d6, "m", paper_dev, "seed 000, Fig. 9",
            None if variant == "unsteered" else d6 < 1.0),
        Kpi("max |lateral force| hinge 1", F1, "kN", paper_F, "seed 000, Fig. 10", F_ok(F1) if F_ok else F1 > 20),
        Kpi("max |lateral force| hinge 2", F2, "kN", "", ""),
        Kpi("swept path width", swept, "m", "", "outermost front point on 17.5 m"),
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
    ]
    images = []
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outl,
                     road=_circle_road(), every=300,
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
    return kpis, images, ("The paper gives no geometry or masses for its bus: ours are estimates from public "
                          "data (ssp/parameters/Bus36m.ssv), so the figures differ. Speed 3 m/s (the paper gives none).")


def scania18m_lane_change(r, out):
    """seed 001's lane change, 60 m at 100 km/h, rear friction 0.2."""
    t = r.time
    s = r["Driver.s"]
    after = s > 25 + 60
    t_after = float(t[after][0]) if after.any() else None
    osc = kpi.oscillation(t, r["Bus.artAngle[1]"], t_from=t_after)
    y3 = r["Bus.yAxle[3]"]
    kpis = [
        Kpi("rear axle A3: overshoot beyond the 3.25 m offset", kpi.overshoot(y3, 3.25), "m", "", "seed 001, initial overshoot"),
        Kpi("articulation oscillation after the lane change: frequency", osc.frequency, "Hz",
            "0.7-1.0 at friction 1.0; plant's rear-sway mode at rear friction 0.2: 0.39 (issue 3)", "seed 001, ch. 4"),
        Kpi("articulation oscillation: damping ratio", osc.damping_ratio, "-",
            "plant's mode, steering held: 0.07 (issue 3)", ""),
        Kpi("max |articulation angle|", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation rate|", kpi.peak(r["Bus.artRate[1]"]) * DEG, "deg/s"),
        Kpi("front axle: max |lateral error|", kpi.peak(r["Driver.eLat"]), "m"),
    ]
    images = []
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in range(1, 4)}
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 4)}, outlines=_outlines(r, 2),
                     road=_lane_change_road(60, 3.25, after=300), every=25,
                     title="Scania 18 m, lane change 3.25 m / 60 m at 100 km/h, rear friction 0.2")
    images.append(("path.png", "Bird's-eye view (stretched: x and y at equal scale), outlines every 0.25 s."))
    report.signals(out / "signals.png", t, [
        ("lateral position [m]", {"A1": ax[1][1], "A3 (rear)": ax[3][1]}),
        ("articulation [deg]", {"hinge": r["Bus.artAngle[1]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge": r["Bus.artRate[1]"] * DEG}),
        ("steering [deg]", {"A1": r["Driver.delta"] * DEG}),
    ], title="Scania18m_LaneChange")
    images.append(("signals.png", "Lateral positions, articulation angle and rate, steering."))
    return kpis, images, ("The driver keeps steering after the lane change, so the articulation oscillation "
                          "seen here is that of the closed loop (bus and driver); the plant's own mode (steering "
                          "held) is computed in tests/test_bus_dynamics_vehicles.py.")


REPORTS = {
    "Urbino18_Circle": urbino18_circle,
    "Bus36m_Circle": bus36m_circle,
    "Bus36m_Circle_Guided": lambda r, out: bus36m_circle(r, out, "guided"),
    "Bus36m_Circle_GuidedForceMin": lambda r, out: bus36m_circle(r, out, "guided+forcemin"),
    "Scania18m_LaneChange": scania18m_lane_change,
}


def generic(r, out):
    series = {n: r[n] for n in r.names[1:]}
    panels = [(n, {n: v}) for n, v in list(series.items())[:8]]
    report.signals(out / "signals.png", r.time, panels, title="recorded signals")
    return [], [("signals.png", "The first recorded signals over time.")], ""


def write_report(bench, result, out_dir, wall=None):
    """PNGs and index.html for one bench run; returns the KPIs."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    kpis, images, notes = REPORTS.get(bench, generic)(result, out)
    span = result.time[-1] - result.time[0]
    intro = f"Bench {bench}: {span:g} s simulated" + (f" in {wall:.2f} s." if wall else ".")
    report.write_html(out, bench, intro, kpis, [(out / i, c) for i, c in images], notes)
    return kpis
