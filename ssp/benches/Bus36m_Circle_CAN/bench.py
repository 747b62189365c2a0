"""Bus36m_Circle_CAN: seed 000's circle with the steering on CAN: the circle's
KPIs (those of Bus36m_Circle_GuidedForceMin), and what the receivers saw: each
one's fallback state (0 normal, 1 holding, 2 ramping, 3 straight) and each
message's longest run without a good frame (artibus.benches)."""
import math

import numpy as np

from artibus import benches, report
from artibus.report import Kpi

direct = benches.load("Bus36m_Circle_GuidedForceMin")

TEXT = direct.TEXT + (" The steering signals travel over CAN (ssp/can/Bus36m.dbc); the bus summary "
                      "(load, response times, frames) is printed by the run and in can_bus.txt.")


def _receivers(r):
    return [n[:-len(".fallback")] for n in r.names if n.endswith(".fallback")]


def _lost(r):
    return [n for n in r.names if n.startswith("can.") and n.endswith(".sinceGood")]


def kpis(r):
    k = direct.kpis(r)
    t = r.time
    for c in _receivers(r):
        fb = r[f"{c}.fallback"]
        on = fb > 0
        k.append(Kpi(f"{c}: worst fallback state (0 normal, 1 holding, 2 ramping, 3 straight; 0 expected "
                     f"without faults)", float(np.max(fb)), "-", "", "our fallback: seed 000 (sec. I) gives "
                     "ECUs on CAN, no fallback"))
        k.append(Kpi(f"{c}: time in fallback", float(np.sum(on)) * (t[1] - t[0]), "s"))
        k.append(Kpi(f"{c}: fallback entered at", float(t[np.argmax(on)]) if on.any() else math.nan, "s",
                     why="" if on.any() else "never in fallback"))
    for n in _lost(r):
        k.append(Kpi(f"{n[4:-len('.sinceGood')]}: longest run of cycles without a good frame",
                     float(np.max(r[n])), "cycles"))
    return k


def figures(r, out):
    images = direct.figures(r, out)
    receivers, lost = _receivers(r), _lost(r)
    if receivers:
        report.signals(out / "fallback.png", r.time, [
            ("fallback state", {c: r[f"{c}.fallback"] for c in receivers}),
            ("cycles since a good frame", {n[4:-len(".sinceGood")]: r[n] for n in lost}),
        ], title="What the receivers saw: fallback states and stale messages")
        images.append(("fallback.png", "Each receiver's fallback state and each message's cycles since its "
                                       "last good frame (E2E check)."))
    return images
