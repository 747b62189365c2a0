"""TrainGuidance and ForceMinimization (seed 000, Tasks 1 and 2) against
geometry derived here, independently of the FMUs: the steady circle solved
for the modules' headings by root finding, the instantaneous centres of the
transient construction intersected as lines, the arc lag's recursion summed
in closed form; then sampling, driving direction and bad input.

The vehicle couplings (BusKinematics, BusDynamics) are in
test_steering_controllers_benches.py."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from scipy.optimize import brentq

from conftest import init

# the 36 m bus (ssp/parameters/Bus36m.ssv): axles +-2.95 m and hinges 6.1 m from each CG
L1, LG1, L2, LG2, L3 = 5.9, 6.1 - 2.95, 6.1 + 2.95, 6.1 - 2.95, 6.1 + 2.95
LA3 = LA5 = 6.1 - 2.95
NO_TEST = {"testSteerAmp": 0.0}


def heading(a):
    return np.array([math.cos(a), math.sin(a)])


def normal_through(P, theta, M):
    """zero when the wheel at P heading theta has its axis (normal) through M"""
    return float(heading(theta) @ (P - M))


def trailing_module(G, M, l, gamma, ref=0.0):
    """Heading of a module hinged at G whose axle, l behind G and steered by
    gamma, turns about M: the root nearest the heading ref of the module in
    front (articulation below 90 deg)."""
    f = lambda th: normal_through(G - l * heading(th), th + gamma, M)
    grid = ref + np.linspace(-1.5, 1.5, 601)
    vals = [f(t) for t in grid]
    roots = [brentq(f, a, b, xtol=1e-15) for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:])
             if fa * fb < 0]
    return min(roots, key=lambda r: abs(r - ref))


def steady_circle(R, gamma4, gamma6):
    """Module 1 with A2 at the origin heading +x turns about M = (0, R)
    (eq. 30). The modules behind it take the headings at which their guided
    axles also turn about M; returns the radii of A4 and A6 about M."""
    M = np.array([0.0, R])
    G1 = np.array([-LG1, 0.0])
    th2 = trailing_module(G1, M, L2, gamma4)
    A4 = G1 - L2 * heading(th2)
    G2 = A4 - LG2 * heading(th2)
    th3 = trailing_module(G2, M, L3, gamma6, th2)
    A6 = G2 - L3 * heading(th3)
    return np.linalg.norm(A4 - M), np.linalg.norm(A6 - M)


def start(fmu, **values):
    init(fmu, **dict(NO_TEST, **values))


def outputs(fmu, *names):
    return dict(zip(names, fmu.get(*names)))


RADII = [12.0, 15.0, 17.5, 25.0, 40.0, 60.0, 100.0]


@pytest.mark.parametrize("side", [1, -1], ids=["left", "right"])
@pytest.mark.parametrize("R", RADII)
def test_steady_state_angles_put_A4_and_A6_on_the_A2_circle(open_fmu, R, side):
    """Eqs. 29-37 with the slips fixed: on a steady circle of A2 (radius R,
    gamma1 = atan(l1/R)), the guided angles make A4 and A6 turn about the same
    centre at the same radius. The headings are found here by root finding,
    not from the paper's triangles."""
    tg = open_fmu("TrainGuidance")
    gamma1 = math.atan(L1 / (side * R))
    start(tg, gamma1=gamma1)            # the lags start in the steady state of gamma1
    out = outputs(tg, "gamma4ss", "gamma6ss", "gamma4", "gamma6")
    assert out["gamma4"] == out["gamma4ss"] and out["gamma6"] == out["gamma6ss"]
    assert np.sign(out["gamma4ss"]) == -side and np.sign(out["gamma6ss"]) == -side   # opposite to A1
    r4, r6 = steady_circle(side * R, out["gamma4ss"], out["gamma6ss"])
    assert r4 == pytest.approx(R, abs=1e-9)
    assert r6 == pytest.approx(R, abs=1e-9)
    # and an angle 0.5 deg off is visibly off the circle: the check can fail
    r4_off, _ = steady_circle(side * R, out["gamma4ss"] + 0.5 * math.pi / 180, out["gamma6ss"])
    assert abs(r4_off - R) > 1e-3


