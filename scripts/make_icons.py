#!/usr/bin/env python3
"""Draw each FMU's icon, src/models/<Name>/model.png (128 x 128 px), which the packer
(src/fmi/package_fmu.py) puts into the FMU's root as FMI 2.0's model.png.

Run once after adding a model (the PNGs are committed; the build needs no matplotlib):

    .venv/bin/python scripts/make_icons.py            # every model without an icon
    .venv/bin/python scripts/make_icons.py --force    # all of them again

Plants are blue, the driver orange, controllers and ECUs green, actuators purple; a
model not drawn below gets a plain chip with its name.
"""
import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle, FancyArrowPatch, FancyBboxPatch, Polygon, Rectangle  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
COLOURS = {"plant": "#1f5fa8", "driver": "#d9772b", "controller": "#2f8f46", "actuator": "#7a4aa8",
           "test": "#666666"}


def chip(ax, label, colour):
    ax.add_patch(FancyBboxPatch((0.06, 0.06), 0.88, 0.88, boxstyle="round,pad=0,rounding_size=0.12",
                                fc=colour, ec="none"))
    ax.text(0.5, 0.13, label, color="white", ha="center", va="center", fontsize=11,
            fontweight="bold", family="DejaVu Sans")


def body(ax, x, y, length, width, angle, fc="white"):
    """a module seen from above, its rear centre at (x, y), heading angle (deg)"""
    a = math.radians(angle)
    c, s = math.cos(a), math.sin(a)
    pts = [(0, -width / 2), (length, -width / 2), (length, width / 2), (0, width / 2)]
    ax.add_patch(Polygon([(x + c * px - s * py, y + s * px + c * py) for px, py in pts],
                         closed=True, fc=fc, ec="#102030", lw=1.2))
    return x + c * length, y + s * length


def bus(ax, x0=0.14, y0=0.42, angles=(18, 0, -18), length=0.22, width=0.1):
    x, y = x0, y0
    for i, ang in enumerate(reversed(angles)):
        x, y = body(ax, x, y, length, width, ang)
        x, y = x + 0.015 * math.cos(math.radians(ang)), y + 0.015 * math.sin(math.radians(ang))


def arrow(ax, p, q, colour="white", lw=2.0):
    ax.add_patch(FancyArrowPatch(p, q, arrowstyle="-|>", mutation_scale=12, color=colour, lw=lw))


def ecu(ax, glyph):
    ax.add_patch(Rectangle((0.27, 0.3), 0.46, 0.46, fc="#e8f3ea", ec="#102030", lw=1.2))
    for k in range(4):
        yy = 0.35 + k * 0.12
        ax.plot([0.2, 0.27], [yy, yy], color="white", lw=2)
        ax.plot([0.73, 0.8], [yy, yy], color="white", lw=2)
    glyph(ax)


