"""Bus36m_Circle_GuidedForceMin: seed 000's 17.5 m circle, 36 m bus,
A4, A6 guided (Task 1), A3, A5 force-minimising (Task 2).
The circle's KPIs and figures (ssp/benches/Bus36m_Circle/bench.py) with this
bench's label, the paper's values and pass rule (artibus.benches)."""
from artibus import benches

circle = benches.load("Bus36m_Circle")

LABEL = "A4, A6 guided (Task 1), A3, A5 force-minimising (Task 2)"
PAPER_DEV = "< 1.0 (steered)"
PAPER_F = "< 4 (steered)"
STEERED = True
TEXT = circle.TEXT


def F_ok(F):
    return F < 4


def kpis(r):
    return circle.circle_kpis(r, STEERED, PAPER_DEV, PAPER_F, F_ok)


def figures(r, out):
    return circle.circle_figures(r, out, LABEL)