def test_steady_state_is_continuous_and_odd_through_straight(open_fmu):
    """gamma1 -> 0 from either side: no jump, no singularity at R2 = infinity,
    exactly 0 straight ahead, mirror-symmetric for left and right turns."""
    tg = open_fmu("TrainGuidance")
    start(tg)
    g1 = np.concatenate([-np.logspace(-1, -12, 12), [0.0], np.logspace(-12, -1, 12)])
    rows = []
    for i, g in enumerate(g1):
        tg.set_values({"gamma1": float(g)})
        tg.slave.doStep(i * 0.01, 0.01)         # one sample
        rows.append(tg.get("gamma4ss", "gamma6ss"))
    g4, g6 = np.array(rows).T
    assert g4[12] == 0.0 and g6[12] == 0.0
    assert np.all(np.isfinite(g4)) and np.all(np.isfinite(g6))
    np.testing.assert_array_equal(g4[:12], -g4[13:][::-1])
    np.testing.assert_array_equal(g6[:12], -g6[13:][::-1])
    # monotone and linear near 0: small-angle slope of the triangle, derived here
    # from R_g1^2 = R2^2 + lg1^2 and |M A4| = R2 for R2 -> infinity:
    # gamma4 ~ -(l2^2 - lg1^2) / (2 l2) * gamma1 / l1
    assert np.all(np.diff(g4) <= 0) and np.all(np.diff(g6) <= 0)
    slope4 = -(L2 ** 2 - LG1 ** 2) / (2 * L2) / L1
    assert g4[13] / g1[13] == pytest.approx(slope4, rel=1e-9)


def test_arc_lag_advances_with_distance_not_time(open_fmu):
    """Eqs. 38-42: standing still nothing moves; driving, the lag after n
    samples of ds = v Ts is the recursion summed in closed form,
    y_n = u (1 - (S/(S + ds))^n); the same distance at a third of the speed
    gives nearly the same angle (the continuous limit is 1 - exp(-s/S))."""
    S4, S6, Ts = 5.0, 10.0, 0.01
    gamma1 = math.atan(L1 / 17.5)
    results = {}
    for v in (0.0, 1.0, 3.0):
        tg = open_fmu("TrainGuidance")
        start(tg, S4=S4, S6=S6, Ts=Ts, gamma1=0.0, v=v)
        assert tg.get("gamma4", "gamma6") == [0.0, 0.0]
        tg.set_values({"gamma1": gamma1})
        n = int(round(9.0 / (v * Ts))) if v else 900
        for i in range(n):
            tg.slave.doStep(i * Ts, Ts)
        results[v] = outputs(tg, "gamma4", "gamma6", "gamma4ss", "gamma6ss")
    assert results[0.0]["gamma4"] == 0.0 and results[0.0]["gamma6"] == 0.0
    u4, u6 = results[3.0]["gamma4ss"], results[3.0]["gamma6ss"]
    ds, n = 3.0 * Ts, 300
    assert results[3.0]["gamma4"] == pytest.approx(u4 * (1 - (S4 / (S4 + ds)) ** n), rel=1e-12)
    assert results[3.0]["gamma6"] == pytest.approx(u6 * (1 - (S6 / (S6 + ds)) ** n), rel=1e-12)
    for v in (1.0, 3.0):
        assert results[v]["gamma4"] == pytest.approx(u4 * (1 - math.exp(-9.0 / S4)), rel=2e-3)
        assert results[v]["gamma6"] == pytest.approx(u6 * (1 - math.exp(-9.0 / S6)), rel=2e-3)


@pytest.mark.parametrize("name", ["TrainGuidance", "ForceMinimization"])
def test_outputs_change_only_at_sample_instants(open_fmu, name):
    """A discrete controller: with a 5 ms communication step the outputs move
    every second step; with 50 ms (five samples a step) they are the same, bit
    for bit, as with 10 ms at the same instants."""
    def run(h, n):
        f = open_fmu(name)
        init(f, testSteerAmp=0.4, testSteerPeriod=2.0)
        outs = []
        for i in range(n):
            f.slave.doStep(i * h, h)
            outs.append(f.get(*(["gamma4", "gamma6"] if name == "TrainGuidance" else ["gamma3", "gamma5"])))
        return np.array(outs)
    fine = run(0.005, 40)
    moved = np.any(np.diff(fine, axis=0) != 0, axis=1)
    assert not np.any(moved[::2]) and np.all(moved[1::2])
    a, b = run(0.01, 100), run(0.05, 20)
    np.testing.assert_array_equal(a[4::5], b)


