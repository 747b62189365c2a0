"""BusKinematics.fmu checked against the closed-form kinematic models of seed 003.

Seed 003 = Michalek, Patkowski, Gawron, "Modular Kinematic Modelling of Articulated
Buses" (/work/shared/seeds/003_4fbc8f762479a4e9.txt).  Everything the FMU is compared
with is computed here from the paper's formulas (14), (15), (17)-(22) and the worked
closed forms (30), (34), (41), (43), (50) and Remark 9; no number printed by the FMU
is used as a reference.  The oracle itself is checked first (without the FMU): the
expanded closed forms must equal their matrix forms, and every closed form must
satisfy the nonholonomic constraints (8) of the whole chain.

Structures (N wagons, driving axle k, steerable wagons I_s, distinguished segment j):

    eq. 30   pusher          N=1  k=1  I_s={}     j=1
    eq. 34   pusher          N=1  k=1  I_s={}     j=0
    eq. 41   puller          N=1  k=0  I_s={1}    j=1
    eq. 43   puller          N=1  k=0  I_s={1}    j=0
    eq. 50   pusher-puller   N=2  k=1  I_s={2}    j=2
    Rem. 9   pulling bi-art. N=2  k=0  I_s={1,2}  j=2

The FMU takes the steering angles as (held) inputs, so only the column of S(q) that
multiplies v_k is checked (the zeta columns only give d(gamma)/dt = zeta, eq. 13).
"""
from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fmpy  # noqa: F401
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

from artibus import fmu_dir  # noqa: E402

FMU_PATH = fmu_dir() / "BusKinematics.fmu"
NMAX = 4  # size of the FMU's arrays L[1..4], Lh[1..4], gamma[1..4], ...
DEG = math.pi / 180.0

C = np.array([1.0, 0.0])  # c^T = [1 0]  (seed 003, Notation)
D = np.array([0.0, 1.0])  # d^T = [0 1]
I2 = np.eye(2)


# --------------------------------------------------------------------------------------
# Vehicle data and the paper's building blocks
# --------------------------------------------------------------------------------------
@dataclass
class Bus:
    """Kinematic parameters; lists are indexed by segment, L[0] = L0, Lh[0] unused."""

    N: int
    L: list
    Lh: list


def J(bus: Bus, i: int, beta: float, g_i: float, g_prev: float) -> np.ndarray:
    """u_i = J_i u_{i-1}.  # seed 003, eq. 14"""
    L, Lh, cg = bus.L[i], bus.Lh[i], math.cos(g_i)
    return np.array(
        [
            [-Lh / L * math.cos(beta - g_i) / cg, math.sin(beta - g_i + g_prev) / (L * cg)],
            [Lh * math.sin(beta) / cg, math.cos(beta + g_prev) / cg],
        ]
    )


def J_inv(bus: Bus, i: int, beta: float, g_i: float, g_prev: float) -> np.ndarray:
    """u_{i-1} = J_i^{-1} u_i, as printed.  # seed 003, eq. 15"""
    L, Lh, cp = bus.L[i], bus.Lh[i], math.cos(g_prev)
    return np.array(
        [
            [-L / Lh * math.cos(beta + g_prev) / cp, math.sin(beta - g_i + g_prev) / (Lh * cp)],
            [L * math.sin(beta) / cp, math.cos(beta - g_i) / cp],
        ]
    )


def Gamma(bus: Bus, i: int, beta: float, g_i: float, g_prev: float) -> np.ndarray:
    """Gamma_i = I - J_i.  # seed 003, definition after eq. 15"""
    return I2 - J(bus, i, beta, g_i, g_prev)


def kappa0(bus: Bus, gF: float) -> float:
    """Tractor curvature.  # seed 003, eq. 19"""
    return math.tan(gF) / bus.L[0]


def kappa1_eq29(bus: Bus, beta1: float, gF: float) -> float:
    """Wagon-1 curvature for gamma_0 = gamma_1 = 0.  # seed 003, eq. 29"""
    return math.tan(beta1 - math.atan(bus.Lh[1] / bus.L[0] * math.tan(gF))) / bus.L[1]


