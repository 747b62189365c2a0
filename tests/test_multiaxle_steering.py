"""ZeroSideslipSteering (seed 004, eq. 3 with delta_n = K(u) delta_1) alone:
its gain against K(u) found numerically from eq. 4's steady state
(test_multiaxle_model.py, no closed form shared with the C code), eq. 3's
distribution, the sampling, and bad input: finite, limited commands and one
warning per episode. The law's C file is also compiled alone, as for an ECU."""
import math
import shutil
import subprocess

import numpy as np
import pytest

from artibus.fmu import SimulationError, simulate
from conftest import ROOT, fmu_file, init
from test_multiaxle_model import BUS, fmu_parameters, steer_weights, zero_sideslip_gain

ALONE = dict(testSteerAmp=0.0, testSpeedRate=0.0)


def ctrl_params(veh, **extra):
    p = fmu_parameters(veh, controller=True)
    p.update(ALONE)
    p.update(extra)
    return p


def sample(veh, delta1, u, **extra):
    """the outputs after one step, inputs constant"""
    r = simulate(fmu_file("ZeroSideslipSteering"), parameters=ctrl_params(veh, **extra),
                 inputs={"delta1": lambda t: delta1, "u": lambda t: u}, stop_time=0.02, step=0.01)
    return r


@pytest.mark.parametrize("u", [0.5, 5.0, 10.0, 20.0, 30.0])
def test_gain_zeroes_the_steady_side_slip_of_eq4(u):
    r = sample(BUS, 0.02, u)
    K = zero_sideslip_gain(u, BUS)
    assert r["K[3]"][-1] == pytest.approx(K, rel=1e-9)
    assert r["delta[3]"][-1] == pytest.approx(0.02 * K, rel=1e-9)
    assert r["delta[1]"][-1] == 0.02 and r["K[1]"][-1] == 1.0
    assert r["delta[2]"][-1] == 0.0 and r["K[2]"][-1] == 0.0      # the fixed drive axle
    for i in range(4, 7):
        assert r[f"delta[{i}]"][-1] == 0.0


def test_eq3_distribution_on_four_steered_axles():
    """every axle steered: delta_i linear in l_i between delta_1 and delta_4,
    and delta_4 = K(u) delta_1 with K from eq. 4"""
    veh = dict(n=4, l=[3.2, 1.6, -1.2, -2.8], k=[-3e5, -3e5, -3.5e5, -3.5e5], m=[900.0] * 4,
               d=[0.0] * 4, steerable=[True] * 4, m_b=32000.0, h_b=0.7, I_ZZb=3e5, I_XXb=4e4,
               I_XZb=0.0, C_phi=2e5, K_phi=4e6)
    for u in (3.0, 12.0, 25.0):
        r = sample(veh, 0.03, u, **{f"deltaMax[{i}]": 1.0 for i in range(1, 5)})
        d = [r[f"delta[{i}]"][-1] for i in range(1, 5)]
        assert d[3] == pytest.approx(0.03 * zero_sideslip_gain(u, veh), rel=1e-9)
        for i in (1, 2):
            s = (veh["l"][0] - veh["l"][i]) / (veh["l"][0] - veh["l"][3])
            assert d[i] == pytest.approx((1 - s) * d[0] + s * d[3], rel=1e-12, abs=1e-15)


def test_standstill_gives_the_finite_limit():
    """u = 0: no division by u; K(0) is the limit of K(u) for u -> 0, no warning"""
    r = sample(BUS, 0.02, 0.0)
    K0 = zero_sideslip_gain(1e-3, BUS)
    assert math.isfinite(r["K[3]"][-1])
    assert r["K[3]"][-1] == pytest.approx(K0, rel=1e-6)


def _run_fmu(open_fmu, params, inputs, steps, h=0.01):
    fmu = open_fmu("ZeroSideslipSteering")
    init(fmu, **params, **inputs)
    rows = []
    for k in range(steps):
        fmu.slave.doStep(k * h, h)
        rows.append(fmu.get(*[f"delta[{i}]" for i in range(1, 7)]))
    return fmu, np.array(rows)


def test_reversing_uses_the_standstill_gain_and_warns_once(open_fmu):
    fmu, rows = _run_fmu(open_fmu, ctrl_params(BUS), {"delta1": 0.02, "u": -3.0}, 50)
    K0 = zero_sideslip_gain(1e-3, BUS)
    assert np.all(np.isfinite(rows))
    assert rows[-1, 2] == pytest.approx(0.02 * K0, rel=1e-6)
    warnings = [m for m in fmu.log if "Warning" in m]
    assert len(warnings) == 1 and "u = -3" in warnings[0] and "K(0)" in warnings[0], fmu.log
    fmu.slave.reset()                   # a new episode warns again
    init(fmu, **ctrl_params(BUS), delta1=0.02, u=-1.0)
    fmu.log.clear()
    fmu.slave.doStep(0.0, 0.01)
    assert sum("Warning" in m for m in fmu.log) == 1


