"""The complementary gain Kc(v) of seed 001, 4.1.2 (artibus.kc), measured
through the co-simulation of Scania18m_OpenLoop, against numbers derived here:
the reference model's closed form from the thesis's Table 3.1, the plant's
steady cornering on a constant steering (another measurement of the same
low-frequency gain), and the classic linear single-track model of the
articulated bus written here (Newton-Euler, two bodies, constant speed)."""
import math

import numpy as np
import pytest

from artibus import ArtibusError, fmu_path
from artibus.bench.parameters import check_against, read_parameters
from artibus.study import kc
from test_bus_dynamics import run_loop
from test_bus_dynamics_vehicles import linear_modes

# seed 001 Table 3.1: f1, b1, b11, f2, b2 [m]
F1, B1, B11, F2, B2 = 1.944, 3.306, 5.128, 4.777, 0.163
L1, L2 = F1 + B1, F2 + B2
A = 1 / L1 + (B11 - B1) / (L1 * L2)          # eq. 2.9
SPEEDS = (10, 50, 90, 130)                   # km/h, all in kc.SPEEDS_KMH
H = 0.01                                     # s, the bench's communication step (BusDynamics default)


def g_ref(f, v):
    """eq. 2.9: Lambda' = -(v/l2) Lambda + v a delta"""
    return v * A / (2j * math.pi * f + v / L2)


def plant_params(u):
    p = read_parameters("Scania18m")
    p.update(testSteerAmp=0.0, tyreModel=1, vx_start=u)
    return p


def linear_plant(p, u):
    """(A, B) of the linear single-track articulated bus at speed u with the
    front steering delta as input: states (v1, r1, r2, Lambda), v1 the lateral
    velocity of the front CG; unknowns of Newton-Euler (v1', r1', r2', lateral
    hinge force Fh). Linear tyres, friction 1. Its eigenvalues are checked
    against test_bus_dynamics_vehicles.linear_modes."""
    f1, b1, b11 = p["xA[1]"], -p["xA[2]"], p["lHf[1]"]
    f2, b2 = p["lHr[1]"], -p["xA[3]"]
    m1, m2, J1, J2 = p["m[1]"], p["m[2]"], p["Jz[1]"], p["Jz[2]"]
    cf, cm, cr = p["C[1]"], p["C[2]"], p["C[3]"]
    K = np.array([[m1, 0, 0, -1], [0, J1, 0, b11], [m2, -m2 * b11, -m2 * f2, 1], [0, 0, J2, f2]])

    def deriv(x, delta):
        v1, r1, r2, lam = x
        v2 = v1 - b11 * r1 - f2 * r2 + u * lam          # rear CG lateral velocity, rear frame
        Ff = cf * (delta - (v1 + f1 * r1) / u)          # front axle steered by delta
        Fm = -cm * (v1 - b1 * r1) / u
        Fr = -cr * (v2 - b2 * r2) / u
        w = np.linalg.solve(K, [Ff + Fm - m1 * u * r1, f1 * Ff - b1 * Fm, Fr - m2 * u * r1, -b2 * Fr])
        return np.array([w[0], w[1], w[2], r1 - r2])

    Am = np.column_stack([deriv(e, 0.0) for e in np.eye(4)])
    return Am, deriv(np.zeros(4), 1.0)


def g_lin(p, u, f):
    """delta -> Lambda of the linear model at f Hz (f = 0: steady state), with
    the co-simulation's input held over each step (sinc; bode takes out the
    half-step delay)."""
    Am, Bm = linear_plant(p, u)
    w = 2 * math.pi * f
    return np.linalg.solve(1j * w * np.eye(4) - Am, Bm)[3] * np.sinc(w * H / 2 / math.pi)


@pytest.fixture(scope="module")
def table():
    return {round(r.kmh): r for r in kc.kc_table(SPEEDS)}


def test_reference_geometry_is_table_2_1_from_the_plant_set():
    g = kc.reference_geometry()
    assert (g["l1"], g["l2"], g["a"]) == pytest.approx((5.250, 4.940, A), rel=1e-12)
    assert g["a"] * g["l2"] == pytest.approx(1.288, abs=5e-4)            # the kinematic DC gain
    assert kc.g_ref(0.3, 20.0, g) == pytest.approx(g_ref(0.3, 20.0), rel=1e-12)


def test_linear_model_is_the_one_checked_against_the_sway_mode():
    p = plant_params(100 / 3.6)
    eig = np.sort_complex(np.linalg.eigvals(linear_plant(p, 100 / 3.6)[0]))
    assert eig == pytest.approx(np.sort_complex(linear_modes(p, 100 / 3.6, 1.0, 1.0)), rel=1e-10)


def test_low_speed_plant_is_the_kinematic_model(table):
    """seed 001, Fig. 4.1: at 10 km/h reference model and plant agree."""
    r, v = table[10], 10 / 3.6
    G = g_ref(kc.F_LO, v)
    assert r.gain == pytest.approx(abs(G), rel=0.02)
    assert abs(math.degrees(r.phase - np.angle(G))) < 1.0
    assert r.kc == pytest.approx(1.0, abs=0.02)


