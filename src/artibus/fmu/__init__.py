"""One FMU on its own: an instance with its variables by name (``Fmu``,
``instance``), a run of it (``simulate``), the recorded ``Result`` and the
``SimulationError`` that carries the results up to a failure, an FMU's
own end of a run (``Termination``) (``result``);
the FMUs' memory callbacks (``memory``)."""
from artibus.fmu.instance import Fmu, claim_logger_proxy                                  # noqa: F401
from artibus.fmu.result import Result, SimulationError, Termination, terminated            # noqa: F401
from artibus.fmu.simulate import DEFAULT_STEPS, DEFAULT_STOP_TIME, check_times, default_step, simulate   # noqa: F401
