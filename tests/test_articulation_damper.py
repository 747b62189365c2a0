"""ArticulationDamper (seed 001, 1.3.1 and App. B): the two-cylinder damper
against the geometry written here independently (pivot vectors, rotation
matrices, cross products, the law of cosines, finite differences), its energy
balance, the end stop in a loop with a rigid body integrated here, the valve
lag against the exponential, and bad input.

Frames: the front section's, origin at the articulation point, x forward,
y left; Lambda = psi1 - psi2; Mjoint turns the rear section counter-clockwise
(BusDynamics Mjoint[1]), so it reduces Lambda."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import DEG, init

NAME = "ArticulationDamper"
PAR = dict(R=0.25, Xrear=0.90, Yrear=0.25, Ap=5.0265e-3, pMax=2e7, v0=0.005,
           LambdaStop=0.9424778, kStop=5e6, cStop=2e5)
OUTS = ["Mjoint", "F[1]", "F[2]", "p[1]", "p[2]", "L[1]", "L[2]", "Ldot[1]", "Ldot[2]", "Mmax", "Ediss"]
SIDE = {1: +1, 2: -1}                    # F[1] left (y > 0), F[2] right


# ---- the geometry, written here -------------------------------------------------

def rot(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def pivots(lam, s, R=PAR["R"], X=PAR["Xrear"], Y=PAR["Yrear"]):
    """front and rear pivot of side s in the front frame: the rear frame is the
    front one turned by psi2 - psi1 = -Lambda"""
    front = np.array([0.0, s * R])
    rear = rot(-lam) @ np.array([-X, s * Y])
    return front, rear


def length(lam, s, **geo):
    f, r = pivots(lam, s, **geo)
    return float(np.linalg.norm(r - f))


def law_of_cosines(lam, s, R=PAR["R"], X=PAR["Xrear"], Y=PAR["Yrear"]):
    """triangle articulation point O, front pivot, rear pivot: sides R and
    sqrt(X^2 + Y^2), the angle at O between them"""
    b = math.hypot(X, Y)
    angle_front = s * math.pi / 2
    angle_rear = math.atan2(s * Y, -X) - lam
    return math.sqrt(R * R + b * b - 2 * R * b * math.cos(angle_front - angle_rear))


def lever(lam, s, eps=1e-6, **geo):
    return (length(lam + eps, s, **geo) - length(lam - eps, s, **geo)) / (2 * eps)


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


# ---- driving the FMU ----------------------------------------------------------------

@pytest.fixture
def damper(open_fmu):
    """damper(**parameters) -> an initialised instance; read(f, Lambda, LambdaDot, pct) -> outputs"""
    def make(**par):
        f = open_fmu(NAME)
        init(f, **par)
        return f
    return make


def read(f, lam, lamdot, pct):
    f.set_values({"Lambda": lam, "LambdaDot": lamdot, "pct": pct})
    return dict(zip(OUTS, f.get(*OUTS)))


def cases(n, seed, stop=PAR["LambdaStop"]):
    rng = np.random.default_rng(seed)
    lam = rng.uniform(-0.999 * stop, 0.999 * stop, n)
    rate = rng.choice([-1, 1], n) * 10 ** rng.uniform(-4, 0.3, n)    # 1e-4 .. 2 rad/s
    pct = rng.uniform(0, 50, n)
    return zip(lam, rate, pct)


# ---- geometry ---------------------------------------------------------------------------

def test_lengths_follow_the_law_of_cosines(damper):
    f = damper()
    for lam, rate, pct in cases(300, 1):
        o = read(f, lam, rate, pct)
        for i in (1, 2):
            assert o[f"L[{i}]"] == pytest.approx(law_of_cosines(lam, SIDE[i]), rel=1e-12)
            assert o[f"L[{i}]"] == pytest.approx(length(lam, SIDE[i]), rel=1e-12)
    # Lambda = 0: both cylinders parallel to the bus, Xrear long (Yrear = R)
    o = read(f, 0.0, 0.0, 3.5)
    assert o["L[1]"] == o["L[2]"] == pytest.approx(PAR["Xrear"], rel=1e-15)


def test_inner_cylinder_shortens_and_is_the_one_that_resists(damper):
    """Lambda growing = the bend increases to the left: the left (inner)
    cylinder is compressed and is the one that resists (seed 001, 1.3.1); its
    push turns the rear section counter-clockwise, against the bend."""
    f = damper()
    for lam in np.linspace(-50, 50, 11) * DEG:
        o = read(f, lam, 0.3, 20.0)
        assert length(lam + 1e-3, +1) < length(lam, +1) and o["Ldot[1]"] < 0 < o["Ldot[2]"]
        assert o["F[1]"] > 0 and o["F[2]"] == 0 and o["p[2]"] == 0
        assert o["Mjoint"] > 0
        o = read(f, lam, -0.3, 20.0)
        assert o["F[2]"] > 0 and o["F[1]"] == 0 and o["Mjoint"] < 0


def test_lever_arm_is_the_derivative_of_the_output_length(damper):
    """Ldot / LambdaDot (the FMU's lever arm) against the central difference of
    the FMU's own length output, and against the geometry here."""
    f = damper()
    eps = 1e-5
    for lam, rate, pct in cases(200, 2):
        o = read(f, lam, rate, pct)
        plus, minus = read(f, lam + eps, rate, pct), read(f, lam - eps, rate, pct)
        for i in (1, 2):
            fd = (plus[f"L[{i}]"] - minus[f"L[{i}]"]) / (2 * eps)
            assert o[f"Ldot[{i}]"] / rate == pytest.approx(fd, rel=1e-7, abs=1e-9)
            assert o[f"Ldot[{i}]"] / rate == pytest.approx(lever(lam, SIDE[i]), rel=1e-7, abs=1e-9)


def test_the_cylinder_forces_are_a_pure_torque_pair(damper):
    """Each cylinder pushes its rear pivot along the line from the front pivot
    and, equally and oppositely, its front pivot: about the articulation point
    the rear section gets the moment Mjoint (counter-clockwise) and the front
    section exactly the reaction -Mjoint; the forces themselves cancel in the
    pin (sum over the bus zero)."""
    for both in (False, True):
        f = damper(bothWays=both)
        for lam, rate, pct in cases(200, 3):
            o = read(f, lam, rate, pct)
            m_rear = m_front = 0.0
            force_sum = np.zeros(2)
            for i in (1, 2):
                s = SIDE[i]
                pf, pr = pivots(lam, s)
                u = (pr - pf) / np.linalg.norm(pr - pf)
                compressing = lever(lam, s) * rate < 0
                push = o[f"F[{i}]"] if compressing else -o[f"F[{i}]"]    # resists: pushes while compressed
                on_rear, on_front = push * u, -push * u
                m_rear += cross(pr, on_rear)
                m_front += cross(pf, on_front)
                force_sum += on_rear + on_front
                if not both and not compressing:
                    assert o[f"F[{i}]"] == 0.0
            scale = PAR["Ap"] * PAR["pMax"] * PAR["R"]
            assert o["Mjoint"] == pytest.approx(m_rear, abs=1e-9 * scale)
            assert m_front == pytest.approx(-m_rear, abs=1e-9 * scale)
            assert np.allclose(force_sum, 0.0, atol=1e-9 * scale)


# ---- the valves ----------------------------------------------------------------------

def test_never_feeds_energy_in_and_zero_at_rest(damper):
    for both in (False, True):
        f = damper(bothWays=both)
        for lam, rate, pct in cases(300, 4):
            o = read(f, lam, rate, pct)
            assert o["Mjoint"] * rate >= 0.0
            assert o["F[1]"] >= 0.0 and o["F[2]"] >= 0.0
            rest = read(f, lam, 0.0, pct)
            assert rest["Mjoint"] == 0.0 and rest["F[1]"] == rest["F[2]"] == 0.0


def test_torque_is_monotone_and_linear_in_the_command(damper):
    """|Mjoint| non-decreasing in pct; with the static valve p = pMax pct/50
    (seed 001, 5.1.1: 50 % = maximum damping), so it is proportional to pct."""
    f = damper()
    grid = np.linspace(0, 50, 26)
    for lam, rate, _ in cases(60, 5):
        m = np.array([abs(read(f, lam, rate, p)["Mjoint"]) for p in grid])
        assert np.all(np.diff(m) >= 0)
        assert m[0] == 0.0
        assert m == pytest.approx(m[-1] * grid / 50, rel=1e-12, abs=1e-9 * m[-1])


def test_force_follows_the_valve_pressure_and_the_piston_speed(damper):
    """F = Ap pMax (pct/50) tanh(|Ldot|/v0) on the resisting cylinder: the
    valve pressure once |Ldot| >> v0, the linear law at small piston speeds."""
    f = damper()
    for lam, rate, pct in cases(200, 6):
        o = read(f, lam, rate, pct)
        i = 1 if lever(lam, +1) * rate < 0 else 2
        ldot = abs(lever(lam, SIDE[i]) * rate)
        want = PAR["Ap"] * PAR["pMax"] * pct / 50 * math.tanh(ldot / PAR["v0"])
        assert o[f"F[{i}]"] == pytest.approx(want, rel=1e-7)
        assert o[f"p[{i}]"] == pytest.approx(want / PAR["Ap"], rel=1e-7)


def test_mmax_is_the_torque_at_50_percent_for_the_direction_of_motion(damper):
    """Mmax against the geometry here (Ap pMax |dL/dLambda| of the cylinder that
    compresses), and against the FMU's own torque at 50 % at a rate where
    |Ldot| >> v0; at rest, the larger of the two directions."""
    f = damper()
    for lam in np.linspace(-53, 53, 23) * DEG:
        up = PAR["Ap"] * PAR["pMax"] * abs(lever(lam, +1))       # Lambda growing: the left one compresses
        down = PAR["Ap"] * PAR["pMax"] * abs(lever(lam, -1))
        o = read(f, lam, 1.0, 50.0)
        assert o["Mmax"] == pytest.approx(up, rel=1e-8)
        assert o["Mjoint"] == pytest.approx(o["Mmax"], rel=1e-12)           # tanh(>= 20) = 1
        o = read(f, lam, -1.0, 50.0)
        assert o["Mmax"] == pytest.approx(down, rel=1e-8)
        assert -o["Mjoint"] == pytest.approx(o["Mmax"], rel=1e-12)
        assert read(f, lam, 0.0, 10.0)["Mmax"] == pytest.approx(max(up, down), rel=1e-8)
    fb = damper(bothWays=True)
    o = read(fb, 30 * DEG, 0.5, 50.0)
    assert o["Mmax"] == pytest.approx(PAR["Ap"] * PAR["pMax"] * (abs(lever(30 * DEG, 1)) +
                                                                  abs(lever(30 * DEG, -1))), rel=1e-8)
    assert o["F[1]"] > 0 and o["F[2]"] > 0


def test_small_rate_damping_is_the_linearised_valve(damper):
    """At |Ldot| << v0 the torque is linear in LambdaDot with the slope
    Ap p h^2 / v0 (tanh'(0) = 1): the rotational damping the co-simulation sees."""
    f = damper()
    for lam in (0.0, 30 * DEG, -45 * DEG):
        for pct in (3.5, 34.0):
            rate = 1e-6
            o = read(f, lam, rate, pct)
            h = lever(lam, +1)
            assert o["Mjoint"] / rate == pytest.approx(PAR["Ap"] * PAR["pMax"] * pct / 50 * h * h / PAR["v0"],
                                                       rel=1e-6)


# ---- stepping: energy, valve lag ---------------------------------------------------------

def test_dissipated_energy_is_the_integral_of_torque_times_rate(damper):
    """Inputs held over each step: Ediss grows by Mjoint LambdaDot h exactly
    (static valve), never decreases."""
    f = damper()
    rng = np.random.default_rng(7)
    t, h, E = 0.0, 0.01, 0.0
    for lam, rate, pct in cases(300, 8):
        o = read(f, lam, rate, pct)
        f.slave.doStep(t, h)
        t += h
        E_new = f.get("Ediss")[0]
        assert E_new >= E
        assert E_new - E == pytest.approx(o["Mjoint"] * rate * h, rel=1e-9, abs=1e-9)
        E = E_new
        h = float(rng.choice([0.001, 0.01, 0.02]))
    assert E > 0


def test_dissipated_energy_with_the_valve_lag_is_exact_over_a_step(damper):
    """tauP > 0: one long step's Ediss increment against the trapezoidal sum of
    Mjoint LambdaDot over 2000 sub-steps from the same saved state."""
    f = damper(tauP=0.03, pct=0.0)
    lam, rate = 20 * DEG, -0.4
    f.set_values({"Lambda": lam, "LambdaDot": rate, "pct": 30.0})
    state = f.slave.getFMUstate()
    f.slave.doStep(0.0, 0.05)
    one = f.get("Ediss")[0]
    f.slave.setFMUstate(state)
    n, h = 2000, 0.05 / 2000
    m = [f.get("Mjoint")[0]]
    for k in range(n):
        f.slave.doStep(k * h, h)
        m.append(f.get("Mjoint")[0])
    f.slave.freeFMUstate(state)
    trap = float(np.sum((np.array(m[1:]) + np.array(m[:-1])) / 2) * h * rate)
    assert one > 0
    assert one == pytest.approx(trap, rel=1e-6)
    assert f.get("Ediss")[0] == pytest.approx(one, rel=1e-9)


@pytest.mark.parametrize("tauP,h", [(0.05, 0.001), (0.03, 0.01), (0.2, 0.005)])
def test_valve_lag_step_response(damper, tauP, h):
    """pct stepped 0 -> 30 % at constant LambdaDot: the torque is
    M_final (1 - exp(-t/tauP)) and crosses 1 - 1/e of its final value at
    t = tauP, within a step."""
    lam, rate = 15 * DEG, 0.2
    final = read(damper(), lam, rate, 30.0)["Mjoint"]            # the static valve's torque
    f = damper(tauP=tauP, pct=0.0, Lambda=lam, LambdaDot=rate)
    assert f.get("Mjoint")[0] == 0.0
    f.set_values({"pct": 30.0})
    assert f.get("Mjoint")[0] == 0.0                               # the pressure has not moved yet
    t, crossed = 0.0, None
    while t < 10 * tauP:
        f.slave.doStep(t, h)
        t += h
        m = f.get("Mjoint")[0]
        assert m == pytest.approx(final * (1 - math.exp(-t / tauP)), rel=1e-9)
        if crossed is None and m >= (1 - 1 / math.e) * final:
            crossed = t
    assert crossed is not None and abs(crossed - tauP) <= h * (1 + 1e-9)
    # a direction reversal: no stored pressure pushes the other way
    f.set_values({"LambdaDot": -rate})
    assert f.get("Mjoint")[0] * -rate > 0


# ---- the end stop in a loop with a rigid body ------------------------------------------------

def run_into_stop(f, J, T, h, lam0, t_end):
    """J Lambda'' = T - Mjoint (Mjoint turns the rear section against Lambda),
    semi-implicit Euler here, the FMU stepped with the inputs held. Returns the
    angles and rates after each step and the rate at contact."""
    stop = PAR["LambdaStop"]
    lam, w, t = lam0, 0.0, 0.0
    lams, ws, w_contact = [], [], None
    for _ in range(int(round(t_end / h))):
        f.set_values({"Lambda": lam, "LambdaDot": w})
        m = f.get("Mjoint")[0]
        f.slave.doStep(t, h)
        t += h
        w += h * (T - m) / J
        lam_next = lam + h * w
        if w_contact is None and lam_next > stop:
            w_contact = w
        lam = lam_next
        lams.append(lam)
        ws.append(w)
    return np.array(lams), np.array(ws), (w_contact or 0.0)


@pytest.mark.parametrize("sign", [1, -1])
def test_end_stop_law_and_its_energy(damper, sign):
    """Beyond LambdaStop, with the valves at 0 % (no hydraulic torque): a spring
    kStop (|Lambda| - LambdaStop) pushing back, plus cStop LambdaDot only while
    moving further in. Ediss counts the stop's damping, not its spring."""
    stop, k, c = PAR["LambdaStop"], PAR["kStop"], PAR["cStop"]
    f = damper(pct=0.0)
    lam, h = sign * (stop + 0.01), 0.01
    for rate, damped in ((0.0, False), (sign * 0.3, True), (-sign * 0.3, False)):
        o = read(f, lam, rate, 0.0)
        want = sign * k * 0.01 + (c * rate if damped else 0.0)
        assert o["Mjoint"] == pytest.approx(want, rel=1e-6)
    # the energy over a few held steps, in and out
    g = damper(pct=0.0)
    t = 0.0
    for rate in (sign * 0.3, -sign * 0.3, sign * 0.1):
        E0 = g.get("Ediss")[0]
        read(g, lam, rate, 0.0)
        g.slave.doStep(t, h)
        t += h
        dE = g.get("Ediss")[0] - E0
        assert dE == pytest.approx(c * rate * rate * h if rate * sign > 0 else 0.0, rel=1e-9, abs=1e-12)
    # inside the stop nothing but the valves
    assert read(g, sign * (stop - 1e-6), sign * 0.3, 0.0)["Mjoint"] == 0.0


@pytest.mark.parametrize("J", [2e4, 5e4, 1.5e5])
@pytest.mark.parametrize("T", [3e4, 1e5, 3e5])
@pytest.mark.parametrize("h", [0.001, 0.01])
def test_end_stop_holds_a_driven_body(damper, J, T, h):
    """From rest at 50 deg, a constant torque drives the body into the stop:
    its angle never exceeds LambdaStop + T/kStop + the dynamic overshoot the
    energy balance allows (kStop d^2/2 <= T d + J w_c^2/2, w_c the rate at
    contact, damping neglected) + a small margin; the oscillation about
    LambdaStop + T/kStop dies out (it may bounce off the stop first). At rest
    there the stop holds T exactly (no hydraulic force at zero rate)."""
    stop, k = PAR["LambdaStop"], PAR["kStop"]
    f = damper(pct=3.5)
    lams, ws, wc = run_into_stop(f, J, T, h, 50 * DEG, 12.0)
    static = T / k
    peak = lams.max()
    assert peak > stop                                 # it did reach the stop: the test can fail
    assert peak <= stop + static + math.sqrt(static ** 2 + J * wc ** 2 / k) + 2e-3
    eq = stop + static
    last = lams[-int(round(1.0 / h)):]                # the last second
    assert np.max(np.abs(last - eq)) < 0.2 * (peak - eq)
    g = damper(pct=3.5)
    assert read(g, stop + static, 0.0, 3.5)["Mjoint"] == pytest.approx(T, rel=1e-9)
    assert read(g, -(stop + static), 0.0, 3.5)["Mjoint"] == pytest.approx(-T, rel=1e-9)


@pytest.mark.parametrize("J", [2e4, 5e4, 1.5e5])
def test_end_stop_from_rest_at_the_stop(damper, J):
    """Released at the stop with the torque already on: the peak stays between
    T/kStop and the undamped step response's 2 T/kStop beyond it."""
    stop, k, T = PAR["LambdaStop"], PAR["kStop"], 1e5
    f = damper(pct=3.5)
    lams, ws, _ = run_into_stop(f, J, T, 0.001, stop, 4.0)
    assert stop + T / k < lams.max() <= stop + 2 * T / k + 1e-4


def test_explicit_coupling_at_10ms_decays_without_overshoot(damper):
    """The damper's steepest rotational damping (small rates, 50 %) times the
    10 ms step over J = 5e4 kg m2 is below 1: coupled explicitly, a free
    relative rotation slows down monotonically and never reverses."""
    h, J = 0.01, 5e4
    slope = PAR["Ap"] * PAR["pMax"] * PAR["R"] ** 2 / PAR["v0"]      # 50 %, Lambda = 0
    assert h * slope / J < 1
    f = damper(pct=50.0)
    lam, w, t = 0.0, 0.3, 0.0
    ws = []
    for _ in range(400):
        f.set_values({"Lambda": lam, "LambdaDot": w})
        m = f.get("Mjoint")[0]
        f.slave.doStep(t, h)
        t += h
        w -= h * m / J
        lam += h * w
        ws.append(w)
    ws = np.array(ws)
    assert np.all(ws >= 0) and np.all(np.diff(ws) <= 0)
    assert ws[-1] < 1e-3 * ws[0]


# ---- bad input ----------------------------------------------------------------------------

@pytest.mark.parametrize("var", ["Lambda", "LambdaDot", "pct"])
def test_nan_input_is_refused(damper, var):
    f = damper()
    read(f, 0.2, 0.1, 10.0)
    before = f.get(*OUTS)
    with pytest.raises(FMICallException):
        f.set_values({var: math.nan})
    assert var in " ".join(f.log)
    after = f.get(*OUTS)
    assert after == before and all(math.isfinite(x) for x in after)


@pytest.mark.parametrize("pct", [-1.0, 50.5, 100.0])
def test_command_outside_0_50_is_an_error(damper, pct):
    f = damper()
    with pytest.raises(FMICallException):
        f.set_values({"pct": pct})
    assert "pct" in " ".join(f.log)


@pytest.mark.parametrize("geo", [dict(R=0.5, Xrear=0.3, Yrear=0.4),      # a cylinder through zero length at 36.9 deg
                                 dict(R=0.5, Xrear=0.3, Yrear=0.43),     # 2.4 cm at 34.9 deg
                                 dict(R=0.5, Xrear=0.45, Yrear=0.2)])    # 1.9 cm at 64 deg: beyond the stop, in the margin
def test_impossible_geometry_is_refused_at_initialisation(open_fmu, geo):
    # the shortest length within |Lambda| <= 64 deg, found here by brute force
    shortest = min(length(lam, s, R=geo["R"], X=geo["Xrear"], Y=geo["Yrear"])
                   for lam in np.linspace(-64, 64, 12801) * DEG for s in (1, -1))
    assert shortest < 0.05
    f = open_fmu(NAME)
    with pytest.raises(Exception):
        init(f, **geo)
    text = " ".join(f.log)
    for name, value in geo.items():
        assert f"{name} = {value:g}" in text


def test_unusual_but_possible_geometry_runs(damper):
    geo = dict(R=0.5, Xrear=0.6, Yrear=0.35)      # shortest 0.19 m at 59.7 deg (checked below)
    shortest = min(length(lam, s, R=0.5, X=0.6, Y=0.35) for lam in np.linspace(-64, 64, 12801) * DEG
                   for s in (1, -1))
    assert shortest > 0.05
    f = damper(**geo)
    for lam, rate, pct in cases(50, 9):
        o = read(f, lam, rate, pct)
        assert o["Mjoint"] * rate >= 0
        assert o["L[1]"] == pytest.approx(length(lam, 1, R=0.5, X=0.6, Y=0.35), rel=1e-12)


def test_geometry_is_checked_only_up_to_the_stop_and_a_margin(damper):
    """rho = R: the left cylinder would pass through zero length at 80 deg,
    beyond LambdaStop + 10 deg: accepted; driven there anyway, its length is
    held at 5 cm with one warning, the outputs stay finite."""
    R, phi = 0.5, 80 * DEG
    geo = dict(R=R, Xrear=R * math.sin(phi), Yrear=R * math.cos(phi))
    assert length(phi, 1, R=R, X=geo["Xrear"], Y=geo["Yrear"]) < 1e-7
    assert min(length(lam, s, R=R, X=geo["Xrear"], Y=geo["Yrear"])
               for lam in np.linspace(-64, 64, 12801) * DEG for s in (1, -1)) > 0.05
    f = damper(**geo)
    o = read(f, phi, 0.5, 20.0)
    assert o["L[1]"] == 0.05 and all(math.isfinite(x) for x in o.values())
    for i in range(3):
        f.slave.doStep(i * 0.01, 0.01)
    assert sum("[Warning]" in line and "Lambda" in line for line in f.log) == 1
    assert all(math.isfinite(x) for x in f.get(*OUTS))


def test_extreme_inputs_and_parameters_give_finite_outputs(damper):
    f = damper(kStop=1e10, cStop=1e9, v0=1e-6, pMax=1e8, Ap=0.1, R=2.0, Xrear=5.0, Yrear=2.0)
    t = 0.0
    for lam in (-math.pi, -1.0, 0.0, 1.3, math.pi):
        for rate in (-100.0, -1e-300, 0.0, 1e-300, 100.0):
            for pct in (0.0, 50.0):
                o = read(f, lam, rate, pct)
                assert all(math.isfinite(x) for x in o.values()), (lam, rate, pct, o)
                f.slave.doStep(t, 0.01)
                t += 0.01
                assert all(math.isfinite(x) for x in f.get(*OUTS))