def test_sample_period_is_a_parameter(open_fmu):
    """Ts = 20 ms: one sample in every second 10 ms step."""
    tg = open_fmu("TrainGuidance")
    start(tg, Ts=0.02, gamma1=0.0, v=5.0)
    tg.set_values({"gamma1": 0.3})
    outs = []
    for i in range(10):
        tg.slave.doStep(i * 0.01, 0.01)
        outs.append(tg.get("gamma4")[0])
    steps = np.diff([0.0] + outs) != 0
    assert list(steps) == [True, False] * 5


# ---- Task 2: instantaneous centres as lines --------------------------------

def intersect(P, d, Q, e):
    """the point P + s d = Q + u e"""
    s, _ = np.linalg.solve(np.column_stack([d, -e]), Q - P)
    return P + s * d


def perp(a):
    return np.array([-math.sin(a), math.cos(a)])


def force_free_by_centres(gamma1, dpsi1, dpsi2, gamma4, gamma6):
    """Seed 000, Fig. 7: module 1 turns about M1 on A2's axle line; module 2
    about M2 where the line M1-G1 (normal to G1's velocity) meets A4's wheel
    axis; A3 must point its axis at M2. Module 3 likewise about M3 on the line
    M2-G2 and A6's axis. Returns gamma3, gamma5 from the centres."""
    psi1, psi2 = 0.0, -dpsi1
    psi3 = psi2 - dpsi2
    A2 = np.zeros(2)
    M1 = A2 + L1 / math.tan(gamma1) * perp(psi1)
    G1 = A2 - LG1 * heading(psi1)
    A4 = G1 - L2 * heading(psi2)
    A3 = G1 - LA3 * heading(psi2)
    M2 = intersect(G1, M1 - G1, A4, perp(psi2 + gamma4))
    G2 = A4 - LG2 * heading(psi2)
    A6 = G2 - L3 * heading(psi3)
    A5 = G2 - LA5 * heading(psi3)
    M3 = intersect(G2, M2 - G2, A6, perp(psi3 + gamma6))

    def pointing(A, M, psi):
        d = M - A                                   # the axis; heading perpendicular, forward
        h = np.array([d[1], -d[0]])
        if h @ heading(psi) < 0:
            h = -h
        return math.remainder(math.atan2(h[1], h[0]) - psi, 2 * math.pi)
    return pointing(A3, M2, psi2), pointing(A5, M3, psi3)


def fm_outputs(fmu, **inputs):
    fmu.slave.reset()
    start(fmu, **inputs)
    return fmu.get("gamma3", "gamma5")


def test_force_minimisation_matches_the_instantaneous_centres(open_fmu):
    """Random transient states (each module with its own centre, Fig. 7):
    gamma3, gamma5 equal the angles constructed from the centres."""
    fm = open_fmu("ForceMinimization")
    rng = np.random.default_rng(6)
    n = 0
    for _ in range(60):
        g1, d1, d2, g4, g6 = rng.uniform([-0.5, -0.7, -0.7, -0.4, -0.4], [0.5, 0.7, 0.7, 0.4, 0.4])
        e3, e5 = force_free_by_centres(g1, d1, d2, g4, g6)
        if max(abs(e3), abs(e5)) > 0.7:            # beyond the steering limits: saturated, below
            continue
        g3, g5 = fm_outputs(fm, gamma1=g1, **{"dPsi[1]": d1, "dPsi[2]": d2}, gamma4=g4, gamma6=g6)
        assert g3 == pytest.approx(e3, abs=1e-9) and g5 == pytest.approx(e5, abs=1e-9)
        n += 1
    assert n > 30


