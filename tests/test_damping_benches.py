"""Seed 001's articulation damping study on the Scania18m_Damping bench: the
thesis's findings on its driving cases, each its own test, against the
thesis's statements (orderings: its figures' numbers were lost in the
text), the calibration (5.2.2: 13.5 % peak on the 200 m / 100 km/h case),
and the sway mode against the linear two-body model written independently
in test_bus_dynamics_vehicles.py."""
import math
import subprocess
import sys

import numpy as np
import pytest

from artibus.bench.parameters import read_parameters
from artibus.study import damping, kpi
from test_bus_dynamics_vehicles import linear_modes, params, prony, sway_mode

DEG = 180 / math.pi
OPTIONS = ("option1", "option2", "option3", "revised")


@pytest.fixture(scope="module")
def lc60():
    """Every damping function on the thesis's comparison case (5.2.1): 3.25 m
    over 60 m at 100 km/h, rear friction 0.2."""
    runs = {f: damping.run(f, "lc60_100") for f in damping.FUNCTIONS}
    return runs, {f: damping.kpis(r, "lc60_100") for f, r in runs.items()}


def test_option1_has_the_largest_initial_overshoot(lc60):
    """5.2.4: 'The initial overshoot (4) is larger' with option 1 than with 2 and 3."""
    _, k = lc60
    print({f: round(k[f].overshoot, 4) for f in damping.FUNCTIONS})
    assert k["option1"].overshoot > k["option2"].overshoot
    assert k["option1"].overshoot > k["option3"].overshoot


def test_option2_is_better_than_the_thesis_timed_baseline(lc60):
    """5.2.5: 'Option 2 has a considerable advantage over the ACS5 damping'
    (Figs. 5.15, 5.16): with the baseline's sway control timed as the thesis
    describes (SwayBaseline.LambdaDotSSC: on after the swing's peak rate), its
    peak articulation after the turn and its initial overshoot are above
    option 2's, both below no damping's. How much is measured, not asserted:
    'considerable' depends on the damper's torque, which the thesis does not
    give (the report shows 0.5x and 2x our estimate); on our estimate the
    margins are a few per cent (printed)."""
    _, k = lc60
    o2, ob, on = (k[f].overshoot for f in ("option2", "baseline", "none"))
    a2, ab, an = (k[f].peak_angle for f in ("option2", "baseline", "none"))
    print(f"peak angle: option 2 {a2:.3f}, baseline {ab:.3f}, none {an:.3f} deg ({100 * (1 - a2 / ab):.1f} % below); "
          f"overshoot: {o2:.4f}, {ob:.4f}, {on:.4f} m ({100 * (1 - o2 / ob):.1f} % below)")
    assert a2 < ab < an
    assert o2 < ob < on


@pytest.mark.xfail(strict=True, reason=(
    "not reproduced: in the swing into the initial overshoot (between the articulation's 2nd and 3rd extrema) "
    "option 2's peak rate is 24.1 deg/s against the baseline's 20.0 (measured 2026-12-03), although option 2 "
    "takes more energy out of that swing (5.1 against 2.1 kJ: 30-34 % requested against the baseline's 13.5 % "
    "ground level); the baseline's higher angle before the swing holds (8.09 against 7.50 deg): the rate of the "
    "swing is set by the driver's counter-steer and the tyres in our closed loop more than by the damper"))
def test_option2_swings_slower_than_the_baseline(lc60):
    """5.2.5, Fig. 5.17: the baseline's rear section, starting from a higher
    angle, swings into the initial overshoot with a higher articulation rate."""
    _, k = lc60
    print("swing rate: option 2", k["option2"].swing_rate, "baseline", k["baseline"].swing_rate)
    assert k["option2"].swing_rate < k["baseline"].swing_rate


