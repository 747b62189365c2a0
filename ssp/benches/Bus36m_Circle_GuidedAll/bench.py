"""Bus36m_Circle_GuidedAll: seed 000's 17.5 m circle, 36 m bus,
A3 steered like A4, A5 like A6 (Task 1 on every trailer axle).
The circle's KPIs and figures (ssp/benches/Bus36m_Circle/bench.py) with this
bench's label, the paper's values and pass rule (artibus.benches)."""
from artibus import benches

circle = benches.load("Bus36m_Circle")

LABEL = "A3 steered like A4, A5 like A6 (Task 1 on every trailer axle)"
PAPER_DEV = "< 1.0 (steered)"
PAPER_F = "> 20 with wrong A3/A5 angles"
STEERED = True
TEXT = circle.TEXT


def F_ok(F):
    return F > 20


def kpis(r):
    return circle.circle_kpis(r, STEERED, PAPER_DEV, PAPER_F, F_ok)


def figures(r, out):
    return circle.circle_figures(r, out, LABEL)
