"""What each bench's report shows: its KPIs next to the papers' values, and
its plots. A bench without an entry here gets the generic report (every
recorded signal over time)."""
import math
from pathlib import Path

import numpy as np

from artibus import damping, kc, kpi, report
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
    "guided all": ("A3 steered like A4, A5 like A6 (Task 1 on every trailer axle)", "< 1.0 (steered)",
                   "> 20 with wrong A3/A5 angles", lambda F: F > 20),
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
        Kpi("deviation of A4 on the circle (transients left out)", steady[4], "m",
            paper_dev if variant != "unsteered" else "", "seed 000, Fig. 9",
            None if variant == "unsteered" else steady[4] < 1.0),
        Kpi("deviation of A6 on the circle (transients left out)", steady[6], "m",
            paper_dev if variant != "unsteered" else "", "seed 000, Fig. 9",
            None if variant == "unsteered" else steady[6] < 1.0),
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
    s_hold = 95.0                      # the bench's Driver.sHold: hands off after the lane change
    after = s > s_hold
    t_after = float(t[after][0]) if after.any() else None
    osc = kpi.oscillation(t, r["Bus.artAngle[1]"], t_from=t_after)
    y3 = r["Bus.yAxle[3]"]
    kpis = [
        Kpi("rear axle A3: initial overshoot beyond the 3.25 m offset", kpi.overshoot(y3[~after], 3.25), "m", "",
            "seed 001, initial overshoot"),
        Kpi("free articulation oscillation after the lane change: frequency", osc.frequency, "Hz",
            "0.7-1.0 at friction 1.0; the plant's rear-sway mode at rear friction 0.2: 0.39", "seed 001, ch. 4; issue 3"),
        Kpi("free articulation oscillation: damping ratio", osc.damping_ratio, "-",
            "the plant's rear-sway mode at rear friction 0.2, steering held: 0.069", "issue 3"),
        Kpi("max |articulation angle|", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation rate|", kpi.peak(r["Bus.artRate[1]"]) * DEG, "deg/s"),
        Kpi("front axle: max |lateral error| while driving", kpi.peak(r["Driver.eLat"][~after]), "m"),
    ]
    images = []
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in range(1, 4)}
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 4)}, outlines=_outlines(r, 2),
                     road=_lane_change_road(60, 3.25, after=350), every=25,
                     title="Scania 18 m, lane change 3.25 m / 60 m at 100 km/h, rear friction 0.2")
    images.append(("path.png", "Bird's-eye view (stretched: x and y at equal scale), outlines every 0.25 s."))
    report.signals(out / "signals.png", t, [
        ("lateral position [m]", {"A1": ax[1][1], "A3 (rear)": ax[3][1]}),
        ("articulation [deg]", {"hinge": r["Bus.artAngle[1]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge": r["Bus.artRate[1]"] * DEG}),
        ("steering [deg]", {"A1": r["Driver.delta"] * DEG}),
    ], title="Scania18m_LaneChange")
    images.append(("signals.png", "Lateral positions, articulation angle and rate, steering."))
    return kpis, images, ("The driver lets go of the wheel 10 m after the lane change (it then holds it "
                          "straight), so the articulation sways freely: that is the plant's rear-sway mode "
                          "(tests/test_bus_dynamics_vehicles.py computes it from a linear model). While the "
                          "driver keeps steering, the closed loop damps the sway much more (damping ratio about 0.2).")


# ---- issue 6: the steered 36 m bus's road tests -----------------------------------

def _slalom_road_module():
    """ssp/roads/slalom.py, which wrote the Bus36m_Slalom road (its geometry, one source)."""
    import importlib.util
    from artibus import ROOT
    spec = importlib.util.spec_from_file_location("artibus_slalom_road", ROOT / "ssp" / "roads" / "slalom.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _hinge_oscillation_kpis(r, t_after, what):
    kpis = []
    t = r.time
    for k in (1, 2):
        a = r[f"Bus.artAngle[{k}]"]
        osc = kpi.oscillation(t, a, t_from=t_after)
        settled = " (settles without oscillating: fewer than 3 extrema)" if osc.periods == 0 else ""
        kpis.append(Kpi(f"articulation hinge {k} after the {what}: damping ratio{settled}", osc.damping_ratio, "-",
                        "stable on dry and wet roads (decays)", "seed 000, sec. IV",
                        None if osc.periods == 0 else osc.damping_ratio > 0))
        kpis.append(Kpi(f"articulation hinge {k} after the {what}: frequency", osc.frequency, "Hz"))
        kpis.append(Kpi(f"max |articulation angle| hinge {k} after the {what}",
                        kpi.peak(a[t >= t_after]) * DEG, "deg"))
    return kpis


def _lateral_path(path, traces, road, cones, title):
    """Axle traces against x with y stretched (a bird's-eye view at equal scale
    would be a thin line for a 300 m long manoeuvre)."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 3.6))
    ax.plot(road[0], road[1], color="0.75", lw=6, solid_capstyle="round", label="road", zorder=0)
    for label, (x, y) in traces.items():
        ax.plot(x, y, lw=1.2, label=label)
    if cones is not None:
        ax.plot(cones, np.zeros_like(cones), "k^", ms=7, label="cones")
    x_all = np.concatenate([x for x, _ in traces.values()])
    ax.set_xlim(float(np.min(x_all)), float(np.max(x_all)))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _bus36m_road_test(r, out, title, road, t_after, what, extra, cones=None):
    t = r.time
    util = max(kpi.peak(r[f"Bus.Fy[{a}]"] / r[f"Bus.Fz[{a}]"]) for a in range(1, 7))
    kpis = [Kpi("front axle A1: max |lateral error| (driver)", kpi.peak(r["Driver.eLat"]), "m")] + extra + [
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
    ] + _hinge_oscillation_kpis(r, t_after, what) + [
        Kpi("max |lateral force| hinge 1", kpi.peak(r["Bus.FjointY[1]"]) / 1e3, "kN", "< 4 (17.5 m circle)",
            "seed 000, Fig. 10"),
        Kpi("max |lateral force| hinge 2", kpi.peak(r["Bus.FjointY[2]"]) / 1e3, "kN"),
        Kpi("max friction used by an axle, |Fy|/Fz", util, "-", "below the friction mu (1.0 dry, 0.5 wet)", ""),
        Kpi("max |lateral acceleration| (modules 1, 2, 3)",
            max(kpi.peak(r[f"Bus.ay[{m}]"]) for m in (1, 2, 3)), "m/s2"),
    ]
    images = []
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in (1, 2, 4, 6)}
    _lateral_path(out / "path.png", {f"A{a}": ax[a] for a in ax}, road, cones, title)
    images.append(("path.png", "Lateral position of the axles against x (y stretched): the road (grey, followed "
                               "by the front axle A1)" + (", the cones (black)." if cones is not None else ".")))
    report.signals(out / "signals.png", t, [
        ("lateral position [m]", {f"A{a}": ax[a][1] for a in (1, 2, 4, 6)}),
        ("articulation [deg]", {"hinge 1": r["Bus.artAngle[1]"] * DEG, "hinge 2": r["Bus.artAngle[2]"] * DEG}),
        ("steering [deg]", {"A1 (driver)": r["Driver.delta"] * DEG, "A3": r["ForceMin.gamma3"] * DEG,
                            "A4": r["Guidance.gamma4"] * DEG, "A5": r["ForceMin.gamma5"] * DEG,
                            "A6": r["Guidance.gamma6"] * DEG}),
        ("hinge lateral force [kN]", {"hinge 1": r["Bus.FjointY[1]"] / 1e3, "hinge 2": r["Bus.FjointY[2]"] / 1e3}),
        ("driver's lateral error [m]", {"A1": r["Driver.eLat"]}),
    ], title=title)
    images.append(("signals.png", f"Lateral positions, articulation, steering angles of the five steered axles, "
                                  f"hinge forces and the driver's error; the {what} ends for the front axle at "
                                  f"t = {t_after:.1f} s."))
    notes = ("Seed 000 reports only that lane change and slalom were stable on dry and wet roads; it gives no "
             "manoeuvre data. Friction is a parameter (tyreModel 1: cornering stiffness mu C, saturated at mu Fz); "
             "the default run is dry (mu = 1.0), the wet case sets Bus.mu[1..6] = 0.5. The damping ratio is that "
             "of the closed loop (driver, controllers and bus) from the articulation's successive extrema after the "
             "front axle has left the manoeuvre; n/a where it settles without oscillating.")
    return kpis, images, notes


def bus36m_lane_change(r, out):
    """the steered 36 m bus, lane change 3.5 m over 40 m at 50 km/h."""
    length, offset, lane, width = 40.0, 3.5, 3.5, 2.55
    t_after = float(r.time[r["Driver.s"] > 25 + length][0]) if (r["Driver.s"] > 25 + length).any() else r.time[-1]
    extra = [
        Kpi("front axle A1: lateral error allowed by the lane", (lane - width) / 2, "m",
            "(lane 3.5 m - body 2.55 m) / 2", "", kpi.peak(r["Driver.eLat"]) < (lane - width) / 2),
        Kpi("A4 overshoot beyond the 3.5 m offset", kpi.overshoot(r["Bus.yAxle[4]"], offset), "m"),
        Kpi("A6 overshoot beyond the 3.5 m offset", kpi.overshoot(r["Bus.yAxle[6]"], offset), "m"),
    ]
    return _bus36m_road_test(r, out, "Steered 36 m bus, lane change 3.5 m / 40 m at 50 km/h",
                             _lane_change_road(length, offset, after=250), t_after, "lane change", extra)


def bus36m_slalom(r, out):
    """the steered 36 m bus, slalom through 6 cones 30 m apart at 40 km/h."""
    from artibus import ROOT, roads
    sl = _slalom_road_module()
    road = roads.read_csv(ROOT / "ssp" / "roads" / "Bus36m_Slalom.csv")
    x1 = r["Bus.xAxle[1]"]
    t_after = float(r.time[x1 > sl.end_of_slalom()][0]) if (x1 > sl.end_of_slalom()).any() else r.time[-1]
    inside = (x1 >= sl.cones()[0]) & (x1 <= sl.cones()[-1])
    in6 = (r["Bus.xAxle[6]"] >= sl.cones()[0]) & (r["Bus.xAxle[6]"] <= sl.cones()[-1])
    amp1 = kpi.peak(r["Bus.yAxle[1]"][inside]) if inside.any() else float("nan")
    amp6 = kpi.peak(r["Bus.yAxle[6]"][in6]) if in6.any() else float("nan")
    extra = [
        Kpi("A1: max |lateral offset| between the cones", amp1, "m", f"road: {sl.AMPLITUDE:g}", ""),
        Kpi("A6: max |lateral offset| between the cones", amp6, "m"),
        Kpi("rearward amplification A6 / A1", amp6 / amp1, "-"),
    ]
    return _bus36m_road_test(r, out, f"Steered 36 m bus, slalom: {sl.CONES} cones {sl.SPACING:g} m apart "
                             f"(path +-{sl.AMPLITUDE:g} m) at 40 km/h", (road[0], road[1]), t_after, "slalom", extra,
                             cones=sl.cones())


def bus36m_circle_backwards(r, out):
    """seed 000's 17.5 m circle driven backwards: the A6 end leads."""
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}
    d3 = kpi.trace_deviation(*ax[5], *ax[3])
    d1 = kpi.trace_deviation(*ax[5], *ax[1])
    # lateral hinge forces in the frame of the module ahead in the direction of travel:
    # G2 in module 3's frame, G1 in module 2's (FjointX/Y[k] are in module k's frame)
    a2, a1 = r["Bus.artAngle[2]"], r["Bus.artAngle[1]"]
    F2 = kpi.peak(np.sin(a2) * r["Bus.FjointX[2]"] + np.cos(a2) * r["Bus.FjointY[2]"]) / 1e3
    F1 = kpi.peak(np.sin(a1) * r["Bus.FjointX[1]"] + np.cos(a1) * r["Bus.FjointY[1]"]) / 1e3
    outl = _outlines(r, 3)
    lead = (outl[:, 11, 0], outl[:, 11, 1])     # module 3's rear left corner: the leading right corner
    swept = kpi.swept_path_width(lead[0][::20], lead[1][::20], outl[::20], bin_length=0.5, samples_per_edge=4)
    kpis = [
        Kpi("max deviation of A3 from the A5 trace", d3, "m", "< 1.0 (steered); as A4 from A2 forwards",
            "seed 000, Fig. 9 and sec. IV", d3 < 1.0),
        Kpi("max deviation of A1 from the A5 trace", d1, "m", "< 1.0 (steered); as A6 from A2 forwards",
            "seed 000, Fig. 9 and sec. IV", d1 < 1.0),
        Kpi("max |lateral force| leading hinge G2 (module 3's frame)", F2, "kN", "< 4 (steered)",
            "seed 000, Fig. 10", F2 < 4),
        Kpi("max |lateral force| hinge G1 (module 2's frame)", F1, "kN"),
        Kpi("swept path width", swept, "m", "", "outermost leading point on 17.5 m"),
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
        Kpi("leading end A6: max |lateral error| (driver)", kpi.peak(r["Driver.eLat"]), "m"),
    ]
    images = []
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outl,
                     road=_circle_road(), every=300,
                     title="36 m bus driven backwards (A6 end leads), guidance + force minimisation, 3 m/s")
    images.append(("path.png", "Bird's-eye view: road (grey, followed by the outermost leading point), "
                               "body outlines every 3 s, axle traces."))
    dev3, in3 = kpi.lateral_distance(*ax[5], *ax[3])
    dev1, in1 = kpi.lateral_distance(*ax[5], *ax[1])
    report.signals(out / "deviation.png", r.time[::5], [
        ("deviation from A5 trace [m]", {"A3": np.where(in3, np.abs(dev3), np.nan),
                                         "A1": np.where(in1, np.abs(dev1), np.nan)}),
        ("road progress [m]", {"s": r["Driver.s"][::5]}),
    ], title="Deviation of A3 and A1 from the trace of A5 (backwards: the mirror of seed 000, Fig. 9)")
    images.append(("deviation.png", "Lateral distance of the trailing axles A3 and A1 from the trace of A5."))
    report.signals(out / "forces.png", r.time, [
        ("hinge lateral force [kN]", {"G2 (leading)": np.sin(a2) * r["Bus.FjointX[2]"] / 1e3
                                      + np.cos(a2) * r["Bus.FjointY[2]"] / 1e3,
                                      "G1": np.sin(a1) * r["Bus.FjointX[1]"] / 1e3
                                      + np.cos(a1) * r["Bus.FjointY[1]"] / 1e3}),
        ("articulation [deg]", {"hinge 1": a1 * DEG, "hinge 2": a2 * DEG}),
        ("steering [deg]", {"A6 (driver)": r["Driver.delta"] * DEG, "A3 (guided)": r["Guidance.gamma4"] * DEG,
                            "A1 (guided)": r["Guidance.gamma6"] * DEG, "A4 (force min.)": r["ForceMin.gamma3"] * DEG,
                            "A2 (force min.)": r["ForceMin.gamma5"] * DEG}),
        ("speed [m/s]", {"vx of module 3": r["Bus.vx[3]"]}),
    ], title="Backwards: hinge forces, articulation, steering, speed")
    images.append(("forces.png", "Lateral hinge forces in the frame of the module ahead in the direction of travel, "
                                 "articulation angles, the steering angles by role, speed (negative: backwards)."))
    return kpis, images, ("Seed 000: 'due to the symmetric vehicle structure the vehicle handling and the tracking "
                          "performance is independent of the driving direction'. The forwards figures are those of "
                          "Bus36m_Circle_GuidedForceMin (A4, A6 from the A2 trace; hinge 1 in module 1's frame); "
                          "tests/test_benches_roads.py compares the two within 10 %. A5 is driven (the mirror of A2).")


