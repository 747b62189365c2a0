"""RoadFollowDriver (seed 001, ch. 3.2) in closed loop and against geometry
derived here: the roads' own analytic shapes (not the FMU's road table), a
kinematic single-track car written in this file, and BusKinematics."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from artibus import fmu_path
from artibus.bench import roads
from artibus.fmu import Fmu

V50 = 50 / 3.6
CAR = dict(L0=2.7, refX=2.7, refY=0.0)          # the test double's wheelbase
BEFORE, AFTER = 25.0, 50.0                      # the driver's default straights
DELTA_MAX, RATE_MAX, TS = 0.8727, 0.5, 0.02     # the driver's default limits and sample time


# ---- the roads' analytic shapes, written here from their definitions ---------

def lane_change_y(x, L=25.0, A=3.25, x0=BEFORE):
    u = np.clip((x - x0) / L, 0.0, 1.0)
    return A / 2 * (1 - np.cos(np.pi * u))


def iso_y(x, b=2.55, x0=BEFORE):
    """ISO 3888-1: sections of 15, 30, 25, 25, 15 m; side lane centre 3.5 m +
    half the difference of the lane widths (b + 1) and (1.1 b + 0.25) left."""
    y3 = 3.5 + ((b + 1) - (1.1 * b + 0.25)) / 2
    up = y3 / 2 * (1 - np.cos(np.pi * np.clip((x - x0 - 15) / 30, 0, 1)))
    down = y3 / 2 * (1 - np.cos(np.pi * np.clip((x - x0 - 70) / 25, 0, 1)))
    return up - down


def lateral_error_y_of_x(px, py, yfun):
    """signed distance (left > 0) of points to the curve y = f(x), by a dense
    local search on the curve"""
    out = np.empty(len(px))
    for k, (a, b) in enumerate(zip(px, py)):
        xs = np.linspace(a - 6, a + 6, 2401)
        ys = yfun(xs)
        i = np.argmin((xs - a) ** 2 + (ys - b) ** 2)
        i = min(max(i, 1), len(xs) - 2)
        tx, ty = xs[i + 1] - xs[i - 1], ys[i + 1] - ys[i - 1]
        d = math.hypot(a - xs[i], b - ys[i])
        out[k] = math.copysign(d, tx * (b - ys[i]) - ty * (a - xs[i]))
    return out


# ---- the driver with a kinematic single-track car (test double) --------------

def car_step(x, y, psi, v, delta, L0, h):
    """the kinematic single-track car over h with delta held: an exact arc of
    curvature tan(delta) / L0 travelled by the rear axle mid-point"""
    kappa = math.tan(delta) / L0
    dpsi = v * h * kappa
    if abs(dpsi) < 1e-9:
        return x + v * h * math.cos(psi), y + v * h * math.sin(psi), psi + dpsi
    return (x + (math.sin(psi + dpsi) - math.sin(psi)) / kappa,
            y - (math.cos(psi + dpsi) - math.cos(psi)) / kappa, psi + dpsi)


def drive_car(road, params, v=V50, start=(0.0, 0.0, 0.0), stop=None, h=TS, mirror=False):
    """Closed loop: driver -> delta -> car; car's rear axle pose and speed ->
    driver. The car: x' = v cos psi, y' = v sin psi, psi' = v tan(delta) / L0
    (exact arcs over each sample). Returns arrays over time."""
    L0 = params.get("L0", CAR["L0"])
    x, y, psi = start
    rows = []
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"road": road, "testVehicle": False, **params, "x": x, "y": y, "psi": psi,
                      "v": v, "chiF": 0.0})
        d.slave.exitInitializationMode()
        t = 0.0
        while True:
            delta, s, eLat = d.get("delta", "s", "eLat")
            finished = d.slave.getBoolean([d.var("finished").valueReference])[0]
            rows.append((t, x, y, psi, delta, s, eLat))
            if finished or (stop is not None and t >= stop):
                break
            assert t < 200, "the car never reached the end of the road"
            x, y, psi = car_step(x, y, psi, v, delta, L0, h)
            d.set_values({"x": x, "y": y, "psi": psi, "v": v, "chiF": delta})
            d.slave.doStep(t, h)
            t += h
    a = np.array(rows)
    return {k: a[:, i] for i, k in enumerate(("t", "x", "y", "psi", "delta", "s", "eLat"))}


def front_point(r, L0):
    return r["x"] + L0 * np.cos(r["psi"]), r["y"] + L0 * np.sin(r["psi"])


def assert_steering_within_limits(delta):
    assert np.all(np.abs(delta) <= DELTA_MAX + 1e-12)
    assert np.all(np.abs(np.diff(delta)) <= RATE_MAX * TS * (1 + 1e-9))


# ---- acceptance: each built-in road at 50 km/h -------------------------------

def test_car_lane_change_50kmh():
    r = drive_car(1, CAR)
    px, py = front_point(r, CAR["L0"])
    e = lateral_error_y_of_x(px, py, lane_change_y)
    assert np.max(np.abs(e)) < 0.3, np.max(np.abs(e))
    assert_steering_within_limits(r["delta"])
    # it went left by 3.25 m and drove on straight
    assert py[-1] == pytest.approx(3.25, abs=0.05)
    assert px[-1] >= BEFORE + 25 + AFTER - 0.5


def test_car_iso3888_50kmh():
    r = drive_car(3, CAR)
    px, py = front_point(r, CAR["L0"])
    e = lateral_error_y_of_x(px, py, iso_y)
    assert np.max(np.abs(e)) < 0.3, np.max(np.abs(e))
    assert_steering_within_limits(r["delta"])
    assert py.max() == pytest.approx(3.5 + ((2.55 + 1) - (1.1 * 2.55 + 0.25)) / 2, abs=0.3)


@pytest.mark.parametrize("R", [17.5, -17.5])
def test_car_full_circle_50kmh(R):
    """360 deg round the circle of centre (25, R) and out along y = 0 again.
    Outside the transitions: more than 5 m of travel from the circle's entry
    and exit, where the curvature jumps and the steering rate limit rules."""
    r = drive_car(2, {**CAR, "R": R})
    px, py = front_point(r, CAR["L0"])
    travel = np.concatenate([[0], np.cumsum(np.hypot(np.diff(px), np.diff(py)))])
    on_circle = (travel > BEFORE + 5) & (travel < BEFORE + 2 * math.pi * abs(R) - 5)
    e_circle = abs(R) - np.hypot(px - BEFORE, py - R)          # > 0 inside
    assert np.max(np.abs(e_circle[on_circle])) < 0.3, np.max(np.abs(e_circle[on_circle]))
    after = travel > BEFORE + 2 * math.pi * abs(R) + 5
    assert after.sum() > 50
    assert np.max(np.abs(py[after])) < 0.3, np.max(np.abs(py[after]))
    before = travel < BEFORE - 5
    assert np.max(np.abs(py[before])) < 0.3
    assert_steering_within_limits(r["delta"])
    # it turned the full 360 deg: the heading gained 2 pi (sign of R), and left along +x
    assert r["psi"][-1] == pytest.approx(math.copysign(2 * math.pi, R), abs=0.05)
    assert px[-1] > BEFORE + AFTER - 1


# ---- acceptance: BusKinematics, Urbino 18, 17.5 m circle at 3 m/s -----------

URBINO = {"N": 1, "k": 1, "L0": 5.9, "Lh[1]": 1.789, "L[1]": 4.211, "testSteerAmp": 0.0}


def drive_bus(driver_params, v=3.0, h=0.05, after=30.0):
    """driver delta -> BusKinematics gammaF; BusKinematics pose of segment 0 -> driver"""
    rows = []
    with Fmu(fmu_path("RoadFollowDriver")) as d, Fmu(fmu_path("BusKinematics")) as b:
        b.slave.setupExperiment(startTime=0.0)
        b.slave.enterInitializationMode()
        b.set_values({**URBINO, "gammaF": 0.0, "v": v})
        b.slave.exitInitializationMode()
        x0, y0, th0 = b.get("x[0]", "y[0]", "theta[0]")
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"road": 2, "R": 17.5, "roadAfter": after, "testVehicle": False,
                      "L0": 5.9, **driver_params, "x": x0, "y": y0, "psi": th0, "v": v})
        d.slave.exitInitializationMode()
        t = 0.0
        while True:
            delta, eLat = d.get("delta", "eLat")
            finished = d.slave.getBoolean([d.var("finished").valueReference])[0]
            x0, y0, th0 = b.get("x[0]", "y[0]", "theta[0]")
            rows.append((t, x0, y0, th0, delta, eLat))
            if finished:
                break
            assert t < 120, "the bus never reached the end of the road"
            b.set_values({"gammaF": delta})
            b.slave.doStep(t, h)
            d.set_values({"x": x0, "y": y0, "psi": th0, "v": v, "chiF": delta})
            d.slave.doStep(t, h)
            t += h
    a = np.array(rows)
    return {k: a[:, i] for i, k in enumerate(("t", "x", "y", "psi", "delta", "eLat"))}


def test_bus_kinematics_urbino_follows_the_17_5_m_circle():
    r = drive_bus({"refX": 5.9, "refY": 0.0})
    px, py = r["x"] + 5.9 * np.cos(r["psi"]), r["y"] + 5.9 * np.sin(r["psi"])   # front axle
    # the front axle starts on the entry straight at x = L0: travel counts from the road's start
    travel = px[0] + np.concatenate([[0], np.cumsum(np.hypot(np.diff(px), np.diff(py)))])
    circle_end = BEFORE + 2 * math.pi * 17.5
    on_circle = (travel > BEFORE + 5) & (travel < circle_end - 1)
    e = 17.5 - np.hypot(px - BEFORE, py - 17.5)
    err = np.max(np.abs(e[on_circle]))
    assert err < 0.10, err
    # the steady steering angle of a front axle on radius R: sin(delta) = L0 / R
    mid = (travel > BEFORE + 40) & (travel < circle_end - 20)
    assert np.median(r["delta"][mid]) == pytest.approx(math.asin(5.9 / 17.5), abs=0.01)
    # out onto the straight y = 0, heading 2 pi, within 0.1 m once settled
    straight = travel > circle_end + 10
    assert straight.sum() > 20
    assert np.max(np.abs(py[straight])) < 0.10, np.max(np.abs(py[straight]))
    assert r["psi"][-1] == pytest.approx(2 * math.pi, abs=0.02)
    print(f"BusKinematics circle: max |e| on circle {err:.4f} m, "
          f"on exit straight {np.max(np.abs(py[straight])):.4f} m")


def test_bus_kinematics_outermost_front_corner_on_the_circle():
    """seed 000: the outermost front point is guided round the 17.5 m circle.
    Urbino 18 front corner: front overhang 2.7 m ahead of the front axle (our
    assumption), half width 1.275 m; in a left turn the outer corner is the
    right one. The corner point is derived here from the rear axle pose."""
    a, b = 5.9 + 2.7, -1.275
    r = drive_bus({"refX": a, "refY": b})
    c, s = np.cos(r["psi"]), np.sin(r["psi"])
    px, py = r["x"] + a * c - b * s, r["y"] + a * s + b * c
    travel = px[0] + np.concatenate([[0], np.cumsum(np.hypot(np.diff(px), np.diff(py)))])
    circle_end = BEFORE + 2 * math.pi * 17.5
    on_circle = (travel > BEFORE + 5) & (travel < circle_end - 1)
    e = 17.5 - np.hypot(px - BEFORE, py - 17.5)
    err = np.max(np.abs(e[on_circle]))
    assert err < 0.10, err
    # the front axle then runs inside the circle: on radius sqrt((R^2 - ...)) < R
    fx, fy = r["x"] + 5.9 * c, r["y"] + 5.9 * s
    mid = (travel > BEFORE + 40) & (travel < circle_end - 20)
    assert np.all(np.hypot(fx[mid] - BEFORE, fy[mid] - 17.5) < 17.5 - 1.0)
    print(f"outermost corner on circle: max |e| {err:.4f} m")


def test_speed_control_pi_with_limits_and_anti_windup():
    """a point mass m v' = Fx, m = 18000 kg, from standstill: first at the
    force limit (v = FxMax / m t), then at vSet without wind-up overshoot"""
    m, h = 18000.0, 0.02
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"testVehicle": False, "v": 0.0})
        d.slave.exitInitializationMode()
        v, t, rows = 0.0, 0.0, []
        while t < 30.0 - 1e-9:
            Fx, vRef = d.get("Fx", "vRef")
            rows.append((t, v, Fx, vRef))
            v += Fx / m * h
            d.set_values({"v": v})
            d.slave.doStep(t, h)
            t += h
    a = np.array(rows)
    t, v, Fx, vRef = a.T
    assert np.all(vRef == pytest.approx(50 / 3.6))
    assert np.all((Fx >= -60000.0) & (Fx <= 30000.0))
    k = np.searchsorted(t, 4.0)
    assert v[k] == pytest.approx(30000.0 / m * 4.0, rel=0.02)       # saturated: constant acceleration
    assert v.max() < 50 / 3.6 + 0.3                                   # no wind-up overshoot
    assert abs(v[-1] - 50 / 3.6) < 0.01


def test_steering_limits_hold_with_a_longer_communication_step():
    """h = 0.05 s over Ts = 0.02 s: 2 or 3 samples per step, each within the
    rate limit (0.15 rad/s: the lane change at 50 km/h reaches it)"""
    r = drive_car(1, {**CAR, "deltaRateMax": 0.15}, h=0.05)
    d = np.abs(np.diff(r["delta"]))
    assert d.max() <= 0.15 * 0.02 * 3 * (1 + 1e-9)
    assert d.max() > 0.15 * 0.02 * 2 * (1 + 1e-9), "the rate limit was never reached: the test cannot fail"
    px, py = front_point(r, CAR["L0"])
    assert py[-1] == pytest.approx(3.25, abs=0.05)


def test_under_steer_compensation_restores_the_ideal_path():
    """A car whose front axle moves at only 80 % of the steering angle (an
    under-steering plant: chiF = 0.8 delta). The compensation (seed 001, 3.2.1)
    with kUS = 1 commands delta + (delta - chiF) = 1.25 x the wanted angle in a
    steady turn, so the front axle moves as the wanted angle says: the path is
    that of the ideal car (chiF = delta) without compensation, and closer to it
    than the under-steering car's path without compensation."""
    def radius_error(gain, kUS):
        L0, v, h = CAR["L0"], V50, TS
        x = y = psi = 0.0
        errs = []
        with Fmu(fmu_path("RoadFollowDriver")) as d:
            d.slave.setupExperiment(startTime=0.0)
            d.slave.enterInitializationMode()
            d.set_values({"road": 2, "testVehicle": False, **CAR, "kUS": kUS, "v": v})
            d.slave.exitInitializationMode()
            t = 0.0
            while t < 7.0:
                chi = gain * d.get("delta")[0]
                x, y, psi = car_step(x, y, psi, v, chi, L0, h)
                d.set_values({"x": x, "y": y, "psi": psi, "v": v, "chiF": chi})
                d.slave.doStep(t, h)
                t += h
                fx, fy = x + L0 * math.cos(psi), y + L0 * math.sin(psi)
                if t > 4.0:
                    errs.append(17.5 - math.hypot(fx - BEFORE, fy - 17.5))
        return np.mean(errs)
    ideal = radius_error(1.0, 0.0)
    plain = radius_error(0.8, 0.0)
    compensated = radius_error(0.8, 1.0)
    assert abs(compensated - ideal) < 0.01, (compensated, ideal)
    assert abs(plain - ideal) > 0.03, (plain, ideal)


