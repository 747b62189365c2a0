"""BusKinematics' prediction model (seed 003, section V, Fig. 11): with
predictionModel the heading of the distinguished segment j integrates the
measured angular velocity omegaMeas instead of the model's omega_j (eq. 22);
unused, the new input changes nothing."""
import math

import numpy as np
import pytest

from artibus import fmu_path
from artibus.bench.parameters import read_parameters
from artibus.fmu import simulate

FMU = fmu_path("BusKinematics")
OUT = ["theta[0]", "theta[1]", "x[0]", "y[0]", "x[1]", "y[1]", "beta[1]", "omega[0]", "omega[1]", "vel[1]",
       "betaDot[1]", "kappa[1]"]


def urbino(**kw):
    p = read_parameters("Urbino18", FMU)
    p.update(testSteerAmp=0.0)
    p.update(kw)
    return p


@pytest.mark.parametrize("j", [0, 1])
def test_unused_input_changes_nothing_bit_for_bit(j):
    """predictionModel false (the default): omegaMeas at any value gives the
    same results bit for bit as leaving it alone, on a run that steers (the
    default experiment's built-in S-curve) and on one driven through inputs."""
    for p, inputs in ((dict(j=j), {}),
                      (urbino(j=j), {"gammaF": lambda t: 0.3 * math.sin(0.4 * t), "v": lambda t: 2.0 + 0.05 * t})):
        a = simulate(FMU, parameters=p, inputs=inputs, stop_time=20.0, step=0.05, outputs=OUT)
        b = simulate(FMU, parameters=p, inputs={**inputs, "omegaMeas": lambda t: 0.7}, stop_time=20.0,
                     step=0.05, outputs=OUT)
        assert "predictionModel" not in p
        np.testing.assert_array_equal(a.array(), b.array())


@pytest.mark.parametrize("w", [0.1, -0.25])
def test_prediction_model_integrates_the_measured_rate(w):
    """Urbino 18 pushing (k = 1), the wagon distinguished (j = 1), front wheels
    straight, constant speed v, joint angle beta0 at the start. Derived here:
    with gammaF = 0 the tractor's curvature is 0 (eq. 19), delta_1 = beta_1
    (eq. 17), kappa_1 = tan(beta_1) / L1 (eq. 20), u_1 = [kappa_1 v, v] (eq.
    21) and eq. 15 gives omega_0 = -L1/Lh1 cos(b) kappa_1 v + sin(b) v / Lh1 = 0:
    so d beta_1/dt = -v tan(beta_1) / L1 (eq. 16), i.e. sin beta_1(t) =
    sin(beta0) exp(-v t / L1). The simulation model turns the wagon with
    omega_1 = -d beta_1/dt: theta_1 = theta_0(0) - beta_1(t). The prediction
    model with omegaMeas = w: theta_1 = theta_1(0) + w t, P1 on the arc of
    radius v/w (x1 = x1(0) + v/w (sin theta_1 - sin theta_1(0)), y1 = y1(0) -
    v/w (cos theta_1 - cos theta_1(0))), beta_1 as before, theta_0 = theta_1 +
    beta_1 (eq. 3); the model's omega_1 output stays eq. 14's."""
    v, b0, th0 = 2.0, 0.3, 0.4
    L1 = 4.211
    t_end = 15.0
    base = urbino(j=1, v=v, theta_start=th0, x_start=1.0, y_start=-2.0, **{"beta_start[1]": b0})
    sim = simulate(FMU, parameters=base, stop_time=t_end, step=0.05, outputs=OUT)
    pred = simulate(FMU, parameters={**base, "predictionModel": True}, inputs={"omegaMeas": lambda t: w},
                    stop_time=t_end, step=0.05, outputs=OUT)
    t = sim.time
    beta = np.arcsin(math.sin(b0) * np.exp(-v * t / L1))
    th1_0 = th0 - b0
    x1_0 = sim["x[1]"][0]
    y1_0 = sim["y[1]"][0]
    assert x1_0 == pytest.approx(1.0 - 1.789 * math.cos(th0) - L1 * math.cos(th1_0), abs=1e-12)
    # the simulation model
    np.testing.assert_allclose(sim["beta[1]"], beta, atol=1e-7)
    np.testing.assert_allclose(sim["theta[1]"], th0 - beta, atol=1e-7)
    np.testing.assert_allclose(sim["theta[0]"], th0, atol=1e-7)
    # the prediction model
    th1 = th1_0 + w * t
    np.testing.assert_allclose(pred["theta[1]"], th1, atol=1e-7)
    np.testing.assert_allclose(pred["beta[1]"], beta, atol=1e-7)
    np.testing.assert_allclose(pred["theta[0]"], th1 + beta, atol=1e-7)
    np.testing.assert_allclose(pred["x[1]"], x1_0 + v / w * (np.sin(th1) - math.sin(th1_0)), atol=1e-6)
    np.testing.assert_allclose(pred["y[1]"], y1_0 - v / w * (np.cos(th1) - math.cos(th1_0)), atol=1e-6)
    np.testing.assert_allclose(pred["omega[1]"], v * np.tan(beta) / L1, atol=1e-7)
    np.testing.assert_allclose(pred["vel[1]"], v, atol=1e-12)
