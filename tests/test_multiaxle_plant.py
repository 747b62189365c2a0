"""MultiAxle3DOF (seed 004, eqs. 1-5) against the paper's equations written
out in numpy (test_multiaxle_model.py): steady states, the exact step
response of the linear system, the two-axle bicycle model, symmetry, and bad
input. No number here was printed by the FMU."""
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from fmpy import read_model_description

from artibus.fmu import Fmu, SimulationError, simulate
from conftest import ROOT, fmu_file, init
from test_multiaxle_model import (BUS, bicycle, eq4, fmu_parameters, state_space, steady_state,
                                  step_response)

STATES = ["w_r", "beta", "p", "phi"]
#: what is left of the transient after 40 s, and the integrator's error
#: (rtol 1e-10): absolute floors for states whose steady value is 0 (p)
ABS = 1e-10


def run(veh, u, delta, stop, step=0.05, Md=0.0, extra=None, outputs=None):
    """the plant from rest with constant inputs (a step at t = 0)"""
    params = fmu_parameters(veh)
    params.update(testSteerAmp=0.0, rtol=1e-10, atol=1e-12)
    params.update(extra or {})
    inputs = {"u": lambda t: u, "M_d": lambda t: Md}
    for i, d in enumerate(delta, 1):
        inputs[f"delta[{i}]"] = (lambda x: lambda t: x)(d)
    return simulate(fmu_file("MultiAxle3DOF"), parameters=params, inputs=inputs,
                    stop_time=stop, step=step, outputs=outputs)


def front_step(veh, d1=0.01):
    return [d1] + [0.0] * (veh["n"] - 1)


@pytest.mark.parametrize("u", [5.0, 10.0, 20.0, 30.0])
def test_steady_state_front_steer_matches_eq4(u):
    """yaw-rate gain, side-slip, roll angle and a_y = u w_r after the transient"""
    d = front_step(BUS)
    r = run(BUS, u, d, stop=40.0, step=0.5)
    ss = steady_state(u, BUS, d)
    for name, ref in zip(STATES, ss):
        assert r[name][-1] == pytest.approx(ref, rel=1e-7, abs=ABS), name
    assert r["a_y"][-1] == pytest.approx(u * ss[0], rel=1e-7)
    assert r["v"][-1] == pytest.approx(u * ss[1], rel=1e-7, abs=1e-12)
    assert abs(ss[1]) > 1e-4 and ss[3] > 0     # the test can fail: side-slip and roll are there


@pytest.mark.parametrize("u", [5.0, 20.0])
def test_steady_state_all_inputs(u):
    """every axle steered with its own angle, a yaw moment M_d, roll offsets
    d_i != 0 and I_XZb != 0: eq. 4's whole right-hand side"""
    veh = dict(BUS, d=[0.05, -0.02, 0.03], I_XZb=2000.0, steerable=[True, True, True])
    d = [0.01, -0.004, 0.006]
    r = run(veh, u, d, Md=3e4, stop=40.0, step=0.5)
    ss = steady_state(u, veh, d, Md=3e4)
    for name, ref in zip(STATES, ss):
        assert r[name][-1] == pytest.approx(ref, rel=1e-7, abs=ABS), name


def test_six_axles_steady_state():
    veh = dict(n=6, l=[4.5, 3.0, 0.5, -1.0, -2.5, -4.0], k=[-3e5] * 6, m=[900.0] * 6,
               d=[0.0] * 6, steerable=[True, True, False, False, True, True],
               m_b=40000.0, h_b=0.7, I_ZZb=4e5, I_XXb=4e4, I_XZb=0.0, C_phi=2e5, K_phi=4e6)
    d = [0.01, 0.007, 0.0, 0.0, -0.002, -0.004]
    for u in (8.0, 25.0):
        r = run(veh, u, d, stop=40.0, step=0.5)
        ss = steady_state(u, veh, d)
        for name, ref in zip(STATES, ss):
            assert r[name][-1] == pytest.approx(ref, rel=1e-7, abs=ABS), name


