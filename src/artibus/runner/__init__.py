"""The co-simulation master: runs an SSP bench of FMI 2.0 co-simulation FMUs
(``Simulation``, ``run``) and writes its results (``save``)."""
from artibus.runner.simulation import (Simulation, can_signal, core_library_path, partial_path,  # noqa: F401
                                       read_units, resolve_resources, run, save, units_path)
