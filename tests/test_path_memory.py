"""TrainGuidance, mode = pathMemory (issue 6, beyond the paper): A4 and A6
follow the dead-reckoned, stored trace of A2 at their own arc-length position.

- with BusDynamics on the bench Bus36m_Circle, variant guidedForceMin (guidance +
  force minimisation, 17.5 m circle at 3 m/s, entry and exit): the max
  deviation of A4 and A6 from the A2 trace (kpi.trace_deviation on the
  simulated traces) below 1.0 m over the whole manoeuvre and below the arc-lag
  mode's figure on the same bench; the first hinge's lateral force below 4 kN;
- the kinematic check with BusKinematics (the 36 m bus's kinematic chain, as
  in test_steering_controllers_benches.py): A4 and A6 on the A2 circle in
  steady state, left and right; and on the A2 trace through entry and exit;
- v = 0, bad input, FMU state with the trace in it.

Every reference is computed here from the simulated traces (circle fits, the
traces' polylines), not taken from the controller.
"""
import math

import numpy as np
import pytest

from artibus import runner
from artibus.bench import ssp
from artibus.study import kpi
from conftest import init
from test_steering_controllers_benches import H, KIN_36M, L1, fit_circle, opened

BENCH, VARIANT = "Bus36m_Circle", "guidedForceMin"
AXLES = ["Bus.xAxle[2]", "Bus.yAxle[2]", "Bus.xAxle[4]", "Bus.yAxle[4]", "Bus.xAxle[6]", "Bus.yAxle[6]"]
#: the circle of the bench (front corner on 17.5 m, A2 on about 15 m) runs for
#: A2's arc length s from 25 m to 25 + 2 pi 17.5 m = 135 m; A6 (24.4 m behind
#: A2) is on it and settled from s = 75 m
STEADY = (75.0, 130.0)


def bench_figures(mode):
    r = runner.run(BENCH, overrides={**ssp.variant_overrides(BENCH, [VARIANT]), "Guidance.mode": mode},
                   record=AXLES + ["Bus.FjointY[1]", "Bus.FjointY[2]", "Driver.s", "Guidance.fault"])
    # every 5th sample: 15 cm apart at 3 m/s (chord error on the circle < 0.3 mm)
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in (2, 4, 6)}
    s = r["Driver.s"][::5]
    steady = (s > STEADY[0]) & (s < STEADY[1])
    f = {"F1": kpi.peak(r["Bus.FjointY[1]"]), "F2": kpi.peak(r["Bus.FjointY[2]"]), "s_end": s[-1],
         "faults": set(np.unique(r["Guidance.fault"]).astype(int))}
    for a in (4, 6):
        d, inside = kpi.lateral_distance(*ax[2], *ax[a])
        f[f"A{a} peak"] = kpi.trace_deviation(*ax[2], *ax[a])
        assert f[f"A{a} peak"] == pytest.approx(np.max(np.abs(d[inside])))
        f[f"A{a} steady"] = float(np.max(np.abs(d[inside & steady])))
    return f


@pytest.fixture(scope="module")
def bench():
    return {mode: bench_figures(mode) for mode in (0, 1)}