def test_speed_profile_against_distance():
    """vRef follows the profile (linear between points, held beyond them) at
    the driver's own progress s; here the car drives at vRef (pass-through
    mode for a kinematic plant)."""
    S, V = [10.0, 40.0, 80.0], [5.0, 12.0, 3.0]
    prof = {"nSpeed": 3, **{f"speedS[{k + 1}]": s for k, s in enumerate(S)},
            **{f"speedV[{k + 1}]": v for k, v in enumerate(V)}}
    x = y = psi = 0.0
    v, h, rows = 0.0, TS, []
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"road": 1, "testVehicle": False, **CAR, **prof, "x": 0.0, "y": 0.0, "psi": 0.0, "v": 0.0})
        d.slave.exitInitializationMode()
        t = 0.0
        while t < 40.0:
            delta, s, vRef = d.get("delta", "s", "vRef")
            rows.append((s, vRef))
            if d.slave.getBoolean([d.var("finished").valueReference])[0]:
                break
            x, y, psi = car_step(x, y, psi, vRef, delta, CAR["L0"], h)
            d.set_values({"x": x, "y": y, "psi": psi, "v": vRef})
            d.slave.doStep(t, h)
            t += h
    s, vRef = np.array(rows).T
    running = s < s.max() - 1e-9
    assert s.max() > 85.0, "the profile's last segment was never reached: the test cannot fail"
    np.testing.assert_allclose(vRef[running], np.interp(s[running], S, V), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("prof, words", [
    ({"nSpeed": 1}, ["nSpeed = 1"]),
    ({"nSpeed": 3, "speedS[1]": 0.0, "speedS[2]": 50.0, "speedS[3]": 50.0}, ["speedS[3] = 50", "speedS[2] = 50"]),
])
def test_bad_speed_profile(prof, words):
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"testVehicle": False, **prof})
        with pytest.raises(FMICallException):
            d.slave.exitInitializationMode()
        for w in words:
            assert w in " ".join(d.log), d.log