def virtual_steering_angles(bus: Bus, beta, gF: float, gam) -> list:
    """delta_1..delta_N by the recursion (17), (20), (19); index 0 unused."""
    kap, deltas = kappa0(bus, gF), [0.0]
    for i in range(1, bus.N + 1):
        gp = gam[i - 1]
        d = beta[i] - math.atan(bus.Lh[i] * kap / math.cos(gp) - math.tan(gp))  # eq. 17
        kap = math.sin(d - gam[i]) / (bus.L[i] * math.cos(d))  # eq. 20
        deltas.append(d)
    return deltas


def e(th: float) -> np.ndarray:
    return np.array([math.cos(th), math.sin(th)])


def chain_poses(bus: Bus, j: int, beta, theta_j: float, p_j) -> tuple[list, list]:
    """Headings and axle mid-points of all segments from the pose of segment j.

    beta_i = theta_{i-1} - theta_i (eq. 3); joint i lies Lh_i behind P_{i-1} along
    theta_{i-1}, P_i lies L_i behind joint i along theta_i (Fig. 2).
    """
    th = [0.0] * (bus.N + 1)
    P = [None] * (bus.N + 1)
    th[j], P[j] = theta_j, np.asarray(p_j, dtype=float)
    for i in range(j, 0, -1):  # towards the tractor
        th[i - 1] = th[i] + beta[i]
        P[i - 1] = P[i] + bus.L[i] * e(th[i]) + bus.Lh[i] * e(th[i - 1])
    for i in range(j + 1, bus.N + 1):  # towards the last wagon
        th[i] = th[i - 1] - beta[i]
        P[i] = P[i - 1] - bus.Lh[i] * e(th[i - 1]) - bus.L[i] * e(th[i])
    return th, P


# --------------------------------------------------------------------------------------
# The closed forms: v_k-column of S(q), per unit v_k.
# Each returns (betaDot_1..N, omega_j, v_j): then
#   d(beta_i)/dt = betaDot_i v_k,  d(theta_j)/dt = omega_j v_k,
#   d(x_j, y_j)/dt = v_j v_k (cos, sin)(theta_j + gamma_j)            (G of eq. 22)
# `gam` is indexed by segment with gam[0] = 0 and gam[i] = 0 for i not in I_s.
# --------------------------------------------------------------------------------------
def cf_eq30(bus, beta, gF, gam):
    """Pusher, j = 1, as printed on the second line of eq. 30."""
    b, k1 = beta[1], kappa1_eq29(bus, beta[1], gF)
    bd1 = -(1.0 + bus.L[1] / bus.Lh[1] * math.cos(b)) * k1 + math.sin(b) / bus.Lh[1]
    return np.array([bd1]), k1, 1.0


def cf_eq30_matrix(bus, beta, gF, gam):
    """Pusher, j = 1, first line of eq. 30: c^T Gamma_1 J_1^{-1} [k1 1]^T, G(theta_1) [k1 1]^T."""
    u1 = np.array([kappa1_eq29(bus, beta[1], gF), 1.0])  # eq. 28
    bd1 = C @ Gamma(bus, 1, beta[1], 0, 0) @ J_inv(bus, 1, beta[1], 0, 0) @ u1
    return np.array([bd1]), u1[0], u1[1]


def cf_eq34(bus, beta, gF, gam):
    """Pusher, j = 0, as printed on the second line of eq. 34."""
    b, k1 = beta[1], kappa1_eq29(bus, beta[1], gF)
    L1, Lh1 = bus.L[1], bus.Lh[1]
    bd1 = -(1.0 + L1 / Lh1 * math.cos(b)) * k1 + math.sin(b) / Lh1
    om0 = (math.sin(b) - L1 * math.cos(b) * k1) / Lh1
    v0 = math.cos(b) + L1 * math.sin(b) * k1
    return np.array([bd1]), om0, v0


def cf_eq34_matrix(bus, beta, gF, gam):
    """Pusher, j = 0, first line of eq. 34: G(theta_0) J_1^{-1} [k1 1]^T  (eq. 33)."""
    u1 = np.array([kappa1_eq29(bus, beta[1], gF), 1.0])
    Ji = J_inv(bus, 1, beta[1], 0, 0)
    bd1 = C @ Gamma(bus, 1, beta[1], 0, 0) @ Ji @ u1
    u0 = Ji @ u1
    return np.array([bd1]), u0[0], u0[1]


