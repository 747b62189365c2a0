"""One FMU on its own: an instance with its variables by name (``Fmu``), a run
of it (``simulate``), the recorded ``Result`` and the ``SimulationError`` that
carries the results up to a failure."""
from artibus.fmu.instance import (DEFAULT_STEPS, DEFAULT_STOP_TIME, Fmu, Result, SimulationError,  # noqa: F401
                                  check_times, claim_logger_proxy, default_step, simulate, unit_of)