@pytest.mark.parametrize("u", [5.0, 20.0, 30.0])
def test_step_response_is_the_exact_linear_solution(u):
    """the whole transient: w_r, beta, p, phi and a_y against
    X(t) = V diag((e^{lambda t} - 1)/lambda) V^-1 B U from eq. 5's eigenvalues"""
    d = front_step(BUS)
    r = run(BUS, u, d, stop=6.0, step=0.02)
    t = r.time
    X, Xdot = step_response(u, BUS, d, t)
    lam = np.linalg.eigvals(state_space(u, BUS)[0])
    assert np.all(lam.real < 0)
    for j, name in enumerate(STATES):
        scale = np.max(np.abs(X[:, j]))
        assert np.max(np.abs(r[name] - X[:, j])) < 1e-6 * scale, name
    ay = u * (Xdot[:, 1] + X[:, 0])
    assert np.max(np.abs(r["a_y"] - ay)) < 1e-6 * np.max(np.abs(ay))


def test_two_axle_plant_is_the_bicycle_model():
    """n = 2, no unsprung masses, h_b = 0: the FMU's w_r and v follow the
    textbook bicycle model's exact step response"""
    a, b, m, Iz, Cf, Cr = 1.2, 1.6, 1600.0, 2800.0, 9e4, 1.1e5
    veh = dict(n=2, l=[a, -b], k=[-Cf, -Cr], m=[0.0, 0.0], d=[0.0, 0.0], steerable=[True, False],
               m_b=m, h_b=0.0, I_ZZb=Iz, I_XXb=500.0, I_XZb=0.0, C_phi=4e3, K_phi=6e4)
    delta = 0.02
    for u in (8.0, 25.0):
        r = run(veh, u, [delta, 0.0], stop=4.0, step=0.02)
        A, B = bicycle(u, a, b, m, Iz, Cf, Cr)
        lam, V = np.linalg.eig(A)
        c = np.linalg.solve(V, B * delta)
        t = r.time[:, None]
        vr = (((np.exp(lam * t) - 1) / lam * c) @ V.T).real      # [v, r]
        assert np.max(np.abs(r["v"] - vr[:, 0])) < 1e-6 * np.max(np.abs(vr[:, 0]))
        assert np.max(np.abs(r["w_r"] - vr[:, 1])) < 1e-6 * np.max(np.abs(vr[:, 1]))
        # the textbook steady state: w_r/delta = u/(L + K_us u^2), K_us = m/L (b/Cf - a/Cr)
        L = a + b
        K_us = m / L * (b / Cf - a / Cr)
        r_ss = run(veh, u, [delta, 0.0], stop=30.0, step=0.5)
        assert r_ss["w_r"][-1] == pytest.approx(u / (L + K_us * u * u) * delta, rel=1e-7)
        assert np.all(np.abs(r["phi"]) < 1e-14)        # h_b = 0: no roll


def test_left_right_symmetry():
    """steering right gives exactly the mirror image of steering left"""
    d = front_step(BUS)
    left = run(BUS, 15.0, d, stop=5.0, step=0.05)
    right = run(BUS, 15.0, [-x for x in d], stop=5.0, step=0.05)
    for name in STATES + ["a_y", "v", "psi", "y", "alpha[1]", "F_Y[3]"]:
        # to rounding: CVODE's difference-quotient Jacobian is not sign-symmetric
        assert np.max(np.abs(left[name] + right[name])) <= 1e-12 * np.max(np.abs(left[name])), name
    assert np.max(np.abs(left["x"] - right["x"])) <= 1e-12 * left["x"][-1]
    assert np.max(np.abs(left["y"])) > 1.0


