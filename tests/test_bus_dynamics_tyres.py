"""BusDynamics tyre models and static axle loads against closed forms:
the lever rule, the bicycle model with friction-scaled cornering stiffness
(seed 001), the friction limit, and the brush (Fiala) model."""
import math

import numpy as np
import pytest

from artibus import fmu_path
from artibus.fmu import Fmu, SimulationError, simulate
from test_bus_dynamics import BICYCLE, NO_TEST_STEER, THREE

G = 9.81
# the defaults of the FMU: Scania 18 m (seed 001, Table 3.1)
f1, b1, b11, f2, b2, m1, m2 = 1.944, 3.306, 5.128, 4.777, 0.163, 8100.0, 8556.0


def initial_outputs(params, inputs, names):
    """outputs in initialization mode (no step): the tyre forces of the start state"""
    with Fmu(fmu_path("BusDynamics")) as fmu:
        fmu.slave.setupExperiment(startTime=0.0)
        fmu.slave.enterInitializationMode()
        fmu.set_values(params)
        fmu.set_values(inputs)
        return dict(zip(names, fmu.get(*names)))


def test_static_loads_of_the_pusher_by_the_lever_rule():
    """Rear module: axle and hinge share m2 g by the lever rule; the front
    module carries its weight plus the hinge load on its two axles."""
    out = initial_outputs(NO_TEST_STEER, {}, ["Fz[1]", "Fz[2]", "Fz[3]"])
    V = m2 * G * b2 / (f2 + b2)
    F3 = m2 * G * f2 / (f2 + b2)
    F1 = (m1 * G * b1 - V * (b11 - b1)) / (f1 + b1)
    F2 = m1 * G + V - F1
    assert out["Fz[3]"] == pytest.approx(F3, rel=1e-12)
    assert out["Fz[1]"] == pytest.approx(F1, rel=1e-12)
    assert out["Fz[2]"] == pytest.approx(F2, rel=1e-12)


def test_static_loads_of_full_trailers_and_given_loads():
    """Modules with two axles are full trailers: each carries its own weight."""
    names = [f"Fz[{a}]" for a in range(1, 7)]
    out = initial_outputs(THREE, {}, names)
    for m, (a1, a2) in zip((1, 2, 3), ((1, 2), (3, 4), (5, 6))):
        x1, x2, W = THREE[f"xA[{a1}]"], THREE[f"xA[{a2}]"], THREE[f"m[{m}]"] * G
        assert out[f"Fz[{a1}]"] == pytest.approx(W * -x2 / (x1 - x2), rel=1e-12)
        assert out[f"Fz[{a2}]"] == pytest.approx(W * x1 / (x1 - x2), rel=1e-12)
    given = dict(THREE, FzFromMasses=False, **{f"Fz0[{a}]": 1000.0 * a for a in range(1, 7)})
    out = initial_outputs(given, {}, names)
    assert [out[n] for n in names] == [1000.0 * a for a in range(1, 7)]


def test_static_loads_that_cannot_be_found_are_an_error():
    p = dict(NO_TEST_STEER, **{"nAxles": 2, "axleModule[2]": 2})  # module 1 on one axle
    with pytest.raises(SimulationError) as e:
        simulate(fmu_path("BusDynamics"), parameters=p, stop_time=0.1, step=0.1)
    assert "module 1" in str(e.value) and "FzFromMasses" in str(e.value)


@pytest.mark.parametrize("model", [1, 3])
@pytest.mark.parametrize("mu", [0.3, 0.7])
@pytest.mark.parametrize("u", [10.0, 20.0])
def test_friction_scales_cornering_stiffness(mu, u, model):
    """tyreModel 1 below the friction limit, and tyreModel 3 everywhere, is
    the bicycle model with C_eff = mu C (seed 001): r/delta = u / (L + K u^2),
    K = m/L (b/(mu Cf) - a/(mu Cr))."""
    a, b = BICYCLE["xA[1]"], -BICYCLE["xA[2]"]
    L, m = a + b, BICYCLE["m[1]"]
    K = m / L * (b / (mu * BICYCLE["C[1]"]) - a / (mu * BICYCLE["C[2]"]))
    delta = 1e-3
    p = dict(BICYCLE, vx_start=u, tyreModel=model, **{"mu[1]": mu, "mu[2]": mu})
    r = simulate(fmu_path("BusDynamics"), parameters=p, inputs={"delta[1]": lambda t: delta},
                 stop_time=15.0, step=0.05, outputs=["r[1]", "vx[1]", "Fy[1]", "Fz[1]"])
    assert abs(r["Fy[1]"][-1]) < 0.1 * mu * r["Fz[1]"][-1]     # far from saturation
    uu = r["vx[1]"][-1]
    assert r["r[1]"][-1] / delta == pytest.approx(uu / (L + K * uu ** 2), rel=5e-3)


