"""Bus36m_Circle: seed 000's 17.5 m circle, 36 m bus, kinetic model, with
seed 000's steering system built in and switched by parameter sets: the
default (no variant) is unsteered, the variants guided, guidedAll and
guidedForceMin steer (variants/*.ssv). The KPIs of one run are a function
of the result alone: the variant that ran is told by the controllers'
recorded outputs (variant_of); the report is a study: every variant side by
side (artibus.benches). The CAN benches take variant_kpis/circle_figures with
their variant's name."""
import dataclasses
import math

import numpy as np

from artibus import ArtibusError, report
from artibus.report import Kpi
from artibus.report.benchkit import DEG, circle_road, outlines
from artibus.study import kpi

BENCH = "Bus36m_Circle"
#: the default, run without a variant
DEFAULT = "unsteered"


def _wrong(F):
    return F > 20


def _small(F):
    return F < 4


#: name: (label, the paper's deviation, the paper's force, the deviation pass rule applies, the force's pass rule)
VARIANTS = {
    "unsteered": ("A3..A6 unsteered", "about 6 (unsteered)", "> 20 with wrong A3/A5 angles", False, _wrong),
    "guided": ("A4, A6 guided (Task 1), A3, A5 straight", "< 1.0 (steered)", "> 20 with wrong A3/A5 angles",
               True, _wrong),
    "guidedAll": ("A3 steered like A4, A5 like A6 (Task 1 on every trailer axle)", "< 1.0 (steered)",
                  "> 20 with wrong A3/A5 angles", True, _wrong),
    "guidedForceMin": ("A4, A6 guided (Task 1), A3, A5 force-minimising (Task 2)", "< 1.0 (steered)",
                       "< 4 (steered)", True, _small),
}

#: the notes of any run on this circle (the CAN benches' too)
CIRCLE_TEXT = ("The paper gives no geometry or masses for its bus: ours are estimates from public "
               "data (ssp/parameters/Bus36m.ssv), so the figures differ. Speed 3 m/s (the paper gives none).")
TEXT = CIRCLE_TEXT + (" The variants are parameter sets of this one bench (Guidance.guided, ForceMin.law; "
                      "`artibus run Bus36m_Circle --variant guided`): the default is unsteered.")


def variant_of(r):
    """The variant a run of this bench is, from what the controllers sent:
    A4/A6 (Guidance.gamma4/6) all exactly 0 -> unsteered; A3/A5
    (ForceMin.gamma3/5) all exactly 0 -> guided; equal to A4/A6 sample for
    sample -> guidedAll; else guidedForceMin. A run that steers A3/A5 but
    not A4/A6 is none of them: None (its KPIs without the paper's bounds)."""
    try:
        g4, g6 = r["Guidance.gamma4"], r["Guidance.gamma6"]
        g3, g5 = r["ForceMin.gamma3"], r["ForceMin.gamma5"]
    except ValueError:
        raise ArtibusError(f"{BENCH}: the KPIs tell the variant from Guidance.gamma4, Guidance.gamma6, "
                           f"ForceMin.gamma3, ForceMin.gamma5: record them") from None
    straight35 = not np.any(g3) and not np.any(g5)
    if not np.any(g4) and not np.any(g6):
        return "unsteered" if straight35 else None
    if straight35:
        return "guided"
    if np.array_equal(g3, g4) and np.array_equal(g5, g6):
        return "guidedAll"
    return "guidedForceMin"


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


#: a run that is none of the variants (A3/A5 steered, A4/A6 straight): no paper value applies
OTHER = ("A3, A5 steered, A4, A6 straight (none of the variants)", "", "", False, lambda F: None)


def variant_kpis(r, variant):
    """The KPIs of a run of the named variant (VARIANTS; None: OTHER), with its paper values and pass rules."""
    _, paper_dev, paper_F, steered, F_ok = VARIANTS.get(variant, OTHER)
    return circle_kpis(r, steered, paper_dev, paper_F, F_ok)