def test_slip_angles_and_forces():
    """alpha_i = beta + l_i w_r/u - delta_i, F_Yi = k_i alpha_i (eq. 2), from
    the FMU's own states; their sum balances M a_y in the steady state"""
    u = 12.0
    d = front_step(BUS)
    r = run(BUS, u, d, stop=40.0, step=0.5)
    beta, wr = r["beta"][-1], r["w_r"][-1]
    F = 0.0
    for i in range(3):
        alpha = beta + BUS["l"][i] * wr / u - d[i]
        assert r[f"alpha[{i + 1}]"][-1] == pytest.approx(alpha, rel=1e-12)
        assert r[f"F_Y[{i + 1}]"][-1] == pytest.approx(BUS["k"][i] * alpha, rel=1e-12)
        F += BUS["k"][i] * alpha
    M = BUS["m_b"] + sum(BUS["m"])
    assert F == pytest.approx(M * r["a_y"][-1], rel=1e-6)
    for i in range(4, 7):
        assert r[f"alpha[{i}]"][-1] == 0.0 and r[f"F_Y[{i}]"][-1] == 0.0


def test_fixed_axle_ignores_its_input():
    d = [0.01, 0.05, 0.0]            # axle 2 is fixed on the bus
    r = run(BUS, 15.0, d, stop=30.0, step=0.5)
    assert r["w_r"][-1] == pytest.approx(steady_state(15.0, BUS, [0.01, 0.0, 0.0])[0], rel=1e-7)


def test_default_experiment_step_steer():
    """running alone, every stimulus off: the start value delta[1] = 0.02 rad
    at 20 m/s is a front step at t = 0"""
    md = read_model_description(str(fmu_file("MultiAxle3DOF")))
    r = simulate(fmu_file("MultiAxle3DOF"), stop_time=float(md.defaultExperiment.stopTime))
    t = r.time
    X, _ = step_response(20.0, BUS, [0.02, 0.0, 0.0], t)
    assert np.max(np.abs(r["w_r"] - X[:, 0])) < 1e-5 * np.max(np.abs(X[:, 0]))


def test_low_speed_warns_once_and_stays_finite(open_fmu):
    fmu = open_fmu("MultiAxle3DOF")
    init(fmu, testSteerAmp=0.0, **{"u": 0.0, "delta[1]": 0.1})
    for k in range(40):
        fmu.slave.doStep(k * 0.05, 0.05)
    out = fmu.get("w_r", "beta", "a_y", "x")
    assert all(math.isfinite(x) for x in out)
    warnings = [m for m in fmu.log if "uMin" in m]
    assert len(warnings) == 1 and "Warning" in warnings[0], fmu.log
    # the model ran as at u = uMin = 1 m/s
    X, _ = step_response(1.0, BUS, [0.1, 0.0, 0.0], [2.0])
    assert out[0] == pytest.approx(X[0, 0], rel=1e-6)
    fmu.slave.reset()
    init(fmu, testSteerAmp=0.0, u=0.5)
    fmu.log.clear()
    fmu.slave.doStep(0.0, 0.05)
    assert sum("uMin" in m for m in fmu.log) == 1    # a new episode warns again


def test_negative_speed_is_refused(open_fmu):
    fmu = open_fmu("MultiAxle3DOF")
    init(fmu)
    with pytest.raises(Exception):
        fmu.set_values({"u": -1.0})
    assert any("u = -1" in m and "minimum" in m for m in fmu.log), fmu.log


def test_roll_instability_is_an_error():
    with pytest.raises(SimulationError) as e:
        simulate(fmu_file("MultiAxle3DOF"), parameters={"K_phi": 1e5}, stop_time=1.0)
    assert "K_phi" in str(e.value) + " ".join(e.value.log)


def test_ssv_matches_the_defaults():
    """ssp/parameters/Bus15mTagAxle.ssv holds the default vehicle"""
    ns = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
    root = ET.parse(ROOT / "ssp/parameters/Bus15mTagAxle.ssv").getroot()
    values = {}
    for p in root.iter("{%s}Parameter" % ns["ssv"]):
        child = next(iter(p))
        v = child.get("value")
        values[p.get("name")] = {"Real": float, "Integer": int}.get(child.tag.split("}")[1], lambda s: s == "true")(v)
    expected = fmu_parameters(BUS)
    assert values == expected
    md = read_model_description(str(fmu_file("MultiAxle3DOF")))
    for v in md.modelVariables:
        if v.name in expected:
            start = {"Real": float, "Integer": int}.get(v.type, lambda s: s == "true")(v.start)
            assert start == expected[v.name], v.name