def cf_eq41(bus, beta, gF, gam):
    """Puller, j = 1, as printed on the second line of eq. 41."""
    b, g, k0 = beta[1], gam[1], kappa0(bus, gF)
    L1, Lh1, cg = bus.L[1], bus.Lh[1], math.cos(gam[1])
    bd1 = (1.0 + Lh1 * math.cos(b - g) / (L1 * cg)) * k0 - math.sin(b - g) / (L1 * cg)
    om1 = (math.sin(b - g) - Lh1 * math.cos(b - g) * k0) / (L1 * cg)
    v1 = (math.cos(b) + Lh1 * math.sin(b) * k0) / cg
    return np.array([bd1]), om1, v1


def cf_eq41_matrix(bus, beta, gF, gam):
    """Puller, j = 1, first line of eq. 41: c^T Gamma_1 [k0 1]^T, G(theta_1, g1) J_1 [k0 1]^T."""
    u0 = np.array([kappa0(bus, gF), 1.0])  # eq. 40
    bd1 = C @ Gamma(bus, 1, beta[1], gam[1], 0) @ u0
    u1 = J(bus, 1, beta[1], gam[1], 0) @ u0  # eq. 39
    return np.array([bd1]), u1[0], u1[1]


def cf_eq43(bus, beta, gF, gam):
    """Puller, j = 0, as printed on the second line of eq. 43."""
    bd1 = cf_eq41(bus, beta, gF, gam)[0]
    return bd1, kappa0(bus, gF), 1.0


def cf_eq43_matrix(bus, beta, gF, gam):
    """Puller, j = 0, first line of eq. 43: G(theta_0) [k0 1]^T."""
    bd1 = cf_eq41_matrix(bus, beta, gF, gam)[0]
    return bd1, kappa0(bus, gF), 1.0


def cf_eq50(bus, beta, gF, gam):
    """Pusher-puller (N=2, k=1, I_s={2}), j = 2.  # seed 003, eq. 50"""
    u1 = np.array([kappa1_eq29(bus, beta[1], gF), 1.0])  # eq. 28 with (29)
    bd1 = C @ Gamma(bus, 1, beta[1], 0, 0) @ J_inv(bus, 1, beta[1], 0, 0) @ u1
    bd2 = C @ Gamma(bus, 2, beta[2], gam[2], 0) @ u1
    u2 = J(bus, 2, beta[2], gam[2], 0) @ u1  # eq. 49
    return np.array([bd1, bd2]), u2[0], u2[1]


def cf_remark9(bus, beta, gF, gam):
    """Pulling bi-articulated (N=2, k=0, I_s={1,2}), j = 2.  # seed 003, Remark 9

    (The printed matrix writes e^T in the beta rows; it is c^T, as in eqs. 16, 41, 50.)
    """
    u0 = np.array([kappa0(bus, gF), 1.0])
    J1 = J(bus, 1, beta[1], gam[1], 0)
    bd1 = C @ Gamma(bus, 1, beta[1], gam[1], 0) @ u0
    bd2 = C @ Gamma(bus, 2, beta[2], gam[2], gam[1]) @ J1 @ u0
    u2 = J(bus, 2, beta[2], gam[2], gam[1]) @ J1 @ u0
    return np.array([bd1, bd2]), u2[0], u2[1]


@dataclass(frozen=True)
class Structure:
    id: str
    N: int
    k: int
    steer: tuple  # I_s
    j: int
    cf: Callable  # the closed form used as the reference
    cf_matrix: Callable | None = None  # the printed matrix form, when it differs


STRUCTURES = [
    Structure("eq30_pusher_j1", 1, 1, (), 1, cf_eq30, cf_eq30_matrix),
    Structure("eq34_pusher_j0", 1, 1, (), 0, cf_eq34, cf_eq34_matrix),
    Structure("eq41_puller_j1", 1, 0, (1,), 1, cf_eq41, cf_eq41_matrix),
    Structure("eq43_puller_j0", 1, 0, (1,), 0, cf_eq43, cf_eq43_matrix),
    Structure("eq50_pusherpuller_j2", 2, 1, (2,), 2, cf_eq50),
    Structure("remark9_puller_j2", 2, 0, (1, 2), 2, cf_remark9),
]
STRUCT_IDS = [s.id for s in STRUCTURES]


