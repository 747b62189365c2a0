"""BusKinematics against geometry derived here, independently of the FMU:
steady circles, reversing, jack-knife, and bad input. (The paper's closed
forms are checked in test_kinematics_closed_forms.py.)"""
import math

import numpy as np
import pytest

from artibus import fmu_path
from artibus.bench.parameters import read_parameters
from artibus.fmu import SimulationError, simulate
from conftest import DEG

URBINO = {"N": 1, "k": 1, "L0": 5.9, "Lh[1]": 1.789, "L[1]": 4.211, "testSteerAmp": 0.0}
BI_ARTICULATED = {"N": 3, "k": 0, "L0": 5.5, "L[1]": 6.0, "Lh[1]": 1.8, "L[2]": 5.0,
                  "Lh[2]": 1.5, "L[3]": 4.5, "Lh[3]": 2.0, "testSteerAmp": 0.0}


def run(params, gammaF, v, stop, step=0.1, **kw):
    return simulate(fmu_path("BusKinematics"), parameters=params,
                    inputs={"gammaF": gammaF, "v": v}, stop_time=stop, step=step, **kw)


def fit_circle(x, y):
    """Least-squares circle through points (Kasa): returns centre and radius."""
    A = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    (cx, cy, c), *_ = np.linalg.lstsq(A, x ** 2 + y ** 2, rcond=None)
    return cx, cy, math.sqrt(c + cx ** 2 + cy ** 2)


def test_urbino_parameter_set_is_table_I():
    p = read_parameters("Urbino18", fmu_path("BusKinematics"))
    assert (p["L0"], p["Lh[1]"], p["L[1]"]) == (5.9, 1.789, 4.211)  # seed 003, Table I


@pytest.mark.parametrize("params", [URBINO, BI_ARTICULATED], ids=["pusher", "3-wagon puller"])
@pytest.mark.parametrize("gF", [20 * DEG, -12 * DEG])
def test_steady_circle_radii(params, gF):
    """Tractor: R0 = L0 / tan(gammaF) (seed 003, eq. 19). Each unsteered wagon
    on a steady circle: its axle, joint and the centre form a right triangle
    at the axle, and the joint lies Lh behind the previous axle, so
    R_i^2 = R_{i-1}^2 + Lh_i^2 - L_i^2."""
    r = run(params, lambda t: gF, lambda t: 3.0, stop=150.0)
    late = r.time > 100.0
    R0 = params["L0"] / math.tan(abs(gF))
    R = R0
    _, _, fit0 = fit_circle(r["x[0]"][late], r["y[0]"][late])
    assert fit0 == pytest.approx(R0, rel=1e-6)
    for i in range(1, params["N"] + 1):
        R = math.sqrt(R ** 2 + params[f"Lh[{i}]"] ** 2 - params[f"L[{i}]"] ** 2)
        _, _, fit = fit_circle(r[f"x[{i}]"][late], r[f"y[{i}]"][late])
        assert fit == pytest.approx(R, rel=1e-6), f"segment {i}"
        # and the joint angle has settled: beta_i' = 0
        assert abs(r[f"betaDot[{i}]"][-1]) < 1e-6


def test_reversing_retraces_the_path():
    """The kinematics are homogeneous of degree one in v: driving back with the
    steering played backwards retraces the path to the start pose. (Driving a
    trailer backwards is unstable: errors grow about like exp(|v| t / L1), so
    the manoeuvre is kept to 25 m for a 1e-6 m check.)"""
    T, h = 10.0, 0.05
    steer = lambda t: 0.3 * math.sin(2 * math.pi * t / T)  # noqa: E731
    params = dict(URBINO, rtol=1e-12, atol=1e-12)

    def gF(t):  # inputs are held over a step: the way back replays the step [2T-t-h, 2T-t]
        return steer(t) if t < T - 1e-9 else steer(2 * T - t - h)

    r = run(params, gF, lambda t: 2.5 if t < T - 1e-9 else -2.5, stop=2 * T, step=h)
    mid = int(round(T / h))
    assert math.hypot(r["x[1]"][mid] - r["x[1]"][0], r["y[1]"][mid] - r["y[1]"][0]) > 20.0
    for name in ("x[0]", "y[0]", "x[1]", "y[1]", "theta[0]", "beta[1]"):
        assert r[name][-1] == pytest.approx(r[name][0], abs=1e-6), name
    # and at every time on the way back it stands where it stood on the way out
    back = r.array()[mid:][::-1]
    out = r.array()[: mid + 1]
    ix = r.names.index("x[1]")
    assert np.max(np.abs(back[:, ix] - out[:, ix])) < 1e-6