def multiaxle_step_steer(r, out):
    """seed 004, Figs. 3-4: step responses at several speeds and the frequency
    response, zero-side-slip steering (ZS) against front-axle steering (FWS),
    each a run of this bench (FWS: the plant ignores the tag axle's angle)."""
    from artibus import bode, runner
    speeds = (5.0, 10.0, 20.0, 30.0)
    delta1 = 0.02                       # the bench's step (Steering.testSteerAmp)

    def variant(u, zs):
        o = {"Vehicle.u": u, "Steering.u": u}
        if not zs:
            o["Vehicle.steerable[3]"] = False
        return o

    runs = {(u, zs): runner.run("MultiAxle_StepSteer", overrides=variant(u, zs)) for u in speeds for zs in (True, False)}
    kpis = []
    for u in speeds:
        for zs in (True, False):
            rr = runs[(u, zs)]
            name = "ZS" if zs else "FWS"
            kpis.append(Kpi(f"{name} at {u:g} m/s: side-slip after 10 s", rr["Vehicle.beta"][-1], "rad",
                            "0 (zero side-slip steering)" if zs else "", "seed 004, eq. 3",
                            abs(rr["Vehicle.beta"][-1]) < 1e-6 if zs else None))
            kpis.append(Kpi(f"{name} at {u:g} m/s: yaw-rate gain", rr["Vehicle.w_r"][-1] / delta1, "1/s"))
    t = runs[(20.0, True)].time
    panels = []
    for sig, label in (("Vehicle.w_r", "yaw rate [rad/s]"), ("Vehicle.a_y", "lateral acc. [m/s2]"),
                       ("Vehicle.beta", "side-slip [rad]")):
        series = {}
        for u in speeds:
            series[f"ZS {u:g} m/s"] = runs[(u, True)][sig]
            series[f"FWS {u:g} m/s"] = runs[(u, False)][sig]
        panels.append((label, series))
    report.signals(out / "step.png", t, panels, title="Front step steer 0.02 rad: ZS (K(u) delta1 on the tag axle) vs FWS")
    freqs = [0.1, 0.2, 0.5, 1.0, 2.0, 3.0]
    resp = {}
    for zs in (True, False):
        o = {**variant(20.0, zs), "Steering.testSteerAmp": 0.0}
        f = bode.frequency_response("MultiAxle_StepSteer", "Steering.delta1", ["Vehicle.w_r", "Vehicle.a_y"],
                                    freqs, 0.01, overrides=o)
        for k, v in f.items():
            resp[f"{'ZS' if zs else 'FWS'} {k.split('.')[-1]}"] = v
    bode.plot(out / "bode.png", resp, "Frequency response at 20 m/s, per rad of delta1 (sine tests through the co-simulation)")
    images = [("step.png", "Step responses at 5, 10, 20 and 30 m/s (seed 004, Fig. 3)."),
              ("bode.png", "Yaw rate and lateral acceleration per front steering angle at 20 m/s (seed 004, Fig. 4).")]
    return kpis, images, ("Vehicle data: ssp/parameters/Bus15mTagAxle.ssv (estimates: seed 004 gives none). "
                          "Zero-side-slip steering trades yaw-rate gain at speed for zero side-slip.")


