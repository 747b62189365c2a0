"""Bus36m_Circle_CAN: seed 000's circle with the steering on CAN: the circle's
KPIs (those of Bus36m_Circle's variant guidedForceMin), and what the receivers saw: each
one's fallback state (0 normal, 1 holding, 2 ramping, 3 straight) and each
message's longest run without a good frame (artibus.benches)."""
from artibus import report
from artibus.bench import script
from artibus.report.benchkit import can_fallback_kpis, can_lost, can_receivers

direct = script.load("Bus36m_Circle")
#: the direct run's counterpart: the variant of Bus36m_Circle with the same controllers
VARIANT = "guidedForceMin"

TEXT = direct.CIRCLE_TEXT + (" The steering signals travel over CAN (ssp/can/Bus36m.dbc); the bus summary "
                      "(load, response times, frames) is printed by the run and in can_bus.txt.")


def kpis(r):
    return direct.variant_kpis(r, VARIANT) + can_fallback_kpis(r)


def figures(r, out):
    images = direct.circle_figures(r, out, direct.VARIANTS[VARIANT][0], variant=VARIANT)
    receivers, lost = can_receivers(r), can_lost(r)
    if receivers:
        report.signals(out / "fallback.png", r.time, [
            ("fallback state [0-3]", {c: r[f"{c}.fallback"] for c in receivers}),
            ("since a good frame [cycles]", {n[4:-len(".sinceGood")]: r[n] for n in lost}),
        ], title="What the receivers saw: fallback states and stale messages")
        images.append(("fallback.png", "Each receiver's fallback state (0 normal, 1 holding, 2 ramping, "
                                       "3 straight) and each message's cycles since its last good frame (E2E check)."))
    return images
