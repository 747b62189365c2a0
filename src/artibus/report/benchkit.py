"""What several benches' KPIs and figures share (roads, outlines, the steered
36 m bus's road tests). A bench's own KPIs, figures and text are in its folder,
``ssp/benches/<Bench>/bench.py`` (see artibus.bench.script)."""
import math

import numpy as np

from artibus.report import plots
from artibus.report.pages import Kpi
from artibus.study import kpi

DEG = 180 / math.pi


def circle_road(R=17.5, before=25.0, after=50.0):
    from artibus.bench import roads
    x, y = roads.generate(roads.CIRCLE, R=R, before=before, after=after)
    return x, y


def lane_change_road(length, offset, before=25.0, after=50.0):
    from artibus.bench import roads
    x, y = roads.generate(roads.LANE_CHANGE, laneLength=length, laneOffset=offset, before=before, after=after)
    return x, y


def fit_radius(x, y):
    """The radius of the circle fitted to the points (x, y) by least squares; NaN
    with fewer than three points (a run too short for the stretch it fits)."""
    if len(x) < 3:
        return math.nan
    A = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    (cx, cy, c), *_ = np.linalg.lstsq(A, x ** 2 + y ** 2, rcond=None)
    return math.sqrt(c + cx ** 2 + cy ** 2)


def outlines(r, n_modules):
    cols = []
    for c in range(1, 4 * n_modules + 1):
        cols.append(np.column_stack([r[f"Bus.xCorner[{c}]"], r[f"Bus.yCorner[{c}]"]]))
    return np.stack(cols, axis=1)


def slalom_road_module():
    """ssp/roads/slalom.py, which wrote the Bus36m_Slalom road (its geometry, one source)."""
    import importlib.util
    from artibus.base import ROOT
    spec = importlib.util.spec_from_file_location("artibus_slalom_road", ROOT / "ssp" / "roads" / "slalom.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def lateral_path(path, traces, road, cones, title, outlines=None):
    """Axle traces against x with y stretched (a bird's-eye view at equal scale
    would be a thin line for a 300 m long manoeuvre); with outlines, the
    swept-path envelope (plots.swept_area)."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 3.6))
    ax.plot(road[0], road[1], color="0.75", lw=6, solid_capstyle="round", label="road", zorder=0)
    if outlines is not None:
        plots._draw_swept_area(ax, plots.swept_area(outlines, resolution=0.03))   # y is stretched: finer
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
    plots.save_figure(fig, path, dpi=110)


# ---- issue 6: the steered 36 m bus's road tests (Bus36m_LaneChange, Bus36m_Slalom) ----

def hinge_oscillation_kpis(r, t_after, what):
    kpis = []
    t = r.time
    for k in (1, 2):
        a = r[f"Bus.artAngle[{k}]"]
        osc = kpi.oscillation(t, a, t_from=t_after)
        settled = " (settles without oscillating: fewer than 3 extrema)" if osc.periods == 0 else ""
        why = "settles without oscillating" if osc.periods == 0 else ""
        kpis.append(Kpi(f"articulation hinge {k} after the {what}: damping ratio{settled}", osc.damping_ratio, "-",
                        "stable on dry and wet roads (decays)", "seed 000, sec. IV",
                        None if osc.periods == 0 else osc.damping_ratio > 0, why=why, bound=0.0,
                        explain="Seed 000 reports the manoeuvre stable, without data. A growing oscillation "
                                "depends on the closed loop: the driver's gains, the guidance's and the force "
                                "minimisation's lags (10 ms ECUs) and the estimated tyre and mass data "
                                "(Bus36m.ssv); a lower speed or a slower driver would change it."))
        kpis.append(Kpi(f"articulation hinge {k} after the {what}: frequency", osc.frequency, "Hz", why=why))
        kpis.append(Kpi(f"max |articulation angle| hinge {k} after the {what}",
                        kpi.peak(a[t >= t_after]) * DEG, "deg"))
    return kpis


def road_test_kpis(r, t_after, what, extra):
    util = max(kpi.peak(r[f"Bus.Fy[{a}]"] / r[f"Bus.Fz[{a}]"]) for a in range(1, 7))
    return [Kpi("front axle A1: max |lateral error| (driver)", kpi.peak(r["Driver.eLat"]), "m")] + extra + [
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
    ] + hinge_oscillation_kpis(r, t_after, what) + [
        Kpi("max |lateral force| hinge 1", kpi.peak_while_moving(r["Bus.FjointY[1]"], r["Bus.v"]) / 1e3, "kN",
            "< 4 (17.5 m circle)", "seed 000, Fig. 10",
            ungraded="a bound for the 17.5 m circle at walking pace, not for this manoeuvre at speed"),
        Kpi("max |lateral force| hinge 2", kpi.peak_while_moving(r["Bus.FjointY[2]"], r["Bus.v"]) / 1e3, "kN"),
        Kpi("max friction used by an axle, |Fy|/Fz", util, "-", "below the friction mu (1.0 dry, 0.5 wet)", ""),
        Kpi("max |lateral acceleration| (modules 1, 2, 3)",
            max(kpi.peak(r[f"Bus.ay[{m}]"]) for m in (1, 2, 3)), "m/s2"),
    ]


def road_test_figures(r, out, title, road, t_after, what, cones=None, bounds=None):
    """The road tests' figures; bounds: [(panel, value, label)] drawn on signals.png (plots.signals)."""
    t = r.time
    images = []
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in (1, 2, 4, 6)}
    lateral_path(out / "path.png", {f"A{a}": ax[a] for a in ax}, road, cones, title, outlines=outlines(r, 3))
    images.append(("path.png", "Lateral position of the axles against x (y stretched): the road (grey, followed "
                               "by the front axle A1), the swept-path envelope (red, dashed)"
                               + (", the cones (black)." if cones is not None else ".")))
    plots.signals(out / "signals.png", t, [
        ("lateral position [m]", {f"A{a}": ax[a][1] for a in (1, 2, 4, 6)}),
        ("articulation [deg]", {"hinge 1": r["Bus.artAngle[1]"] * DEG, "hinge 2": r["Bus.artAngle[2]"] * DEG}),
        ("steering [deg]", {"A1 (driver)": r["Driver.delta"] * DEG, "A3": r["ForceMin.gamma3"] * DEG,
                            "A4": r["Guidance.gamma4"] * DEG, "A5": r["ForceMin.gamma5"] * DEG,
                            "A6": r["Guidance.gamma6"] * DEG}),
        ("hinge lateral force [kN]", {"hinge 1": r["Bus.FjointY[1]"] / 1e3, "hinge 2": r["Bus.FjointY[2]"] / 1e3}),
        ("driver's lateral error [m]", {"A1": r["Driver.eLat"]}),
    ], title=title, bounds=bounds)
    images.append(("signals.png", f"Lateral positions, articulation, steering angles of the five steered axles, "
                                  f"hinge forces and the driver's error; the {what} ends for the front axle at "
                                  f"t = {t_after:.1f} s."))
    return images