def draw(name):
    fig = plt.figure(figsize=(1.28, 1.28), dpi=100)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.axis("off")
    import numpy as np
    t = np.linspace(0, 1, 100)
    if name == "BusKinematics":
        chip(ax, "kinematics", COLOURS["plant"])
        ax.plot(0.5 + 0.38 * np.cos(np.pi * (0.15 + 0.7 * t)), 0.25 + 0.45 * np.sin(np.pi * (0.15 + 0.7 * t)),
                color="white", lw=1.5, ls="--")
        bus(ax)
    elif name == "BusDynamics":
        chip(ax, "dynamics", COLOURS["plant"])
        bus(ax)
        for x in (0.25, 0.5, 0.74):
            arrow(ax, (x, 0.36), (x, 0.24), "#ffd24a")
    elif name == "MultiAxle3DOF":
        chip(ax, "3 DOF", COLOURS["plant"])
        body(ax, 0.15, 0.5, 0.7, 0.18, 0)
        for x in (0.28, 0.55, 0.72):
            ax.add_patch(Rectangle((x - 0.04, 0.38), 0.08, 0.04, fc="#102030"))
            ax.add_patch(Rectangle((x - 0.04, 0.58), 0.08, 0.04, fc="#102030"))
        ax.add_patch(matplotlib.patches.Arc((0.5, 0.5), 0.5, 0.5, theta1=200, theta2=330, color="white", lw=2))
    elif name == "RoadFollowDriver":
        chip(ax, "driver", COLOURS["driver"])
        ax.add_patch(Circle((0.5, 0.55), 0.27, fc="none", ec="white", lw=5))
        ax.add_patch(Circle((0.5, 0.55), 0.06, fc="white"))
        for ang in (90, 210, 330):
            a = math.radians(ang)
            ax.plot([0.5, 0.5 + 0.25 * math.cos(a)], [0.55, 0.55 + 0.25 * math.sin(a)], color="white", lw=3)
    elif name == "TrainGuidance":
        chip(ax, "guidance", COLOURS["controller"])
        ax.plot(0.5 + 0.36 * np.cos(np.pi * (0.1 + 0.8 * t)), 0.2 + 0.5 * np.sin(np.pi * (0.1 + 0.8 * t)),
                color="white", lw=2, ls="--")
        bus(ax, angles=(25, 0, -25))
    elif name == "ForceMinimization":
        chip(ax, "force min", COLOURS["controller"])
        bus(ax, angles=(10, 0, -10))
        arrow(ax, (0.42, 0.47), (0.42, 0.7), "#ffd24a")
        ax.text(0.62, 0.7, "min", color="white", fontsize=11, ha="center", va="center")
    elif name == "ZeroSideslipSteering":
        chip(ax, "zero slip", COLOURS["controller"])
        body(ax, 0.15, 0.5, 0.7, 0.18, 0)
        for x, d in ((0.25, 20), (0.5, 8), (0.75, -6)):
            a = math.radians(d)
            ax.plot([x - 0.06 * math.cos(a), x + 0.06 * math.cos(a)],
                    [0.5 - 0.06 * math.sin(a), 0.5 + 0.06 * math.sin(a)], color="#102030", lw=4)
    elif name == "ArticulationDamper":
        chip(ax, "damper", COLOURS["actuator"])
        body(ax, 0.08, 0.5, 0.3, 0.4, 0)
        body(ax, 0.62, 0.5, 0.3, 0.4, 0)
        for yy in (0.38, 0.62):
            ax.add_patch(Rectangle((0.34, yy - 0.04), 0.18, 0.08, fc="#c9b6e0", ec="#102030"))
            ax.plot([0.52, 0.66], [yy, yy], color="#102030", lw=3)
        ax.add_patch(Circle((0.5, 0.5), 0.03, fc="#102030"))
    elif name == "DampingController":
        chip(ax, "damping", COLOURS["controller"])
        ecu(ax, lambda a: a.plot(0.3 + 0.4 * t, 0.53 + 0.15 * np.exp(-3 * t) * np.sin(5 * np.pi * t),
                                 color="#102030", lw=2))
    elif name == "SwayBaseline":
        chip(ax, "baseline", COLOURS["controller"])
        ecu(ax, lambda a: a.plot([0.3, 0.42, 0.42, 0.58, 0.58, 0.7], [0.4, 0.4, 0.55, 0.55, 0.66, 0.66],
                                 color="#102030", lw=2))
    elif name == "SteeringECU":
        chip(ax, "ECU", COLOURS["controller"])
        ecu(ax, lambda a: a.text(0.5, 0.53, "CAN", ha="center", va="center", fontsize=11, color="#102030",
                                 fontweight="bold"))
    elif name == "SteeringActuator":
        chip(ax, "actuator", COLOURS["actuator"])
        ax.add_patch(Rectangle((0.43, 0.3), 0.14, 0.46, fc="#102030", ec="white", lw=1.5))
        ax.add_patch(matplotlib.patches.Arc((0.5, 0.53), 0.62, 0.62, theta1=-40, theta2=40, color="white", lw=2))
        arrow(ax, (0.78, 0.62), (0.74, 0.7))
    else:
        chip(ax, name[:10], COLOURS["test"])
        ax.text(0.5, 0.55, "".join(c for c in name if c.isupper())[:3] or name[:2], color="white",
                ha="center", va="center", fontsize=26, fontweight="bold")
    out = ROOT / "src" / "models" / name / "model.png"
    fig.savefig(out, dpi=100, transparent=True, metadata={"Software": None})
    plt.close(fig)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--force", action="store_true", help="draw icons that exist again")
    ap.add_argument("names", nargs="*", help="models (default: every modelDescription/<Name>.xml)")
    a = ap.parse_args()
    names = a.names or sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))
    for name in names:
        if (ROOT / "src" / "models" / name).is_dir() and (a.force or not (ROOT / "src" / "models" / name / "model.png").exists()):
            print(draw(name))


if __name__ == "__main__":
    main()
