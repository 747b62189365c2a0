"""DampingController (seed 001: the thesis's model-based articulation damping)
against numbers derived here: the reference model (eq. 2.9, eq. 2.3) solved
by SciPy, the torque formulas of eqs. 5.3-5.5 and 6.1.3 evaluated here on
errors from the reference's closed form, the direction gate, torque to
percentage through Mmax, the Kc table, sampling, bad input."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from scipy.integrate import solve_ivp

from artibus import runner
from conftest import init

# seed 001, Tables 3.1 and 5.1
F1, B1, B11, F2, B2 = 1.944, 3.306, 5.128, 4.777, 0.163
L1, L2 = F1 + B1, F2 + B2
A = 1 / L1 + (B11 - B1) / (L1 * L2)
CREAR, M2 = 1375760.0, 8556.0
TS = 0.02
KMH = 1 / 3.6


def small_angle(v, lam, d):
    """eq. 2.9"""
    return -(v / L2) * lam + v * A * d


def exact(v, lam, d):
    """eq. 2.3"""
    return (v * math.sin(d) / L1
            - (v * math.cos(d) * math.sin(lam) - v * math.sin(d) * (B11 - B1) * math.cos(lam) / L1) / L2)


def run(fmu, n, h=TS, t0=0.0, **signals):
    """n steps of h from t0; each signal f(t) is set before the step from t.
    Returns {output: array} after each step (the sample at t, as outputs change
    only at the sample instants), and the times t."""
    names = ["pct", "T", "LambdaRef", "LambdaDotRef", "eLambda", "eLambdaDot", "Kc", "active"]
    rows, ts = [], []
    for i in range(n):
        t = t0 + i * h
        fmu.set_values({k: f(t) for k, f in signals.items()})
        fmu.slave.doStep(t, h)
        rows.append(fmu.get(*names))
        ts.append(t)
    out = {k: np.array(c) for k, c in zip(names, zip(*rows))}
    return out, np.array(ts)


def continuous(rhs, v, t_samples, d_samples, lam0=0.0):
    """The continuous model driven by the sampled steering joined linearly
    between the samples (the input the bilinear transform assumes), solved by
    SciPy; returns angle and rate at the samples."""
    d = lambda t: np.interp(t, t_samples, d_samples)
    sol = solve_ivp(lambda t, y: [rhs(v, y[0], float(d(t)))], (t_samples[0], t_samples[-1]), [lam0],
                    t_eval=t_samples, rtol=1e-11, atol=1e-14, max_step=TS / 4)
    lam = sol.y[0]
    return lam, np.array([rhs(v, x, dd) for x, dd in zip(lam, d_samples)])


# ---- the reference model ------------------------------------------------------

@pytest.mark.parametrize("kmh", [50, 100])
@pytest.mark.parametrize("shape", ["step", "ramp"])
def test_reference_model_matches_eq_2_9(open_fmu, kmh, shape):
    """Step and ramp of delta at 50 and 100 km/h: the bilinear (trapezoidal)
    discretisation at 50 Hz against eq. 2.9 solved continuously, within 1 % of
    the response's peak. (Against a continuous model whose steering jumps
    where the sample sees it, the trapezoid is half a sample ahead: 4.7 % of
    the final value at the first sample at 100 km/h, the nature of the
    bilinear transform, not an error.)"""
    v = kmh * KMH
    fmu = open_fmu("DampingController")
    init(fmu, option=0, v=v, v2=v, delta=0.0)
    if shape == "step":
        d = lambda t: 0.02 if t >= 0.2 - 1e-9 else 0.0
    else:
        d = lambda t: 0.01 * min(max(t - 0.2, 0.0), 2.0)
    out, t = run(fmu, 250, delta=d)
    lam, rate = continuous(small_angle, v, t, np.array([d(x) for x in t]))
    assert np.max(np.abs(out["LambdaRef"] - lam)) <= 0.01 * np.max(np.abs(lam))
    assert np.max(np.abs(out["LambdaDotRef"] - rate)) <= 0.01 * np.max(np.abs(rate))
    assert lam[-1] == pytest.approx(A * L2 * d(t[-1]), rel=1e-3)       # the kinematic gain a l2 = 1.288


def test_exact_model_matches_eq_2_3(open_fmu):
    """exactRef: the trapezoidal rule with Newton's method against eq. 2.3
    solved continuously, large angles (delta up to 0.5 rad at 10 m/s)."""
    v = 10.0
    fmu = open_fmu("DampingController")
    init(fmu, option=0, exactRef=True, v=v, v2=v, delta=0.0)
    d = lambda t: 0.5 * math.sin(2 * math.pi * 0.3 * t)
    out, t = run(fmu, 400, delta=d)
    lam, rate = continuous(exact, v, t, np.array([d(x) for x in t]))
    assert np.max(np.abs(lam)) > 0.4
    assert np.max(np.abs(out["LambdaRef"] - lam)) <= 0.002 * np.max(np.abs(lam))
    assert np.max(np.abs(out["LambdaDotRef"] - rate)) <= 0.002 * np.max(np.abs(rate))


def _lane_change_steering(**driver):
    v = 50 * KMH
    r = runner.run("Scania18m_LaneChange", stop_time=8.0, overrides={
        "Driver.laneLength": 25.0, "Driver.vSet": v, "Bus.vx_start": v, "Bus.C[3]": CREAR,
        "Driver.sHold": 1e9, **{f"Driver.{k}": x for k, x in driver.items()}})
    t = np.arange(0.0, 8.0 - 1e-9, TS)
    return v, t, np.interp(t, r.time, r["Driver.delta"])


@pytest.fixture(scope="module")
def lane_change_steering():
    """Seed 001's reference-model case (4.2): lane change 3.25 m over 25 m at
    50 km/h, friction 1 front and rear: the steering of our road-follow driver
    on BusDynamics with the Scania 18 m data (Scania18m_LaneChange with the
    case's numbers, the driver following to the end). Sampled at 50 Hz."""
    return _lane_change_steering()


@pytest.fixture(scope="module")
def thesis_range_steering():
    """The same case with look-ahead times (Driver.tNear 0.3 s, tFar 0.5 s) that
    give about the thesis's steering range (Fig. 4.5's axis, -4..+6 deg; ours
    then about -4.7..+5.8 deg)."""
    return _lane_change_steering(tNear=0.3, tFar=0.5)


def bench_kc():
    """The controller's complementary-gain table as on the bench (Scania18mKc.ssv)."""
    from artibus.bench.parameters import read_parameters
    p = read_parameters("Scania18mKc")
    n = int(p["nKc"])
    return {"nKc": n, **{f"KcSpeed[{i}]": p[f"KcSpeed[{i}]"] for i in range(1, n + 1)},
            **{f"KcGain[{i}]": p[f"KcGain[{i}]"] for i in range(1, n + 1)}}


def exact_vs_small(open_fmu, v, t, delta, kc=None):
    """The FMU's exact and small-angle references on the same steering (with
    kc, the complementary-gain table: delta* = Kc(v) delta drives both, as on
    the bench): deviations relative to the manoeuvre's peak angle and peak
    rate, as the thesis gives them (4.3.1: 'an error of about 0.07 %', 'with
    max articulation angle of ...')."""
    outs = {}
    for ex in (False, True):
        fmu = open_fmu("DampingController")
        init(fmu, option=0, exactRef=ex, v=v, v2=v, delta=0.0, **(kc or {}))
        outs[ex], _ = run(fmu, len(t), delta=lambda s: float(np.interp(s, t, delta)))
    E, S = outs[True], outs[False]
    angle = np.max(np.abs(E["LambdaRef"] - S["LambdaRef"])) / np.max(np.abs(E["LambdaRef"]))
    rate = np.max(np.abs(E["LambdaDotRef"] - S["LambdaDotRef"])) / np.max(np.abs(E["LambdaDotRef"]))
    return E, S, angle, rate


def test_exact_vs_small_angle_on_the_25m_lane_change(open_fmu, lane_change_steering):
    """Our steering on this case spans -6.6..+7.0 deg (the thesis's Fig. 4.5:
    -4..+6 deg), the reference articulation 6.2 deg and 15 deg/s. Each discrete
    reference follows its continuous equation (so the deviation measured is the
    equations', not the discretisation's); the deviation is that of the
    continuous equations; and, as the thesis concludes (4.3.1), it is less than
    the cosine approximation's own error (eq. 2.11) at the largest angle of the
    manoeuvre. Measured (without Kc): angle 0.17 %, rate 0.24 % of their peaks."""
    v, t, delta = lane_change_steering
    E, S, angle, rate = exact_vs_small(open_fmu, v, t, delta)
    lamE, rateE = continuous(exact, v, t, delta)
    lamS, rateS = continuous(small_angle, v, t, delta)
    assert np.max(np.abs(E["LambdaRef"] - lamE)) <= 0.01 * np.max(np.abs(lamE))
    assert np.max(np.abs(S["LambdaRef"] - lamS)) <= 0.01 * np.max(np.abs(lamS))
    angle_c = np.max(np.abs(lamE - lamS)) / np.max(np.abs(lamE))
    rate_c = np.max(np.abs(rateE - rateS)) / np.max(np.abs(rateE))
    assert angle == pytest.approx(angle_c, rel=0.05)
    assert rate == pytest.approx(rate_c, rel=0.05)
    largest = max(np.max(np.abs(delta)), np.max(np.abs(lamE)))
    cos_error = (1 - math.cos(largest)) / math.cos(largest)                # eq. 2.11
    assert 0 < angle < cos_error and 0 < rate < cos_error


#: the tolerance on the thesis's 0.07 / 0.12 %: its steering history is lost (Fig. 4.5 keeps only its
#: axis, -4..+6 deg). The two references differ by terms of second order in the angles, so their
#: difference grows about as the square of the steering amplitude: an amplitude known to about 10 %
#: (the axis's ticks bound it, the curve is lost) gives about 20 % on the figures.
E1_TOLERANCE = 0.20


def test_thesis_exact_vs_small_angle_figures(open_fmu, thesis_range_steering):
    """Seed 001, 4.3.1: about 0.07 % in angle, 0.12 % in rate, with the
    reference models driven as on the bench: delta* = Kc(v) delta, the
    controller's complementary gain (Scania18mKc.ssv: 0.764 at 50 km/h), on a
    steering history in the thesis's range (-4..+6 deg, Fig. 4.5). Within
    E1_TOLERANCE of the thesis's figures; measured 2026-12-03: about 0.075 %
    and 0.117 %. Without Kc the figures are 0.13 / 0.20 % on this steering: Kc
    scales the reference angle down, and with it the second-order terms."""
    v, t, delta = thesis_range_steering
    assert -5.5 < math.degrees(np.min(delta)) < -3.5 and 5.0 < math.degrees(np.max(delta)) < 6.5   # Fig. 4.5
    kc = bench_kc()
    _, _, angle, rate = exact_vs_small(open_fmu, v, t, delta, kc)
    print(f"exact against small angle with Kc: angle {100 * angle:.4f} %, rate {100 * rate:.4f} %")
    assert angle == pytest.approx(0.0007, rel=E1_TOLERANCE)
    assert rate == pytest.approx(0.0012, rel=E1_TOLERANCE)


# ---- torque, gate, percentage -------------------------------------------------

def torque(option, eL, eLd, v2, K1=0.130, K2=0.565, K3=0.605, Krev=80.0):
    T1 = K1 * CREAR * L2 * eL                          # eq. 5.3
    T2 = K2 * CREAR * L2 ** 2 * eLd / v2               # eq. 5.4
    return {1: T1, 2: T2, 3: K3 * (T1 + T2), 4: Krev * M2 * eLd}[option]   # eq. 5.5, 6.1.3


@pytest.mark.parametrize("option", [1, 2, 3, 4])
def test_torque_options_gate_and_percentage(open_fmu, option):
    """delta = 0: from the measured Lambda0 at sample 0 the reference decays as
    the bilinear recursion's closed form LambdaRef_k = Lambda0 rho^k,
    rho = (2 - p Ts)/(2 + p Ts), p = v/l2, LambdaDotRef_k = -p LambdaRef_k.
    Random measured angles, rates, v2 and Mmax: T is the option's formula on
    those errors when it opposes the articulation motion (T LambdaDot > 0),
    else 0; pct = 50 |T|/Mmax within [3.5, 34] %."""
    v, lam0 = 5.0, 0.1
    p = v / L2
    rho = (2 - p * TS) / (2 + p * TS)
    fmu = open_fmu("DampingController")
    init(fmu, option=option, Krev=80.0, v=v, v2=v, delta=0.0, Lambda=lam0, LambdaDot=0.0)
    rng = np.random.default_rng(option)
    gated = opened = 0
    lam, rate, v2, mmax = lam0, 0.0, v, 2.4e4
    for k in range(150):
        if k > 0:                                     # the inputs of sample k
            lam, rate = rng.uniform(-0.15, 0.15), rng.uniform(-0.1, 0.1)
            v2, mmax = rng.uniform(4, 6), rng.uniform(5e3, 5e4)
            fmu.set_values({"Lambda": lam, "LambdaDot": rate, "v2": v2, "Mmax": mmax})
        fmu.slave.doStep(k * TS, TS)
        T, pct, eL, eLd, active = fmu.get("T", "pct", "eLambda", "eLambdaDot", "active")
        if k == 0:                                    # the reference starts at the measurement
            assert eL == 0 and eLd == 0 and T == 0 and pct == 3.5
            continue
        ref = lam0 * rho ** k
        assert eL == pytest.approx(lam - ref, abs=1e-12)
        assert eLd == pytest.approx(rate + p * ref, abs=1e-11)
        want = torque(option, lam - ref, rate + p * ref, v2)
        if want * rate > 0:
            opened += 1
            assert T == pytest.approx(want, rel=1e-9)
            assert pct == pytest.approx(min(max(50 * abs(want) / mmax, 3.5), 34.0), rel=1e-9)
            assert active == (1.0 if 50 * abs(want) / mmax > 3.5 else 0.0)
        else:
            gated += 1
            assert T == 0 and pct == 3.5 and active == 0
    assert gated > 15 and opened > 15


def test_revised_law_start_gain_equals_option_2_at_100_kmh(open_fmu):
    """Krev's start value: K2 Crear l2^2 / (100 km/h m2), so option 4 asks
    the torque of option 2 at 100 km/h (spec: about 80 N.m.s/(kg.rad))."""
    fmu = open_fmu("DampingController")
    krev = float(fmu.var("Krev").start)
    assert krev == pytest.approx(0.565 * CREAR * L2 ** 2 / (100 * KMH * M2), rel=1e-12)
    assert krev == pytest.approx(79.8, abs=0.05)


def test_option_0_and_5(open_fmu):
    """0: the floor only (with pctFloor 0, no damping); 5: pctExternal passed
    through within [pctFloor, pctMax]."""
    fmu = open_fmu("DampingController")
    init(fmu, option=0, pctFloor=0.0, v=20.0, v2=20.0, Lambda=0.1, LambdaDot=0.5)
    out, _ = run(fmu, 20, Lambda=lambda t: 0.1 + 0.5 * t)
    assert np.all(out["pct"] == 0) and np.all(out["T"] == 0)
    fmu.slave.reset()
    init(fmu, option=5, v=20.0, v2=20.0)
    ext = [10.0, 40.0, 2.0, 0.0, 34.0, 20.5]
    out, _ = run(fmu, len(ext), pctExternal=lambda t: ext[int(round(t / TS))])
    assert list(out["pct"]) == [10.0, 34.0, 3.5, 3.5, 34.0, 20.5]
    assert list(out["active"]) == [1, 1, 0, 0, 1, 1]


def test_kc_table(open_fmu):
    """delta* = Kc(v) delta, Kc linear in v between the table's points, held
    beyond its ends; the reference's steady state is a l2 Kc delta."""
    fmu = open_fmu("DampingController")
    table = {"nKc": 3, "KcSpeed[1]": 10.0, "KcSpeed[2]": 20.0, "KcSpeed[3]": 30.0,
             "KcGain[1]": 1.0, "KcGain[2]": 0.8, "KcGain[3]": 0.5}
    for v in (5.0, 10.0, 14.0, 20.0, 27.5, 30.0, 40.0):
        fmu.slave.reset()
        init(fmu, option=0, v=v, v2=v, delta=0.01, **table)
        out, _ = run(fmu, 1000)
        kc = np.interp(v, [10, 20, 30], [1.0, 0.8, 0.5])
        assert out["Kc"][-1] == pytest.approx(kc, rel=1e-14)
        assert out["LambdaRef"][-1] == pytest.approx(A * L2 * kc * 0.01, rel=1e-6)


def test_outputs_change_only_at_sample_instants(open_fmu):
    """Ts = 20 ms: with 10 ms steps the outputs move every second step; with
    100 ms steps (five samples each) they equal the 20 ms run at the same
    instants, bit for bit."""
    def go(h, n):
        fmu = open_fmu("DampingController")
        init(fmu, v=20.0, v2=20.0, delta=0.0)
        sig = dict(delta=lambda t: 0.03 * math.cos(3 * t), Lambda=lambda t: 0.02 * math.sin(2.5 * t),
                   LambdaDot=lambda t: 0.05 * math.cos(2.5 * t))
        rows = []
        for i in range(n):
            t = i * h
            per = round(0.1 / h)
            if i % per == 0:                            # inputs change every 100 ms in both runs
                fmu.set_values({k: f(0.1 * (i // per)) for k, f in sig.items()})
            fmu.slave.doStep(t, h)
            rows.append(fmu.get("LambdaRef", "LambdaDotRef", "pct", "T"))
        return np.array(rows)
    fine = go(0.01, 100)
    moved = np.any(np.diff(fine[:, :2], axis=0) != 0, axis=1)
    assert not np.any(moved[::2]) and np.all(moved[1::2])
    np.testing.assert_array_equal(go(0.02, 50)[4::5], go(0.1, 10))


# ---- bad input ------------------------------------------------------------------

@pytest.mark.parametrize("v", [0.0, -5.0])
def test_standing_or_reversing_gives_the_floor(open_fmu, v):
    """At or below zero speed: no NaN, the reference held at the measured
    values, the floor only; reversing warns once."""
    fmu = open_fmu("DampingController")
    init(fmu, v=20.0, v2=20.0)
    run(fmu, 10)
    fmu.log.clear()
    out, _ = run(fmu, 30, t0=10 * TS, v=lambda t: v, v2=lambda t: v, Lambda=lambda t: 0.2 + t,
                 LambdaDot=lambda t: 1.0, delta=lambda t: 0.3)
    for k, x in out.items():
        assert np.all(np.isfinite(x)), k
    assert np.all(out["pct"] == 3.5) and np.all(out["T"] == 0) and np.all(out["eLambdaDot"] == 0)
    assert np.all(out["LambdaDotRef"] == 1.0)
    warnings = [m for m in fmu.log if "[Warning]" in m and "v = " in m]
    assert len(warnings) == (1 if v < 0 else 0), fmu.log


@pytest.mark.parametrize("name,value", [("pctMax", 60.0), ("pctFloor", -1.0), ("pctExternal", 51.0),
                                        ("pctAtMmax", 0.0), ("Mmax", -1.0)])
def test_percentage_limits_out_of_range_are_refused(open_fmu, name, value):
    fmu = open_fmu("DampingController")
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        fmu.set_values({name: value})
    assert any(name in m for m in fmu.log)


def test_floor_above_the_limit_is_refused(open_fmu):
    fmu = open_fmu("DampingController")
    with pytest.raises(FMICallException):
        init(fmu, pctFloor=20.0, pctMax=10.0)
    assert any("pctFloor = 20" in m for m in fmu.log)


def test_kc_speeds_not_increasing_are_refused(open_fmu):
    fmu = open_fmu("DampingController")
    with pytest.raises(FMICallException):
        init(fmu, nKc=2, **{"KcSpeed[1]": 10.0, "KcSpeed[2]": 10.0})
    assert any("KcSpeed" in m for m in fmu.log)


def test_run_alone_requests_the_floor(open_fmu):
    """The start values (2 m/s, delta 0.1 rad, Lambda and LambdaDot 0): the
    reference articulation rises towards a l2 delta with time constant l2/v,
    the measured one does not move, the gate stays closed: pct = pctFloor."""
    fmu = open_fmu("DampingController")
    init(fmu)
    out, t = run(fmu, 500)
    assert np.all(out["pct"] == 3.5) and np.all(out["active"] == 0)
    lam, _ = continuous(small_angle, 2.0, t, np.full(len(t), 0.1))
    assert np.max(np.abs(out["LambdaRef"] - lam)) < 1e-3 * A * L2 * 0.1