@dataclass
class Config:
    bus: Bus
    beta: list  # index 1..N (index 0 unused)
    gF: float
    gam_in: list  # the four FMU inputs gamma[1..4] (index 0 unused)
    v: float
    theta0: float  # tractor pose, as the FMU takes it
    x0: float
    y0: float

    def gam(self, st: Structure) -> list:
        """Effective steering angles: gamma_i = 0 unless i in I_s (eq. 21, step S2)."""
        return [0.0] + [self.gam_in[i] if i in st.steer else 0.0 for i in range(1, self.bus.N + 1)]


def random_config(st: Structure, rng: np.random.Generator) -> Config:
    """Random configuration inside the model's domain |delta_i| < pi/2 (Remark 4), with margin."""
    while True:
        N = st.N
        L = [rng.uniform(3.0, 7.0)] + list(rng.uniform(3.0, 8.0, N))
        Lh = [float("nan")] + list(rng.uniform(0.5, 2.5, N))
        cfg = Config(
            bus=Bus(N, L, Lh),
            beta=[0.0] + list(rng.uniform(-40.0, 40.0, N) * DEG),
            gF=rng.uniform(-35.0, 35.0) * DEG,
            gam_in=[0.0] + list(rng.uniform(-20.0, 20.0, NMAX) * DEG),
            v=rng.uniform(-5.0, 5.0),
            theta0=rng.uniform(-math.pi, math.pi),
            x0=rng.uniform(-50.0, 50.0),
            y0=rng.uniform(-50.0, 50.0),
        )
        deltas = virtual_steering_angles(cfg.bus, cfg.beta, cfg.gF, cfg.gam(st))
        if max(abs(d) for d in deltas[1:]) < 80.0 * DEG:
            return cfg


def pose_j(cfg: Config, st: Structure):
    """Pose of segment j from the tractor pose (what the FMU takes as start values)."""
    th, P = chain_poses(cfg.bus, 0, cfg.beta, cfg.theta0, (cfg.x0, cfg.y0))
    return th[st.j], P[st.j]