def circle_figures(r, out, label, prefix=""):
    ax = _axles(r)
    outl = outlines(r, 3)
    images = []
    report.birds_eye(out / f"{prefix}path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outl,
                     road=circle_road(), every=300,
                     title=f"36 m bus, {label}, 17.5 m circle at 3 m/s")
    images.append((f"{prefix}path.png", "Bird's-eye view: road (grey, followed by the outermost front point), "
                                        "body outlines every 3 s, axle traces."))
    dev4, in4 = kpi.lateral_distance(*ax[2], *ax[4])
    dev6, in6 = kpi.lateral_distance(*ax[2], *ax[6])
    s = r["Driver.s"]
    report.signals(out / f"{prefix}deviation.png", r.time[::5], [
        ("deviation from A2 trace [m]", {"A4": np.where(in4, np.abs(dev4), np.nan),
                                         "A6": np.where(in6, np.abs(dev6), np.nan)}),
        ("road progress [m]", {"s": s[::5]}),
    ], title="Deviation of A4 and A6 from the trace of A2 (seed 000, Fig. 9)")
    images.append((f"{prefix}deviation.png", "Lateral distance of A4 and A6 from the trace of A2."))
    report.signals(out / f"{prefix}forces.png", r.time, [
        ("hinge lateral force [kN]", {"hinge 1": r["Bus.FjointY[1]"] / 1e3, "hinge 2": r["Bus.FjointY[2]"] / 1e3}),
        ("articulation [deg]", {"hinge 1": r["Bus.artAngle[1]"] * DEG, "hinge 2": r["Bus.artAngle[2]"] * DEG}),
        ("articulation rate [deg/s]", {"hinge 1": r["Bus.artRate[1]"] * DEG, "hinge 2": r["Bus.artRate[2]"] * DEG}),
        ("steering A1 [deg]", {"driver": r["Driver.delta"] * DEG}),
    ], title="Hinge forces (seed 000, Fig. 10), articulation, steering")
    images.append((f"{prefix}forces.png", "Lateral hinge forces in the front module's frame, articulation "
                                          "angles and rates, steering."))
    return images


def kpis(r):
    return variant_kpis(r, variant_of(r))


def figures(r, out):
    return circle_figures(r, out, VARIANTS.get(variant_of(r), OTHER)[0])


def run_variant(variant, stop_time=None):
    """A run of the named variant with the bench's own parameters."""
    from artibus import runner
    from artibus.bench import ssp
    names = [] if variant == DEFAULT else [variant]
    return runner.run(BENCH, stop_time=stop_time, overrides=ssp.variant_overrides(BENCH, names))


def study(r, out):
    """Every variant side by side: this run's KPIs and figures under the name
    of its variant, the other variants run here with the bench's own
    parameters over the same time; a figure of all four (seed 000, Figs. 9-10)."""
    own = variant_of(r)
    runs = {v: (r if v == own else run_variant(v, stop_time=float(r.time[-1]))) for v in VARIANTS}
    K = [] if own is not None else [dataclasses.replace(k, name=f"this run: {k.name}") for k in variant_kpis(r, None)]
    for v, rr in runs.items():
        K += [dataclasses.replace(k, name=f"{v}: {k.name}")
              for k in variant_kpis(rr, v)]
    name = f"the variant {own}" if own else "none of the variants"
    images = circle_figures(r, out, f"{VARIANTS.get(own, OTHER)[0]}, this run")
    panels = [("deviation A4 from A2 trace [m]", {}), ("deviation A6 from A2 trace [m]", {}),
              ("hinge 1 lateral force [kN]", {})]
    t = r.time[::5]
    for v, rr in runs.items():
        ax = _axles(rr)
        for i, a in enumerate((4, 6)):
            d, inside = kpi.lateral_distance(*ax[2], *ax[a])
            panels[i][1][v] = np.where(inside, np.abs(d), np.nan)[:len(t)]
        panels[2][1][v] = rr["Bus.FjointY[1]"][::5][:len(t)] / 1e3
    report.signals(out / "variants.png", t, panels,
                   title="Every variant: deviations of A4, A6 from the trace of A2 (seed 000, Fig. 9), "
                         "hinge 1 lateral force (Fig. 10)")
    images.append(("variants.png", "The four variants side by side: unsteered, guided, guidedAll, "
                                   "guidedForceMin."))
    text = (TEXT + f" This run is {name} ({VARIANTS.get(own, OTHER)[0]}); the KPIs of the other variants "
            "come from runs of the bench's own parameters over the same time.")
    return K, images, text
