"""``artibus demo``: the Urbino 18 Electric (seed 003, Table I) pushed at 3 m/s
through an S-curve (25 deg left, 25 deg right, straight), BusKinematics alone;
its results, bird's-eye view and signals, and a page showing them (``page``),
which the index of ``artibus run --all --report DIR`` links as DIR/demo/."""
import html
import math
from pathlib import Path

import numpy as np

from artibus import files
from artibus.base import fmu_path
from artibus.bench.parameters import read_parameters
from artibus.fmu import simulate
from artibus.report.plots import birds_eye, signals
from artibus.runner import save


def s_curve(out, csv):
    """The S-curve run: its results saved as ``csv`` and its plots written into
    the folder ``out``. Returns (the plot's path, max |beta[1]| in rad)."""
    fmu = fmu_path("BusKinematics")
    params = read_parameters("Urbino18", fmu)
    params["testSteerAmp"] = 0.0
    amp, period = math.radians(25.0), 24.0

    def gammaF(t):
        return amp * math.sin(2 * math.pi * t / period) if t < period else 0.0

    result = simulate(fmu, parameters=params, inputs={"gammaF": gammaF, "v": lambda t: 3.0},
                      stop_time=40.0, step=0.05)
    png = out / "BusKinematics_Urbino18_SCurve.png"
    save(result, csv)
    theta0 = result["theta[0]"]
    front = (result["x[0]"] + params["L0"] * np.cos(theta0), result["y[0]"] + params["L0"] * np.sin(theta0))
    birds_eye(png, {"front axle": front, "tractor rear axle P0": (result["x[0]"], result["y[0]"]),
                    "wagon axle P1": (result["x[1]"], result["y[1]"])},
              title="Urbino 18 pusher, S-curve at 3 m/s (seed 003 model)")
    signals(out / "BusKinematics_Urbino18_SCurve_signals.png", result.time,
            [("steering gammaF [deg]", {"gammaF": np.degrees([gammaF(t) for t in result.time])}),
             ("joint angle [deg]", {"beta[1]": np.degrees(result["beta[1]"])})], title="S-curve")
    return png, max(abs(result["beta[1]"]))


def signals_png(out):
    return Path(out) / "BusKinematics_Urbino18_SCurve_signals.png"


MARK = '<meta name="generator" content="artibus demo">'
TITLE = "The kinematic demo: Urbino 18 pusher on an S-curve"


def page(out, csv, pngs, bmax):
    """OUT/index.html showing the demo's plots and linking its results (OUT/demo.html
    where OUT already holds another page's index.html, e.g. a run's index). Returns its path."""
    out = Path(out)
    target = out / "index.html"
    if target.is_file() and MARK not in target.read_text(encoding="utf-8", errors="replace"):
        target = out / "demo.html"
    e = html.escape
    rel = lambda p: e(str(Path(p).resolve().relative_to(out.resolve())) if Path(p).resolve().is_relative_to(
        out.resolve()) else str(Path(p).resolve()))
    figs = "".join(f'<figure><img src="{rel(p)}" alt="{e(Path(p).stem)}"></figure>' for p in pngs)
    text = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">{MARK}<title>{e(TITLE)}</title>
<style>body {{ font-family: sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; }}
img {{ max-width: 100%; }}</style></head><body>
<p><a href="../index.html">all benches</a></p>
<h1>{e(TITLE)}</h1>
<p>BusKinematics alone (Michałek, Patkowski and Gawron's modular kinematic model, seed 003) with the
Urbino 18 Electric's data (Table I), pushed at 3 m/s: steering 25 deg left, 25 deg right, then straight.
Largest joint angle |beta[1]| = {math.degrees(bmax):.1f} deg (the Urbino 18's mechanical limit: 54 deg).
Results: <a href="{rel(csv)}">{e(Path(csv).name)}</a>.</p>
{figs}
</body></html>
"""
    return files.write_text(target, text)