def test_path_memory_on_the_dynamic_bench_beats_the_arc_lag(bench):
    """Issue 6: with BusDynamics, guidance + force minimisation, mode = 1:
    A4 and A6 within 1.0 m of the A2 trace over the whole manoeuvre (entry
    and exit included), below the arc-lag mode's figure on the same bench;
    the first hinge's lateral force below 4 kN."""
    arc, pm = bench[0], bench[1]
    for name, f in (("arcLag", arc), ("pathMemory", pm)):
        print(f"{name}: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                                      for k, v in f.items()))
    assert pm["s_end"] > 25 + 2 * math.pi * 17.5             # it went all the way round and out
    for a in (4, 6):
        assert pm[f"A{a} peak"] < 1.0
        assert pm[f"A{a} peak"] < arc[f"A{a} peak"]
        assert pm[f"A{a} steady"] <= pm[f"A{a} peak"]
    assert pm["F1"] < 4000.0 and pm["F2"] < 4000.0
    assert not pm["faults"] & {1, 16}                         # no bad input, never lost the trace


# ---- BusKinematics ------------------------------------------------------------

def kinematic_run(gamma1_of_s, length, v=5.0, mode=1, kin_extra=None, tg_extra=None, bias=0.0):
    """BusKinematics (36 m chain) with TrainGuidance in the loop (10 ms; the
    controller's outputs of the last sample applied over the next step), the
    articulation angles measured as the differences of the segments' headings.
    gamma1 is a function of the distance driven by A2 (the ECU's gamma1
    sensor reads it plus `bias`). Returns the poses of
    A2, A4, A6, the headings, the guidance's outputs per step."""
    kin = opened("BusKinematics", dict(KIN_36M, v=v, **(kin_extra or {})))
    tg = opened("TrainGuidance", dict({"testSteerAmp": 0.0, "v": v, "gamma1": gamma1_of_s(0.0),
                                       "mode": mode}, **(tg_extra or {})))
    rows = []
    try:
        n = int(round(length / v / H))
        for i in range(n):
            t = i * H
            g1 = gamma1_of_s(v * t)
            th0, th1, th2 = kin.get("theta[0]", "theta[1]", "theta[2]")
            g4, g6, e4, e6, fault = tg.get("gamma4", "gamma6", "e4", "e6", "fault")
            kin.set_values({"gammaF": g1, "gamma[1]": g4, "gamma[2]": g6})
            tg.set_values({"gamma1": g1 + bias, "dPsi[1]": th0 - th1, "dPsi[2]": th1 - th2})
            kin.slave.doStep(t, H)
            tg.slave.doStep(t, H)
            rows.append(kin.get("x[0]", "y[0]", "x[1]", "y[1]", "x[2]", "y[2]") + [g4, g6, e4, e6, fault])
    finally:
        kin.close()
        tg.close()
    return np.array(rows)


@pytest.mark.parametrize("side", [1, -1], ids=["left", "right"])
@pytest.mark.parametrize("R2", [12.0, 17.5, 30.0, 100.0])
def test_kinematic_check_path_memory_A4_A6_on_the_circle_of_A2(R2, side):
    """Issue 6's kinematic check for mode 1: straight 20 m, then
    gamma1 = atan(l1/R2) for two laps; over the last half lap A4 and A6 are on
    the circle of A2 within 1 cm."""
    gamma1 = math.atan(L1 / (side * R2))
    lap = 2 * math.pi * R2
    p = kinematic_run(lambda s: gamma1 if s >= 20.0 else 0.0, 20.0 + 2 * lap)
    steady = p[-int(round(0.5 * lap / 5.0 / H)):]
    cx, cy, R = fit_circle(steady[:, 0], steady[:, 1])
    assert R == pytest.approx(R2, rel=1e-4)
    for i, axle in ((1, "A4"), (2, "A6")):
        dev = np.hypot(steady[:, 2 * i] - cx, steady[:, 2 * i + 1] - cy) - R
        print(f"R2 = {side * R2}: {axle} {np.max(np.abs(dev)) * 1000:.2f} mm off the A2 circle")
        assert np.max(np.abs(dev)) < 0.01, f"{axle}: {np.max(np.abs(dev)):.4f} m off the A2 circle"
    assert np.all(np.sign(steady[:, 6]) == -side) and np.all(np.sign(steady[:, 7]) == -side)  # opposite to A1


def s_curve(s):
    """straight 20 m, left on R2 = 15 m for 40 m, right on R2 = 20 m for 40 m, straight"""
    if s < 20:
        return 0.0
    if s < 60:
        return math.atan(L1 / 15.0)
    if s < 100:
        return -math.atan(L1 / 20.0)
    return 0.0


def test_kinematic_path_memory_follows_the_A2_trace_through_entry_and_exit():
    """The whole manoeuvre (entry, a left and a right turn, exit) in the
    kinematic model: with exact odometry the follow-the-leader keeps A4 and A6
    within 3 cm of the A2 trace everywhere; the arc-lag mode on the same path
    leaves them decimetres off (the check can fail)."""
    dev = {}
    for mode in (0, 1):
        p = kinematic_run(s_curve, 150.0, mode=mode)
        dev[mode] = [kpi.trace_deviation(p[::5, 0], p[::5, 1], p[::5, 2 * i], p[::5, 2 * i + 1]) for i in (1, 2)]
        print(f"mode {mode}: A4 {dev[mode][0]:.4f} m, A6 {dev[mode][1]:.4f} m from the A2 trace")
    assert max(dev[1]) < 0.03
    assert min(dev[0]) > 0.1


def test_kinematic_path_memory_starting_articulated_in_a_curve():
    """A start in the middle of a steady circle (BusKinematics started with
    the articulation it settles to on R2 = 20 m, measured in a first run): the
    trace is seeded from the bus as it stands (arcs through A2, A4, A6), so
    A4 and A6 are on the A2 circle from the first metre on, within 1 cm."""
    R2 = 20.0
    gamma1 = math.atan(L1 / R2)
    kin = opened("BusKinematics", dict(KIN_36M, v=5.0))
    tg = opened("TrainGuidance", {"testSteerAmp": 0.0, "v": 5.0, "mode": 1})
    try:   # settle on the circle, from straight
        for i in range(int(2 * 2 * math.pi * R2 / 5.0 / H)):
            th0, th1, th2 = kin.get("theta[0]", "theta[1]", "theta[2]")
            g4, g6 = tg.get("gamma4", "gamma6")
            kin.set_values({"gammaF": gamma1, "gamma[1]": g4, "gamma[2]": g6})
            tg.set_values({"gamma1": gamma1, "dPsi[1]": th0 - th1, "dPsi[2]": th1 - th2})
            kin.slave.doStep(i * H, H)
            tg.slave.doStep(i * H, H)
        th0, th1, th2 = kin.get("theta[0]", "theta[1]", "theta[2]")
    finally:
        kin.close()
        tg.close()
    b1, b2 = th0 - th1, th1 - th2
    assert b1 > 0.3 and b2 > 0.3
    p = kinematic_run(lambda s: gamma1, 30.0, kin_extra={"beta_start[1]": b1, "beta_start[2]": b2},
                      tg_extra={"gamma1": gamma1, "dPsi[1]": b1, "dPsi[2]": b2})
    cx, cy, R = fit_circle(p[:, 0], p[:, 1])
    assert R == pytest.approx(R2, rel=1e-4)
    for i, axle in ((1, "A4"), (2, "A6")):
        dev = np.hypot(p[:, 2 * i] - cx, p[:, 2 * i + 1] - cy) - R
        print(f"start in the curve: {axle} at most {np.max(np.abs(dev)) * 1000:.2f} mm off the A2 circle")
        assert np.max(np.abs(dev)) < 0.01
    assert np.all(p[:, 10] == 0)                               # no fault


def test_odometry_drift_from_a_biased_steering_sensor():
    """How the dead reckoning degrades (guidance.h): the ECU's gamma1 reads
    0.5 deg too much while the bus drives straight. The stored trace is bent
    with the curvature error dk = tan(bias)/l1 relative to the bus: an axle the
    arc s behind A2 would sit dk s^2 / 2 off the real trace, less dk s / kPath
    because the bent estimate turns under the bus (dk v) and the feedback keeps
    an estimated offset of -dk s / kPath to follow it: dk (s^2/2 - s/kPath),
    s = lg1 + l2 = 12.2 m for A4, twice that for A6. It does not grow with the
    distance driven, only with the distance A2-axle squared."""
    bias = 0.5 * math.pi / 180
    p = kinematic_run(lambda s: 0.0, 200.0, bias=bias)
    dk = math.tan(bias) / L1
    kpath = 0.5                                                   # the default
    for i, s_axle in ((1, 3.15 + 9.05), (2, 2 * (3.15 + 9.05))):
        expected = dk * (s_axle ** 2 / 2 - s_axle / kpath)
        off_mid, off_end = abs(p[len(p) // 2, 2 * i + 1]), abs(p[-1, 2 * i + 1])   # A2 runs on y = 0
        print(f"A{2 + 2 * i}: {off_end:.3f} m off the trace, dk (s^2/2 - s/kPath) = {expected:.3f} m")
        assert off_end == pytest.approx(expected, rel=0.1)
        assert off_end == pytest.approx(off_mid, rel=0.02)                # bounded, not growing
    # and with the sensor right, the same run stays on the line
    p0 = kinematic_run(lambda s: 0.0, 60.0)
    assert np.max(np.abs(p0[:, [3, 5]])) < 1e-9                   # y of A4, A6


def test_backwards_uses_the_mirrored_hinges_and_reseeds(open_fmu):
    """Backwards the leading module sees G2 first, as -dPsi[2], then G1 as
    -dPsi[1] (as in ForceMinimization): the same outputs as forwards with the
    chain's angles in that order; changing direction re-seeds the trace."""
    def run(backwards, d1, d2):
        tg = open_fmu("TrainGuidance")
        init(tg, testSteerAmp=0.0, mode=1, v=3.0, backwards=backwards, **{"dPsi[1]": d1, "dPsi[2]": d2})
        out = []
        for i in range(300):
            t = i * H
            tg.set_values({"gamma1": 0.2 * math.sin(t)})
            tg.slave.doStep(t, H)
            out.append(tg.get("gamma4", "gamma6", "e4", "e6"))
        return np.array(out), tg
    back, tg = run(True, 0.15, -0.25)
    fwd, _ = run(False, 0.25, -0.15)
    np.testing.assert_array_equal(back, fwd)
    tg.set_values({"backwards": False})
    tg.slave.doStep(3.0, H)
    e4, e6 = tg.get("e4", "e6")
    assert abs(e4) < 1e-5 and abs(e6) < 1e-5                  # re-seeded from the bus as it stands


@pytest.mark.parametrize("mode", [0, 1])
def test_standing_still_nothing_moves(open_fmu, mode):
    """v = 0: no motion, nothing recorded, the outputs hold, whatever gamma1
    and the articulation angles do."""
    tg = open_fmu("TrainGuidance")
    init(tg, testSteerAmp=0.0, mode=mode, v=3.0, gamma1=0.2)
    for i in range(100):
        tg.slave.doStep(i * H, H)
    held = tg.get("gamma4", "gamma6", "e4", "e6")
    tg.set_values({"v": 0.0})
    for i in range(100, 400):
        tg.set_values({"gamma1": 0.3 * math.sin(i / 20), "dPsi[1]": 0.1 * math.cos(i / 30)})
        tg.slave.doStep(i * H, H)
    assert tg.get("gamma4", "gamma6", "e4", "e6") == held
    assert tg.get("fault")[0] == 0


def test_path_memory_left_and_right_are_mirror_images(open_fmu):
    """The same manoeuvre mirrored (gamma1 and the articulation angles
    negated): the outputs are negated, to rounding."""
    def run(sign):
        tg = open_fmu("TrainGuidance")
        init(tg, testSteerAmp=0.0, mode=1, v=4.0)
        out = []
        for i in range(600):
            t = i * H
            tg.set_values({"gamma1": sign * 0.3 * math.sin(t / 2), "dPsi[1]": sign * 0.2 * math.sin(t / 2 - 0.5),
                           "dPsi[2]": sign * 0.2 * math.sin(t / 2 - 1.0)})
            tg.slave.doStep(t, H)
            out.append(tg.get("gamma4", "gamma6", "e4", "e6"))
        return np.array(out)
    a, b = run(1), run(-1)
    np.testing.assert_allclose(a, -b, atol=1e-9)
    assert np.max(np.abs(a[:, :2])) > 0.05


@pytest.mark.parametrize("serialize", [False, True])
def test_path_memory_state_round_trip(open_fmu, serialize):
    """The stored trace is part of the FMU state: restored, the run repeats
    bit for bit."""
    tg = open_fmu("TrainGuidance")
    init(tg, testSteerAmp=0.0, mode=1, v=3.0)

    def advance(t0, n=300):
        rows = []
        for i in range(n):
            t = t0 + i * H
            tg.set_values({"gamma1": 0.25 * math.sin(t), "dPsi[1]": 0.1 * math.sin(t - 0.7),
                           "dPsi[2]": 0.1 * math.sin(t - 1.4)})
            tg.slave.doStep(t, H)
            rows.append(tg.get("gamma4", "gamma6", "e4", "e6"))
        return np.array(rows)
    advance(0.0)
    state = tg.slave.getFMUstate()
    if serialize:
        state = tg.slave.deSerializeFMUstate(tg.slave.serializeFMUstate(state))
    first = advance(3.0)
    tg.slave.setFMUstate(state)
    second = advance(3.0)
    tg.slave.freeFMUstate(state)
    assert np.array_equal(first, second)
    assert np.ptp(first[:, 0]) > 0.01


def warnings(fmu):
    return [line for line in fmu.log if line.startswith("[Warning]")]


def test_path_memory_bad_input_holds_and_warns_once_per_episode(open_fmu):
    """v < 0: held, one warning per episode; absurd steering and a jack-knifed
    articulation: finite and within the limits; a sample longer than the
    trace buffer allows: re-seeded, one warning."""
    tg = open_fmu("TrainGuidance")
    init(tg, testSteerAmp=0.0, mode=1, v=3.0, gamma1=0.1)
    t = 0.0

    def steps(n, **inputs):
        nonlocal t
        tg.set_values(inputs)
        for _ in range(n):
            tg.slave.doStep(t, H)
            t += H
        return tg.get("gamma4", "gamma6", "e4", "e6", "fault")
    steps(100)
    held = tg.get("gamma4", "gamma6")
    out = steps(30, v=-1.0)
    assert out[:2] == held and out[4] == 2
    assert len(warnings(tg)) == 1
    steps(10, v=3.0)
    steps(10, v=-0.5)
    assert len(warnings(tg)) == 2
    for g1, d1, d2 in ((1.5, 0.0, 0.0), (-1.5, 3.0, -3.0), (0.0, 1.6, 1.6), (0.5, -3.1, 3.1)):
        out = steps(50, v=3.0, gamma1=g1, **{"dPsi[1]": d1, "dPsi[2]": d2})
        assert all(math.isfinite(x) for x in out)
        assert abs(out[0]) <= 0.75 and abs(out[1]) <= 0.75
    n = len(warnings(tg))
    out = steps(3, v=1e6, gamma1=0.0, **{"dPsi[1]": 0.0, "dPsi[2]": 0.0})   # 10 km per sample
    assert int(out[4]) & 16 and all(math.isfinite(x) for x in out)
    assert len(warnings(tg)) == n + 1