def test_kc_falls_with_speed(table):
    """seed 001, 4.1.2: the plant's gain is lower at higher speed, the
    reference model's almost the same."""
    kcs = [table[s].kc for s in SPEEDS]
    assert all(a > b for a, b in zip(kcs, kcs[1:])), kcs
    assert kcs[-1] < 0.5
    assert all(r.gain_ref == pytest.approx(A * L2, rel=0.01) for s, r in table.items() if s >= 50)


def test_kc_is_flat_at_the_low_frequency(table):
    for r in table.values():
        assert r.kc_check == pytest.approx(r.kc, rel=0.005), r
        assert abs(r.drift) < 5e-4, r             # the speed holds without drive force


@pytest.mark.parametrize("kmh", SPEEDS)
def test_kc_is_the_steady_cornering_gain(table, kmh):
    """Another measurement of the same gain: a constant steering of 2 mrad,
    the speed held by a PI governor on the driven rear axle, until the
    articulation angle is steady; Lambda / delta / (a l2) within 2 % of Kc.
    Both against the linear model's steady state."""
    u, delta = kmh / 3.6, 0.002
    integ = {"F": 0.0}

    def control(t, val):
        e = u - val["vx[1]"]
        integ["F"] += 2e4 * 0.05 * e
        return {"delta[1]": delta, "Fx[3]": 2e4 * e + integ["F"]}

    r = run_loop(plant_params(u), 600, 0.05, control, ["artAngle[1]", "vx[1]"])
    lam = r["artAngle[1]"]
    assert abs(lam[-1] - lam[-21]) < 1e-5 * abs(lam[-1])                  # steady
    assert r["vx[1]"][-1] == pytest.approx(u, rel=1e-4)
    kc_steady = lam[-1] / delta / (A * L2)
    assert table[kmh].kc == pytest.approx(kc_steady, rel=0.02)
    assert kc_steady == pytest.approx(g_lin(plant_params(u), u, 0.0).real / (A * L2), rel=0.005)
    assert table[kmh].gain == pytest.approx(abs(g_lin(plant_params(u), u, kc.F_LO)), rel=0.005)


def test_bode_at_100_kmh_and_the_rear_sway_peak():
    """Figs. 4.2/4.3: the measured response against the linear model; the
    rear-sway resonance near seed 001's 4.5 rad/s (0.7 Hz), the plant's gain
    there above the reference model's."""
    u = 100 / 3.6
    p = plant_params(u)
    geo = kc.reference_geometry()
    pts = kc.plant_points(u, [0.05, 0.2, 0.5, 0.8, 1.2, 2.5], geo)
    for q in pts:
        G = g_lin(p, u, q.frequency)
        assert q.gain == pytest.approx(abs(G), rel=0.01), q
        assert abs(math.degrees(math.remainder(q.phase - np.angle(G), 2 * math.pi))) < 1.0, q
    f_pk, g_pk, _ = kc.sway_peak(u, pts, geo)
    fd = np.linspace(0.3, 1.5, 2401)
    gd = np.abs([g_lin(p, u, f) for f in fd])
    assert f_pk == pytest.approx(fd[np.argmax(gd)], rel=0.02)
    assert g_pk == pytest.approx(gd.max(), rel=0.01)
    assert 2 * math.pi * f_pk == pytest.approx(4.5, abs=0.5)
    assert g_pk > abs(g_ref(f_pk, u))


def test_parameter_set_round_trip_and_limits(tmp_path):
    rows = [kc.KcRow(v, 1.0, 0.0, 1.0, k, k, 0.0) for v, k in ((5.0, 0.9), (20.0, 0.5), (30.0, 0.2))]
    path = kc.write_ssv(tmp_path / "k.ssv", rows, "test")
    q = read_parameters(path)
    assert q["nKc"] == 3
    assert [q[f"KcSpeed[{i}]"] for i in (1, 2, 3)] == [5.0, 20.0, 30.0]
    assert [q[f"KcGain[{i}]"] for i in (1, 2, 3)] == [0.9, 0.5, 0.2]
    with pytest.raises(ValueError, match="1..12"):
        kc.write_ssv(tmp_path / "x.ssv", rows * 5, "test")


def test_committed_table_is_current(table):
    """ssp/parameters/Scania18mKc.ssv (generated by scripts/kc_table.py) holds
    what the plant measures now, at the speeds measured here."""
    q = read_parameters("Scania18mKc")
    n = q["nKc"]
    speeds = [q[f"KcSpeed[{i}]"] for i in range(1, n + 1)]
    assert n <= 12 and all(a < b for a, b in zip(speeds, speeds[1:]))
    for kmh, r in table.items():
        i = min(range(n), key=lambda i: abs(speeds[i] - r.speed))
        assert speeds[i] == pytest.approx(r.speed, abs=1e-5)
        assert q[f"KcGain[{i + 1}]"] == pytest.approx(r.kc, rel=2e-3), kmh


def test_committed_table_fits_the_damping_controller():
    try:
        fmu = fmu_path("DampingController")
    except ArtibusError:
        pytest.skip("DampingController not built")
    check_against(read_parameters("Scania18mKc"), fmu, "Scania18mKc.ssv")