@pytest.mark.parametrize("model", [1, 2])
def test_lateral_force_is_limited_by_friction(model):
    """Large slip: |Fy| reaches mu Fz and does not exceed it."""
    mu = 0.4
    names = ["Fy[1]", "Fz[1]", "alpha[1]"]
    for d in (0.3, -0.5, 0.7):   # beyond the sliding limit of both models (0.19 and 0.23 rad here)
        out = initial_outputs(dict(BICYCLE, tyreModel=model, **{"mu[1]": mu}), {"delta[1]": d}, names)
        # straight ahead, no yaw: the slip angle is delta, up to the low-speed blend vSlip
        u = BICYCLE.get("vx_start", 10.0)
        expected = math.atan2(math.sin(d) * u, math.hypot(math.cos(d) * u, 0.01))
        assert out["alpha[1]"] == pytest.approx(expected, abs=1e-15)
        assert expected == pytest.approx(d, abs=1e-6)
        assert out["Fy[1]"] == pytest.approx(math.copysign(mu * out["Fz[1]"], d), rel=1e-12)


def test_seed001_linear_model_scales_by_friction_without_a_limit():
    """tyreModel 3 (seed 001's extensive model, eq. C.1 with the friction
    coefficient scaling the tyre coefficient): Fy = mu C alpha at any slip,
    also far beyond mu Fz, where tyreModel 1 saturates."""
    mu = 0.2
    names = ["Fy[1]", "Fz[1]", "alpha[1]"]
    for d in (0.01, -0.3, 0.5):
        out = initial_outputs(dict(BICYCLE, tyreModel=3, **{"mu[1]": mu}), {"delta[1]": d}, names)
        assert out["Fy[1]"] == pytest.approx(mu * BICYCLE["C[1]"] * out["alpha[1]"], rel=1e-12)
    assert abs(out["Fy[1]"]) > 2 * mu * out["Fz[1]"]


def test_brush_model_closed_form():
    """Fiala's brush model (Pacejka, Tyre and Vehicle Dynamics, 2012, eq. 3.35 ff.):
    Fy = C t - C^2 |t| t / (3 mu Fz) + C^3 t^3 / (27 mu^2 Fz^2), t = tan(alpha),
    up to full sliding at |t| = 3 mu Fz / C; slope C at alpha = 0."""
    mu = 0.8
    p = dict(BICYCLE, tyreModel=2, **{"mu[1]": mu})
    names = ["Fy[1]", "Fz[1]", "alpha[1]"]
    C = BICYCLE["C[1]"]
    for d in (1e-6, 0.005, -0.02, 0.04, 0.06):
        out = initial_outputs(p, {"delta[1]": d}, names)
        Fz, t = out["Fz[1]"], math.tan(out["alpha[1]"])
        if abs(t) < 3 * mu * Fz / C:
            F = C * t - C ** 2 * abs(t) * t / (3 * mu * Fz) + C ** 3 * t ** 3 / (27 * mu ** 2 * Fz ** 2)
        else:
            F = math.copysign(mu * Fz, t)
        assert out["Fy[1]"] == pytest.approx(F, rel=1e-9), d
    small = initial_outputs(p, {"delta[1]": 1e-6}, names)
    assert small["Fy[1]"] / 1e-6 == pytest.approx(C, rel=1e-5)


def test_brush_model_bicycle_at_small_steering():
    """At small slip the brush model has the slope C: the linear yaw gain."""
    a, b = BICYCLE["xA[1]"], -BICYCLE["xA[2]"]
    L, m, Cf, Cr = a + b, BICYCLE["m[1]"], BICYCLE["C[1]"], BICYCLE["C[2]"]
    K = m / L * (b / Cf - a / Cr)
    delta, u = 1e-4, 15.0
    r = simulate(fmu_path("BusDynamics"), parameters=dict(BICYCLE, vx_start=u, tyreModel=2),
                 inputs={"delta[1]": lambda t: delta}, stop_time=15.0, step=0.05,
                 outputs=["r[1]", "vx[1]"])
    uu = r["vx[1]"][-1]
    assert r["r[1]"][-1] / delta == pytest.approx(uu / (L + K * uu ** 2), rel=5e-3)


def test_brush_model_saturates_smoothly_in_a_step_steer():
    """Hard step steer at 15 m/s on mu 0.5: the front axle saturates; the
    simulation runs and the lateral acceleration stays below mu g."""
    p = dict(BICYCLE, vx_start=15.0, tyreModel=2, **{"mu[1]": 0.5, "mu[2]": 0.5})
    r = simulate(fmu_path("BusDynamics"), parameters=p, inputs={"delta[1]": lambda t: 0.4},
                 stop_time=5.0, step=0.01, outputs=["ay[1]", "Fy[1]", "Fz[1]"])
    assert np.max(np.abs(r["Fy[1]"])) == pytest.approx(0.5 * r["Fz[1]"][0], rel=1e-6)
    assert np.max(np.abs(r["ay[1]"])) < 0.5 * G * (1 + 1e-9)
