"""Bus36m_Circle_CAN_Backwards: seed 000's circle driven backwards (the A6
end leads) with the steering on CAN: the KPIs of Bus36m_Circle_Backwards,
what the receivers saw (each one's fallback state and each message's
longest run without a good frame, as Bus36m_Circle_CAN) and the driving
direction each ECU steered for (artibus.benches)."""
import numpy as np

from artibus import report
from artibus.bench import script
from artibus.report.benchkit import DEG, can_fallback_kpis, can_lost, can_receivers, circle_road, outlines
from artibus.study import kpi

direct = script.load("Bus36m_Circle_Backwards")

TEXT = direct.TEXT + (" The steering signals travel over CAN (ssp/can/Bus36m.dbc) in the paper's topology, one "
                      "SteeringECU per module: the tractor ECU (module 1) decides the driving direction from the "
                      "sign of the wheel speed and sends it, and steers A1 and A2 backwards; module 2's ECU steers "
                      "A3 and A4; module 3's steers nothing backwards. The bus summary (load, response times, "
                      "frames) is printed by the run and in can_bus.txt.")


def kpis(r):
    return direct.kpis(r) + can_fallback_kpis(r, entered_at=False)


def figures(r, out):
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outlines(r, 3),
                     road=circle_road(), every=300,
                     title="36 m bus driven backwards on CAN (A6 end leads), guidance + force minimisation, 3 m/s")
    images = [("path.png", "Bird's-eye view: road (grey, followed by the outermost leading point), "
                           "body outlines every 3 s, axle traces.")]
    dev3, in3 = kpi.lateral_distance(*ax[5], *ax[3])
    dev1, in1 = kpi.lateral_distance(*ax[5], *ax[1])
    G2, G1 = direct._hinge_forces(r)
    report.signals(out / "deviation.png", r.time[::5], [
        ("deviation from A5 trace [m]", {"A3": np.where(in3, np.abs(dev3), np.nan),
                                         "A1": np.where(in1, np.abs(dev1), np.nan)}),
        ("hinge lateral force [kN]", {"G2 (leading)": G2[::5] / 1e3, "G1": G1[::5] / 1e3}),
    ], title="Backwards on CAN: deviations from the trace of A5, hinge forces (the mirror of seed 000, Figs. 9-10)",
        bounds=[(0, 1.0, "paper: < 1.0 m steered (seed 000, Fig. 9)"),
                (1, 4.0, "paper: < 4 kN with force minimisation (seed 000, Fig. 10)"),
                (1, -4.0, "paper: < 4 kN with force minimisation (seed 000, Fig. 10)")])
    images.append(("deviation.png", "Lateral distance of the trailing axles A3 and A1 from the trace of A5; the "
                                    "hinge forces in the frame of the module ahead in the direction of travel."))
    panels = []
    steer = {f"A{a}": r[f"Bus.delta[{a}]"] * DEG for a in range(1, 7) if f"Bus.delta[{a}]" in r.names}
    if steer:
        panels.append(("steering [deg]", steer))
    ecus = [c for c in ("ECU1", "ECU2", "ECU3") if f"{c}.drivingDirection" in r.names]
    if ecus:
        panels.append(("driving direction [0 fwd, 1 back]", {c: r[f"{c}.drivingDirection"] for c in ecus}))
    receivers, lost = can_receivers(r), can_lost(r)
    if receivers:
        panels.append(("fallback state [0-3]", {c: r[f"{c}.fallback"] for c in receivers}))
    if lost:
        panels.append(("since a good frame [cycles]", {n[4:-len(".sinceGood")]: r[n] for n in lost}))
    if panels:
        report.signals(out / "network.png", r.time, panels,
                       title="Backwards on CAN: steering, driving direction, what the receivers saw")
        images.append(("network.png", "Steered angles, the driving direction each ECU steered for (0 forwards, "
                                      "1 backwards), each receiver's fallback state (0 normal, 1 holding, "
                                      "2 ramping, 3 straight) and each message's cycles since its last good "
                                      "frame (E2E check)."))
    return images