def wrap(a):
    return (np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi


# --------------------------------------------------------------------------------------
# 0. The oracle itself (no FMU)
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("st", [s for s in STRUCTURES if s.cf_matrix], ids=lambda s: s.id)
def test_oracle_expanded_equals_matrix_form(st):
    """The expanded second lines of eqs. 30, 34, 41, 43 equal their matrix first lines."""
    rng = np.random.default_rng(1000 + STRUCT_IDS.index(st.id))
    for _ in range(50):
        cfg = random_config(st, rng)
        a = st.cf(cfg.bus, cfg.beta, cfg.gF, cfg.gam(st))
        b = st.cf_matrix(cfg.bus, cfg.beta, cfg.gF, cfg.gam(st))
        np.testing.assert_allclose(a[0], b[0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a[1:], b[1:], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("st", STRUCTURES, ids=STRUCT_IDS)
def test_oracle_satisfies_constraints_8(st):
    """Each closed form moves the whole chain without side slip (eq. 8) at speed v_k (eq. 11).

    The velocity of every axle mid-point (and of the tractor's front wheel) is obtained by
    central differences of the rigid geometry along q' = S(q) u; its component normal to the
    wheel plane must vanish, and P_k must move at v_k along its wheel plane.
    """
    rng = np.random.default_rng(2000 + STRUCT_IDS.index(st.id))
    h = 1e-6
    for _ in range(30):
        cfg = random_config(st, rng)
        bus, gam, v = cfg.bus, cfg.gam(st), cfg.v
        th_j, p_j = pose_j(cfg, st)
        bd, om, vj = st.cf(bus, cfg.beta, cfg.gF, gam)
        beta = np.array(cfg.beta)
        betadot = np.concatenate([[0.0], bd]) * v
        pdot = vj * v * e(th_j + gam[st.j])

        def geom(s):
            th, P = chain_poses(bus, st.j, beta + s * betadot, th_j + s * om * v, p_j + s * pdot)
            PF = P[0] + bus.L[0] * e(th[0])  # effective front wheel
            return np.array(th), np.array(P), PF

        thp, Pp, PFp = geom(h)
        thm, Pm, PFm = geom(-h)
        th0, _, _ = geom(0.0)
        Pdot, PFdot = (Pp - Pm) / (2 * h), (PFp - PFm) / (2 * h)
        for i in range(bus.N + 1):
            ang = th0[i] + gam[i]
            lateral = -Pdot[i][0] * math.sin(ang) + Pdot[i][1] * math.cos(ang)
            assert abs(lateral) < 1e-7, (st.id, i, lateral)
        angF = th0[0] + cfg.gF
        assert abs(-PFdot[0] * math.sin(angF) + PFdot[1] * math.cos(angF)) < 1e-7
        angk = th0[st.k] + gam[st.k]
        vk = Pdot[st.k][0] * math.cos(angk) + Pdot[st.k][1] * math.sin(angk)
        assert abs(vk - v) < 1e-7, (st.id, vk, v)


# --------------------------------------------------------------------------------------
# FMU driver
# --------------------------------------------------------------------------------------
class FmuRunner:
    def __init__(self, md, unzipdir):
        self.md, self.unzipdir = md, unzipdir
        self.vr = {sv.name: sv.valueReference for sv in md.modelVariables}
        self.slave = None
        self.state = None  # None | "instantiated" | "running"
        self._new_instance()

    def _new_instance(self):
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="t",
        )
        self.slave.instantiate()
        self.state = "instantiated"

    def start(self, cfg: Config, st: Structure, j: int | None = None, rtol=1e-10, atol=1e-12):
        """(Re)initialise with the given configuration and held inputs."""
        s = self.slave
        if self.state == "running":
            try:
                s.reset()
            except Exception:  # e.g. after an error state: start over with a new instance
                try:
                    s.freeInstance()
                except Exception:
                    pass
                self._new_instance()
                s = self.slave
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        self.state = "running"
        vr, bus = self.vr, cfg.bus
        s.setInteger([vr["N"], vr["k"], vr["j"]], [st.N, st.k, st.j if j is None else j])
        reals = {
            "L0": bus.L[0],
            "theta_start": cfg.theta0,
            "x_start": cfg.x0,
            "y_start": cfg.y0,
            "rtol": rtol,
            "atol": atol,
            "testSteerAmp": 0.0,  # no built-in stimulus: gammaF is the input below
            "gammaF": cfg.gF,
            "v": cfg.v,
        }
        for i in range(1, NMAX + 1):
            inside = i <= bus.N
            reals[f"L[{i}]"] = bus.L[i] if inside else 4.0
            reals[f"Lh[{i}]"] = bus.Lh[i] if inside else 1.5
            reals[f"beta_start[{i}]"] = cfg.beta[i] if inside else 0.0
            reals[f"gamma[{i}]"] = cfg.gam_in[i]  # set for non-steerable wagons too: must be ignored
        s.setReal([vr[n] for n in reals], list(reals.values()))
        s.setBoolean(
            [vr[f"steerable[{i}]"] for i in range(1, NMAX + 1)],
            [i in st.steer for i in range(1, NMAX + 1)],
        )
        s.exitInitializationMode()

    def get(self, *names) -> dict:
        vals = self.slave.getReal([self.vr[n] for n in names])
        return dict(zip(names, vals))

    def close(self):
        try:
            if self.state == "running":
                self.slave.terminate()
        finally:
            self.slave.freeInstance()


@pytest.fixture(scope="module")
def fmu():
    assert FMU_PATH.exists(), f"{FMU_PATH} not built: run the set-up command of the README"
    md = read_model_description(str(FMU_PATH))
    unzipdir = extract(str(FMU_PATH))
    runner = FmuRunner(md, unzipdir)
    yield runner
    runner.close()
    shutil.rmtree(unzipdir, ignore_errors=True)


# --------------------------------------------------------------------------------------
# 1. State derivatives at t = 0 against S(q) u
# --------------------------------------------------------------------------------------
N_RANDOM = 20


def close_enough(actual, expected, tol=1e-9):
    return abs(actual - expected) <= tol * (1.0 + abs(expected))


@pytest.mark.parametrize("case", range(N_RANDOM))
@pytest.mark.parametrize("st", STRUCTURES, ids=STRUCT_IDS)
def test_state_derivatives_match_closed_form(fmu, st, case):
    """betaDot_i, omega_j = d(theta_j)/dt, v_j and the x_j, y_j rows vs. the v_k column of
    S(q) in eqs. 30 / 34 / 41 / 43 / 50 / Remark 9 (with eqs. 14, 15, 19, 22, 29)."""
    rng = np.random.default_rng([3000 + STRUCT_IDS.index(st.id), case])
    cfg = random_config(st, rng)
    gam, j, v = cfg.gam(st), st.j, cfg.v
    fmu.start(cfg, st)

    names = [f"betaDot[{i}]" for i in range(1, st.N + 1)]
    names += [f"theta[{j}]", f"omega[{j}]", f"vel[{j}]", f"vel[{st.k}]"]
    out = fmu.get(*names)

    bd, om, vj = st.cf(cfg.bus, cfg.beta, cfg.gF, gam)
    th_j, _ = pose_j(cfg, st)
    ctx = f"{st.id} case {case}: {cfg}"

    # theta_j = theta_0 - beta_1 - ... - beta_j (eq. 3)
    assert abs(wrap(out[f"theta[{j}]"] - th_j)) < 1e-12, ctx
    # the driving axle moves at the input speed (eq. 11)
    assert close_enough(out[f"vel[{st.k}]"], v), (ctx, out[f"vel[{st.k}]"], v)
    # beta rows of S(q) u
    for i in range(1, st.N + 1):
        got, want = out[f"betaDot[{i}]"], bd[i - 1] * v
        assert close_enough(got, want), f"betaDot[{i}] = {got!r}, closed form {want!r}; {ctx}"
    # theta_j row
    assert close_enough(out[f"omega[{j}]"], om * v), (
        f"omega[{j}] = {out[f'omega[{j}]']!r}, closed form {om * v!r}; {ctx}"
    )
    # x_j, y_j rows: v_j (cos, sin)(theta_j + gamma_j)  (G of eq. 22)
    assert close_enough(out[f"vel[{j}]"], vj * v), (
        f"vel[{j}] = {out[f'vel[{j}]']!r}, closed form {vj * v!r}; {ctx}"
    )
    ang_fmu, ang = out[f"theta[{j}]"] + gam[j], th_j + gam[j]
    for f in (math.cos, math.sin):
        assert close_enough(out[f"vel[{j}]"] * f(ang_fmu), vj * v * f(ang)), ctx


# --------------------------------------------------------------------------------------
# 2. Trajectories: integrate the closed form and compare with the FMU
# --------------------------------------------------------------------------------------
T_END, H = 20.0, 0.1

MANOEUVRES = {  # moderate constant steering, forward driving at 2..4 m/s
    "eq30_pusher_j1": dict(gF=0.30, gam=[0, 0.0, 0, 0, 0], v=3.0, beta=[0, 0.10]),
    "eq34_pusher_j0": dict(gF=-0.25, gam=[0, 0.2, 0, 0, 0], v=2.5, beta=[0, -0.15]),
    "eq41_puller_j1": dict(gF=0.30, gam=[0, -0.15, 0, 0, 0], v=3.5, beta=[0, 0.05]),
    "eq43_puller_j0": dict(gF=-0.20, gam=[0, 0.10, 0, 0, 0], v=2.0, beta=[0, -0.10]),
    "eq50_pusherpuller_j2": dict(gF=0.25, gam=[0, 0.1, -0.12, 0, 0], v=4.0, beta=[0, 0.10, -0.05]),
    "remark9_puller_j2": dict(gF=0.28, gam=[0, -0.10, -0.15, 0, 0], v=3.0, beta=[0, 0.05, 0.10]),
}


def manoeuvre_config(st: Structure) -> Config:
    m = MANOEUVRES[st.id]
    # Urbino 18 Electric (Table I) for tractor and wagon 1; a second wagon of similar size
    L = [5.9, 4.211, 4.8][: st.N + 1]
    Lh = [float("nan"), 1.789, 1.6][: st.N + 1]
    return Config(Bus(st.N, L, Lh), m["beta"], m["gF"], m["gam"], m["v"], 0.4, 10.0, -5.0)


@pytest.mark.parametrize("st", STRUCTURES, ids=STRUCT_IDS)
def test_trajectory_matches_integrated_closed_form(fmu, st):
    """Pose q_j and joint angles from the FMU vs. solve_ivp of q' = S(q) u
    (eqs. 30 / 34 / 41 / 43 / 50 / Remark 9) with constant gammaF, gamma_s, v_k."""
    cfg = manoeuvre_config(st)
    bus, gam, v, N = cfg.bus, cfg.gam(st), cfg.v, st.N
    th_j0, p_j0 = pose_j(cfg, st)

    def rhs(t, y):  # y = [beta_1..beta_N, theta_j, x_j, y_j]
        beta = [0.0] + list(y[:N])
        bd, om, vj = st.cf(bus, beta, cfg.gF, gam)
        ang = y[N] + gam[st.j]
        return np.concatenate([bd * v, [om * v, vj * v * math.cos(ang), vj * v * math.sin(ang)]])

    t_eval = np.linspace(0.0, T_END, int(round(T_END / H)) + 1)
    y0 = np.array(cfg.beta[1:] + [th_j0, p_j0[0], p_j0[1]])
    sol = solve_ivp(rhs, (0.0, T_END), y0, method="DOP853", t_eval=t_eval, rtol=1e-12, atol=1e-12)
    assert sol.success, sol.message
    ref = sol.y

    fmu.start(cfg, st, rtol=1e-10, atol=1e-12)
    names = [f"beta[{i}]" for i in range(1, N + 1)] + [f"theta[{st.j}]", f"x[{st.j}]", f"y[{st.j}]"]
    got = np.empty_like(ref)
    for n, t in enumerate(t_eval):
        if n > 0:
            fmu.slave.doStep(currentCommunicationPoint=t_eval[n - 1], communicationStepSize=H)
        got[:, n] = list(fmu.get(*names).values())

    # tolerances: relative 1e-6 of the trajectory scale
    path = abs(v) * T_END  # path length of P_k
    pos_tol = 1e-6 * max(path, 1.0)
    ang_tol = 1e-6 * max(1.0, float(np.ptp(ref[N])))
    err_beta = np.max(np.abs(got[:N] - ref[:N]), axis=1)
    err_theta = np.max(np.abs(wrap(got[N] - ref[N])))
    err_pos = np.max(np.hypot(got[N + 1] - ref[N + 1], got[N + 2] - ref[N + 2]))
    msg = (
        f"{st.id}: max |d beta| = {err_beta}, max |d theta_j| = {err_theta:.3e} (tol {ang_tol:.1e}), "
        f"max |d p_j| = {err_pos:.3e} m (tol {pos_tol:.1e}); "
        f"final ref beta={ref[:N, -1]}, theta_j={ref[N, -1]:.6f}, p_j=({ref[N + 1, -1]:.6f}, {ref[N + 2, -1]:.6f}); "
        f"final FMU beta={got[:N, -1]}, theta_j={got[N, -1]:.6f}, p_j=({got[N + 1, -1]:.6f}, {got[N + 2, -1]:.6f})"
    )
    assert np.all(err_beta <= 1e-6 * 1.0), msg  # joint angles: scale 1 rad
    assert err_theta <= ang_tol, msg
    assert err_pos <= pos_tol, msg


# --------------------------------------------------------------------------------------
# 3. Joint-angle bound (31) for the Urbino 18 Electric
# --------------------------------------------------------------------------------------
def beta_bound_eq31(L0: float, Lh1: float, gF_max: float) -> float:
    """|beta_1| < pi/2 - atan(Lh1/L0 tan(gammaF_max)).  # seed 003, eq. 31"""
    return math.pi / 2 - math.atan(Lh1 / L0 * math.tan(gF_max))


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["left", "right"])
def test_beta_max_urbino18(fmu, sign):
    """betaMax[1] with Table I data and gammaF = +-42 deg equals b_1 of eq. 31 (74.7 deg)."""
    st = Structure("urbino18_pusher", 1, 1, (), 1, cf_eq30)
    L0, Lh1, L1 = 5.9, 1.789, 4.211  # Table I
    gF = sign * 42.0 * DEG
    cfg = Config(Bus(1, [L0, L1], [float("nan"), Lh1]), [0.0, 0.0], gF, [0.0] * 5, 1.0, 0.0, 0.0, 0.0)
    fmu.start(cfg, st)
    got = fmu.get("betaMax[1]")["betaMax[1]"]
    b1 = beta_bound_eq31(L0, Lh1, 42.0 * DEG)
    assert abs(b1 / DEG - 74.7) < 0.05  # the paper's value (Remark 8)
    assert abs(got / DEG - 74.7) < 0.05, f"betaMax[1] = {got / DEG:.4f} deg, paper 74.7 deg"
    assert abs(got - b1) <= 1e-9, f"betaMax[1] = {got!r} rad, eq. 31 gives {b1!r} rad"
