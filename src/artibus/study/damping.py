"""Seed 001's articulation damping study on the bench ``Scania18m_Damping``:
its damping functions and driving cases (the bench's variants), the KPIs of
one run, the calibration of the controller's gains (thesis 5.2.2) and the
report that sets the functions side by side as the thesis's Figs. 5.9-5.21 do.

Every KPI is a function of one run's result; nothing here draws unless asked.
"""
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from artibus.base import ROOT, ArtibusError
from artibus import runner
from artibus.bench import ssp

BENCH = "Scania18m_Damping"
DEG = 180 / math.pi

#: the damping functions the thesis compares (variants of the bench)
FUNCTIONS = ("none", "floor", "baseline", "option1", "option2", "option3", "revised")
LABELS = {"none": "no damping", "floor": "3.5 % floor only", "baseline": "baseline (ACS5-like)",
          "option1": "option 1 (angle)", "option2": "option 2 (rate)", "option3": "option 3 (both)",
          "revised": "revised (6.1.3)"}
#: which gain of DampingGains.ssv each option's calibration sets (thesis Table 5.3)
GAINS = {"option1": "K1", "option2": "K2", "option3": "K3", "revised": "Krev"}
THESIS_GAINS = {"K1": 0.130, "K2": 0.565, "K3": 0.605, "Krev": None}


@dataclass(frozen=True)
class Case:
    length: float       # lane change length, m
    speed_kmh: float
    mu_rear: float


#: the driving cases (variants of the bench): seed 001, 4.2, 5.2.1, 5.2.2, 5.2.5
CASES = {"lc25_50": Case(25.0, 50.0, 1.0), "lc60_100": Case(60.0, 100.0, 0.2),
         "lc200_100": Case(200.0, 100.0, 0.2), "lc60_130": Case(60.0, 130.0, 0.2)}
ROAD_BEFORE = 25.0      # RoadFollowDriver.roadBefore (its default): straight before the lane change
OFFSET = 3.25           # lane offset, m (seed 001, 4.2)
TARGET_PCT = 13.5       # the calibration's peak damping (seed 001, 5.2.2: ACS5's ground level at 100 km/h)
SETTLED_DEG = 1.0       # the articulation oscillation has settled below this, deg
OSCILLATION_DEG = 0.5   # an extremum of the articulation angle above this counts as an oscillation, deg
GAINS_FILE = ROOT / "ssp" / "parameters" / "DampingGains.ssv"


def run(function, case="lc60_100", overrides=None, stop_time=None, record=None, heavy_rear=False):
    """One run of the bench with a damping function and a driving case; with
    heavy_rear, the vehicle of Table 5.4 (variant heavyRear)."""
    for name, known in ((function, FUNCTIONS), (case, CASES)):
        if name not in known:
            raise ArtibusError(f"{name}: not one of {', '.join(known)}")
    values = ssp.variant_overrides(BENCH, [function, case] + (["heavyRear"] if heavy_rear else []))
    values.update(overrides or {})
    return runner.run(BENCH, overrides=values, stop_time=stop_time, record=record)


@dataclass
class Kpis:
    overshoot: float        # rear axle beyond the 3.25 m offset after the lane change, m (the thesis's (4))
    peak_angle: float       # max |articulation angle| after the lane change, deg
    peak_rate: float        # max |articulation rate| after the lane change, deg/s
    oscillations: int       # extrema of the articulation angle above OSCILLATION_DEG after the lane change
    settling: float         # time from the end of the lane change until |angle| stays below SETTLED_DEG, s
    peak_pct: float         # max damping request, %
    min_pct: float          # min damping request, %
    energy: float           # energy the damper took out, J
    t_end: float            # when the front axle left the lane change, s


