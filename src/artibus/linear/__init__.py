"""Linear models (`artibus linearize`, issue 43): one Model Exchange FMU at an operating point
(artibus.linear.fmu: ``linearize``), a bench's Model Exchange plants with its controllers in the
loop (artibus.linear.bench: ``linearize_bench``), the describing function of a saturating
controller (artibus.linear.describing)."""
from artibus.linear.fmu import Linear, Mode, Signal, linearize

__all__ = ["Linear", "Mode", "Signal", "linearize"]
