"""Bus36m_Circle_Backwards: seed 000's 17.5 m circle driven backwards: the A6
end leads. Its KPIs (a function of the result alone), figures and text
(artibus.benches)."""
import numpy as np

from artibus import report
from artibus.report import Kpi
from artibus.report.benchkit import DEG, circle_road, outlines
from artibus.study import kpi

TEXT = ("Seed 000: 'due to the symmetric vehicle structure the vehicle handling and the tracking "
        "performance is independent of the driving direction'. The forwards figures are those of "
        "Bus36m_Circle's variant guidedForceMin (A4, A6 from the A2 trace; hinge 1 in module 1's frame); "
        "tests/test_benches_roads.py compares the two within 10 %. A5 is driven (the mirror of A2). "
        "Why the KPIs match the forwards bench's: the bus is symmetric (Bus36m.ssv: three equal modules, "
        "the centre of mass mid-wheelbase, equal axles and hinges), so driven backwards it is the same "
        "vehicle with its ends' roles swapped, steered by the same laws; the figures differ only by the "
        "controllers' and the driver's small asymmetries (the driver's reference point, the sampling order).")


#: what a failure of this bench's bounds means
EXPLAIN = ("The paper states the tracking is independent of the driving direction (a symmetric bus); our bus is "
                    "symmetric (Bus36m.ssv), so a failure here means the backwards run differs from the forwards "
                    "one: compare Bus36m_Circle's variant guidedForceMin (the forwards figures); it depends on the "
                    "driver's reference point and the controllers' driving-direction handling.")


def _axles(r):
    return {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}


def _hinge_forces(r):
    """Lateral hinge forces in the frame of the module ahead in the direction of
    travel: G2 in module 3's frame, G1 in module 2's (FjointX/Y[k] are in module k's frame)."""
    a2, a1 = r["Bus.artAngle[2]"], r["Bus.artAngle[1]"]
    return (np.sin(a2) * r["Bus.FjointX[2]"] + np.cos(a2) * r["Bus.FjointY[2]"],
            np.sin(a1) * r["Bus.FjointX[1]"] + np.cos(a1) * r["Bus.FjointY[1]"])


def kpis(r):
    ax = _axles(r)
    d3 = kpi.trace_deviation(*ax[5], *ax[3])
    d1 = kpi.trace_deviation(*ax[5], *ax[1])
    G2, G1 = _hinge_forces(r)
    F2 = kpi.peak_while_moving(G2, r["Bus.v"]) / 1e3     # while the bus moves (|v| > 0.1 m/s)
    F1 = kpi.peak_while_moving(G1, r["Bus.v"]) / 1e3
    outl = outlines(r, 3)
    lead = (outl[:, 11, 0], outl[:, 11, 1])     # module 3's rear left corner: the leading right corner
    swept = kpi.swept_path_width(lead[0][::20], lead[1][::20], outl[::20], bin_length=0.5, samples_per_edge=4)
    return [
        Kpi("max deviation of A3 from the A5 trace", d3, "m", "< 1.0 (steered); as A4 from A2 forwards",
            "seed 000, Fig. 9 and sec. IV", d3 < 1.0, bound=1.0,
            explain=EXPLAIN),
        Kpi("max deviation of A1 from the A5 trace", d1, "m", "< 1.0 (steered); as A6 from A2 forwards",
            "seed 000, Fig. 9 and sec. IV", d1 < 1.0, bound=1.0,
            explain=EXPLAIN),
        Kpi("max |lateral force| leading hinge G2 (module 3's frame)", F2, "kN", "< 4 (steered)",
            "seed 000, Fig. 10", F2 < 4, bound=4.0,
            explain=EXPLAIN),
        Kpi("max |lateral force| hinge G1 (module 2's frame)", F1, "kN"),
        Kpi("swept path width", swept, "m", "", "outermost leading point on 17.5 m"),
        Kpi("max |articulation angle| hinge 1", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
        Kpi("max |articulation angle| hinge 2", kpi.peak(r["Bus.artAngle[2]"]) * DEG, "deg"),
        Kpi("leading end A6: max |lateral error| (driver)", kpi.peak(r["Driver.eLat"]), "m"),
    ]


def figures(r, out):
    ax = _axles(r)
    a2, a1 = r["Bus.artAngle[2]"], r["Bus.artAngle[1]"]
    images = []
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outlines(r, 3),
                     road=circle_road(), every=300,
                     title="36 m bus driven backwards (A6 end leads), guidance + force minimisation, 3 m/s")
    images.append(("path.png", "Bird's-eye view: road (grey, followed by the outermost leading point), "
                               "body outlines every 3 s, axle traces."))
    dev3, in3 = kpi.lateral_distance(*ax[5], *ax[3])
    dev1, in1 = kpi.lateral_distance(*ax[5], *ax[1])
    report.signals(out / "deviation.png", r.time[::5], [
        ("deviation from A5 trace [m]", {"A3": np.where(in3, np.abs(dev3), np.nan),
                                         "A1": np.where(in1, np.abs(dev1), np.nan)}),
        ("road progress [m]", {"s": r["Driver.s"][::5]}),
    ], title="Deviation of A3 and A1 from the trace of A5 (backwards: the mirror of seed 000, Fig. 9)",
        bounds=[(0, 1.0, "paper: < 1.0 m steered (seed 000, Fig. 9; independent of the direction, sec. IV)")])
    images.append(("deviation.png", "Lateral distance of the trailing axles A3 and A1 from the trace of A5."))
    report.signals(out / "forces.png", r.time, [
        ("hinge lateral force [kN]", {"G2 (leading)": np.sin(a2) * r["Bus.FjointX[2]"] / 1e3
                                      + np.cos(a2) * r["Bus.FjointY[2]"] / 1e3,
                                      "G1": np.sin(a1) * r["Bus.FjointX[1]"] / 1e3
                                      + np.cos(a1) * r["Bus.FjointY[1]"] / 1e3}),
        ("articulation [deg]", {"hinge 1": a1 * DEG, "hinge 2": a2 * DEG}),
        ("steering [deg]", {"A6 (driver)": r["Driver.delta"] * DEG, "A3 (guided)": r["Guidance.gamma4"] * DEG,
                            "A1 (guided)": r["Guidance.gamma6"] * DEG, "A4 (force min.)": r["ForceMin.gamma3"] * DEG,
                            "A2 (force min.)": r["ForceMin.gamma5"] * DEG}),
        ("speed [m/s]", {"vx of module 3": r["Bus.vx[3]"]}),
    ], title="Backwards: hinge forces, articulation, steering, speed",
        bounds=[(0, 4.0, "paper: < 4 kN with force minimisation (seed 000, Fig. 10)"),
                (0, -4.0, "paper: < 4 kN with force minimisation (seed 000, Fig. 10)")])
    images.append(("forces.png", "Lateral hinge forces in the frame of the module ahead in the direction of travel, "
                                 "articulation angles, the steering angles by role, speed (negative: backwards)."))
    return images
