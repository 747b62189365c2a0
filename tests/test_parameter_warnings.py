"""A parameter that does not act in the configuration its FMU is in is said
so (issue 15): BusDynamics' friction mu[] under the linear tyre (tyreModel 0,
seed 000 eq. 24, Fy = C alpha) warns, naming the axle; where friction acts
(tyreModel 1, 2, 3) it does not, and the result moves with mu."""
import subprocess
import sys

import pytest

from conftest import init


def _warnings(fmu):
    return [m for m in fmu.log if m.startswith("[Warning]")]


def test_friction_under_the_linear_tyre_warns(open_fmu):
    bus = open_fmu("BusDynamics")
    init(bus, **{"tyreModel": 0, "mu[3]": 0.5})
    w = _warnings(bus)
    assert len(w) == 1 and "mu[3] = 0.5 has no effect" in w[0] and "tyreModel 0" in w[0]


@pytest.mark.parametrize("model", [1, 2, 3])
def test_friction_that_acts_gives_no_warning(open_fmu, model):
    bus = open_fmu("BusDynamics")
    init(bus, **{"tyreModel": model, "mu[3]": 0.5})
    assert _warnings(bus) == []


def test_the_cli_prints_the_warning_naming_the_component(tmp_path):
    out = tmp_path / "r.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", "Bus36m_Circle", "--set", "Bus.tyreModel=0",
                        "--set", "Bus.mu[2]=0.5", "--stop-time", "0.5", "-o", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "warning: Bus: mu[2] = 0.5 has no effect" in p.stderr
    assert out.is_file()
