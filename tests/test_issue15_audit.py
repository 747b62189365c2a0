"""Issue 15's "Why" list: the defects that had no test reproducing them yet
(the others are named in the report of the audit, e.g. test_runner_types.py,
test_runner_safety.py, test_reports.py, test_cli.py)."""
import ast
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from artibus import ROOT, runner
from artibus.bench import script
from artibus.fmu import SimulationError
from artibus.runner import Simulation
from test_runner_types import comp, make_ssp

DEG = math.pi / 180


def test_jack_knife_in_a_bench_names_the_component_and_the_fmus_message(tmp_path):
    """'A jack-knife is reported as "component 'Bus' failed: no message"' (FMPy's
    one logger sent it to the last-instantiated FMU's log). Here Bus (an Urbino 18
    pushed backwards at full lock, seed 003) is instantiated first, a TypesTest
    after it: the error names Bus, its jack-knife message and beta[1]."""
    path = make_ssp(tmp_path, comp("Bus", "BusKinematics", [("gammaF", "input"), ("v", "input"),
                                                             ("beta[1]", "output")])
                    + comp("Last", "TypesTest", [("real_out", "output")]), "",
                    stop=60.0, fmus=("BusKinematics", "TypesTest"))
    urbino = {"Bus.N": 1, "Bus.k": 1, "Bus.L0": 5.9, "Bus.Lh[1]": 1.789, "Bus.L[1]": 4.211,
              "Bus.beta_start[1]": 10 * DEG, "Bus.v": 0.0, "Bus.gammaF": 0.0}   # (the stimuli add to these)
    with Simulation(path, step=0.1, overrides=urbino,
                    stimuli={"Bus.gammaF": lambda t: -25 * DEG, "Bus.v": lambda t: -3.0}) as sim:
        assert [u.path for u in sim.units][-1] == "Last"
        with pytest.raises(SimulationError) as e:
            sim.run()
    msg = str(e.value)
    assert "component 'Bus' failed" in msg and "jack-knife" in msg and "beta[1]" in msg, msg
    assert "no message" not in msg
    assert 0 < e.value.result.time[-1] < 60.0


def test_readme_example_mu_on_scania_lane_change_acts():
    """'--set Bus.mu[3]=0.5 on Scania18m_LaneChange changes nothing: that bench's
    tyre model ignores mu, and nothing says so.' Now the run moves with mu[3] (the
    rear axle's lateral forces and the path) and the FMU warns of nothing."""
    with Simulation("Scania18m_LaneChange") as sim:
        dry = sim.run()
        assert not any(m.startswith("[Warning]") and "mu[" in m for u in sim.units for m in u.fmu.log)
    with Simulation("Scania18m_LaneChange", overrides={"Bus.mu[3]": 0.5}) as sim:
        wet = sim.run()
        assert not any(m.startswith("[Warning]") and "mu[" in m for u in sim.units for m in u.fmu.log)
    assert dry.names == wet.names
    differ = [n for n in dry.names if not np.array_equal(dry[n], wet[n])]
    assert "Bus.Fy[3]" in differ and "Bus.yAxle[1]" in differ, differ
    assert np.max(np.abs(wet["Bus.Fy[3]"] - dry["Bus.Fy[3]"])) > 100.0       # N: not a rounding effect


def test_backwards_bench_says_why_its_kpis_match_the_forwards_bench():
    """'Identical Backwards/Forwards KPIs are not explained (the bus is symmetric).'"""
    text = script.load("Bus36m_Circle_Backwards").TEXT
    assert "symmetric" in text and "forwards" in text


def _kpi_strings():
    """Every string constant among the arguments of a Kpi(...) call in the benches'
    bench.py files and artibus' own modules: the KPIs' names, units, paper values, sources."""
    files = sorted((ROOT / "ssp" / "benches").glob("*/bench.py")) + sorted((ROOT / "src" / "artibus").rglob("*.py"))
    found = []
    for f in files:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == "Kpi":
                for arg in list(node.args) + [k.value for k in node.keywords]:
                    for c in ast.walk(arg):
                        if isinstance(c, ast.Constant) and isinstance(c.value, str):
                            found.append((f.relative_to(ROOT), c.value))
    return found


def test_no_kpi_cites_an_internal_issue():
    """'A "paper" column cites an internal issue number.'"""
    found = _kpi_strings()
    assert len(found) > 50                                         # the scan sees the KPIs
    assert any(s.startswith("seed 000, Fig. 9") for _, s in found)   # the benches' sources
    assert any(str(f).startswith("src/artibus/study/") for f, _ in found)   # and the sub-packages' KPIs
    bad = [(str(f), s) for f, s in found if re.search(r"\bissues?\b|#\d", s, re.IGNORECASE)]
    assert bad == []


def test_tiny_step_runs_in_bounded_memory(tmp_path):
    """'--step 1e-8 --stop-time 1e-6 takes 886 MB' (a step plan entry per base step
    of the slowest component's period: 10^6 here). The run's peak resident memory,
    measured by the process that waits for it, stays below 300 MB."""
    out = tmp_path / "r.csv"
    code = ("import resource, subprocess, sys; "
            f"p = subprocess.run([sys.executable, '-m', 'artibus', 'run', 'Scania18m_OpenLoop', '--step', '1e-8', "
            f"'--stop-time', '1e-6', '-o', {str(out)!r}], capture_output=True, text=True); "
            "print(p.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); "
            "sys.stderr.write(p.stderr)")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    rc, kb = map(int, p.stdout.split())
    assert rc == 0, p.stderr
    assert kb < 300 * 1024, f"{kb / 1024:.0f} MB"
    assert len(np.loadtxt(out, delimiter=",", skiprows=1)) == 101   # 1e-6 s in steps of 1e-8, and t = 0
    assert runner.read_units(out)["time"] == "s"


def test_bode_page_has_enough_frequencies_and_a_panel_per_output(tmp_path, monkeypatch):
    """'The Bode page has 6 frequencies and one dB axis for two quantities.'
    MultiAxle_StepSteer's study (its step runs real, the sine runs stubbed: a
    first-order lag per output) asks for at least 20 log-spaced frequencies over
    more than a decade and draws a column per output, each with its own unit."""
    from artibus.study import bode
    asked, drawn = [], {}

    def fake_response(bench, input, outputs, frequencies, amplitude, **kw):
        asked.append(np.asarray(frequencies, float))
        return {o: [bode.Point(f, 1 / math.hypot(1, f), -math.atan(f)) for f in frequencies] for o in outputs}

    real_plot = bode.plot

    def spy_plot(path, responses, title, units=None, **kw):
        drawn.update(responses=responses, units=units)
        return real_plot(path, responses, title, units=units, **kw)

    monkeypatch.setattr(bode, "frequency_response", fake_response)
    monkeypatch.setattr(bode, "plot", spy_plot)
    b = script.load("MultiAxle_StepSteer")
    b.study(None, tmp_path)
    f = asked[0]
    assert len(f) >= 20 and f[-1] / f[0] > 10
    np.testing.assert_allclose(np.diff(np.log(f)), np.log(f[1] / f[0]))      # log spaced
    assert list(drawn["responses"]) == ["Vehicle.w_r", "Vehicle.a_y"]
    assert drawn["units"] == {"Vehicle.w_r": "rad/s", "Vehicle.a_y": "m/s2"}
    from PIL import Image
    with Image.open(tmp_path / "bode.png") as im:
        assert im.width > im.height                   # the two outputs side by side
