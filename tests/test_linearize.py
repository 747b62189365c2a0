"""`artibus linearize` (issue 43, its first part): A, B, C, D of one Model Exchange FMU by finite
differences or the FMU's directional derivatives, the modes, the frequency response; each checked
against what is derived here independently of artibus.linear.fmu:

- MultiAxle3DOF: seed 004's balances (eq. 2, roll rate p = dphi/dt) linearised by hand from the
  bench's parameter set (the .ssv read here with lxml); eq. 5 as printed against them (the
  entries that differ, and which form gives stable modes);
- the Reference-FMUs' Dahlquist (der(x) = -k x: A = -k) and VanDerPol (its Jacobian in closed
  form), FMI 2.0 and 3.0, also through fmi2/fmi3GetDirectionalDerivative (their C code has it;
  the copy tested says providesDirectionalDerivative(s)="true");
- the Scania 18 m (BusDynamics, seed 001's vehicle, 100 km/h, friction 1): the rear-sway mode
  against the thesis's ~4.5 rad/s (Fig. 4.2) and the peak of `artibus bode`'s measured response;
- bad input: one-line errors naming the FMU and the variable."""
import math
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from artibus.base import ArtibusError

ROOT = Path(__file__).resolve().parents[1]
FMUS = ROOT / "fmus"
REFERENCE = ROOT / ".tools" / "reference-fmus"
PARAMETERS = ROOT / "ssp" / "parameters"
G = 9.81          # gravity in seed 004's roll balance (m_b g h_b), as MultiAxle3DOF's README/header state


def fmu(name):
    path = FMUS / f"{name}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built")
    return path


def reference(model, version):
    path = REFERENCE / ("fmi3" if version == 3 else "") / f"{model}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/build_reference_fmus.sh)")
    return path


def ssv(name):
    """{name: value} of ssp/parameters/<name>.ssv, read here (lxml), not by artibus"""
    root = etree.parse(str(PARAMETERS / f"{name}.ssv")).getroot()
    out = {}
    for p in root.iterfind("{*}Parameters/{*}Parameter"):
        v = p[0]
        tag = etree.QName(v).localname
        text = v.get("value")
        out[p.get("name")] = (float(text) if tag == "Real" else int(text) if tag == "Integer"
                              else text == "true" if tag == "Boolean" else text)
    return out


def index(signals, names):
    pos = {s.name: k for k, s in enumerate(signals)}
    return [pos[n] for n in names]


# --- seed 004: MultiAxle3DOF against eq. 2 by hand ------------------------------------------------

#: the bench MultiAxle_StepSteer's vehicle (Bus15mTagAxle.ssv, u = 20 m/s), with roll offsets d_i and
#: a product of inertia I_XZb set so that every term of eq. 2 is exercised (the set has them 0)
EXTRA = {"d[1]": 0.12, "d[2]": -0.05, "d[3]": 0.08, "I_XZb": 3500.0}
U = 20.0


def vehicle():
    p = ssv("Bus15mTagAxle")
    p.update(EXTRA)
    n = p["n"]
    arr = lambda key: np.array([p[f"{key}[{i}]"] for i in range(1, n + 1)])   # noqa: E731
    return p, n, arr("l"), arr("k"), arr("m"), arr("d")