def test_steering_limits_and_one_warning(open_fmu):
    """a driver angle beyond what the tag axle can follow: every output within
    its limit, one warning for the whole episode"""
    fmu, rows = _run_fmu(open_fmu, ctrl_params(BUS, **{"deltaMax[3]": 0.2}), {"delta1": 0.6, "u": 0.0}, 30)
    assert rows[-1, 0] == 0.6
    assert rows[-1, 2] == pytest.approx(-0.2)          # K(0) * 0.6 = -0.61, limited
    assert np.all(np.abs(rows[:, 2]) <= 0.2)
    assert sum("steering limit" in m for m in fmu.log) == 1, fmu.log
    fmu.set_values({"delta1": 5.0})                     # beyond the front axle's limit too
    fmu.slave.doStep(0.3, 0.01)
    d = fmu.get("delta[1]", "delta[3]")
    assert d[0] == pytest.approx(0.8727) and abs(d[1]) == pytest.approx(0.2)
    assert sum("steering limit" in m for m in fmu.log) == 1


def test_pole_of_the_gain_stays_bounded(open_fmu):
    """a vehicle whose K(u) has a pole (a stiff fixed middle axle far behind
    the centre of gravity): at the pole the outputs are finite and limited"""
    veh = dict(BUS, l=[2.0, -3.0, -4.5], k=[-4e5, -2e6, -6e5], m=[0.0, 0.0, 0.0], m_b=20000.0)
    # the pole where K's denominator vanishes, from eq. 4: beta_ss does not depend on K there
    us = np.linspace(1.0, 30.0, 2901)
    K = np.array([zero_sideslip_gain(u, veh) for u in us])
    i = np.argmax(np.abs(K))
    assert abs(K[i]) > 100, "no pole: the test cannot fail"
    u_pole = us[i]
    fmu, rows = _run_fmu(open_fmu, ctrl_params(veh), {"delta1": 0.05, "u": u_pole}, 5)
    assert np.all(np.isfinite(rows))
    assert abs(rows[-1, 2]) <= 0.35 and rows[-1, 0] == 0.05
    assert any("pole" in m for m in fmu.log), fmu.log


def test_outputs_change_only_at_samples():
    """Ts = 0.05 s with 0.01 s communication steps: the command is held between
    samples (the built-in speed ramp makes it move)"""
    r = simulate(fmu_file("ZeroSideslipSteering"),
                 parameters=ctrl_params(BUS, Ts=0.05, testSpeedRate=2.0, testSteerAmp=0.05, delta1=0.0),
                 stop_time=1.0, step=0.01)
    d3 = r["delta[3]"]
    changes = np.nonzero(np.diff(d3))[0] + 1
    tc = r.time[changes]
    assert np.allclose(np.round(tc / 0.05) * 0.05, tc, atol=1e-9)
    assert len(changes) == 20
    # the sample at t_k uses u = 2 t_k
    for k in (5, 10, 20):
        t = 0.05 * k
        j = np.argmin(np.abs(r.time - t))
        assert d3[j] == pytest.approx(0.05 * zero_sideslip_gain(2 * t, BUS), rel=1e-9)


def test_default_experiment_alone_gives_the_standstill_gain():
    """running alone, every stimulus off: the start values delta1 = 0.02 rad at
    u = 0: the gain K(0) and a held, nonzero command for the tag axle"""
    r = simulate(fmu_file("ZeroSideslipSteering"))
    assert np.allclose(r["K[3]"], zero_sideslip_gain(1e-3, BUS), rtol=1e-6)
    assert np.all(r["delta[3]"] == r["delta[3]"][0]) and r["delta[3]"][0] != 0.0


def test_configuration_errors_name_the_problem():
    for veh, words in ((dict(BUS, steerable=[True, False, False]), "no axle behind axle 1"),
                       (dict(BUS, steerable=[False, False, True]), "steerable[1]"),
                       (dict(BUS, l=[5.4, -3.05, -1.55]), "not ordered")):
        with pytest.raises(SimulationError) as e:
            simulate(fmu_file("ZeroSideslipSteering"), parameters=ctrl_params(veh), stop_time=0.1)
        assert words in " ".join(e.value.log), e.value.log


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_law_compiles_alone_as_for_an_ecu(tmp_path):
    """zero_sideslip.c with tests/c/ecu_zero_sideslip.c: ISO C99, -pedantic,
    no FMI include path, no malloc; the checks in the program pass"""
    src = ROOT / "src/models/ZeroSideslipSteering"
    law = (src / "zero_sideslip.c").read_text() + (src / "zero_sideslip.h").read_text()
    for word in ("malloc", "calloc", "realloc", "free(", "fmi2", "static double state", "printf"):
        assert word not in law, word
    exe = tmp_path / "ecu"
    subprocess.run(["cc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2",
                    f"-I{src}", str(ROOT / "tests/c/ecu_zero_sideslip.c"), str(src / "zero_sideslip.c"),
                    "-lm", "-o", str(exe)], check=True)
    r = subprocess.run([str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout
    assert "0 failed" in r.stdout
