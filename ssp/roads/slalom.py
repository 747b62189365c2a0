"""Writes the slalom road of the Bus36m_Slalom bench: Bus36m_Slalom.csv beside
this script (run it with the project's Python: .venv/bin/python ssp/roads/slalom.py).

The road is the path of the front axle (the driver's guided point) through a
line of cones on y = 0:

- a straight of BEFORE m from the start (x = 0);
- an entry half cosine over SPACING m from y = 0 to y = +AMPLITUDE, arriving
  parallel to the cone line beside the first cone;
- CONES cones SPACING m apart, passed alternately on the left and on the right
  at AMPLITUDE from each: y = AMPLITUDE cos(pi (x - x_first) / SPACING), a sine
  slalom of wavelength 2 SPACING, curvature at most AMPLITUDE (pi/SPACING)^2;
- an exit half cosine over SPACING m back to y = 0, then a straight of AFTER m.

Heading is continuous everywhere; curvature jumps by a factor 2 where the
half cosines meet the slalom (the driver's steering-rate limit smooths it).
"""
import math
from pathlib import Path

import numpy as np

BEFORE = 25.0      # m of straight before the entry
SPACING = 30.0     # m between cones
AMPLITUDE = 1.5    # m from the cone line to the path at each cone
CONES = 6
AFTER = 250.0      # m of straight after the exit
STEP = 0.25        # m between the points of the polyline (the driver resamples at its ds)

FILE = Path(__file__).with_name("Bus36m_Slalom.csv")


def cones():
    """x of the cones (on y = 0)."""
    return BEFORE + SPACING * (1 + np.arange(CONES))


def path(x):
    """Lateral offset of the road at x."""
    x = np.asarray(x, float)
    x_first, x_last = cones()[0], cones()[-1]
    y_last = AMPLITUDE * math.cos(math.pi * (x_last - x_first) / SPACING)
    y = np.zeros_like(x)
    entry = (x > BEFORE) & (x < x_first)
    y[entry] = 0.5 * AMPLITUDE * (1 - np.cos(math.pi * (x[entry] - BEFORE) / SPACING))
    slalom = (x >= x_first) & (x <= x_last)
    y[slalom] = AMPLITUDE * np.cos(math.pi * (x[slalom] - x_first) / SPACING)
    exit_ = (x > x_last) & (x < x_last + SPACING)
    y[exit_] = 0.5 * y_last * (1 + np.cos(math.pi * (x[exit_] - x_last) / SPACING))
    return y


def end_of_slalom():
    """x where the exit half cosine is back on the straight."""
    return cones()[-1] + SPACING


def main():
    from artibus.bench import roads
    n = int(round((end_of_slalom() + AFTER) / STEP))
    x = np.linspace(0.0, n * STEP, n + 1)
    roads.write_csv(FILE, x, path(x))
    print(f"{FILE}: {len(x)} points, {x[-1]:g} m")


if __name__ == "__main__":
    main()