def test_force_minimisation_is_finite_where_the_centre_goes_to_infinity(open_fmu):
    """Straight tractor (gamma1 = 0: M1 at infinity) and parallel axle lines
    (M2 at infinity): finite, and the limit of the nearby curved states."""
    fm = open_fmu("ForceMinimization")
    assert fm_outputs(fm, gamma1=0.0) == [0.0, 0.0]
    state = {"dPsi[1]": 0.2, "dPsi[2]": -0.1, "gamma4": -0.05, "gamma6": 0.03}
    g0 = fm_outputs(fm, gamma1=0.0, **state)
    ga = fm_outputs(fm, gamma1=1e-7, **state)
    gb = force_free_by_centres(1e-7, state["dPsi[1]"], state["dPsi[2]"], state["gamma4"], state["gamma6"])
    assert np.all(np.isfinite(g0))
    np.testing.assert_allclose(g0, ga, atol=1e-6)
    np.testing.assert_allclose(ga, gb, atol=1e-7)
    # a pure translation of module 2 (its centre at infinity): A3 parallel to A4
    g = fm_outputs(fm, gamma1=0.0, **{"dPsi[1]": 0.0, "dPsi[2]": 0.0}, gamma4=0.0, gamma6=0.0)
    assert g == [0.0, 0.0]


def test_steady_circle_with_guidance_and_force_minimisation_has_one_centre(open_fmu):
    """On the steady circle every module turns about M: A3 and A5 then point
    their axes at M too, at the radius found geometrically."""
    tg, fm = open_fmu("TrainGuidance"), open_fmu("ForceMinimization")
    for R in (12.0, -17.5, 50.0):
        gamma1 = math.atan(L1 / R)
        tg.slave.reset()
        start(tg, gamma1=gamma1)
        g4, g6 = tg.get("gamma4ss", "gamma6ss")
        M = np.array([0.0, R])
        G1 = np.array([-LG1, 0.0])
        th2 = trailing_module(G1, M, L2, g4)
        G2 = G1 - (L2 + LG2) * heading(th2)
        th3 = trailing_module(G2, M, L3, g6, th2)
        g3, g5 = fm_outputs(fm, gamma1=gamma1, **{"dPsi[1]": -th2, "dPsi[2]": th2 - th3}, gamma4=g4, gamma6=g6)
        A3 = G1 - LA3 * heading(th2)
        A5 = G2 - LA5 * heading(th3)
        assert normal_through(A3, th2 + g3, M) == pytest.approx(0.0, abs=1e-9)
        assert normal_through(A5, th3 + g5, M) == pytest.approx(0.0, abs=1e-9)


# ---- driving direction -------------------------------------------------------

def test_backwards_mirrors_the_hinges(open_fmu):
    """Backwards the A6 end leads: the leading module sees hinge G2 first, as
    psi3 - psi2 = -dPsi[2], then G1 as -dPsi[1]; steering angles keep their
    sign (each module frame turned by 180 deg)."""
    fm = open_fmu("ForceMinimization")
    g1, d1, d2, g4, g6 = 0.2, 0.15, -0.25, -0.1, 0.05
    back = fm_outputs(fm, backwards=True, gamma1=g1, **{"dPsi[1]": d1, "dPsi[2]": d2}, gamma4=g4, gamma6=g6)
    fwd = fm_outputs(fm, gamma1=g1, **{"dPsi[1]": -d2, "dPsi[2]": -d1}, gamma4=g4, gamma6=g6)
    assert back == fwd
    assert back != fm_outputs(fm, gamma1=g1, **{"dPsi[1]": d1, "dPsi[2]": d2}, gamma4=g4, gamma6=g6)


def test_change_of_direction_restarts_the_lags_from_the_steady_state(open_fmu):
    tg = open_fmu("TrainGuidance")
    start(tg, gamma1=0.0, v=2.0)
    tg.set_values({"gamma1": 0.3})
    for i in range(50):
        tg.slave.doStep(i * 0.01, 0.01)
    g4, g4ss = tg.get("gamma4", "gamma4ss")
    assert 0 < abs(g4) < abs(g4ss)                  # half-way through the lag
    tg.set_values({"backwards": True, "v": 0.0})
    tg.slave.doStep(0.5, 0.01)
    assert tg.get("gamma4")[0] == g4ss


# ---- bad input ------------------------------------------------------------------

def warnings(fmu):
    return [line for line in fmu.log if line.startswith("[Warning]")]


def bounded(fmu, names, limit=0.75):
    vals = fmu.get(*names)
    return all(math.isfinite(x) and abs(x) <= limit for x in vals)


