"""Seed 004's linear 3-DOF multi-axle model written out in numpy from the
paper's equations (eq. 4 and the A, B of eq. 5), independently of the C code:
the reference the FMU tests (test_multiaxle_plant.py, _steering.py,
_closed_loop.py) compare against, and a few checks of the reference itself.

Two slips in the paper's matrices, found here and corrected:
- eq. 4's fourth row reads phi' + p = 0; it must be phi' - p = 0 (p is the
  roll rate, the third row's p' its derivative). As printed the roll mode is
  unstable for every vehicle (test_paper_row_4_as_printed_is_unstable).
  Steady states are not affected (p = 0 there).
- B (eq. 5), third row: the delta_n column has +sum k_i d_i (l_i - l_1)/(l_n - l_1)
  where eq. 4's right-hand side -sum k_i d_i delta_i gives a minus sign; only
  matters when d_i != 0.
"""
import numpy as np
import pytest

G = 9.81

#: the FMUs' default vehicle, written out here: a 15 m three-axle city bus
#: (front axle steered, drive axle fixed, tag axle steerable). Seed 004 gives
#: no vehicle data: every value is an estimate (see the report / README).
BUS = dict(n=3, l=[5.40, -1.55, -3.05], k=[-4.0e5, -6.0e5, -3.8e5], m=[700.0, 1300.0, 600.0],
           d=[0.0, 0.0, 0.0], steerable=[True, False, True], m_b=23400.0, h_b=0.6,
           I_ZZb=4.2e5, I_XXb=3.0e4, I_XZb=0.0, C_phi=1.3e5, K_phi=2.0e6)


def fmu_parameters(veh, controller=False):
    """{FMU variable name: value} for a vehicle dict (the plant's names; the
    controller takes the subset it shares with the plant)."""
    p = {"n": veh["n"], "m_b": veh["m_b"]}
    keys = ["l", "k", "m", "steerable"] + ([] if controller else ["d"])
    for key in keys:
        for i, x in enumerate(veh[key], 1):
            p[f"{key}[{i}]"] = x
    if not controller:
        p.update({k: veh[k] for k in ("h_b", "I_ZZb", "I_XXb", "I_XZb", "C_phi", "K_phi")})
    return p


def eq4(u, veh, paper_row4=False):
    """E, F, G of eq. 4, E X' + F X = G [delta_1..delta_n, M_d], X = [w_r, beta, p, phi]."""
    l, k, m, d = (np.asarray(veh[x], float) for x in ("l", "k", "m", "d"))
    m_b, h_b = veh["m_b"], veh["h_b"]
    M = m.sum() + m_b
    sml = (m * l).sum()
    Izz = (m * l * l).sum() + veh["I_ZZb"]
    Ixx = veh["I_XXb"] + m_b * h_b ** 2
    Ixz = veh["I_XZb"]
    E = np.array([[sml, u * M, -m_b * h_b, 0],
                  [Izz, u * sml, Ixz, 0],
                  [Ixz, -u * m_b * h_b, Ixx, 0],
                  [0, 0, 0, 1]])
    F = np.array([[u * M - (k * l).sum() / u, -k.sum(), 0, 0],
                  [u * sml - (k * l * l).sum() / u, -(k * l).sum(), 0, 0],
                  [-u * m_b * h_b - (k * l * d).sum() / u, -(k * d).sum(), veh["C_phi"], veh["K_phi"] - m_b * G * h_b],
                  [0, 0, 1 if paper_row4 else -1, 0]])
    G_ = np.zeros((4, len(l) + 1))
    G_[0, :-1] = -k
    G_[1, :-1] = -k * l
    G_[2, :-1] = -k * d
    G_[1, -1] = 1.0
    return E, F, G_


def state_space(u, veh, paper_row4=False):
    """A, B of eq. 5 with inputs [delta_1..delta_n, M_d]."""
    E, F, G_ = eq4(u, veh, paper_row4)
    return -np.linalg.solve(E, F), np.linalg.solve(E, G_)


def steady_state(u, veh, delta, Md=0.0):
    """[w_r, beta, p, phi] with X' = 0: F X = G U."""
    E, F, G_ = eq4(u, veh)
    return np.linalg.solve(F, G_ @ np.append(delta, Md))


def step_response(u, veh, delta, t, Md=0.0):
    """exact solution from rest of X' = A X + B U for a step U at t = 0
    (eigen-decomposition: X(t) = V diag((e^{lambda t} - 1)/lambda) V^-1 B U)."""
    A, B = state_space(u, veh)
    lam, V = np.linalg.eig(A)
    c = np.linalg.solve(V, B @ np.append(delta, Md))
    t = np.asarray(t, float)[:, None]
    X = ((np.exp(lam * t) - 1) / lam * c) @ V.T
    Xdot = (np.exp(lam * t) * c) @ V.T
    return X.real, Xdot.real


