"""Write ssp/benches/Bus36m_Circle/sensitivity_A6.csv: how far the unsteered
36 m bus's rearmost axle A6 leaves the trace of A2 on seed 000's 17.5 m circle
(the paper: "approximately 6 m") when the estimated lengths of our bus
(ssp/parameters/Bus36m.ssv: the paper gives none) are changed: the trailers'
axle spread (xA[3..6], 5.9 m) and the hinges' distances from the modules'
centres (lHr[1..2], lHf[1..2], 6.1 m). A few runs of the bench Bus36m_Circle,
unsteered (its default), each with one change; the bench's report draws the
CSV (sensitivity_A6.png, the explanation of its A6 row).

    .venv/bin/python scripts/bus36m_offtracking_sensitivity.py

A few seconds a run."""
import csv
import sys
from pathlib import Path

from artibus import ROOT, runner
from artibus.study import kpi

OUT = ROOT / "ssp" / "benches" / "Bus36m_Circle" / "sensitivity_A6.csv"
HINGES = ("lHr[1]", "lHr[2]", "lHf[1]", "lHf[2]")
TRAILER_AXLES = {"xA[3]": 1, "xA[4]": -1, "xA[5]": 1, "xA[6]": -1}

#: label, trailer axle spread [m], hinge distance from the modules' centres [m]
CASES = [
    ("our estimate (Bus36m.ssv)", 5.9, 6.1),
    ("trailer axles 4.9 m apart", 4.9, 6.1),
    ("trailer axles 6.9 m apart", 6.9, 6.1),
    ("hinges 5.6 m from the centres", 5.9, 5.6),
    ("hinges 6.6 m from the centres", 5.9, 6.6),
    ("axles 6.9 m apart, hinges 6.6 m", 6.9, 6.6),
]


def deviations(spread, hinge):
    o = {f"Bus.{n}": hinge for n in HINGES}
    o.update({f"Bus.{n}": s * spread / 2 for n, s in TRAILER_AXLES.items()})
    r = runner.run("Bus36m_Circle", overrides=o)
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in (2, 4, 6)}
    return kpi.trace_deviation(*ax[2], *ax[4]), kpi.trace_deviation(*ax[2], *ax[6])


def main():
    rows = []
    for label, spread, hinge in CASES:
        d4, d6 = deviations(spread, hinge)
        print(f"{label}: A4 {d4:.3f} m, A6 {d6:.3f} m", flush=True)
        rows.append([label, spread, hinge, f"{d4:.4f}", f"{d6:.4f}"])
    part = OUT.with_suffix(".csv.part")
    with open(part, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "trailer_axle_spread_m", "hinge_from_centre_m", "max_dev_A4_m", "max_dev_A6_m"])
        w.writerows(rows)
    part.replace(OUT)
    print(OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
