"""The co-simulation master: runs an SSP bench of FMI 2.0 and 3.0 co-simulation FMUs.

- ``simulation``: ``Simulation`` (a bench set up and ready to run; its
  algorithm, Gauss-Seidel or Jacobi, multi-rate) and ``run``;
- ``setup``: what ``Simulation.__init__`` does (units, parameters, connections,
  the CAN network, recording, stimuli), one function a part;
- ``unit``: a component while it runs and its calls into the FMU;
- ``plan``: the components' order and the multi-rate step plan;
- ``core``: the one stepping loop, in C (src/runner_core/), and the callbacks it
  makes for what runs in Python; ``corelib``, ``layout``: its library and its
  structs, built from the library's own layout of core.h; ``can_core``,
  ``lsbus_core``: the CAN and FMI-LS-BUS networks in the core;
- ``lsbus``: ``Network``, the FMI-LS-BUS 1.0 master for FMI 3.0 CAN nodes with clocks
  (directly, or through a bus simulation FMU such as CanBus), in Python on FMPy: the
  reference the core's is held to, and the master for networks the core does not take;
- ``results``, ``tables``: result files (``save``, units, partial results) and
  the pool of result tables.
"""
from artibus.fmu import Result, SimulationError                                     # noqa: F401 (a run's)
from artibus.runner.can_core import can_signal                                      # noqa: F401
from artibus.runner.corelib import core_library_path                                  # noqa: F401
from artibus.runner.results import partial_path, read_units, save, save_partial, units_path   # noqa: F401
from artibus.runner.setup import resolve_resources                                  # noqa: F401
from artibus.runner.simulation import Simulation, run                               # noqa: F401
