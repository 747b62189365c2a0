import math
from pathlib import Path

import pytest

from artibus import fmu_dir
from artibus.fmu import Fmu

# FMPy's default memory callbacks (fmpy.simulate_fmu, an FMU2Slave given no
# callbacks) call libc's calloc/free looked up in libc.so.6, which a preloaded
# ASan never sees: the process's own, as artibus.simulation's (artibus.memory)
import fmpy.fmi2 as _fmi2                     # noqa: E402
from artibus.fmu import memory as _memory         # noqa: E402
_fmi2.defaultCallbacks.allocateMemory = _fmi2.fmi2CallbackAllocateMemoryTYPE(_memory.calloc)
_fmi2.defaultCallbacks.freeMemory = _fmi2.fmi2CallbackFreeMemoryTYPE(_memory.free)

ROOT = Path(__file__).resolve().parents[1]
#: every FMU the repository declares (one modelDescription/<Name>.xml each)
FMU_NAMES = sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))


def fmu_file(name):
    path = fmu_dir() / f"{name}.fmu"
    assert path.is_file(), f"{path} not built: run the set-up command of the README"
    return path


@pytest.fixture
def open_fmu():
    """open_fmu(name) -> artibus.simulation.Fmu, freed after the test."""
    opened = []

    def make(name):
        f = Fmu(fmu_file(name))
        opened.append(f)
        return f

    yield make
    for f in opened:
        f.close()


def init(fmu, **values):
    """setupExperiment + initialization mode with the given values set."""
    fmu.initialize(values)


DEG = math.pi / 180
