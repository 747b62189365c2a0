"""Draws docs/geometry.png: the geometry conventions of the vehicle parameter
sets (which length is measured from where, the sign of each angle), for
BusDynamics (seed 000's single-track multibody model; the names of
modelDescription/BusDynamics.xml, the numbers of ssp/parameters/Template.ssv)
and BusKinematics (seed 003, Fig. 2: segments, hitching offsets, joint angles).

    .venv/bin/python scripts/geometry_drawing.py [-o docs/geometry.png]
"""
import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

# the Template's Scania 18 m (seed 001 Tables 3.1, 5.1)
XA = {1: 1.944, 2: -3.306, 3: -0.163}
LHF, LHR = 5.128, 4.777
LFRONT, LREAR = (4.644, 4.777), (5.128, 3.451)
W = 2.55


def rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def dim(ax, p0, p1, text, off, colour="tab:blue", size=8):
    """A dimension line from p0 to p1 (arrows at both ends), shifted by ``off`` (a vector), labelled."""
    p0, p1, off = np.asarray(p0), np.asarray(p1), np.asarray(off)
    a, b = p0 + off, p1 + off
    ax.annotate("", xy=b, xytext=a, arrowprops=dict(arrowstyle="<->", color=colour, lw=1.0))
    for p, q in ((p0, a), (p1, b)):
        ax.plot([p[0], q[0]], [p[1], q[1]], color=colour, lw=0.5, ls=":")
    m = (a + b) / 2
    ax.text(m[0], m[1] + 0.12 * np.sign(off[1] if off[1] else 1), text, color=colour, fontsize=size,
            ha="center", va="bottom" if off[1] >= 0 else "top")


def angle_arc(ax, centre, r, a0, a1, text, colour="tab:red", at=None):
    t = np.linspace(a0, a1, 40)
    ax.plot(centre[0] + r * np.cos(t), centre[1] + r * np.sin(t), color=colour, lw=1.2)
    ax.annotate("", xy=(centre[0] + r * math.cos(a1), centre[1] + r * math.sin(a1)),
                xytext=(centre[0] + r * math.cos(t[-3]), centre[1] + r * math.sin(t[-3])),
                arrowprops=dict(arrowstyle="->", color=colour, lw=1.2))
    am = (a0 + a1) / 2
    tip = np.array([centre[0] + r * math.cos(am), centre[1] + r * math.sin(am)])
    if at is None:
        ax.text(centre[0] + (r + 0.35) * math.cos(am), centre[1] + (r + 0.35) * math.sin(am), text, color=colour,
                fontsize=9, ha="center", va="center")
    else:                                   # the label elsewhere, a thin line to the arc
        pos = tip + np.asarray(at)
        ax.annotate(text, xy=tip, xytext=pos, color=colour, fontsize=9, ha="center", va="center",
                    arrowprops=dict(arrowstyle="-", color=colour, lw=0.5))