def kpis(r, case="lc60_100"):
    """The KPIs of one run (a result with the bench's signals) of a case."""
    c = CASES[case]
    x_end = ROAD_BEFORE + c.length
    t = r.time
    lam = r["Bus.artAngle[1]"] * DEG
    rate = r["Bus.artRate[1]"] * DEG
    front_done = r["Bus.xAxle[1]"] > x_end
    if not front_done.any():
        raise ArtibusError(f"{BENCH}: the run ends before the front axle leaves the lane change "
                           f"(x = {x_end:g} m): give a longer stop time")
    t_end = float(t[np.argmax(front_done)])
    after = t >= t_end
    rear_done = r["Bus.xAxle[3]"] > x_end
    overshoot = float(np.max(r["Bus.yAxle[3]"][rear_done]) - OFFSET) if rear_done.any() else math.nan
    la = lam[after]
    d = np.diff(la)
    ext = np.nonzero(d[:-1] * d[1:] < 0)[0] + 1
    oscillations = int(np.sum(np.abs(la[ext]) > OSCILLATION_DEG))
    above = np.nonzero(np.abs(la) > SETTLED_DEG)[0]
    if len(above) == 0:
        settling = 0.0
    elif above[-1] == len(la) - 1:
        settling = math.inf            # still above at the end of the run
    else:
        settling = float(t[after][above[-1] + 1] - t_end)
    pct = r["Controller.pct"]
    return Kpis(overshoot=overshoot, peak_angle=float(np.max(np.abs(la))),
                peak_rate=float(np.max(np.abs(rate[after]))), oscillations=oscillations,
                settling=settling, peak_pct=float(np.max(pct)), min_pct=float(np.min(pct)),
                energy=float(r["Damper.Ediss"][-1]), t_end=t_end)


# ---- calibration (seed 001, 5.2.2) ------------------------------------------------

def read_gains(path=GAINS_FILE):
    from artibus.bench.parameters import read_parameters
    return read_parameters(str(path))


def write_gains(gains, path=GAINS_FILE, notes=""):
    """DampingGains.ssv, written whole to a temporary file and renamed."""
    path = Path(path)
    # rounded to 6 significant digits: the bisection's tolerance is 1e-6 in log(K)
    rows = "\n".join(f'    <ssv:Parameter name="{k}"><ssv:Real value="{float(f"{v:.6g}")!r}"/></ssv:Parameter>'
                     f'  <!-- thesis: {THESIS_GAINS[k] if THESIS_GAINS[k] is not None else "not given"} -->'
                     for k, v in gains.items())
    text = f'''<?xml version="1.0" encoding="UTF-8"?>
<!-- The damping controller's gains, written by `artibus calibrate` (seed 001, 5.2.2): for each option the gain
     that makes the peak damping on the 200 m / 100 km/h / rear-friction-0.2 lane change {TARGET_PCT} %. {notes} -->
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="DampingGains">
  <ssv:Parameters>
{rows}
  </ssv:Parameters>
</ssv:ParameterSet>
'''
    with tempfile.NamedTemporaryFile("w", dir=path.parent, prefix=path.name, suffix=".part",
                                     delete=False) as f:
        f.write(text)
    Path(f.name).replace(path)
    return path


def peak_pct(function, gains, case="lc200_100"):
    """Peak damping request of a function on a case with the given gains."""
    o = {f"Controller.{k}": v for k, v in gains.items()}
    return kpis(run(function, case, overrides=o), case).peak_pct


def calibrate(target=TARGET_PCT, case="lc200_100", tol=0.01, log=print):
    """The gain of each option that makes its peak damping on the case equal
    to ``target`` % (bisection in log(K); the peak request is continuous and
    non-decreasing in the gain). Option 3 scales the sum of options 1 and 2
    at their calibrated gains by K3, as the thesis does. Returns {gain: value}
    and {gain: peak % reached}."""
    from scipy.optimize import brentq
    gains = read_gains()
    reached = {}
    for function in ("option1", "option2", "option3", "revised"):
        name = GAINS[function]
        # from the thesis's gain, not the file's: the same gains whatever the file held
        k0 = THESIS_GAINS[name] or 80.0

        def f(logk):
            return peak_pct(function, {**gains, name: math.exp(logk)}, case) - target
        lo, hi = math.log(k0) - 1.0, math.log(k0) + 1.0
        flo, fhi = f(lo), f(hi)
        for _ in range(12):       # widen until the target is bracketed
            if flo < 0 < fhi:
                break
            if flo >= 0:
                lo, hi, fhi = lo - 2.0, lo, flo
                flo = f(lo)
            else:
                lo, hi, flo = hi, hi + 2.0, fhi
                fhi = f(hi)
        else:
            raise ArtibusError(f"calibrate {function}: no gain {name} gives a peak of {target} % "
                               f"on {case} (the damping stays at its floor or its limit)")
        logk = brentq(f, lo, hi, xtol=1e-6)
        gains[name] = math.exp(logk)
        reached[name] = f(logk) + target
        if abs(reached[name] - target) > tol:
            raise ArtibusError(f"calibrate {function}: reached {reached[name]:.3f} % instead of {target} %")
        log(f"{function}: {name} = {gains[name]:.4g}  (thesis: {THESIS_GAINS[name] or 'not given'}), "
            f"peak damping {reached[name]:.3f} % on {case}")
    return gains, reached