def test_option1_oscillates_longer(lc60):
    """5.2.4: with option 1 'the subsequent oscillations continue farther'."""
    _, k = lc60
    print({f: (k[f].oscillations, k[f].settling) for f in damping.FUNCTIONS})
    assert k["option1"].oscillations > k["option2"].oscillations
    assert k["option1"].settling > k["option2"].settling


def test_damping_stays_between_the_floor_and_the_limit(lc60):
    """5.1.1: 3.5 % always present, at most 34 %; 'none' is zero throughout."""
    runs, _ = lc60
    for f in OPTIONS + ("baseline", "floor"):
        pct = runs[f]["Controller.pct"]
        assert np.min(pct) >= 3.5 - 1e-12 and np.max(pct) <= 34.0 + 1e-12, f
    assert np.all(runs["floor"]["Controller.pct"] == 3.5)
    assert np.all(runs["none"]["Controller.pct"] == 0.0)
    assert np.all(runs["none"]["Damper.Mjoint"] == 0.0)
    for f in OPTIONS:
        assert np.max(runs[f]["Controller.pct"]) > 3.5 + 1.0, f        # the controllers do act


def test_damping_only_against_the_articulation_motion(lc60):
    """5.1.1: damping applied only when the requested torque opposes the
    articulation angular velocity. The controller's request T (BusDynamics'
    sign: a damping torque has T * artRate >= 0) above the floor must match
    the sign of the measured rate it was computed from (the controller holds
    its output for a 20 ms sample computed from the inputs at its start: the
    rate of that sample instant, up to three 10 ms rows back; at an extremum
    of the angle the rate has turned since, and the one-way valves then give
    no torque). The damper's torque never feeds energy in."""
    runs, _ = lc60
    for f in OPTIONS:
        r = runs[f]
        T, rate, active = r["Controller.T"], r["Bus.artRate[1]"], r["Controller.active"] > 0.5
        rows = np.nonzero(active)[0]
        assert len(rows) > 10, f
        ok = [any(T[i] * rate[j] > 0 for j in (i - 3, i - 2, i - 1, i) if j >= 0) for i in rows]
        assert all(ok), f
        assert np.all(r["Damper.Mjoint"] * rate >= 0), f
        assert np.all(np.diff(r["Damper.Ediss"]) >= -1e-9), f


def test_calibrated_gains_give_the_thesis_peak_damping():
    """5.2.2: each option's gain (DampingGains.ssv, written by `artibus
    calibrate`) makes the peak damping on the 200 m / 100 km/h / rear friction
    0.2 lane change 13.5 %, within 0.05 percentage points."""
    gains = read_parameters(str(damping.GAINS_FILE))
    assert set(damping.GAINS.values()) <= set(gains)
    for f in OPTIONS:
        p = damping.kpis(damping.run(f, "lc200_100"), "lc200_100").peak_pct
        print(f, damping.GAINS[f], gains[damping.GAINS[f]], p)
        assert p == pytest.approx(damping.TARGET_PCT, abs=0.05), f