def dynamics(ax):
    psi1, psi2 = math.radians(12.0), 0.0
    cg2 = np.array([0.0, 0.0])
    hinge = cg2 + rot(psi2) @ np.array([LHR, 0.0])
    cg1 = hinge + rot(psi1) @ np.array([LHF, 0.0])
    bodies = {1: (cg1, psi1), 2: (cg2, psi2)}
    for k, (cg, psi) in bodies.items():
        R = rot(psi)
        lf, lr = LFRONT[k - 1], LREAR[k - 1]
        q = np.array([[lf, W / 2], [lf, -W / 2], [-lr, -W / 2], [-lr, W / 2], [lf, W / 2]]) @ R.T + cg
        ax.fill(q[:, 0], q[:, 1], facecolor="0.93", edgecolor="0.3", lw=1.0)
        ax.plot(*cg, "ko", ms=5)
        ax.text(cg[0], cg[1] - 0.35, f"CG {k}", fontsize=8, ha="center", va="top")
        ax.plot(*(np.array([[lf + 1.0, 0], [-lr - 0.4, 0]]) @ R.T + cg).T, color="0.5", lw=0.6, ls="--")
    # axles
    for a, x in XA.items():
        k = 1 if a < 3 else 2
        cg, psi = bodies[k]
        R = rot(psi)
        steer = math.radians(20.0) if a == 1 else 0.0
        c = R @ np.array([x, 0.0]) + cg
        for side in (1, -1):
            wc = R @ np.array([x, side * (W / 2 - 0.35)]) + cg
            wd = rot(psi + steer) @ np.array([0.5, 0.0])
            ax.plot([wc[0] - wd[0], wc[0] + wd[0]], [wc[1] - wd[1], wc[1] + wd[1]], color="k", lw=4,
                    solid_capstyle="butt")
        ax.plot(*np.array([R @ np.array([x, W / 2 - 0.35]) + cg, R @ np.array([x, -W / 2 + 0.35]) + cg]).T,
                color="k", lw=1)
        ax.text(c[0], c[1] + 0.25, f"A{a}", fontsize=9, ha="center", fontweight="bold")
    # dimensions, module 1 (drawn in its frame, then turned)
    R1 = rot(psi1)
    n1 = R1 @ np.array([0, 1.0])
    dim(ax, cg1, R1 @ np.array([XA[1], 0]) + cg1, "xA[1] > 0", 2.2 * n1)
    dim(ax, cg1, R1 @ np.array([XA[2], 0]) + cg1, "xA[2] < 0", 2.2 * n1)
    dim(ax, cg1, hinge, "lHf[1]", -2.0 * n1, "tab:purple")
    dim(ax, cg1, R1 @ np.array([LFRONT[0], 0]) + cg1, "lFront[1]", 3.2 * n1, "tab:green")
    dim(ax, cg1, R1 @ np.array([-LREAR[0], 0]) + cg1, "lRear[1]", 3.2 * n1, "tab:green")
    # module 2
    dim(ax, hinge, cg2, "lHr[1]", np.array([0, -2.0]), "tab:purple")
    dim(ax, cg2, np.array([XA[3], 0]), "xA[3] < 0", np.array([0, 2.2]))
    dim(ax, cg2, np.array([-LREAR[1], 0]), "lRear[2]", np.array([0, -3.2]), "tab:green")
    dim(ax, cg2, np.array([LFRONT[1], 0]), "lFront[2]", np.array([0, -3.2]), "tab:green")
    wl = np.array([-LREAR[1] - 0.6, -W / 2])
    dim(ax, wl, wl + np.array([0, W]), "", np.array([0, 0]), "tab:green")
    ax.text(wl[0] - 0.15, 0, "width[2]", color="tab:green", fontsize=8, ha="right", va="center")
    ax.plot(*hinge, "o", ms=8, mfc="white", mec="tab:purple", mew=2)
    ax.text(hinge[0] - 0.3, hinge[1] + 0.35, "hinge 1", color="tab:purple", fontsize=8, ha="right")
    # angles: yaw from the global x axis, steering against the module, articulation
    ax.plot([cg1[0], cg1[0] + 3.0], [cg1[1], cg1[1]], color="tab:red", lw=0.8, ls="--")
    angle_arc(ax, cg1, 1.2, 0.0, psi1, "psi[1] > 0 (yaw from the x axis)", at=(2.6, -2.3))
    a1 = R1 @ np.array([XA[1], 0]) + cg1
    d1 = rot(psi1) @ np.array([1.6, 0])
    ax.plot([a1[0], a1[0] + d1[0]], [a1[1], a1[1] + d1[1]], color="tab:red", lw=0.8, ls="--")
    angle_arc(ax, a1, 1.4, psi1, psi1 + math.radians(20), "delta[1] > 0 (against the module)", at=(3.0, 1.4))
    ax.plot([hinge[0], hinge[0] + 3.2], [hinge[1], hinge[1]], color="tab:red", lw=0.8, ls="--")
    angle_arc(ax, hinge, 1.3, psi2, psi1, "artAngle[1] = psi[1] - psi[2] > 0", at=(2.8, -3.6))
    ax.annotate("", xy=(-8.7, 3.0), xytext=(-10.2, 3.0), arrowprops=dict(arrowstyle="->"))
    ax.annotate("", xy=(-10.2, 4.5), xytext=(-10.2, 3.0), arrowprops=dict(arrowstyle="->"))
    ax.text(-8.6, 3.0, "x", va="center")
    ax.text(-10.2, 4.6, "y", ha="center", va="bottom")
    ax.text(-10.2, 2.6, "angles counter-clockwise\npositive (a left turn > 0)", fontsize=7, va="top")
    ax.set_ylim(-5.6, 7.2)
    ax.set_title("BusDynamics (seed 000, sec. II): lengths from each module's centre of mass, "
                 "x forwards, y to the left\nmodules and axles numbered from the front; xA ahead of the CG "
                 "positive; lHf back from CG k to hinge k, lHr back from hinge k to CG k+1", fontsize=9)


