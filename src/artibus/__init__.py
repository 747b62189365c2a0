"""artibus: co-simulation components for articulated and multi-axle buses.

The FMUs are built from C (``src/models``); this package runs them with FMPy,
reads parameter sets (SSP ``.ssv``), and draws the results. Its parts
(docs/developer/layout.md): ``artibus.bench`` (SSP benches, parameter sets,
names, units, the vehicle check, roads), ``artibus.fmu`` (one FMU alone),
``artibus.runner`` (the co-simulation master), ``artibus.can`` (the CAN network,
logs, replay), ``artibus.study`` (sweeps, KPIs, frequency responses, the damping
study), ``artibus.report`` (report pages and plots), ``artibus.cli``.

The public API at the top, imported when first used::

    import artibus
    result = artibus.run("Bus36m_Circle")                  # artibus.runner.run
    with artibus.Simulation("Bus36m_Circle") as sim:       # artibus.runner.Simulation
        result = sim.run()
    table = artibus.sweep("Bus36m_Circle", grid={"Driver.vSet": [2, 3, 4]}, out="sweep-out")
"""
from artibus.base import ROOT, ArtibusError, __version__, fmu_dir, fmu_path   # noqa: F401

__all__ = ["ROOT", "ArtibusError", "__version__", "fmu_dir", "fmu_path", "run", "Simulation", "sweep"]


def __getattr__(name):
    """artibus.run, artibus.Simulation (artibus.runner), artibus.sweep (the callable
    module artibus.study.sweep: ``artibus.sweep(bench, ...)`` runs a sweep)."""
    if name == "run":
        from artibus.runner import run
        return run
    if name == "Simulation":
        from artibus.runner import Simulation
        return Simulation
    if name == "sweep":
        from artibus.study import sweep
        return sweep
    raise AttributeError(f"module 'artibus' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | {"run", "Simulation", "sweep"})