def test_jackknife_is_an_error_not_integrated_through():
    """Reversing a pusher with the wheel turned folds the joint until the
    virtual steering angle reaches 90 deg (eq. 17): fmi2Error, partial results kept."""
    with pytest.raises(SimulationError) as e:
        run(dict(URBINO, **{"beta_start[1]": 10 * DEG}), lambda t: -25 * DEG, lambda t: -3.0, stop=60.0)
    err = e.value
    assert "jack-knife" in str(err) and "beta[1]" in str(err)
    res = err.result
    assert 0 < res.time[-1] < 60.0
    beta, bmax = abs(res["beta[1]"][-1]), res["betaMax[1]"][-1]
    # the bound from eq. 17 evaluated here: |delta_1| = 90 deg where
    # beta_1 = a + sign(beta_1) 90 deg, a = atan(Lh1/L0 tan(gammaF))
    a = math.atan(1.789 / 5.9 * math.tan(-25 * DEG))
    expected = 90 * DEG + math.copysign(1.0, res["beta[1]"][-1]) * a
    assert bmax == pytest.approx(expected, abs=1e-9)
    assert bmax - 1e-4 < beta <= bmax   # it stopped at the bound, not beyond


def test_geometry_holds_for_four_wagons():
    """Holonomic constraints: |joint_i - P_i| = L_i, |P_{i-1} - joint_i| = Lh_i,
    along the segments' headings, at every point of a manoeuvre."""
    p = {"N": 4, "k": 2, "j": 3, "L0": 5.0, "testSteerAmp": 0.0}
    for i in range(1, 5):
        p[f"L[{i}]"], p[f"Lh[{i}]"] = 4.0 + 0.5 * i, 1.0 + 0.2 * i
    r = run(p, lambda t: 0.3 * math.sin(t / 3), lambda t: 2.5, stop=30.0)
    for i in range(1, 5):
        jx = r[f"x[{i-1}]"] - p[f"Lh[{i}]"] * np.cos(r[f"theta[{i-1}]"])
        jy = r[f"y[{i-1}]"] - p[f"Lh[{i}]"] * np.sin(r[f"theta[{i-1}]"])
        d = np.hypot(jx - r[f"x[{i}]"], jy - r[f"y[{i}]"])
        assert np.allclose(d, p[f"L[{i}]"], atol=1e-9)
        assert np.allclose(r[f"beta[{i}]"], r[f"theta[{i-1}]"] - r[f"theta[{i}]"], atol=1e-12)
    assert np.allclose(r["vel[2]"], 2.5)  # the driving axle moves at v


@pytest.mark.parametrize("params, words", [
    ({"L[1]": 0.0}, ["L[1]", "= 0", "minimum"]),
    ({"Lh[1]": -1.0}, ["Lh[1]", "= -1", "minimum"]),
    ({"L0": -5.9}, ["L0", "= -5.9"]),
    ({"N": 5}, ["N", "= 5", "maximum"]),
    ({"N": 0}, ["N", "= 0", "minimum"]),
    ({"k": 2}, ["k = 2", "0..N = 0..1"]),
    ({"j": 3}, ["j = 3"]),
    ({"rtol": math.nan}, ["rtol", "nan"]),
    ({"beta_start[1]": 100 * DEG}, ["beta_start[1]", "betaMax[1]"]),
])
def test_bad_parameters(params, words):
    with pytest.raises(SimulationError) as e:
        run(dict(URBINO, **params), lambda t: 0.1, lambda t: 3.0, stop=1.0)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


@pytest.mark.parametrize("name, value", [
    ("gammaF", math.pi / 2), ("gammaF", -math.pi / 2), ("gammaF", 2.0),
    ("gammaF", math.nan), ("gammaF", math.inf), ("v", math.nan), ("v", -math.inf),
])
def test_bad_inputs(name, value):
    """Steering at or beyond pi/2, NaN/Inf: fmi2Error naming the input and value."""
    inputs = {"gammaF": 0.1, "v": 3.0}

    def f(n):
        return lambda t: value if (n == name and t >= 1.0) else inputs[n]

    with pytest.raises(SimulationError) as e:
        run(URBINO, f("gammaF"), f("v"), stop=3.0)
    msg = str(e.value)
    assert name in msg and f"{value:g}"[:4] in msg, msg
    assert 0.9 <= e.value.result.time[-1] <= 1.1   # the results before it are kept


def test_steered_wagon_beyond_pi_half():
    p = dict(URBINO, **{"steerable[1]": True, "k": 0})
    with pytest.raises(SimulationError) as e:
        simulate(fmu_path("BusKinematics"), parameters=p,
                 inputs={"gamma[1]": lambda t: math.pi / 2, "v": lambda t: 1.0}, stop_time=1.0, step=0.1)
    assert "gamma[1]" in str(e.value) and "pi/2" in str(e.value)