def kinematics(ax):
    L0, Lh1, L1 = 5.9, 1.789, 4.211          # Urbino 18, seed 003 Table I
    th0, th1 = math.radians(14.0), 0.0
    P1 = np.array([0.0, 0.0])
    J1 = P1 + rot(th1) @ np.array([L1, 0])
    P0 = J1 + rot(th0) @ np.array([Lh1, 0])
    F = P0 + rot(th0) @ np.array([L0, 0])
    ax.plot(*np.array([F, P0, J1]).T, color="0.3", lw=3)
    ax.plot(*np.array([J1, P1]).T, color="0.3", lw=3)
    for p, name, dy in ((F, "front wheel", -0.45), (P0, "P0 (rear axle of segment 0)", -0.9),
                        (P1, "P1 (axle of wagon 1)", -0.45)):
        ax.plot(*p, "ks", ms=6)
        ax.text(p[0] + (1.0 if name.startswith("P0") else 0), p[1] + dy, name, fontsize=8, ha="center", va="top")
    ax.plot(*J1, "o", ms=8, mfc="white", mec="tab:purple", mew=2)
    ax.text(J1[0], J1[1] + 0.4, "joint 1", color="tab:purple", fontsize=8, ha="center")
    n0 = rot(th0) @ np.array([0, 1.0])
    dim(ax, P0, F, "L0 (wheelbase)", 1.3 * n0)
    dim(ax, J1, P0, "Lh[1] > 0: joint behind P0", -1.6 * n0, "tab:purple")
    dim(ax, P1, J1, "L[1]: joint to the wagon axle", np.array([0, -1.3]), "tab:green")
    ax.plot([P0[0], P0[0] + 2.5], [P0[1], P0[1]], color="tab:red", lw=0.8, ls="--")
    angle_arc(ax, P0, 2.0, 0.0, th0, "theta[0]")
    ax.plot([J1[0], J1[0] + 2.6], [J1[1], J1[1]], color="tab:red", lw=0.8, ls="--")
    angle_arc(ax, J1, 1.4, th1, th0, "beta[1] = theta[0] - theta[1] > 0", at=(-2.0, 2.0))
    dF = rot(th0 + math.radians(20)) @ np.array([1.4, 0])
    ax.plot([F[0] - dF[0] / 2, F[0] + dF[0]], [F[1] - dF[1] / 2, F[1] + dF[1]], color="k", lw=4)
    ax.plot([F[0], F[0] + 1.9 * math.cos(th0)], [F[1], F[1] + 1.9 * math.sin(th0)], color="tab:red", lw=0.8,
            ls="--")
    angle_arc(ax, F, 1.6, th0, th0 + math.radians(20), "gammaF > 0")
    ax.set_title("BusKinematics (seed 003, Fig. 2): segment 0 (tractor) and wagons 1..N; "
                 "theta headings, counter-clockwise positive", fontsize=9)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default=str(ROOT / "docs" / "geometry.png"))
    args = p.parse_args(argv)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(11, 10.5), gridspec_kw={"height_ratios": [1.3, 1]})
    dynamics(a1)
    kinematics(a2)
    for ax in (a1, a2):
        ax.set_aspect("equal")
        ax.axis("off")
    a1.set_xlim(-11, 18)
    a2.set_xlim(-1.5, 19)
    fig.tight_layout()
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    print(out)


if __name__ == "__main__":
    main()
