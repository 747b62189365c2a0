"""artibus replay (issue 12): a log drives the kinematic replay bench; seed
003, section V's comparison of model against measured."""
import math
import subprocess
import sys

import numpy as np
import pytest

from artibus import ArtibusError, ROOT, fmu_path
from artibus.bench.parameters import read_parameters
from artibus.can import replay
from artibus.fmu import simulate

LOG = ROOT / "ssp" / "logs" / "Urbino18_test.csv"
C = [0.69, 0.71, 9.8e-5, 3.2e-5]          # seed 003, Appendix A, as printed
DEG_ = math.pi / 180


def alpha_of(gamma_deg):
    """the sensor angle for an effective steering angle: the real root of the cubic (numpy)."""
    out = []
    for g in gamma_deg:
        roots = np.roots([C[3], C[2], C[1], C[0] - g])
        out.append(float(roots[np.argmin(np.abs(roots.imag))].real))
    return np.array(out)


@pytest.fixture(scope="module")
def clean_log(tmp_path_factory):
    """A log without noise: a run of BusKinematics alone (FMPy-driven, not the runner)."""
    p = read_parameters("Urbino18", fmu_path("BusKinematics"))
    p.update(testSteerAmp=0.0, x_start=2.0, y_start=-1.0, theta_start=0.3)

    def g(t):
        return math.radians(20 * math.sin(2 * math.pi * t / 16)) if t < 16 else 0.0

    def v(t):
        return 3.0 + 0.1 * t

    r = simulate(fmu_path("BusKinematics"), parameters=p, inputs={"gammaF": g, "v": v}, stop_time=20.0, step=0.01)
    alpha = alpha_of([math.degrees(g(t)) for t in r.time])
    rows = ["time_s,alpha_sensor_deg,v1_tacho_mps,beta1_sensor_deg,x1_dgps_m,y1_dgps_m,theta1_dgps_deg"]
    for i, t in enumerate(r.time):
        rows.append(f"{t:.2f},{alpha[i]:.17g},{v(t):.17g},{math.degrees(r['beta[1]'][i]):.17g},{r['x[1]'][i]:.17g},"
                    f"{r['y[1]'][i]:.17g},{math.degrees(r['theta[1]'][i]):.17g}")
    f = tmp_path_factory.mktemp("log") / "clean.csv"
    f.write_text("# test\n" + "\n".join(rows) + "\n")
    return f, r


def test_replay_of_a_clean_log_reproduces_the_run(clean_log):
    """Steering through the inverse polynomial and back, the start pose rebuilt
    from P1, theta1, beta1 (P0 = P1 + L1 u(theta1) + Lh1 u(theta0)): the
    replayed model follows the original run to integration accuracy."""
    f, r = clean_log
    rep = replay.replay(f, "Urbino18_Replay")
    m = rep.result
    np.testing.assert_allclose(m["Bus.x[1]"], r["x[1]"], atol=1e-5)
    np.testing.assert_allclose(m["Bus.y[1]"], r["y[1]"], atol=1e-5)
    np.testing.assert_allclose(m["Bus.theta[1]"], r["theta[1]"], atol=1e-6)
    np.testing.assert_allclose(m["Bus.beta[1]"], r["beta[1]"], atol=1e-6)
    assert all(mx < 1e-3 for _, _, mx, _ in rep.errors)