def eq2_matrices(u=U, steer_all=False):
    """Seed 004, eq. 2 with v = u beta (the FMU's state is the lateral velocity v; beta = v/u),
    written as  Mm [v', w_r', p'] = Kx [w_r, v, p, phi] + Ku [delta_1..n, M_d]  and phi' = p:

      lateral  M (v' + u w_r) + (sum m_i l_i) w_r' - m_b h_b p' = sum k_i (v/u + l_i w_r/u - delta_i)
      yaw      (sum m_i l_i)(v' + u w_r) + I_ZZ w_r' + I_XZb p' = sum k_i l_i (...) + M_d
      roll     I_XX p' + C_phi p + (K_phi - m_b g h_b) phi - m_b h_b (v' + u w_r) + I_XZb w_r'
                 = sum d_i k_i (...)
      I_ZZ = sum (m_i l_i^2) + I_ZZb (the I_ZZi of the axles 0), M = sum m_i + m_b, I_XX = I_XXb + m_b h_b^2.

    Returns A (4x4) and B (4 x n+1) in the states (w_r, v, p, phi), inputs (delta_1..n, M_d); a
    fixed axle's (steerable[i] false) column 0 unless ``steer_all`` (eq. 3 steers every axle)."""
    p, n, l, k, m, d = vehicle()
    mb, hb = p["m_b"], p["h_b"]
    M, sml = m.sum() + mb, (m * l).sum()
    Izz, Ixx, Ixz = (m * l * l).sum() + p["I_ZZb"], p["I_XXb"] + mb * hb * hb, p["I_XZb"]
    Mm = np.array([[M, sml, -mb * hb], [sml, Izz, Ixz], [-mb * hb, Ixz, Ixx]])      # rows: lat, yaw, roll
    Kx = np.array([   # d(right side - the u w_r terms moved right)/d(w_r, v, p, phi)
        [(k * l).sum() / u - M * u, k.sum() / u, 0, 0],
        [(k * l * l).sum() / u - sml * u, (k * l).sum() / u, 0, 0],
        [(d * k * l).sum() / u + mb * hb * u, (d * k).sum() / u, -p["C_phi"], -(p["K_phi"] - mb * G * hb)]])
    # a fixed axle (steerable[i] false): delta_i = 0
    steer = np.array([1.0 if p[f"steerable[{i}]"] or steer_all else 0.0 for i in range(1, n + 1)])
    Ku = np.column_stack([np.array([-k, -k * l, -d * k]) * steer, [0.0, 1.0, 0.0]])
    acc = np.linalg.solve(Mm, np.hstack([Kx, Ku]))        # rows v', w_r', p'
    A = np.vstack([acc[1, :4], acc[0, :4], acc[2, :4], [0, 0, 1, 0]])
    B = np.vstack([acc[1, 4:], acc[0, 4:], acc[2, 4:], np.zeros(n + 1)])
    return A, B, (Mm, M, sml, Izz, Ixx, Ixz, l, k, d, mb, hb, p)


STATES = ["w_r", "v", "p", "phi"]


def linear_multiaxle(**kw):
    from artibus.linear import linearize
    p, n, *_ = vehicle()
    params = {**p, "u": U}
    inputs = [f"delta[{i}]" for i in range(1, n + 1)] + ["M_d"]
    return linearize(fmu("MultiAxle3DOF"), parameters=params, inputs=inputs, outputs=["beta", "a_y"], **kw), n


def test_multiaxle_A_and_B_are_seed_004_eq_2_linearised_by_hand():
    lin, n = linear_multiaxle(derivatives="fd")
    A, B, _ = eq2_matrices()
    s = index(lin.states, STATES)
    assert "finite differences" in lin.method and "1e-05" in lin.method
    # the model is linear in the states and inputs: central differences are exact to rounding;
    # 1e-6 relative to each row's largest entry
    for i in range(4):
        scale = max(np.abs(A[i]).max(), np.abs(B[i]).max())
        np.testing.assert_allclose(lin.A[s[i], s], A[i], rtol=0, atol=1e-6 * scale)
        np.testing.assert_allclose(lin.B[s[i], :], B[i], rtol=0, atol=1e-6 * scale)
    # the positions: psi' = w_r, y' = u sin(psi) + v cos(psi) -> u dpsi + dv at psi = 0 (x' has none)
    psi, y = index(lin.states, ["psi", "y"])
    assert lin.A[psi, s[0]] == pytest.approx(1.0, rel=1e-9)
    assert lin.A[y, psi] == pytest.approx(U, rel=1e-6) and lin.A[y, s[1]] == pytest.approx(1.0, rel=1e-9)
    # C: beta = v/u; a_y = v' + u w_r (its row: A's v' row plus u in w_r's column), D likewise
    beta, ay = index(lin.outputs, ["beta", "a_y"])
    np.testing.assert_allclose(lin.C[beta, s], [0, 1 / U, 0, 0], atol=1e-12)
    np.testing.assert_allclose(lin.C[ay, s], A[1] + np.array([U, 0, 0, 0]), atol=1e-6 * np.abs(A[1]).max())
    np.testing.assert_allclose(lin.D[ay], B[1], atol=1e-6 * np.abs(B[1]).max())
    # every mode of eq. 2 is stable; the frequency response at w -> 0 is the steady-state gain -C A^-1 B
    ev = np.linalg.eigvals(A)
    assert np.all(ev.real < 0)
    key = lambda z: (round(z.real, 6), z.imag)                 # noqa: E731
    dyn = [m.eigenvalue for m in lin.modes() if m.kind != "integrator"]
    np.testing.assert_allclose(sorted([z for z in ev if z.imag >= 0], key=key), sorted(dyn, key=key), rtol=1e-6)
    g0 = lin.frequency_response("delta[1]", "w_r", [1e-6])[0]
    assert g0.real == pytest.approx((-np.linalg.solve(A, B[:, 0]))[0], rel=1e-5)