def test_calibrate_prints_the_gains_next_to_the_thesis(tmp_path):
    """`artibus calibrate --dry-run`: finds the gains again (from the written
    ones), prints them beside 0.130 / 0.565 / 0.605, writes nothing."""
    before = damping.GAINS_FILE.read_bytes()
    r = subprocess.run([sys.executable, "-m", "artibus", "calibrate", "--dry-run"], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert damping.GAINS_FILE.read_bytes() == before
    lines = {ln.split()[0]: ln.split() for ln in r.stdout.splitlines() if ln.split() and ln.split()[0] in ("K1", "K2", "K3", "Krev")}
    assert set(lines) == {"K1", "K2", "K3", "Krev"}
    assert lines["K1"][2] == "0.13" and lines["K2"][2] == "0.565" and lines["K3"][2] == "0.605"
    gains = read_parameters(str(damping.GAINS_FILE))
    for name, row in lines.items():
        assert float(row[1]) == pytest.approx(gains[name], rel=2e-3)
        assert float(row[-2]) == pytest.approx(damping.TARGET_PCT, abs=0.05)


def test_free_sway_without_damping_is_the_plants_rear_sway_mode():
    """No damping, rear friction 0.2, 100 km/h: after the lane change the
    driver lets go (sHold) and the articulation sways freely at the frequency
    and damping ratio of the rear-sway mode of the linear two-body model."""
    r = damping.run("none", "lc60_100", overrides={"Driver.sHold": 95.0})
    t, lam = r.time, r["Bus.artAngle[1]"]
    t0 = float(t[np.argmax(r["Driver.s"] > 100.0)])      # hands off, steering back at straight
    free = lam[t >= t0]
    h = t[1] - t[0]
    f_sim, z_sim = sway_mode(prony(free[::2] - free[-1], 2 * h, 4))
    p = params("Scania18m")
    f_lin, z_lin = sway_mode(linear_modes(p, 100 / 3.6, 1.0, 0.2))
    osc = kpi.oscillation(t, lam, t_from=t0)
    print(f"free sway: simulated {f_sim:.4f} Hz, {z_sim:.4f} (zero crossings: {osc.frequency:.4f} Hz, "
          f"{osc.damping_ratio:.4f}); linear {f_lin:.4f} Hz, {z_lin:.4f}")
    assert f_sim == pytest.approx(f_lin, rel=0.02)
    assert z_sim == pytest.approx(z_lin, abs=0.01)


def _extrema(t, x, above):
    """Indices of the extrema of x with |x| above `above`."""
    d = np.diff(x)
    i = np.nonzero(d[:-1] * d[1:] < 0)[0] + 1
    return i[np.abs(x[i]) > above]


def _ssc_on(r):
    on = r["Baseline.sscActive"] > 0.5
    return float(r.time[np.argmax(on)]) if on.any() else math.nan


def test_baseline_sway_control_never_on_in_the_normal_lane_change():
    """5.2.2: the 200 m / 100 km/h lane change is a normal, low-dynamics one:
    the baseline's damping there is its ground level, 13.5 % at 100 km/h (the
    calibration target); the sway control never switches on."""
    r = damping.run("baseline", "lc200_100")
    assert np.all(r["Baseline.sscActive"] == 0)
    assert np.max(r["Controller.pct"]) == pytest.approx(13.5, abs=0.1)


def test_baseline_sway_control_comes_on_after_the_swings_peak_rate_at_100_kmh():
    """5.2.5: on the 60 m lane change at 100 km/h the sway control 'does not
    activate until certain conditions are met', so the baseline's rear swings
    into the initial overshoot (between the articulation's 2nd and 3rd
    extrema) with a higher rate than option 2's (Fig. 5.17): the sway control
    comes on only after that swing's peak articulation rate ('as late as ...')."""
    r = damping.run("baseline", "lc60_100")
    t, lam, rate = r.time, r["Bus.artAngle[1]"] * DEG, np.abs(r["Bus.artRate[1]"])
    ext = _extrema(t, lam, 1.0)
    swing = (t >= t[ext[1]]) & (t <= t[ext[2]])
    t_peak = float(t[swing][np.argmax(rate[swing])])
    on = _ssc_on(r)
    print("articulation extrema at", t[ext[:4]], "the swing's peak rate at", t_peak, "SSC on at", on)
    assert math.isfinite(on) and on > t_peak


def test_baseline_sway_control_on_for_the_first_overshoot_at_130_kmh():
    """5.2.5: at 130 km/h 'the SSC activate[s] also for the overshoot from the
    first turn (2)': on between the articulation's 1st and 2nd extrema."""
    r = damping.run("baseline", "lc60_130")
    t = r.time
    ext = _extrema(t, r["Bus.artAngle[1]"] * DEG, 1.0)
    on = _ssc_on(r)
    print("articulation extrema at", t[ext[:4]], "SSC on at", on)
    assert t[ext[0]] < on < t[ext[1]]


