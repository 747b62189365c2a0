"""artibus replay (issue 12): a log drives the kinematic replay bench; seed
003, section V's comparison of model against measured."""
import math
import subprocess
import sys

import numpy as np
import pytest

from artibus import ROOT, ArtibusError, fmu_path, replay
from artibus.parameters import read_parameters
from artibus.simulation import simulate

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


# --- a CAN run's own log replayed into its bench (issue 12) --------------------------------

CAN_BENCH = "Bus36m_Circle_CAN"
DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
TO_SI = {"deg": math.pi / 180, "km/h": 1 / 3.6, "": 1.0}      # the DBC's units to the FMUs' (rad, m/s)
FRONT = "SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1]"
PLANT = ([f"Bus.{n}[{a}]" for n in ("xAxle", "yAxle") for a in range(1, 7)]
         + ["Bus.artAngle[1]", "Bus.artAngle[2]", "Bus.vx[1]"])


def can_routes():
    """{receiver "C.v": (message, signal)} of the bench's routed connections (read from its .ssd)."""
    from artibus import ssp
    b = ssp.read(ssp.ssp_path(CAN_BENCH))
    return {f"{c.end[0]}.{c.end[1]}": (c.can["message"], c.can["signal"]) for c in b.connections if c.can}


ROUTED = can_routes()


@pytest.fixture(scope="module")
def can_original(tmp_path_factory):
    """The CAN bench run once per log format, its traffic logged; the plant and
    every routed input recorded."""
    from artibus.runner import Simulation
    d = tmp_path_factory.mktemp("canlog")
    out = {}
    for suffix in ("blf", "asc"):
        log = d / f"run.{suffix}"
        with Simulation(CAN_BENCH, record=PLANT + ["Driver.delta"] + sorted(ROUTED), can_log=log) as sim:
            out[suffix] = (sim.run(), log)
    return out


def path_distance(r, ref, a):
    return np.hypot(r[f"Bus.xAxle[{a}]"] - ref[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"] - ref[f"Bus.yAxle[{a}]"])


@pytest.mark.parametrize("suffix", ["blf", "asc"])
def test_can_log_replayed_into_its_bench_reproduces_the_run_bit_for_bit(can_original, suffix):
    """The log replaces the network: every routed input (data and alive
    counters) fed from the frames of its route, the frame of cycle k from
    t = k T on, the driver and the mechanics in the loop as before. The
    receivers then get what the network gave them, so the ECUs, actuators and
    plant repeat the run bit for bit; each sender, computed again, matches
    its logged frames within half a step of its signal's resolution (the DBC's
    scale, read here with cantools)."""
    import cantools
    r0, log = can_original[suffix]
    rep = replay.replay(log, CAN_BENCH, record=PLANT + sorted(ROUTED))
    r = rep.result
    assert len(r.time) == len(r0.time) and r.time[-1] == pytest.approx(70.0)
    for x in PLANT + sorted(ROUTED):
        np.testing.assert_array_equal(r[x], r0[x], err_msg=x)
    db = cantools.database.load_file(str(DBC))
    checked = set()
    for label, rms, mx, unit in rep.errors:
        msg, _, sig = label.split(" ")[0].partition(".")
        s = db.get_message_by_name(msg).get_signal_by_name(sig)
        assert unit == (s.unit or "") and mx <= s.scale / 2 * (1 + 1e-6), (label, mx, s.scale)
        checked.add((msg, sig))
    assert checked == {v for v in ROUTED.values() if v[1] != "AliveCounter"}


def _tv(x):
    """running total variation of a series"""
    return np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])


@pytest.mark.parametrize("suffix", ["blf", "asc"])
def test_front_angle_from_the_log_keeps_the_trajectory_within_the_resolution_bound(can_original, suffix):
    """The front wheels too at the logged sensor angle (--map
    SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1]; the driver stays in the
    loop for the drive force only, which is not on the steering CAN). The
    plant's front angle then differs from the run's by the frame's
    quantisation only: at most q/2, q = 0.025 deg (the DBC's scale), and the
    rest of its inputs are the run's. Bound: for a linear response y = h * e
    to an input error |e| <= q/2, |y| <= q/2 int |h|, and int |h| is the total
    variation of the step response; the step responses are replays with a
    constant offset of +q/2 and -q/2 on the front angle (their deviation from
    the replay without offset); the bound is the larger running total
    variation (per coordinate for the axle paths). Axle paths and
    articulation angles stay within it; the front steering is open loop
    now, so they do differ."""
    import cantools
    r0, log = can_original[suffix]
    s = cantools.database.load_file(str(DBC)).get_message_by_name("SensorA1_Angle").get_signal_by_name("RoadWheelAngleA1")
    q = s.scale * TO_SI[s.unit]
    rep = replay.replay(log, CAN_BENCH, maps=[FRONT], record=PLANT)
    r = rep.result
    # the front angle the plant got in the step from t_k (recorded in row k + 1, with the step's
    # inputs): the driver's output at t_k (row k) in the run, within q/2
    e = r["Bus.delta[1]"][1:] - r0["Driver.delta"][:-1]
    assert np.max(np.abs(e)) <= q / 2 * (1 + 1e-9)
    steps = [replay.replay(log, CAN_BENCH, maps=[FRONT], record=PLANT, offsets={"Bus.delta[1]": sg * q / 2}).result
             for sg in (1, -1)]
    for g in (1, 2):
        x = f"Bus.artAngle[{g}]"
        bound = max(np.max(_tv(st[x] - r[x])) for st in steps)
        dev = np.max(np.abs(r[x] - r0[x]))
        assert 0 < dev <= bound, (x, dev, bound)
    for a in range(1, 7):
        bx, by = (max(np.max(_tv(st[f"Bus.{c}Axle[{a}]"] - r[f"Bus.{c}Axle[{a}]"])) for st in steps) for c in "xy")
        dev = np.max(path_distance(r, r0, a))
        assert 0 < dev <= math.hypot(bx, by), (a, dev, bx, by)


def test_replay_cli_on_a_can_log(can_original, tmp_path):
    """artibus replay LOG --bench Bus36m_Circle_CAN --map ...: the routed inputs
    and the mapped one listed, the senders' errors printed and written."""
    _, log = can_original["asc"]
    out = tmp_path / "rep"
    p = subprocess.run([sys.executable, "-m", "artibus", "replay", str(log), "--bench", CAN_BENCH, "--map", FRONT,
                        "--stop-time", "2", "-o", str(tmp_path / "r.csv"), "--report", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "Bus.delta[1] <- SensorA1_Angle.RoadWheelAngleA1" in p.stdout
    assert "ECU3.aliveG2 <- SensorG2_Angle.AliveCounter" in p.stdout
    assert "SensorG1_Angle.ArtAngleG1 (Bus.artAngle[1])" in (out / "errors.csv").read_text()


def test_cut_errors_and_no_network_when_every_route_is_cut():
    from artibus.runner import Simulation
    with pytest.raises(ArtibusError, match="cut Bus.gammaF: the input is not connected"):
        Simulation("Urbino18_Replay", cut=["Bus.gammaF"])
    with pytest.raises(ArtibusError, match="cut Bus.x.0.: not an input"):
        Simulation("Urbino18_Replay", cut=["Bus.x[0]"])
    with Simulation(CAN_BENCH, cut=list(ROUTED)) as sim:
        assert sim.can is None and not any(l.name in ROUTED for l in sim.links)
    with pytest.raises(ArtibusError, match="every connection .* is cut"):
        Simulation(CAN_BENCH, cut=list(ROUTED), can_log="x.blf")