def lateral_acceleration(u, X, Xdot):
    """a_y = v' + u w_r = u (beta' + w_r) for a constant u"""
    return u * (Xdot[:, 1] + X[:, 0])


def steer_weights(veh):
    """eq. 3 on the steerable axles: delta_i = (a_i + b_i K) delta_1; r is the
    rearmost steerable axle (the paper's n when every axle steers)."""
    l = np.asarray(veh["l"], float)
    steer = np.asarray(veh["steerable"], bool)
    r = max(i for i in range(1, len(l)) if steer[i])
    s = (l[0] - l) / (l[0] - l[r])
    a = np.where(steer, 1 - s, 0.0)
    b = np.where(steer, s, 0.0)
    a[r], b[r] = 0.0, 1.0
    return a, b


def zero_sideslip_gain(u, veh):
    """K(u) found numerically: beta_ss is affine in K (the steady state is
    linear in the steering), so two solves give the root. No closed form."""
    a, b = steer_weights(veh)
    b0 = steady_state(max(u, 1e-3), veh, a)[1]
    b1 = steady_state(max(u, 1e-3), veh, a + b)[1]
    return -b0 / (b1 - b0)


def bicycle(u, a, b, m, Iz, Cf, Cr):
    """the textbook single-track (bicycle) model, positive cornering
    stiffnesses, state [v, r], input delta_f (e.g. Rajamani, ch. 2.3)"""
    A = np.array([[-(Cf + Cr) / (m * u), -u - (Cf * a - Cr * b) / (m * u)],
                  [-(Cf * a - Cr * b) / (Iz * u), -(Cf * a * a + Cr * b * b) / (Iz * u)]])
    B = np.array([Cf / m, Cf * a / Iz])
    return A, B


# ---- checks of the reference itself -------------------------------------------

def test_paper_row_4_as_printed_is_unstable():
    for u in (5.0, 20.0):
        A_paper, _ = state_space(u, BUS, paper_row4=True)
        A, _ = state_space(u, BUS)
        assert np.max(np.linalg.eigvals(A_paper).real) > 1.0
        assert np.max(np.linalg.eigvals(A).real) < -0.1


def test_two_axle_reduction_of_eq4_is_the_bicycle_model():
    """n = 2, no unsprung masses, no roll coupling (h_b = 0): the lateral/yaw
    part of eq. 4 is the textbook bicycle model, beta = v/u."""
    a, b, m, Iz, Cf, Cr = 1.2, 1.6, 1600.0, 2800.0, 9e4, 1.1e5
    veh = dict(n=2, l=[a, -b], k=[-Cf, -Cr], m=[0.0, 0.0], d=[0.0, 0.0], steerable=[True, False],
               m_b=m, h_b=0.0, I_ZZb=Iz, I_XXb=500.0, I_XZb=0.0, C_phi=4e3, K_phi=6e4)
    for u in (5.0, 15.0, 30.0):
        A, B = state_space(u, veh)
        Ab, Bb = bicycle(u, a, b, m, Iz, Cf, Cr)
        # X = [w_r, beta]; bicycle [v, r] with v = u beta
        T = np.array([[0, u], [1, 0]])          # [v, r] = T [w_r, beta]
        A2 = T @ A[:2, :2] @ np.linalg.inv(T)
        B2 = T @ B[:2, 0]
        assert np.allclose(A2, Ab, rtol=1e-12, atol=1e-12)
        assert np.allclose(B2, Bb, rtol=1e-12)


def test_zero_sideslip_gain_textbook_4ws():
    """the numerical K(u) against the classic 4WS closed form"""
    a, b, m, Cf, Cr = 1.2, 1.6, 1600.0, 9e4, 1.1e5
    L = a + b
    veh = dict(n=2, l=[a, -b], k=[-Cf, -Cr], m=[0.0, 0.0], d=[0.0, 0.0], steerable=[True, True],
               m_b=m, h_b=0.0, I_ZZb=2800.0, I_XXb=500.0, I_XZb=0.0, C_phi=4e3, K_phi=6e4)
    for u in (2.0, 10.0, 25.0):
        textbook = -(b - m * a * u * u / (Cr * L)) / (a + m * b * u * u / (Cf * L))
        assert zero_sideslip_gain(u, veh) == pytest.approx(textbook, rel=1e-9)
