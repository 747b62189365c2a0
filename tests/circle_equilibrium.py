"""The steady circular equilibrium of a BusDynamics train, computed
independently of the plant (issues 3 and 5).

Written here from first principles; it shares no code with the plant
(src/models/BusDynamics/dynamics.cpp), only its documented data and laws
(modelDescription/BusDynamics.xml). The tests compare the FMU's simulated
steady state against it.

All modules turn at one constant yaw rate Omega about one fixed centre O, so
in module 1's frame (which rotates with Omega) the configuration is
stationary. For each module, Newton-Euler with the centripetal acceleration
of its CG, -Omega^2 (CG - O), and no angular acceleration:

    sum of tyre forces + hinge forces      = m_m * (-Omega^2 (CG_m - O))
    sum of their moments about CG_m        = 0

The tyre forces come from the slip angle of each axle in the rigid rotation
about O: its velocity Omega e_z x (A - O) has the components (u, w) along and
across the wheel, and alpha = atan2(-w, sqrt(u^2 + vSlip^2)) (the vSlip
description). The lateral force law is the one the tyreModel parameter
documents:

    tyreModel 0   Fy = C alpha                                (seed 000, eq. 24)
    tyreModel 1   Fy = mu C alpha, saturated at +-mu Fz       (seed 001)

with the loads Fz given (the plant's static loads). Axle 1 is steered by
delta1, the others are locked straight; the drive force acts on one axle
(A2 by default) along its wheel.

Unknowns: O (2), the yaw angles of modules 2..n relative to module 1, the
hinge forces (force of the front module on the rear one, equal and opposite
on the front module; 2 each) and the drive force: 3 n unknowns, 3 n
equations. The operating point is only delta1 and the speed V of module 1's
CG.

The data P is a dict of 1-based lists (index 0 unused) with the parameter
names of BusDynamics.xml: nMod, nAxles, tyreModel, vSlip, m[m], lHf[k],
lHr[k], axleModule[a], xA[a], C[a], mu[a] (tyreModel 1 only), Fz[a].
"""
import math

import numpy as np
from scipy.optimize import least_squares


def _e(a):
    return np.array([math.cos(a), math.sin(a)])


def _cross(r, f):
    return r[0] * f[1] - r[1] * f[0]


FS = 1e4      # force scale of the unknowns and residuals


def lateral_tyre_force(P, a, alpha):
    """Fy of axle a at slip angle alpha, by the documented tyreModel law."""
    if P["tyreModel"] == 0:
        return P["C"][a] * alpha
    if P["tyreModel"] == 1:
        lim = P["mu"][a] * P["Fz"][a]
        return min(max(P["mu"][a] * P["C"][a] * alpha, -lim), lim)
    raise ValueError(f"tyreModel {P['tyreModel']}: only 0 and 1 are written here")


def _unpack(x, n):
    O = x[0:2]
    th = [None, 0.0] + list(x[2:n + 1])                      # yaw of module m - yaw of module 1
    F = [None] + [FS * x[n + 1 + 2 * (k - 1): n + 3 + 2 * (k - 1)] for k in range(1, n)]
    return O, th, F, FS * x[-1]