REPORTS = {
    "Urbino18_Circle": urbino18_circle,
    "Bus36m_Circle": bus36m_circle,
    "Bus36m_Circle_Guided": lambda r, out: bus36m_circle(r, out, "guided"),
    "Bus36m_Circle_GuidedForceMin": lambda r, out: bus36m_circle(r, out, "guided+forcemin"),
    "Bus36m_Circle_CAN": lambda r, out: bus36m_circle_can(r, out),
    "Bus36m_Circle_GuidedAll": lambda r, out: bus36m_circle(r, out, "guided all"),
    "MultiAxle_StepSteer": multiaxle_step_steer,
    "Scania18m_LaneChange": scania18m_lane_change,
    "Bus36m_LaneChange": bus36m_lane_change,
    "Bus36m_Slalom": bus36m_slalom,
    "Bus36m_Circle_Backwards": bus36m_circle_backwards,
    "Scania18m_Damping": damping.report,
    "Scania18m_OpenLoop": kc.report,
}


def bus36m_circle_can(r, out):
    """seed 000's circle with the steering on CAN: the circle's KPIs, and what
    the receivers saw: each one's fallback state (0 normal, 1 holding, 2
    ramping, 3 straight) and each message's longest run without a good frame."""
    kpis, images, notes = bus36m_circle(r, out, "guided+forcemin")
    receivers = [n[:-len(".fallback")] for n in r.names if n.endswith(".fallback")]
    t = r.time
    for c in receivers:
        fb = r[f"{c}.fallback"]
        on = fb > 0
        kpis.append(Kpi(f"{c}: worst fallback state (0 normal, 1 holding, 2 ramping, 3 straight)",
                        float(np.max(fb)), "-", "0 without faults", "issue 12"))
        kpis.append(Kpi(f"{c}: time in fallback", float(np.sum(on)) * (t[1] - t[0]), "s"))
        kpis.append(Kpi(f"{c}: fallback entered at", float(t[np.argmax(on)]) if on.any() else math.nan, "s"))
    lost = [n for n in r.names if n.startswith("can.") and n.endswith(".sinceGood")]
    for n in lost:
        kpis.append(Kpi(f"{n[4:-len('.sinceGood')]}: longest run of cycles without a good frame",
                        float(np.max(r[n])), "cycles"))
    if receivers:
        report.signals(out / "fallback.png", t, [
            ("fallback state", {c: r[f"{c}.fallback"] for c in receivers}),
            ("cycles since a good frame", {n[4:-len(".sinceGood")]: r[n] for n in lost}),
        ], title="What the receivers saw: fallback states and stale messages")
        images.append(("fallback.png", "Each receiver's fallback state and each message's cycles since its "
                                       "last good frame (E2E check)."))
    return kpis, images, notes + " The steering signals travel over CAN (ssp/can/Bus36m.dbc); the bus summary " \
                                 "(load, response times, frames) is printed by the run and in can_bus.txt."


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
