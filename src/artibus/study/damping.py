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

from artibus.base import ArtibusError
from artibus import runner
from artibus.bench import ssp

from artibus.study.damping_cases import (BENCH, CASES, DEG, FUNCTIONS, GAINS, GAINS_FILE, LABELS,  # noqa: F401
                                         OFFSET, OSCILLATION_DEG, ROAD_BEFORE, SETTLED_DEG, TARGET_PCT,
                                         THESIS_GAINS, Case)


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
    swing_rate: float = math.nan    # max |articulation rate| in the swing into the initial overshoot (between
    #                                 the articulation's 2nd and 3rd extrema above 1 deg: the thesis's (3)-(4)), deg/s


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
    d_all = np.diff(lam)
    ext_all = np.nonzero(d_all[:-1] * d_all[1:] < 0)[0] + 1
    ext_all = ext_all[np.abs(lam[ext_all]) > 1.0]
    swing_rate = (float(np.max(np.abs(rate[ext_all[1]:ext_all[2] + 1]))) if len(ext_all) >= 3 else math.nan)
    return Kpis(swing_rate=swing_rate, overshoot=overshoot, peak_angle=float(np.max(np.abs(la))),
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

#: a line style per function, so that seven curves stay apart in print and for colour-blind readers
STYLES = {"none": (0, (1, 1)), "floor": (0, (5, 2)), "baseline": "-", "option1": (0, (3, 1, 1, 1)),
          "option2": "-", "option3": (0, (6, 2, 1, 2)), "revised": (0, (2, 2)), "reference": ":"}
WIDTHS = {"option2": 2.0, "baseline": 1.6}


def _overlay(path, runs, signals, title, t_window=None, vlines=None, bounds=None):
    """One panel per quantity, every damping function overlaid (as the thesis's
    Figs. 5.11-5.14 compare the options), each in its own colour and line style.
    signals: [(ylabel, f(result) -> values)]; vlines: [(t, label)];
    bounds: [(panel, value, label)] the thesis's bounds, dashed."""
    import matplotlib.pyplot as plt
    from artibus.report import plots
    fig, axes = plt.subplots(len(signals), 1, figsize=(10, 2.6 * len(signals)), sharex=True, squeeze=False)
    colours = dict(zip(FUNCTIONS, plots.colours() * 2))
    colours["reference"] = "0.45"
    for ax, (ylabel, f) in zip(axes[:, 0], signals):
        for name, r in runs.items():
            y = f(r, name)
            if y is None:
                continue
            ax.plot(r.time, y, lw=WIDTHS.get(name, 1.2), color=colours.get(name), label=LABELS.get(name, name),
                    ls=STYLES.get(name, "-"))
        for t, label in vlines or []:
            ax.axvline(t, color="tab:red", lw=0.8, ls="-.", label=label)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if t_window:
            ax.set_xlim(*t_window)
    for i, value, label in bounds or []:
        plots.draw_bound(axes[i, 0], value, label)
    plots.legend_beside(axes[0, 0], fontsize=8)       # beside the panel: never over a curve
    for i, _, _ in bounds or []:
        plots.legend_beside(axes[i, 0], fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    plots.wrapped_title(fig, title)
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
            ax.plot(r["Bus.xAxle[3]"], r["Bus.yAxle[3]"], lw=WIDTHS.get(name, 1.2), color=col,
                    ls=STYLES.get(name, "-"), label=LABELS.get(name, name))
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


def _fmt(x, nd=4):
    return "inf" if x == math.inf else f"{x:.{nd}g}"


#: the thesis's claims on the 60 m / 100 km/h case as this page grades them: quantity -> (paper text, source)
REVISED_NOTE = ("The revised law (6.1.3), T = Krev m2 dLambdaDot, has no 1/v and scales with the rear mass; "
                "calibrated as the thesis does (13.5 % peak on the 200 m case at 100 km/h with the nominal m2), "
                "it is option 2's law exactly at 100 km/h and nominal m2 (Krev m2 = K2 Crear l2^2 / v), so on "
                "every 100 km/h case with the nominal rear its numbers equal option 2's. It differs at another "
                "speed and with another rear mass: shown apart below (130 km/h, heavy rear).")
#: damper torque factors of the sensitivity (HubnerDamper.ssv's torque is an estimate, known to a factor of 2)
TORQUE_FACTORS = (0.5, 2.0)


def function_rows(k, same_as_option2=False):
    """The seven functions' KPIs of one case as table rows: function, overshoot, peak angle, peak rate,
    oscillations, dissipated energy, settling, peak damping (k: {function: Kpis}); same_as_option2: the
    revised law's row says it equals option 2 there (100 km/h, nominal rear)."""
    return [[LABELS[f] + (" (= option 2 at 100 km/h, see below)" if f == "revised" and same_as_option2 else ""),
             kk.overshoot, kk.peak_angle, kk.peak_rate, kk.oscillations, kk.energy / 1e3, kk.settling, kk.peak_pct]
            for f, kk in k.items()]


FUNCTION_HEADER = ["function", "rear axle overshoot beyond 3.25 m [m]", "peak |articulation| [deg]",
                   "peak |articulation rate| [deg/s]", "oscillations above 0.5 deg [-]", "energy dissipated [kJ]",
                   "settling below 1 deg [s] (no thesis claim)", "peak damping request [%]"]


def comparison_kpis(k, calib, fast, e1, gains, ssc, torque):
    """The page's KPI rows, one quantity each, the thesis's value beside it, graded only where the
    thesis states an ordering or a number for that case; calibration targets "calibrated".
    k: {function: Kpis} of the 60 m / 100 km/h case; calib: {function: peak % on the 200 m case};
    fast: {function: Kpis} at 130 km/h; e1: (angle %, rate %) exact vs small-angle reference with Kc;
    gains: {gain: value}; ssc: {case: time the baseline's SSC first switched on, s, or nan};
    torque: {factor: {function: Kpis}} of option 2 and the baseline with the damper's torque scaled."""
    from artibus.report import Kpi
    S4, S5 = "seed 001, 5.2.4", "seed 001, 5.2.5"
    o = {f: kk.overshoot for f, kk in k.items()}
    a = {f: kk.peak_angle for f, kk in k.items()}
    q = {f: kk.swing_rate for f, kk in k.items()}
    dep = ("Our plant is BusDynamics with the thesis's vehicle data and estimated yaw inertias; the damper is "
           "an estimate (HubnerDamper.ssv: torque known to a factor of 2), the gains re-calibrated on it.")
    K = [
        Kpi("60 m / 100 km/h: initial overshoot, option 1", o["option1"], "m",
            f"larger than option 2's and 3's ({_fmt(o['option2'])}, {_fmt(o['option3'])} m here)", S4,
            o["option1"] > max(o["option2"], o["option3"]), bound=max(o["option2"], o["option3"]),
            explain="Option 1 damps on the angle error, so its damping stops at the angle's extrema (the gate); "
                    "that it overshoots most depends on its gain K1, calibrated here. " + dep),
        Kpi("60 m / 100 km/h: initial overshoot, option 2", o["option2"], "m",
            f"at most option 3's, slightly (option 3: {_fmt(o['option3'])} m here)", S4 + " (5.2.4: 'slightly smaller')",
            o["option2"] <= o["option3"], bound=o["option3"],
            explain="The thesis finds option 2's overshoot slightly below option 3's. Option 3 scales the sum of "
                    "options 1 and 2 by K3 (calibrated here): the order depends on K3 and on how much the angle "
                    "term cancels the rate term. " + dep),
        Kpi("60 m / 100 km/h: initial overshoot, baseline", o["baseline"], "m",
            f"above option 2's ({_fmt(o['option2'])} m), below no damping's ({_fmt(o['none'])} m)",
            S5 + ", Figs. 5.15-5.19", o["option2"] < o["baseline"] < o["none"], bound=(o["option2"], o["none"]),
            explain="The thesis's advantage of option 2 comes from the baseline's sway control switching on "
                    "late (after the swing's peak rate); its threshold is ours (SwayBaseline.LambdaDotSSC, set "
                    "to the thesis's timing) and the margin depends on the damper's torque. " + dep),
        Kpi("60 m / 100 km/h: peak |articulation| after the lane change, option 2", a["option2"], "deg",
            f"below the baseline's ({_fmt(a['baseline'])} deg), 'a considerable advantage'", S5 + ", Fig. 5.16",
            a["option2"] < a["baseline"] < a["none"], bound=a["baseline"],
            explain="The thesis's mechanism: the baseline's sway control comes on late, so the angle before the "
                    "swing and the rate in it are higher. With our threshold the sway control comes on after the "
                    "swing's peak rate, as the thesis describes; the margin depends on the damper's torque, which "
                    "the thesis does not give (see the torque sensitivity below). " + dep),
        Kpi("60 m / 100 km/h: peak |articulation rate| in the swing into the initial overshoot, option 2",
            q["option2"], "deg/s", f"below the baseline's ({_fmt(q['baseline'])} deg/s here)", S5 + ", Fig. 5.17",
            q["option2"] < q["baseline"], bound=q["baseline"],
            explain="The thesis explains option 2's advantage by the baseline's rear swinging into the initial "
                    "overshoot from a higher angle, hence with a higher rate. Here the first half holds (the "
                    "baseline's angle before the swing is the larger) but not the second: option 2 takes more "
                    "energy out of that swing than the baseline (it requests 30-34 % there, the baseline its "
                    "13.5 % ground level), yet swings faster, because in our closed loop the rate of that swing "
                    "is set by the driver's counter-steer (the driver keeps steering, as in the thesis) and the "
                    "tyres more than by the damper. It depends on the driver model (Driver.tNear/tFar), the "
                    "estimated yaw inertias and the damper's torque; the thesis's Fig. 5.17 kept only its axis "
                    "(-15..20 deg/s), so its rates cannot be compared. " + dep),
        Kpi("60 m / 100 km/h: oscillations above 0.5 deg after the lane change, option 1", k["option1"].oscillations,
            "-", f"more than option 2's ({k['option2'].oscillations}): 'continue farther'", S4,
            k["option1"].oscillations > k["option2"].oscillations, bound=k["option2"].oscillations,
            explain="Counted as extrema above 0.5 deg (our threshold; the thesis counts none). " + dep),
        Kpi("60 m / 100 km/h: settling below 1 deg after the lane change, option 2", k["option2"].settling, "s",
            f"no claim (floor only: {_fmt(k['floor'].settling)} s here)", "none: the thesis makes no claim on "
            "settling time", ungraded="the thesis makes no claim on settling time (its one 'half', 1.6, is about "
            "another paper's active rear steering); shown as a figure"),
    ]
    lo = min(kk.min_pct for f, kk in k.items() if f not in ("none",))
    hi = max(kk.peak_pct for f, kk in k.items() if f not in ("none",))
    K.append(Kpi("60 m / 100 km/h: highest damping request of any function", hi, "%", "at most 34", "seed 001, 5.1.1",
                 hi <= 34 + 1e-9, bound=34.0, explain="pctMax (34 %) caps every request: a value above it is a bug."))
    K.append(Kpi("60 m / 100 km/h: lowest damping request of any function but none", lo, "%", "at least 3.5 (floor)",
                 "seed 001, 5.1.1", lo >= 3.5 - 1e-9, bound=3.5, explain="pctFloor (3.5 %) is always present: a value "
                 "below it is a bug."))
    for f in ("option1", "option2", "option3", "revised"):
        K.append(Kpi(f"200 m / 100 km/h: peak damping request, {LABELS[f]}", calib[f], "%", "13.5",
                     "seed 001, 5.2.2 (the calibration case)", calibrated=True))
    for g, v in gains.items():
        t = THESIS_GAINS[g]
        K.append(Kpi(f"calibrated gain {g}", v, "-", "not given" if t is None else f"{t:g}", "seed 001, Table 5.3",
                     ungraded="a plant-specific gain: calibrated on our plant and estimated damper (the thesis gives "
                              "neither its damper's torque nor its extensive model's data in full)"))
    for case, what in (("lc60_100", "60 m / 100 km/h: after the swing's peak articulation rate"),
                       ("lc60_130", "60 m / 130 km/h: already for the overshoot from the first turn (2)"),
                       ("lc200_100", "200 m / 100 km/h: never")):
        v = ssc.get(case, math.nan)
        K.append(Kpi(f"baseline: sway control (SSC) first on, {case}", v, "s", what, S5 + " (the threshold is ours, "
                     "set to this timing)", calibrated=True, why="never on" if not math.isfinite(v) else ""))
    K.append(Kpi("60 m / 130 km/h: peak |articulation| after the lane change, option 2", fast["option2"].peak_angle,
                 "deg", f"'only a small change' against the baseline ({_fmt(fast['baseline'].peak_angle)} deg here)",
                 S5 + ", Fig. 5.20", ungraded="the thesis states no order at 130 km/h, only a small difference"))
    if "revised" in fast:
        K.append(Kpi("60 m / 130 km/h: peak |articulation| after the lane change, revised law",
                     fast["revised"].peak_angle, "deg", "not simulated in the thesis", "seed 001, 6.1.3"))
    for f_ in sorted(torque):
        kk = torque[f_]
        K.append(Kpi(f"damper torque x{f_:g}: peak |articulation|, option 2", kk["option2"].peak_angle, "deg",
                     f"below the baseline's ({_fmt(kk['baseline'].peak_angle)} deg here)", S5,
                     ungraded="a sensitivity: the thesis does not give its damper's torque"))
        K.append(Kpi(f"damper torque x{f_:g}: initial overshoot, option 2", kk["option2"].overshoot, "m",
                     f"below the baseline's ({_fmt(kk['baseline'].overshoot)} m here)", S5,
                     ungraded="a sensitivity: the thesis does not give its damper's torque"))
    ea, er = e1
    K.append(Kpi("25 m / 50 km/h, steering in the thesis's range: reference models exact (2.3) against "
                 "small-angle (2.9), both with Kc: angle, "
                 "max difference over its peak", ea, "%", "about 0.07", "seed 001, 4.3.1",
                 abs(ea - 0.07) <= E1_TOLERANCE * 0.07, explain=E1_EXPLAIN,
                 bound=(0.07 * (1 - E1_TOLERANCE), 0.07 * (1 + E1_TOLERANCE))))
    K.append(Kpi("25 m / 50 km/h, steering in the thesis's range: the same, rate", er, "%", "about 0.12", "seed 001, 4.3.1",
                 abs(er - 0.12) <= E1_TOLERANCE * 0.12, explain=E1_EXPLAIN,
                 bound=(0.12 * (1 - E1_TOLERANCE), 0.12 * (1 + E1_TOLERANCE))))
    return K


#: E1's tolerance on the thesis's 0.07 / 0.12 %: its steering history is lost (Fig. 4.5 keeps only its axis,
#: -4..+6 deg); the difference of the two references grows about as the square of the steering amplitude, and
#: an amplitude known to about 10 % gives about 20 %
E1_TOLERANCE = 0.20
E1_EXPLAIN = ("The thesis's steering history is lost (Fig. 4.5 keeps only its axis, -4..+6 deg); the references' "
              "difference grows about as the square of the steering amplitude, so it depends on our driver's "
              "steering on this case (Driver.tNear/tFar) and on the complementary gain Kc (Scania18mKc.ssv). "
              f"The bound: within {E1_TOLERANCE:.0%} of the thesis's figure.")


def ssc_on(r):
    """When the baseline's sway control first switched on (s), nan if never."""
    on = r["Baseline.sscActive"] > 0.5
    return float(r.time[np.argmax(on)]) if on.any() else math.nan


#: the driver's look-ahead times that steer the 25 m / 50 km/h case in about the thesis's range
#: (Fig. 4.5's axis, -4..+6 deg; on this bench ours then -4.9..+5.9, the default driver -6.6..+7.0)
THESIS_RANGE_DRIVER = {"Driver.tNear": 0.3, "Driver.tFar": 0.5}


def reference_difference(case="lc25_50", function="floor", overrides=None):
    """E1 on the bench: the controller's exact (2.3) and small-angle (2.9) reference models, both driven by
    Kc(v) delta as on the bench, on the same run: max difference / peak, angle and rate, in %.
    The two runs differ only in the reference the controller computes (its output drives the damper,
    so the steering is the same run's to the sample when the damping stays at the floor)."""
    ex = run(function, case, overrides={**(overrides or {}), "Controller.exactRef": True})
    sa = run(function, case, overrides={**(overrides or {}), "Controller.exactRef": False})
    da = np.max(np.abs(ex["Controller.LambdaRef"] - sa["Controller.LambdaRef"])) / np.max(np.abs(ex["Controller.LambdaRef"]))
    dr = (np.max(np.abs(ex["Controller.LambdaDotRef"] - sa["Controller.LambdaDotRef"]))
          / np.max(np.abs(ex["Controller.LambdaDotRef"])))
    return 100 * da, 100 * dr


def calibrated_gain(function, overrides=None, target=TARGET_PCT, case="lc200_100", xtol=1e-4):
    """The gain of one option (GAINS) that makes its peak damping on the calibration case ``target`` %
    with further overrides (e.g. another damper), as the thesis calibrates (5.2.2): bisection in log(K)
    around the written gain. Returns (gain, peak % reached)."""
    from scipy.optimize import brentq
    name = GAINS[function]
    k0 = read_gains()[name]
    over = dict(overrides or {})

    def f(logk):
        return kpis(run(function, case, overrides={**over, f"Controller.{name}": math.exp(logk)}), case).peak_pct - target
    lo, hi = math.log(k0) - 1.5, math.log(k0) + 1.5
    if not f(lo) < 0 < f(hi):
        raise ArtibusError(f"{function}: no gain {name} within e^+-1.5 of {k0:g} gives {target} % on {case}")
    logk = brentq(f, lo, hi, xtol=xtol)
    return math.exp(logk), f(logk) + target


def torque_sensitivity(factors=TORQUE_FACTORS, case="lc60_100"):
    """Option 2 and the baseline with the damper's torque scaled (Damper.pMax x factor; HubnerDamper.ssv's
    torque is an estimate, the thesis gives none), option 2's gain K2 re-calibrated for each damper as the
    thesis calibrates (13.5 % peak on the 200 m case). Returns {factor: {function: Kpis}} and
    {factor: (K2, its peak % on the calibration case)}."""
    base = read_parameters_damper()["pMax"]
    out, gains = {}, {}
    for f in factors:
        o = {"Damper.pMax": base * f}
        gains[f] = calibrated_gain("option2", o)
        o2 = {**o, "Controller.K2": gains[f][0]}
        out[f] = {"baseline": kpis(run("baseline", case, overrides=o), case),
                  "option2": kpis(run("option2", case, overrides=o2), case)}
    return out, gains


def read_parameters_damper():
    from artibus.bench.parameters import read_parameters
    return read_parameters("HubnerDamper")


def report(r, out):
    """The Scania18m_Damping report: every damping function on the thesis's
    comparison case (a table of the seven functions), the 130 km/h case, the
    calibration case, the baseline's sway-control timing, the damper-torque
    sensitivity of option 2 against the baseline and the reference-model case;
    the KPIs one quantity a row, the thesis's value beside each."""
    from artibus.report import Table
    out = Path(out)
    runs = {f: run(f, "lc60_100") for f in FUNCTIONS}   # whatever variant r was run with
    k = {f: kpis(rr, "lc60_100") for f, rr in runs.items()}
    # heavy rear (Table 5.4): more sway; the thesis (5.3.1) wants more damping for it
    heavy = {f: kpis(run(f, "lc60_100", heavy_rear=True), "lc60_100") for f in ("floor", "baseline", "option2", "revised")}
    calib_runs = {f: run(f, "lc200_100") for f in ("option1", "option2", "option3", "revised", "baseline")}
    calib = {f: kpis(rr, "lc200_100").peak_pct for f, rr in calib_runs.items()}
    # 130 km/h: the thesis compares the baseline and option 2 there
    fast = {f: run(f, "lc60_130") for f in ("floor", "baseline", "option2", "revised")}
    kf = {f: kpis(rr, "lc60_130") for f, rr in fast.items()}
    ssc = {"lc60_100": ssc_on(runs["baseline"]), "lc60_130": ssc_on(fast["baseline"]),
           "lc200_100": ssc_on(calib_runs["baseline"])}
    torque, torque_gains = torque_sensitivity()
    torque[1.0] = {f: k[f] for f in ("baseline", "option2")}
    torque_gains[1.0] = (read_gains()["K2"], calib["option2"])
    e1 = reference_difference(overrides=THESIS_RANGE_DRIVER)
    e1_default = reference_difference()
    gains = {g: v for g, v in read_gains().items() if g in THESIS_GAINS}
    K = comparison_kpis(k, calib, kf, e1, gains, ssc, {f: v for f, v in torque.items() if f != 1.0})
    from artibus.report import Kpi
    for what, v in zip(("angle", "rate"), e1_default):
        K.append(Kpi(f"25 m / 50 km/h, our default driver (steering -6.6..+7.0 deg): reference models' {what} "
                     "difference", v, "%", f"about {0.07 if what == 'angle' else 0.12}", "seed 001, 4.3.1",
                     ungraded="our default driver steers beyond the thesis's range (Fig. 4.5: -4..+6 deg); "
                              "graded above on a steering in that range"))

    images = []
    _rear_path(out / "rear_path.png", runs, "lc60_100",
               "Rear axle A3, lane change 3.25 m over 60 m at 100 km/h, rear friction 0.2 (seed 001, Fig. 5.9)")
    images.append(("rear_path.png", "Rear axle's lateral position against x for every damping function, "
                                    "the lane 3 m wide; below, zoomed on the initial overshoot (seed 001, Figs. 5.9-5.10)."))
    t_end = k["option2"].t_end
    win = (max(0.0, t_end - 4.0), min(r.time[-1], t_end + 8.0))
    with_ref = dict(runs, reference=runs["option2"])
    t_ssc = ssc["lc60_100"]
    _overlay(out / "articulation.png", with_ref, [
        ("articulation [deg]", lambda rr, n: (rr["Controller.LambdaRef"] if n == "reference" else rr["Bus.artAngle[1]"]) * DEG),
        ("articulation rate [deg/s]", lambda rr, n: (rr["Controller.LambdaDotRef"] if n == "reference" else rr["Bus.artRate[1]"]) * DEG),
    ], "Articulation angle and rate, every function; dotted grey: the reference model (seed 001, Figs. 5.11-5.12)",
        win, vlines=[(t_ssc, "baseline's sway control on")] if math.isfinite(t_ssc) else None)
    images.append(("articulation.png", "Articulation angle and rate of every damping function, and the kinematic "
                                       "reference model's (with the complementary gain) as the controller computes "
                                       "it; the vertical line: when the baseline's sway control switches on."))
    _overlay(out / "damping.png", runs, [
        ("damping request [%]", lambda rr, n: rr["Controller.pct"]),
        ("hinge torque [kN m]", lambda rr, n: rr["Damper.Mjoint"] / 1e3),
        ("steering [deg]", lambda rr, n: rr["Driver.delta"] * DEG),
    ], "Damping request, the damper's torque on the rear section, steering (seed 001, Figs. 5.13-5.14)", win,
        bounds=[(0, 34.0, "pctMax 34 % (seed 001, 5.1.1)"), (0, 3.5, "floor 3.5 % (seed 001, 5.1.1)")])
    images.append(("damping.png", "Damping percentage requested (dashed: the thesis's floor and maximum), torque "
                                  "on the rear section (BusDynamics' Mjoint: counter-clockwise on the rear module; "
                                  "the front module gets the reaction), steering."))
    _overlay(out / "fast.png", fast, [
        ("articulation [deg]", lambda rr, n: rr["Bus.artAngle[1]"] * DEG),
        ("articulation rate [deg/s]", lambda rr, n: rr["Bus.artRate[1]"] * DEG),
        ("damping request [%]", lambda rr, n: rr["Controller.pct"]),
    ], "60 m at 130 km/h, rear friction 0.2: baseline against option 2 and the revised law (seed 001, 5.2.5)",
        bounds=[(2, 34.0, "pctMax 34 % (seed 001, 5.1.1)")])
    images.append(("fast.png", "At 130 km/h: the floor only, the baseline, option 2 and the revised law (which "
                               "differs from option 2 here: it has no 1/v)."))
    _torque_figure(out / "torque.png", torque)
    images.append(("torque.png", "Option 2 against the baseline with the damper's torque at 0.5, 1 and 2 times our "
                                 "estimate (HubnerDamper.ssv; option 2's gain scaled with it): peak articulation and "
                                 "initial overshoot."))
    tables = [
        Table("60 m / 100 km/h / rear friction 0.2: the seven damping functions", FUNCTION_HEADER,
              function_rows(k, same_as_option2=True),
              note="After the front axle leaves the lane change. Settling below 1 deg is a figure of ours: the "
                   "thesis makes no claim on settling time. " + REVISED_NOTE),
        Table("The revised law apart: where it differs from option 2", ["case", "function"] + FUNCTION_HEADER[1:],
              [["130 km/h"] + row for row in function_rows({f: kf[f] for f in ("option2", "revised")})]
              + [["heavy rear (Table 5.4)"] + row for row in function_rows({f: heavy[f] for f in ("option2", "revised")})],
              note="At 130 km/h the revised law asks 30 % more than option 2 (no 1/v), with the heavy rear 18 % "
                   "more (m2 10131 against 8556 kg); both saturate at the 34 % limit in the swings that matter, "
                   "so the differences stay small."),
        Table("Heavy rear (Table 5.4), 60 m / 100 km/h: the thesis (5.3.1) asks for more damping", FUNCTION_HEADER,
              function_rows(heavy)),
        Table("Option 2 against the baseline with the damper's torque scaled (the thesis does not give it)",
              ["damper torque", "K2 (re-calibrated)", "option 2 peak |articulation| [deg]", "baseline [deg]",
               "peak angle, option 2 below the baseline by [%]", "option 2 overshoot [m]", "baseline [m]",
               "overshoot, option 2 below the baseline by [%]"],
              [[f"x{f:g}", torque_gains[f][0], tk["option2"].peak_angle, tk["baseline"].peak_angle,
                100 * (1 - tk["option2"].peak_angle / tk["baseline"].peak_angle), tk["option2"].overshoot,
                tk["baseline"].overshoot, 100 * (1 - tk["option2"].overshoot / tk["baseline"].overshoot)]
               for f, tk in sorted(torque.items())],
              note="Damper.pMax scaled; option 2's gain K2 re-calibrated for each damper as the thesis does (13.5 % "
                   "peak on the 200 m case); the baseline's levels are static percentages, so its torque scales "
                   "with the damper. A negative 'below by' is option 2 above the baseline. Whether option 2's "
                   "advantage is 'considerable' (5.2.5) depends on this torque, which the thesis does not give."),
    ]
    notes = [("Our plant is BusDynamics with the thesis's vehicle data (Tables 3.1, 5.1) and estimated yaw "
              "inertias and front stiffnesses, its linear tyre scaled by the friction (tyreModel 3, as the "
              "thesis's extensive model); the damper's geometry and pressures are estimates (HubnerDamper.ssv). "
              "The gains are re-calibrated on our plant (artibus calibrate, DampingGains.ssv), so they differ "
              "from the thesis's 0.130 / 0.565 / 0.605. The baseline is modelled from the thesis's description "
              "of ACS5, not from production code; its sway-control threshold (SwayBaseline.LambdaDotSSC) is "
              "ours, set so that the sway control switches on as the thesis describes (after the swing's peak "
              "articulation rate at 100 km/h, already for the first overshoot at 130 km/h, never on the 200 m "
              "case).")] + tables
    return K, images, notes


def _torque_figure(path, torque):
    """Option 2 and the baseline against the damper's torque factor: peak angle and overshoot."""
    import matplotlib.pyplot as plt
    from artibus.report import save_figure
    fs = sorted(torque)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, attr, ylabel in ((axes[0], "peak_angle", "peak |articulation| after the lane change [deg]"),
                             (axes[1], "overshoot", "rear axle initial overshoot [m]")):
        for fn, st in (("baseline", "s--"), ("option2", "o-")):
            ax.plot(fs, [getattr(torque[f][fn], attr) for f in fs], st, label=LABELS[fn])
        ax.set_xscale("log", base=2)
        ax.set_xticks(fs, [f"x{f:g}" for f in fs])
        ax.set_xlabel("damper torque against our estimate\n(HubnerDamper.ssv) [factor]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("60 m / 100 km/h / rear friction 0.2: option 2 against the baseline, damper torque scaled", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def gains_table(gains, reached):
    """`artibus calibrate`'s table: each gain beside the thesis's and the peak damping it reached."""
    lines = [f"{'gain':6s} {'artibus':>10s} {'thesis':>8s} {'ratio':>7s}  peak damping on lc200_100"]
    for name, value in gains.items():
        thesis = THESIS_GAINS.get(name)
        ratio = f"{value / thesis:7.3f}" if thesis else "      -"
        lines.append(f"{name:6s} {value:10.4g} {thesis if thesis else 'n/a':>8} {ratio}  "
                     f"{reached.get(name, float('nan')):.3f} %")
    return "\n".join(lines)