def test_negative_speed_holds_and_warns_once_per_episode(open_fmu):
    tg = open_fmu("TrainGuidance")
    start(tg, gamma1=0.0, v=2.0)
    tg.set_values({"gamma1": 0.3})
    t = 0.0
    def steps(n):
        nonlocal t
        for _ in range(n):
            tg.slave.doStep(t, 0.01)
            t += 0.01
    steps(20)
    held = tg.get("gamma4", "gamma6")
    tg.set_values({"v": -1.5})
    steps(30)
    assert tg.get("gamma4", "gamma6") == held and bounded(tg, ["gamma4", "gamma6"])
    assert tg.get("fault")[0] == 2
    assert len(warnings(tg)) == 1 and "v = -1.5" in warnings(tg)[0]
    tg.set_values({"v": 2.0})
    steps(5)
    assert tg.get("fault")[0] == 0 and tg.get("gamma4") != held[:1]
    tg.set_values({"v": -0.1})
    steps(5)
    assert len(warnings(tg)) == 2                    # a new episode, a new warning


@pytest.mark.parametrize("gamma1", [1.3, -1.3, 1.5])
def test_steering_beyond_the_geometry_saturates_and_warns_once(open_fmu, gamma1):
    """|gamma1| so large that A2's circle (R2 = l1/tan(gamma1) < 4 m) admits no
    triangle M-G1-A4: the paper's arccos argument leaves [-1, 1]."""
    tg = open_fmu("TrainGuidance")
    start(tg, v=3.0)
    tg.set_values({"gamma1": gamma1})
    for i in range(300):
        tg.slave.doStep(i * 0.01, 0.01)
    assert bounded(tg, ["gamma4", "gamma6", "gamma4ss", "gamma6ss"])
    assert tg.get("gamma4ss")[0] == pytest.approx(-math.copysign(0.75, gamma1))
    assert int(tg.get("fault")[0]) & 4
    assert len(warnings(tg)) == 1 and "arccos" in warnings(tg)[0]


def test_geometry_without_a_triangle_saturates(open_fmu):
    """A parameter set (l2 = 1 m, lg1 = 8 m) for which even gamma1 = 0.5 has no
    steady-state triangle: bounded output and one warning."""
    tg = open_fmu("TrainGuidance")
    start(tg, l2=1.0, lg1=8.0, v=1.0)
    tg.set_values({"gamma1": 0.5})
    for i in range(10):
        tg.slave.doStep(i * 0.01, 0.01)
    assert bounded(tg, ["gamma4", "gamma6", "gamma4ss", "gamma6ss"])
    assert len(warnings(tg)) == 1


@pytest.mark.parametrize("state", [
    {"dPsi[1]": 2.0}, {"dPsi[1]": -2.5, "dPsi[2]": 3.0}, {"gamma1": 1.5707963267948966},
    {"gamma4": 1.6, "gamma6": -1.6}, {"dPsi[2]": 1.9, "gamma1": 0.5}])
def test_force_minimisation_in_a_jack_knifed_state_saturates_and_warns_once(open_fmu, state):
    fm = open_fmu("ForceMinimization")
    start(fm)
    fm.set_values(state)
    for i in range(20):
        fm.slave.doStep(i * 0.01, 0.01)
    assert bounded(fm, ["gamma3", "gamma5"])
    assert int(fm.get("fault")[0]) & 4
    assert len(warnings(fm)) == 1


@pytest.mark.parametrize("name,var", [("TrainGuidance", "gamma1"), ("TrainGuidance", "v"),
                                      ("ForceMinimization", "dPsi[1]"), ("ForceMinimization", "gamma4")])
def test_nan_input_is_refused_and_outputs_stay_finite(open_fmu, name, var):
    """NaN never reaches the algorithm through the FMI layer (fmi2Error naming
    the variable); the outputs read in the error state are the last finite
    ones. (The algorithms' own NaN handling is checked by tests/c/ecu_steering.c.)"""
    f = open_fmu(name)
    init(f, testSteerAmp=0.3)
    for i in range(10):
        f.slave.doStep(i * 0.01, 0.01)
    outs = [v.name for v in f.md.modelVariables if v.causality == "output"]
    before = f.get(*outs)
    with pytest.raises(FMICallException):
        f.set_values({var: math.nan})
    assert var in " ".join(f.log)
    after = f.get(*outs)
    assert after == before and all(math.isfinite(x) for x in after)