ROAD_TEST_TEXT = (
    "Seed 000 reports only that lane change and slalom were stable on dry and wet roads; it gives no "
    "manoeuvre data. Friction is a parameter (tyreModel 1: cornering stiffness mu C, saturated at mu Fz); "
    "the default run is dry (mu = 1.0), the wet case sets Bus.mu[1..6] = 0.5. The damping ratio is that "
    "of the closed loop (driver, controllers and bus) from the articulation's successive extrema after the "
    "front axle has left the manoeuvre; n/a where it settles without oscillating.")


# ---- the steering on CAN (Bus36m_Circle_CAN, Bus36m_Circle_CAN_Backwards) ----

def can_receivers(r):
    """The components that report a fallback state (a column <name>.fallback)."""
    return [n[:-len(".fallback")] for n in r.names if n.endswith(".fallback")]


def can_lost(r):
    """Each message's cycles since its last good frame (the columns can.<message>.sinceGood)."""
    return [n for n in r.names if n.startswith("can.") and n.endswith(".sinceGood")]


def can_fallback_kpis(r, entered_at=True):
    """What the receivers on CAN saw: each one's worst fallback state and its time in
    fallback (with entered_at, also when it first fell back), and each message's
    longest run of cycles without a good frame."""
    k = []
    t = r.time
    for c in can_receivers(r):
        fb = r[f"{c}.fallback"]
        on = fb > 0
        k.append(Kpi(f"{c}: worst fallback state (0 normal, 1 holding, 2 ramping, 3 straight; 0 expected "
                     "without faults)", float(np.max(fb)), "-", "", "our fallback: seed 000 (sec. I) gives "
                     "ECUs on CAN, no fallback"))
        k.append(Kpi(f"{c}: time in fallback", float(np.sum(on)) * (t[1] - t[0]), "s"))
        if entered_at:
            k.append(Kpi(f"{c}: fallback entered at", float(t[np.argmax(on)]) if on.any() else math.nan, "s",
                         why="" if on.any() else "never in fallback"))
    for n in can_lost(r):
        k.append(Kpi(f"{n[4:-len('.sinceGood')]}: longest run of cycles without a good frame",
                     float(np.max(r[n])), "cycles"))
    return k
