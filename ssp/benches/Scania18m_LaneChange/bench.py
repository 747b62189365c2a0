"""Scania18m_LaneChange: seed 001's lane change, 60 m at 100 km/h, rear
friction 0.2. Its KPIs (a function of the result alone), figures and text
(artibus.benches)."""
from artibus import report
from artibus.report import Kpi
from artibus.report.benchkit import DEG, lane_change_road, outlines
from artibus.study import kpi

S_HOLD = 95.0                      # the bench's Driver.sHold: hands off after the lane change

TEXT = ("The driver lets go of the wheel 10 m after the lane change (it then holds it "
        "straight), so the articulation sways freely: that is the plant's rear-sway mode "
        "(tests/test_bus_dynamics_vehicles.py computes it from a linear model). While the "
        "driver keeps steering, the closed loop damps the sway much more (damping ratio about 0.2).")


def kpis(r):
    t = r.time
    after = r["Driver.s"] > S_HOLD
    t_after = float(t[after][0]) if after.any() else None
    osc = kpi.oscillation(t, r["Bus.artAngle[1]"], t_from=t_after)
    y3 = r["Bus.yAxle[3]"]
    return [
        Kpi("rear axle A3: initial overshoot beyond the 3.25 m offset", kpi.overshoot(y3[~after], 3.25), "m", "",
            "seed 001, initial overshoot"),
        Kpi("free articulation oscillation after the lane change: frequency", osc.frequency, "Hz",
            "0.7-1.0 at friction 1.0 (here rear friction 0.2: the plant's linear rear-sway mode is at 0.39)",
            "seed 001, 4.4.2 (Fig. 4.10)", ungraded="the thesis's figure is at friction 1.0; here rear friction 0.2"),
        Kpi("free articulation oscillation: damping ratio", osc.damping_ratio, "-",
            "not given", "ours: the plant's linear rear-sway mode at rear friction 0.2, steering held, 0.069 "
            "(tests/test_bus_dynamics_vehicles.py)"),
        Kpi("max |articulation angle|", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation rate|", kpi.peak(r["Bus.artRate[1]"]) * DEG, "deg/s"),
        Kpi("front axle: max |lateral error| while driving", kpi.peak(r["Driver.eLat"][~after]), "m"),
    ]


def figures(r, out):
    t = r.time
    images = []
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in range(1, 4)}
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 4)}, outlines=outlines(r, 2),
                     road=lane_change_road(60, 3.25, after=350), every=25,
                     title="Scania 18 m, lane change 3.25 m / 60 m at 100 km/h, rear friction 0.2")
    images.append(("path.png", "Bird's-eye view (stretched: x and y at equal scale), outlines every 0.25 s."))
    report.signals(out / "signals.png", t, [
        ("lateral position [m]", {"A1": ax[1][1], "A3 (rear)": ax[3][1]}),
        ("articulation [deg]", {"hinge": r["Bus.artAngle[1]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge": r["Bus.artRate[1]"] * DEG}),
        ("steering [deg]", {"A1": r["Driver.delta"] * DEG}),
    ], title="Scania18m_LaneChange")
    images.append(("signals.png", "Lateral positions, articulation angle and rate, steering."))
    return images