def test_multiaxle_A_B_C_D_from_its_directional_derivatives_are_eq_2_to_1e_12():
    """MultiAxle3DOF's own fmi2GetDirectionalDerivative (issue 43: lateral3dof.c on dual numbers)
    gives eq. 2 linearised by hand to 1e-12 relative to each row's largest entry (the finite
    differences above: 1e-6)"""
    lin, n = linear_multiaxle(derivatives="exact")
    A, B, _ = eq2_matrices()
    assert lin.method.startswith("directional derivatives (fmi2GetDirectionalDerivative)")
    s = index(lin.states, STATES)
    for i in range(4):
        scale = max(np.abs(A[i]).max(), np.abs(B[i]).max())
        np.testing.assert_allclose(lin.A[s[i], s], A[i], rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(lin.B[s[i], :], B[i], rtol=0, atol=1e-12 * scale)
    psi, y = index(lin.states, ["psi", "y"])
    assert lin.A[psi, s[0]] == 1.0 and lin.A[y, s[1]] == pytest.approx(1.0, rel=1e-15)
    assert lin.A[y, psi] == pytest.approx(U, rel=1e-12)
    beta, ay = index(lin.outputs, ["beta", "a_y"])
    np.testing.assert_allclose(lin.C[beta, s], [0, 1 / U, 0, 0], rtol=1e-15, atol=0)
    np.testing.assert_allclose(lin.C[ay, s], A[1] + np.array([U, 0, 0, 0]), rtol=0,
                               atol=1e-12 * np.abs(A[1]).max())
    np.testing.assert_allclose(lin.D[ay], B[1], rtol=0, atol=1e-12 * np.abs(B[1]).max())


def test_seed_004_eq_5_as_printed_disagrees_with_eq_2():
    """Eq. 5 (A = -P K, B = P F, P = -[mass matrix of eq. 4]^-1, X = [w_r, beta, p, phi]) against
    eq. 2 in the same states: (1) the minus in P flips A's and B's first three rows: A's dynamic
    rows are the negative of eq. 2's, every mode of eq. 5 as printed unstable; (2) B's roll row
    has +sum k_i d_i (l_i - l_1)/(l_n - l_1) in the delta_n column where eq. 2 (and the delta_1
    column beside it) give a minus; (3) eq. 4's fourth row reads phi' + p = 0, eq. 2's p = dphi/dt
    gives phi' - p = 0 (eq. 5's A = -P K has the two slips cancel in that row: phi' = p). Eq. 2 is
    the right form: with it every mode is stable, as a bus at 20 m/s is."""
    A2, B2, (Mm, M, sml, Izz, Ixx, Ixz, l, k, d, mb, hb, p) = eq2_matrices(steer_all=True)
    n = len(l)
    u = U
    T = np.diag([1, 1 / u, 1, 1])                     # (w_r, v, p, phi) -> (w_r, beta, p, phi)
    A2b = T @ A2 @ np.linalg.inv(T)
    r1, rn = (l[-1] - l) / (l[-1] - l[0]), (l - l[0]) / (l[-1] - l[0])       # eq. 3
    B2b = T @ np.column_stack([B2[:, :n] @ r1, B2[:, :n] @ rn, B2[:, n]])   # inputs delta_1, delta_n, M_d
    M4 = np.array([[sml, u * M, -mb * hb, 0], [Izz, u * sml, Ixz, 0], [Ixz, -u * mb * hb, Ixx, 0], [0, 0, 0, 1]])
    K4 = np.array([[u * M - (k * l).sum() / u, -k.sum(), 0, 0],
                   [u * sml - (k * l * l).sum() / u, -(k * l).sum(), 0, 0],
                   [-u * mb * hb - (k * l * d).sum() / u, -(k * d).sum(), p["C_phi"], p["K_phi"] - mb * G * hb],
                   [0, 0, 1, 0]])
    F5 = np.array([[-(k * r1).sum(), -(k * rn).sum(), 0], [-(k * l * r1).sum(), -(k * l * rn).sum(), 1],
                   [-(k * d * r1).sum(), +(k * d * rn).sum(), 0], [0, 0, 0]])          # as printed
    P = -np.linalg.inv(M4)
    A5, B5 = -P @ K4, P @ F5
    sc = np.abs(A2b).max()
    np.testing.assert_allclose(A5[:3], -A2b[:3], atol=1e-9 * sc)                 # (1): the sign of P
    np.testing.assert_allclose(A5[3], A2b[3], atol=1e-12)                        # (3): phi' = p there
    assert np.all(np.linalg.eigvals(A2b).real < 0) and np.any(np.linalg.eigvals(A5).real > 0)
    F2 = F5.copy()
    F2[2, 1] = -F2[2, 1]                                                          # (2): the roll row's sign
    assert abs(F5[2, 1]) > 0
    np.testing.assert_allclose(np.linalg.inv(M4) @ F2, B2b, atol=1e-9 * np.abs(B2b).max())
    assert not np.allclose(B5, B2b, atol=1e-6 * np.abs(B2b).max())
    # eq. 4's fourth row as printed: phi' + p = 0, against eq. 2's phi' = p
    row4_printed = -np.linalg.solve(M4, K4)[3]          # phi' = -(M4^-1 K4) row 4 = -p
    assert row4_printed[2] == pytest.approx(-1.0) and A2b[3, 2] == pytest.approx(1.0)


def test_steady_state_of_a_front_step_steer_is_eq_2s_equilibrium():
    """--steady: integrated until w_r, v, p, phi rest (psi, x, y move on: free states), the point
    equal to x_ss = -A^-1 B u of eq. 2 with delta_1 = 0.02 rad."""
    from artibus.linear import linearize
    p, n, *_ = vehicle()
    lin = linearize(fmu("MultiAxle3DOF"), steady=True, parameters={**p, "u": U, "delta[1]": 0.02},
                    inputs=["delta[1]"], outputs=["beta"])
    A, B, _ = eq2_matrices()
    x_ss = -np.linalg.solve(A, B[:, 0] * 0.02)
    got = np.array([lin.states[i].value for i in index(lin.states, STATES)])
    np.testing.assert_allclose(got, x_ss, rtol=1e-4, atol=1e-8)
    assert set(lin.dynamic) == set(STATES) and lin.time > 0


# --- Reference-FMUs: closed forms, FMI 2.0 and 3.0 --------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_dahlquist_A_is_minus_k(version):
    from artibus.linear import linearize
    lin = linearize(reference("Dahlquist", version), parameters={"k": 2.5}, at=0.3)
    assert [s.name for s in lin.states] == ["x"]
    assert lin.A[0, 0] == pytest.approx(-2.5, rel=1e-9)
    assert lin.states[0].value == pytest.approx(math.exp(-2.5 * 0.3), rel=1e-4)   # x(0.3) = e^-kt
    (m,) = lin.modes()
    assert m.kind == "real" and m.tau == pytest.approx(1 / 2.5, rel=1e-9)


def vdp_jacobian(x0, x1, mu):
    """der(x0) = x1, der(x1) = mu (1 - x0^2) x1 - x0 (the Reference-FMUs' VanDerPol)"""
    return np.array([[0.0, 1.0], [-2 * mu * x0 * x1 - 1, mu * (1 - x0 * x0)]])


def with_directional_derivatives(path, tmp_path):
    """A copy of a Reference-FMU whose <ModelExchange> says providesDirectionalDerivative(s)="true":
    its C code implements fmi2/fmi3GetDirectionalDerivative (getPartialDerivative in model.c), the
    fmi-sys sources' modelDescription.xml does not say so (the Reference-FMUs' own release does)."""
    out = tmp_path / path.name
    attr = "providesDirectionalDerivatives" if "fmi3" in str(path) else "providesDirectionalDerivative"
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(out, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                text, k = re.subn(r"<ModelExchange\b", f'<ModelExchange {attr}="true"', text, count=1)
                assert k == 1
                data = text.encode()
            zout.writestr(item, data)
    return out


@pytest.mark.parametrize("version", [2, 3])
def test_van_der_pol_jacobian_by_finite_differences_and_directional_derivatives(version, tmp_path):
    from artibus.linear import linearize
    mu = 1.5
    lin = linearize(reference("VanDerPol", version), parameters={"mu": mu})      # at x = (2, 0)
    assert [s.name for s in lin.states] == ["x0", "x1"]
    np.testing.assert_allclose(lin.A, vdp_jacobian(2.0, 0.0, mu), rtol=1e-8, atol=1e-9)
    lin = linearize(reference("VanDerPol", version), parameters={"mu": mu}, at=0.7)
    x0, x1 = (s.value for s in lin.states)
    assert abs(x1) > 0.1                          # a point where every entry counts
    np.testing.assert_allclose(lin.A, vdp_jacobian(x0, x1, mu), rtol=1e-7, atol=1e-8)
    exact = linearize(with_directional_derivatives(reference("VanDerPol", version), tmp_path),
                      parameters={"mu": mu}, at=0.7)
    assert exact.method.startswith("directional derivatives") and f"fmi{version}" in exact.method
    np.testing.assert_allclose(exact.A, vdp_jacobian(x0, x1, mu), rtol=1e-13, atol=1e-13)


# --- seed 001: the Scania 18 m's rear-sway mode ------------------------------------------------------

def scania_linear():
    from artibus.linear import linearize
    params = {**ssv("Scania18m"), "tyreModel": "linearSaturated", "vx_start": 100 / 3.6}
    return linearize(fmu("BusDynamics"), parameters=params, inputs=["delta[1]"], outputs=["artAngle[1]"])


def test_scania_rear_sway_mode_is_the_thesis_and_the_measured_bode_peak(tmp_path):
    """The lightly damped oscillatory mode of the Scania 18 m straight ahead at 100 km/h, friction 1:
    its damped frequency wd = |Im lambda| and natural frequency wn = |lambda| within 10 % of seed
    001's ~4.5 rad/s (Fig. 4.2); the peak of `artibus bode`'s measured delta[1] -> artAngle[1]
    (sine tests through the co-simulation, Scania18m_OpenLoop) within 2 % of wd (a resonance
    peak of a mode with zeta ~ 0.2 lies near wd, below wn), and the linear model's own gain there
    within 2 % of the measured one."""
    lin = scania_linear()
    osc = [m for m in lin.modes() if m.kind == "oscillatory"]
    sway = min(osc, key=lambda m: m.zeta)
    print(f"rear sway: natural {sway.wn:.3f} rad/s, damped {sway.wd:.3f} rad/s, zeta {sway.zeta:.3f}")
    assert abs(sway.wd / 4.5 - 1) < 0.10 and abs(sway.wn / 4.5 - 1) < 0.10
    assert sway.wd < sway.wn and 0.05 < sway.zeta < 0.5
    out = tmp_path / "bode.csv"
    fmin, fmax, n = 4.0 / (2 * math.pi), 5.2 / (2 * math.pi), 13
    r = subprocess.run([sys.executable, "-m", "artibus", "bode", "Scania18m_OpenLoop", "--input", "Bus.delta[1]",
                        "--measure", "Bus.artAngle[1]", "--fmin", str(fmin), "--fmax", str(fmax), "--n", str(n),
                        "--amplitude", "0.001", "--settle", "5", "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = np.array([[float(x) for x in line.split(",")[:2]] for line in out.read_text().splitlines()[1:]])
    w, gain = 2 * math.pi * rows[:, 0], rows[:, 1]
    k = int(np.clip(np.argmax(gain), 1, len(w) - 2))
    c2, c1, _ = np.polyfit(np.log(w[k - 1:k + 2]), np.log(gain[k - 1:k + 2]), 2)     # the top, in log-log
    w_peak = math.exp(-c1 / (2 * c2))
    print(f"measured peak {w_peak:.3f} rad/s")
    assert abs(w_peak / sway.wd - 1) < 0.02
    g_lin = np.abs(lin.frequency_response("delta[1]", "artAngle[1]", w))
    np.testing.assert_allclose(g_lin, gain, rtol=0.02)


# --- the command and bad input ------------------------------------------------------------------------

def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "artibus", "linearize", *map(str, args)],
                          capture_output=True, text=True)


def test_cli_writes_mat_csv_and_bode_plot(tmp_path):
    from scipy.io import loadmat
    path = fmu("MultiAxle3DOF")
    mat, csv, png = tmp_path / "lin.mat", tmp_path / "lin.csv", tmp_path / "bode.png"
    r = run_cli(path, "--ssv", PARAMETERS / "Bus15mTagAxle.ssv", "--set", "u=20", "--inputs", "delta[1],M_d",
                "--outputs", "beta", "-o", mat, "--bode", "delta[1]:w_r", "--plot", png)
    assert r.returncode == 0, r.stderr
    assert "directional derivatives (fmi2GetDirectionalDerivative)" in r.stdout   # the FMU's (issue 43)
    m = loadmat(mat)
    assert [str(x[0]) for x in m["states"].ravel()][:4] == STATES
    assert m["A"].shape == (7, 7) and m["B"].shape == (7, 2) and m["C"].shape == (1, 7) and m["D"].shape == (1, 2)
    # der(phi) = p and der(psi) = w_r, by name
    names = [str(x[0]) for x in m["states"].ravel()]
    assert m["A"][names.index("phi"), names.index("p")] == pytest.approx(1.0, rel=1e-9)
    assert m["A"][names.index("psi"), names.index("w_r")] == pytest.approx(1.0, rel=1e-9)
    assert png.stat().st_size > 1000
    r = run_cli(path, "--set", "u=20", "--inputs", "delta[1]", "--outputs", "beta", "-o", csv)
    assert r.returncode == 0, r.stderr
    blocks = csv.read_text().split("\n\n")
    assert [b.splitlines()[0].split(",")[0] for b in blocks[1:]] == ["A", "B", "C", "D"]
    assert blocks[3].splitlines()[1].startswith("beta [rad],0.0,0.05,")      # C: beta = v/u, u = 20


@pytest.mark.parametrize("args, words", [
    (["MultiAxle3DOF", "--inputs", "Md"], ["MultiAxle3DOF", "'Md'", "M_d"]),
    (["MultiAxle3DOF", "--outputs", "delta[1]"], ["delta[1]", "no Real output"]),
    (["MultiAxle3DOF", "--set", "K_ph=1"], ["'K_ph'", "K_phi"]),
    (["ZeroSideslipSteering"], ["ZeroSideslipSteering", "no Model Exchange", "Co-Simulation"]),
    (["BusDynamics", "--ssv", "Scania18m", "--set", "psi_start[2]=2.0", "--inputs", "delta[1]"],
     ["BusDynamics", "jack-knifed", "artAngle[1]"]),
    (["MultiAxle3DOF", "--at", "nan"], ["--at nan", "finite"]),
    (["MultiAxle3DOF", "--at", "1", "--steady"], ["--at TIME or --steady, not both"]),
    (["Scania18m_OpenLoop", "--at", "-1"], ["Scania18m_OpenLoop", "--at -1 s", "before", "start time"]),
])
def test_bad_input_is_one_line_naming_the_fmu_and_the_variable(args, words):
    if not args[0].startswith("Scania"):
        fmu(args[0])
    r = run_cli(*args)
    assert r.returncode != 0
    err = r.stderr.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    for w in words:
        assert w in err, err


def test_never_steady_says_so():
    """A constant articulation torque on the Scania 18 m: the bus turns for ever (world-frame
    velocities rotate), no rest of its dynamic states: the error names the state still moving."""
    from artibus.linear import linearize
    params = {**ssv("Scania18m"), "tyreModel": "linearSaturated", "vx_start": 10.0, "delta[1]": 0.02}
    with pytest.raises(ArtibusError, match=r"BusDynamics is not steady after 5 s: the derivative of zd\[\d\]"):
        linearize(fmu("BusDynamics"), steady=True, steady_limit=5.0, parameters=params, inputs=["delta[1]"])


def test_an_operating_point_beyond_the_integration_says_where_it_failed():
    """der(x) = 800 x from x = 1 overflows before t = 1 s: the error names the FMU, the time and
    the state's infinite derivative (not a linear model of an overflown state)."""
    path = reference("Dahlquist", 3)
    r = run_cli(path, "--set", "k=-800", "--at", "1")
    err = r.stderr.strip()
    assert r.returncode == 1 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "Dahlquist failed on the way to the operating point" in err and "inf" in err, err
