"""The documented sweep behind TrainGuidance's way constants S4, S6 (seed 000,
eqs. 38-42): on the bench Bus36m_Circle, variant guidedForceMin (the 36 m bus on the
17.5 m circle, entry and exit included) the peak and the steady deviation of
A4 and A6 from the trace of A2 for a range of way constants.

usage: .venv/bin/python scripts/way_constant_sweep.py
"""
import numpy as np

from artibus import runner
from artibus.bench import ssp
from artibus.study import kpi

BENCH, VARIANT = "Bus36m_Circle", "guidedForceMin"
ARC = 2 * np.pi * 17.5


def deviations(S4, S6):
    r = runner.run(BENCH, overrides={**ssp.variant_overrides(BENCH, [VARIANT]), "Guidance.S4": S4, "Guidance.S6": S6})
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in (2, 4, 6)}
    s = r["Driver.s"][::5]
    steady = (s > 25 + 0.4 * ARC) & (s < 25 + 0.9 * ARC)
    out = []
    for a in (4, 6):
        d, inside = kpi.lateral_distance(*ax[2], *ax[a])
        out += [np.max(np.abs(d[inside])), np.max(np.abs(d[inside & steady]))]
    return out


def main():
    print(f"{BENCH} --variant {VARIANT}: deviation from the A2 trace [m], peak (whole manoeuvre) and steady (on the circle);")
    print("each way constant swept with the other at its default (S4 = 14 m, S6 = 36 m)")
    print(f"{'S [m]':>6} {'A4 peak':>8} {'A4 steady':>10} {'A6 peak':>8} {'A6 steady':>10}")
    for S in (0, 5, 10, 14, 20, 25, 30, 36, 45, 60):
        p4, s4, _, _ = deviations(S, 36.0)
        _, _, p6, s6 = deviations(14.0, S)
        print(f"{S:6.0f} {p4:8.3f} {s4:10.3f} {p6:8.3f} {s6:10.3f}")


if __name__ == "__main__":
    main()