# ---- the report (the main job) ------------------------------------------------------

def _overlay(path, runs, signals, title, t_window=None):
    """One panel per quantity, every damping function overlaid (as the thesis's
    Figs. 5.11-5.14 compare the options). signals: [(ylabel, f(result) -> values)]."""
    import matplotlib.pyplot as plt
    from artibus.report import plots
    fig, axes = plt.subplots(len(signals), 1, figsize=(10, 2.6 * len(signals)), sharex=True, squeeze=False)
    colours = dict(zip(FUNCTIONS + ("reference",), plots.colours() * 2))
    for ax, (ylabel, f) in zip(axes[:, 0], signals):
        for name, r in runs.items():
            y = f(r, name)
            if y is None:
                continue
            ax.plot(r.time, y, lw=1.2, color=colours.get(name), label=LABELS.get(name, name),
                    ls="--" if name == "reference" else "-")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if t_window:
            ax.set_xlim(*t_window)
    axes[0, 0].legend(loc="upper right", fontsize=8, ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].set_title(title)
    fig.tight_layout()
    from artibus.report import save_figure
    save_figure(fig, path, dpi=110)


def _rear_path(path, runs, case, title):
    """The rear axle's lateral position against x with the lane (seed 001, Figs. 5.9-5.10)."""
    import matplotlib.pyplot as plt
    from artibus.bench import roads
    from artibus.report import plots
    c = CASES[case]
    x, y = roads.generate(roads.LANE_CHANGE, laneLength=c.length, laneOffset=OFFSET,
                          before=ROAD_BEFORE, after=600.0)
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5))
    for ax, zoom in zip(axes, (False, True)):
        ax.fill_between(x, y - 1.5, y + 1.5, color="0.9", label="lane (3 m)")
        ax.plot(x, y, color="0.6", lw=1, label="lane centre")
        for (name, r), col in zip(runs.items(), plots.colours() * 2):
            ax.plot(r["Bus.xAxle[3]"], r["Bus.yAxle[3]"], lw=1.2, color=col, label=LABELS.get(name, name))
        x_end = ROAD_BEFORE + c.length
        if zoom:
            ax.set_xlim(x_end - 10, x_end + 250)
            ax.set_ylim(OFFSET - 1.0, OFFSET + 1.2)
            ax.set_title("zoomed: the initial overshoot and the oscillations after it (seed 001, Fig. 5.10)")
        else:
            ax.set_xlim(0, x_end + 250)
            ax.set_title(title)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("rear axle y [m]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="lower right", fontsize=8, ncol=2)
    fig.tight_layout()
    from artibus.report import save_figure
    save_figure(fig, path, dpi=110)


def _fmt(x, nd=3):
    return "inf" if x == math.inf else f"{x:.{nd}g}"


def report(r, out):
    """The Scania18m_Damping report: every damping function on the thesis's
    comparison case, the 130 km/h case, the calibration case and the
    reference-model case; a KPI table per case."""
    from artibus.report import Kpi
    out = Path(out)
    runs = {f: run(f, "lc60_100") for f in FUNCTIONS}   # whatever variant r was run with
    k = {f: kpis(rr, "lc60_100") for f, rr in runs.items()}
    K = []
    src = "seed 001, 5.2.4-5.2.5"
    K.append(Kpi("60 m / 100 km/h / rear friction 0.2: rear axle initial overshoot, option 1 / 2 / 3",
                 k["option1"].overshoot, "m",
                 f"option 1 larger than 2 and 3 (here {_fmt(k['option2'].overshoot)} / {_fmt(k['option3'].overshoot)})",
                 src, k["option1"].overshoot > max(k["option2"].overshoot, k["option3"].overshoot)))
    K.append(Kpi("  same: option 2 / baseline / no damping overshoot", k["option2"].overshoot, "m",
                 f"option 2 < baseline < none (here {_fmt(k['baseline'].overshoot)} / {_fmt(k['none'].overshoot)})",
                 src, k["option2"].overshoot < k["baseline"].overshoot < k["none"].overshoot))
    K.append(Kpi("  same: peak |articulation| after the lane change, option 2 / baseline / none",
                 k["option2"].peak_angle, "deg",
                 f"option 2 < baseline < none (here {_fmt(k['baseline'].peak_angle)} / {_fmt(k['none'].peak_angle)})",
                 src, k["option2"].peak_angle < k["baseline"].peak_angle < k["none"].peak_angle))
    K.append(Kpi("  same: oscillations above 0.5 deg after the lane change, option 1 / option 2",
                 k["option1"].oscillations, "-", f"option 1 oscillates longer (option 2: {k['option2'].oscillations})",
                 src, k["option1"].oscillations > k["option2"].oscillations))
    K.append(Kpi("  same: settling below 1 deg, option 2 / floor only", k["option2"].settling, "s",
                 f"at most half the floor's ({_fmt(k['floor'].settling)})", f"{src}; the bound (half) is ours",
                 k["option2"].settling <= 0.5 * k["floor"].settling))
    lo = min(k[f].min_pct for f in ("option1", "option2", "option3", "revised", "baseline"))
    hi = max(k[f].peak_pct for f in ("option1", "option2", "option3", "revised", "baseline"))
    K.append(Kpi("  same: damping request range over every option and the baseline (max)", hi, "%",
                 f"within 3.5-34 (min here {_fmt(lo)})", "seed 001, 5.1.1", 3.5 - 1e-9 <= lo and hi <= 34 + 1e-9))
    for f in FUNCTIONS:
        kk = k[f]
        K.append(Kpi(f"  {LABELS[f]}: overshoot {_fmt(kk.overshoot)} m, peak angle {_fmt(kk.peak_angle)} deg, "
                     f"peak rate {_fmt(kk.peak_rate)} deg/s, {kk.oscillations} oscillations, settles in "
                     f"{_fmt(kk.settling)} s, peak damping", kk.peak_pct, "%",
                     "", f"dissipated {kk.energy / 1e3:.3g} kJ"))
    # heavy rear (Table 5.4): more sway; the thesis (5.3.1) wants more damping for it
    heavy = {f: kpis(run(f, "lc60_100", heavy_rear=True), "lc60_100") for f in ("floor", "baseline", "option2", "revised")}
    for f, kk in heavy.items():
        K.append(Kpi(f"heavy rear (Table 5.4), 60 m / 100 km/h: {LABELS[f]}: overshoot {_fmt(kk.overshoot)} m, "
                     f"peak angle {_fmt(kk.peak_angle)} deg, settles in {_fmt(kk.settling)} s; energy taken out",
                     kk.energy / 1e3, "kJ", "", "seed 001, 5.3.1, Table 5.4"))
    # calibration case: every option's peak at 13.5 %
    for f in ("option1", "option2", "option3", "revised"):
        p = kpis(run(f, "lc200_100"), "lc200_100").peak_pct
        K.append(Kpi(f"200 m / 100 km/h / 0.2: peak damping, {LABELS[f]}", p, "%", "13.5 (calibrated)",
                     "seed 001, 5.2.2", abs(p - TARGET_PCT) <= 0.05))
    # 130 km/h: the thesis compares the baseline and option 2 there
    fast = {f: run(f, "lc60_130") for f in ("floor", "baseline", "option2")}
    kf = {f: kpis(rr, "lc60_130") for f, rr in fast.items()}
    K.append(Kpi("60 m / 130 km/h / 0.2: peak |articulation| after the lane change, option 2 / baseline",
                 kf["option2"].peak_angle, "deg", f"option 2 below the baseline (here {_fmt(kf['baseline'].peak_angle)})",
                 "seed 001, 5.2.5", kf["option2"].peak_angle < kf["baseline"].peak_angle))
    # reference-model case: exact against small angle
    ex = run("option2", "lc25_50", overrides={"Controller.exactRef": True})
    sa = run("option2", "lc25_50", overrides={"Controller.exactRef": False})
    da = np.max(np.abs(ex["Controller.LambdaRef"] - sa["Controller.LambdaRef"])) / np.max(np.abs(ex["Controller.LambdaRef"]))
    dr = (np.max(np.abs(ex["Controller.LambdaDotRef"] - sa["Controller.LambdaDotRef"]))
          / np.max(np.abs(ex["Controller.LambdaDotRef"])))
    K.append(Kpi("25 m / 50 km/h: reference model, exact (2.3) against small-angle (2.9): angle, max difference / peak",
                 100 * da, "%", "0.07", "seed 001, 4.3.1"))
    K.append(Kpi("  same: rate", 100 * dr, "%", "0.12", "seed 001, 4.3.1"))

    images = []
    _rear_path(out / "rear_path.png", runs, "lc60_100",
               "Rear axle A3, lane change 3.25 m over 60 m at 100 km/h, rear friction 0.2 (seed 001, Fig. 5.9)")
    images.append(("rear_path.png", "Rear axle's lateral position against x for every damping function, "
                                    "the lane 3 m wide; below, zoomed on the initial overshoot (seed 001, Figs. 5.9-5.10)."))
    t_end = k["option2"].t_end
    win = (max(0.0, t_end - 4.0), min(r.time[-1], t_end + 8.0))
    with_ref = dict(runs, reference=runs["option2"])
    _overlay(out / "articulation.png", with_ref, [
        ("articulation [deg]", lambda rr, n: (rr["Controller.LambdaRef"] if n == "reference" else rr["Bus.artAngle[1]"]) * DEG),
        ("articulation rate [deg/s]", lambda rr, n: (rr["Controller.LambdaDotRef"] if n == "reference" else rr["Bus.artRate[1]"]) * DEG),
    ], "Articulation angle and rate, every function; dashed: the reference model (seed 001, Figs. 5.11-5.12)", win)
    images.append(("articulation.png", "Articulation angle and rate of every damping function, and the kinematic "
                                       "reference model's (with the complementary gain) as the controller computes it."))
    _overlay(out / "damping.png", runs, [
        ("damping request [%]", lambda rr, n: rr["Controller.pct"]),
        ("hinge torque [kN m]", lambda rr, n: rr["Damper.Mjoint"] / 1e3),
        ("steering [deg]", lambda rr, n: rr["Driver.delta"] * DEG),
    ], "Damping request, the damper's torque on the rear section, steering (seed 001, Figs. 5.13-5.14)", win)
    images.append(("damping.png", "Damping percentage requested, torque on the rear section (BusDynamics' Mjoint: "
                                  "counter-clockwise on the rear module; the front module gets the reaction), steering."))
    _overlay(out / "fast.png", fast, [
        ("articulation [deg]", lambda rr, n: rr["Bus.artAngle[1]"] * DEG),
        ("articulation rate [deg/s]", lambda rr, n: rr["Bus.artRate[1]"] * DEG),
        ("damping request [%]", lambda rr, n: rr["Controller.pct"]),
    ], "60 m at 130 km/h, rear friction 0.2: baseline against option 2 (seed 001, 5.2.5)")
    images.append(("fast.png", "At 130 km/h: the floor only, the baseline and option 2."))
    notes = ("Our plant is BusDynamics with the thesis's vehicle data (Tables 3.1, 5.1) and estimated yaw "
             "inertias and front stiffnesses, its linear tyre scaled by the friction (tyreModel 3, as the "
             "thesis's extensive model); the damper's geometry and pressures are estimates (HubnerDamper.ssv). "
             "The gains are re-calibrated on our plant (artibus calibrate, DampingGains.ssv), so they differ "
             "from the thesis's 0.130 / 0.565 / 0.605. The baseline is modelled from the thesis's description "
             "of ACS5, not from production code.")
    return K, images, notes