def equilibrium_state(P, x, delta1, V, drive_axle=2):
    """Residuals of the steady circular motion and everything it implies, in
    module 1's frame, origin at module 1's CG."""
    n, na = P["nMod"], P["nAxles"]
    O, th, F, Fdrive = _unpack(x, n)
    Om = math.copysign(V / math.hypot(*O), O[1])           # centre on the left: turning left
    # geometry, from module 1 back along the chain
    cg, hinge = [None, np.zeros(2)], [None]
    for k in range(1, n):
        hinge.append(cg[k] - P["lHf"][k] * _e(th[k]))
        cg.append(hinge[k] - P["lHr"][k] * _e(th[k + 1]))
    axle = [None] + [cg[P["axleModule"][a]] + P["xA"][a] * _e(th[P["axleModule"][a]])
                     for a in range(1, na + 1)]
    force = [None] + [np.zeros(2) for _ in range(n)]
    moment = [None] + [0.0] * n
    alpha, Fy = [None], [None]
    for a in range(1, na + 1):
        m = P["axleModule"][a]
        steer = delta1 if a == 1 else 0.0
        along, across = _e(th[m] + steer), _e(th[m] + steer + math.pi / 2)
        rel = axle[a] - O
        vel = Om * np.array([-rel[1], rel[0]])               # Omega e_z x (A - O)
        u, w = vel @ along, vel @ across
        al = math.atan2(-w, math.sqrt(u * u + P["vSlip"] ** 2))
        fy = lateral_tyre_force(P, a, al)
        f = (Fdrive if a == drive_axle else 0.0) * along + fy * across
        force[m] += f
        moment[m] += _cross(axle[a] - cg[m], f)
        alpha.append(al)
        Fy.append(fy)
    for k in range(1, n):            # F[k]: of module k on module k+1, at hinge k
        force[k + 1] += F[k]
        moment[k + 1] += _cross(hinge[k] - cg[k + 1], F[k])
        force[k] -= F[k]
        moment[k] -= _cross(hinge[k] - cg[k], F[k])
    res = []
    for m in range(1, n + 1):
        res += list((force[m] + P["m"][m] * Om ** 2 * (cg[m] - O)) / FS)
        res.append(moment[m] / (10 * FS))
    # hinge forces in the front module's frame, as the plant reports them
    FjX = [None] + [F[k] @ _e(th[k]) for k in range(1, n)]
    FjY = [None] + [F[k] @ _e(th[k] + math.pi / 2) for k in range(1, n)]
    radius = [None] + [math.hypot(*(axle[a] - O)) for a in range(1, na + 1)]
    cg_radius = [None] + [math.hypot(*(cg[m] - O)) for m in range(1, n + 1)]
    return np.array(res), dict(O=O, th=th, F=F, Fdrive=Fdrive, Omega=Om, radius=radius,
                               cg_radius=cg_radius, FjointX=FjX, FjointY=FjY, alpha=alpha,
                               Fy=Fy, artAngle=[None] + [th[k] - th[k + 1] for k in range(1, n)])


def solve_equilibrium(P, delta1, V):
    """The steady circle for front steering delta1 and CG-1 speed V, from
    guesses that know nothing of the simulation: the centre on the tractor's
    rear-axle line at its kinematic distance, a grid of articulation angles,
    no forces. The solution with every articulation angle between 0 and 90 deg
    (a left turn, the trailers inside) must be unique; it is returned."""
    n = P["nMod"]
    L = P["xA"][1] - P["xA"][2]
    found = []
    for a1 in (0.3, 0.6, 0.9, 1.2):
        for a2 in (0.3, 0.6, 0.9, 1.2):
            th = -np.cumsum([a1, a2][:n - 1])
            x0 = np.r_[P["xA"][2], L / math.tan(delta1), th, np.zeros(2 * (n - 1)), 1.0]
            sol = least_squares(lambda x: equilibrium_state(P, x, delta1, V)[0], x0,
                                method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=300)
            res, info = equilibrium_state(P, sol.x, delta1, V)
            if np.abs(res).max() < 1e-9 and info["Omega"] > 0 and \
                    all(0 < info["artAngle"][k] < math.pi / 2 for k in range(1, n)):
                found.append((sol.x, info))
    assert found, "no steady circular equilibrium with articulation angles in (0, 90 deg)"
    for x, _ in found[1:]:
        assert np.allclose(x, found[0][0], atol=1e-6), "more than one equilibrium"
    return found[0][1]


def fit_circle(x, y):
    """Centre and radius of the circle through a trace: algebraic fit, then
    geometric least squares; also the rms distance of the points from it."""
    A = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    (cx, cy, c), *_ = np.linalg.lstsq(A, x ** 2 + y ** 2, rcond=None)
    p0 = np.array([cx, cy, math.sqrt(c + cx ** 2 + cy ** 2)])
    sol = least_squares(lambda p: np.hypot(x - p[0], y - p[1]) - p[2], p0, xtol=1e-14, ftol=1e-14)
    return sol.x[:2], sol.x[2], math.sqrt(np.mean(sol.fun ** 2))