def test_prediction_model_of_a_clean_log_reproduces_the_run(clean_log):
    """seed 003's prediction model (variant prediction: the wagon's heading
    from omega_1tacho of eq. 51, computed from the logged steering, joint angle
    and wagon speed): with exact sensors omega_1tacho is the run's omega_1, so
    the wagon's heading and path follow the run as closely as the integrating
    model's, which the replay runs beside it."""
    f, r = clean_log
    rep = replay.replay(f, "Urbino18_Replay", variants=["prediction"], record=["Bus.omegaMeas", "Bus.omega[1]"])
    m = rep.result
    assert rep.label == "prediction model" and rep.base[0] == "model"
    # the rate the model got from t_k on (recorded in row k + 1): eq. 51 as printed, at the run's
    # values at t_k: omega_0 = v0 tan(gammaF) / L0, [omega_1, v1] = J_1(beta_1, 0, 0) [omega_0, v0],
    # J_1 = [[-Lh1/L1 cos b, sin b / L1], [Lh1 sin b, cos b]] (eq. 14), solved for the logged v1
    p = read_parameters("Urbino18", fmu_path("BusKinematics"))
    L0, L1, Lh1 = (float(p[n]) for n in ("L0", "L[1]", "Lh[1]"))
    t, b = r.time, r["beta[1]"]
    gF = np.radians(replay.map_steering(alpha_of([math.degrees(20 * DEG_ * math.sin(2 * math.pi * x / 16))
                                                   if x < 16 else 0.0 for x in t]), C))
    k0 = np.tan(gF) / L0
    v0 = (3.0 + 0.1 * t) / (Lh1 * np.sin(b) * k0 + np.cos(b))
    w1 = (-Lh1 / L1 * np.cos(b) * k0 + np.sin(b) / L1) * v0
    np.testing.assert_allclose(m["Bus.omegaMeas"][1:], w1[:-1], atol=1e-9)
    # integrated over a step h the held rate differs from the run's omega_1(beta(t)) by
    # h^2/2 d omega/dt; summed to t, h/2 (omega(t) - omega(0)): at most h max |omega_1|; the path
    # then by at most that angle times the distance driven
    h = t[1] - t[0]
    dth = h * np.max(np.abs(r["omega[1]"]))
    np.testing.assert_allclose(m["Bus.theta[1]"], r["theta[1]"], atol=dth)
    dist = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r["x[1]"]), np.diff(r["y[1]"])))])
    d = np.hypot(m["Bus.x[1]"] - r["x[1]"], m["Bus.y[1]"] - r["y[1]"])
    assert np.all(d <= dth * dist + 1e-6)
    np.testing.assert_allclose(m["Bus.beta[1]"], r["beta[1]"], atol=1e-6)
    base = rep.base[1]
    np.testing.assert_allclose(base["Bus.theta[1]"], r["theta[1]"], atol=1e-6)
    assert all(mx < 1e-3 for _, _, mx, _ in rep.base[2])


def test_prediction_variant_report_has_both_models(tmp_path):
    out = tmp_path / "rep"
    p = subprocess.run([sys.executable, "-m", "artibus", "replay", str(LOG), "--bench", "Urbino18_Replay",
                        "--variant", "prediction", "-o", str(tmp_path / "r.csv"), "--report", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    errs = {l.split(",")[0].strip('"'): float(l.split(",")[2]) for l in (out / "errors.csv").read_text().splitlines()[1:]}
    for q in ("joint angle beta1", "wagon heading theta1", "path of P1 (distance at the fixes)"):
        assert math.isfinite(errs[q]) and math.isfinite(errs[f"{q} [prediction model]"])
    assert "prediction model against measured" in p.stdout and "model against measured" in p.stdout


def test_shipped_log_replay_errors_are_those_of_its_sensors(tmp_path):
    """The shipped synthetic log (scripts/make_test_log.py: backlash 0.5 deg on
    the joint sensor, 0.4 deg in the steering, noise, quantisation): the joint
    angle within backlash/2 + 3 noise sd + half a step + the steering play's
    effect (< 1 deg); heading and path drift as seed 003 describes, but stay
    small over 70 s (< 3 deg, < 2 m)."""
    head = LOG.read_text().splitlines()[0]
    assert "SYNTHETIC" in head and "make_test_log.py" in head
    out = tmp_path / "rep"
    p = subprocess.run([sys.executable, "-m", "artibus", "replay", str(LOG), "--bench", "Urbino18_Replay",
                        "-o", str(tmp_path / "r.csv"), "--report", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    errs = {l.split(",")[0].strip('"'): float(l.split(",")[2]) for l in (out / "errors.csv").read_text().splitlines()[1:]}
    assert errs["joint angle beta1"] < 1.0
    assert errs["wagon heading theta1"] < 3.0
    assert errs["path of P1 (distance at the fixes)"] < 2.0
    assert (out / "angles.png").is_file() and (out / "path.png").is_file()
    assert "seed 003 App. A steering map" in p.stdout


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace("v1_tacho_mps", "speed"), ["no signal 'v1_tacho_mps'", "Bus.v"]),
    (lambda t: t.replace("beta1_sensor_deg", "beta"), ["no signal 'beta1_sensor_deg'", "start state"]),
    (lambda t: t.replace("\n0.05,", "\n0.05,x", 1), ["data row 6", "not a number"]),
])
def test_log_errors_name_file_and_signal(tmp_path, edit, words):
    f = tmp_path / "bad.csv"
    f.write_text(edit(LOG.read_text()))
    out = tmp_path / "out.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "replay", str(f), "--bench", "Urbino18_Replay", "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert str(f) in p.stderr and all(w in p.stderr for w in words), p.stderr
    assert list(tmp_path.iterdir()) == [f]


def test_map_errors():
    with pytest.raises(ArtibusError, match="no component 'Nope'"):
        replay.replay(LOG, "Urbino18_Replay", maps=["v1_tacho_mps=Nope.v"])
    with pytest.raises(ArtibusError, match="expected SIGNAL=COMP.INPUT"):
        replay.replay(LOG, "Urbino18_Replay", maps=["v1_tacho_mps"])
