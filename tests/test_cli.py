"""The command line as a daily tool (issue 15): --version, a short `list`,
`info` by bench name with "did you mean", --set over arrays, -o meaning the
results file in every command, no traceback for bad times or output places."""
import os
import subprocess
import sys

import pytest

import artibus
from artibus import ArtibusError, fmu_dir
from artibus.bench import ssp
from artibus.bench.names import expand


def artibus_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "artibus", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def one_line_error(r, code=1):
    assert r.returncode == code, r.stderr
    assert "Traceback" not in r.stderr
    return r.stderr.strip().splitlines()[-1]


def test_version(tmp_path):
    r = artibus_cli("--version", cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.strip() == f"artibus {artibus.__version__}"


def test_list_is_one_line_per_bench_and_fmu(tmp_path):
    """Issue 15: `list` printed 518 lines (every bound parameter)."""
    benches, fmus = ssp.bench_names(), sorted(p.stem for p in fmu_dir().glob("*.fmu"))
    r = artibus_cli("list", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    for name in benches + fmus:
        assert sum(1 for line in lines if line.startswith(f"  {name}:")) == 1, name
    assert len(lines) <= len(benches) + len(fmus) + 6
    long = artibus_cli("list", "--parameters", cwd=tmp_path)
    assert long.returncode == 0 and len(long.stdout.splitlines()) > len(lines) + 100
    assert "      Bus.mu[1] = " in long.stdout or "      Bus." in long.stdout


def test_info_takes_a_bench_name(tmp_path):
    """Issue 15: `info` did not take bench names (it said "FMU not built")."""
    r = artibus_cli("info", "Scania18m_OpenLoop", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "components:" in r.stdout and "  Bus: resources/BusDynamics.fmu" in r.stdout
    r = artibus_cli("info", "BusKinematics", cwd=tmp_path)
    assert r.returncode == 0 and "parameters (" in r.stdout


@pytest.mark.parametrize("typo, meant", [("Scania18m_OpenLop", "Scania18m_OpenLoop"),
                                         ("BusKinematic", "BusKinematics")])
def test_info_typo_says_did_you_mean(tmp_path, typo, meant):
    line = one_line_error(artibus_cli("info", typo, cwd=tmp_path))
    assert line.startswith(f"artibus: error: {typo}: no such bench or FMU; did you mean {meant}")
    assert "not built" not in line


@pytest.mark.parametrize("verb", ["run", "simulate"])
@pytest.mark.parametrize("value", ["inf", "-1", "nan", "0", "abc"])
def test_bad_stop_time_is_a_usage_error(tmp_path, verb, value):
    """Issue 15: --stop-time inf ended in a traceback."""
    target = "Scania18m_OpenLoop" if verb == "run" else "BusKinematics"
    r = artibus_cli(verb, target, f"--stop-time={value}", cwd=tmp_path)
    line = one_line_error(r, code=2)
    assert line.startswith(f"artibus {verb}: error: argument --stop-time: ")


def test_simulate_output_checked_before_the_run(tmp_path):
    line = one_line_error(artibus_cli("simulate", "BusKinematics", "-o", str(tmp_path), cwd=tmp_path))
    assert line == f"artibus: error: -o {tmp_path}: is a directory (give a file name, e.g. {tmp_path / 'results.csv'})"
    assert list(tmp_path.iterdir()) == []


def test_demo_o_is_the_results_file(tmp_path):
    """-o is the results file in every command (demo took a directory there)."""
    line = one_line_error(artibus_cli("demo", "-o", str(tmp_path / "out"), cwd=tmp_path))
    assert "--report DIR" in line


def test_bode_o_is_the_results_file(tmp_path):
    """bode's --output named the measured variable while its -o named the CSV."""
    line = one_line_error(artibus_cli("bode", "MultiAxle_StepSteer", "--input", "Steering.delta1",
                                      "--output", "Vehicle.w_r", cwd=tmp_path))
    assert "--measure Vehicle.w_r" in line


# --- --set over arrays ---------------------------------------------------------------

NAMES = [f"mu[{i}]" for i in range(1, 7)] + ["m[1]", "m[2]", "v"]


def test_expand_star_and_inclusive_range():
    assert expand("mu[*]", "0.5", NAMES) == [(f"mu[{i}]", "0.5") for i in range(1, 7)]
    assert expand("mu[1:6]", "0.5", NAMES) == [(f"mu[{i}]", "0.5") for i in range(1, 7)]
    assert expand("mu[2:3]", "1", NAMES) == [("mu[2]", "1"), ("mu[3]", "1")]
    assert expand("mu[4]", "1", NAMES) == [("mu[4]", "1")]
    assert expand("v", "1", NAMES) == [("v", "1")]


@pytest.mark.parametrize("sel", ["mu[0:6]", "mu[1:7]", "mu[5:9]"])
def test_range_outside_the_array_names_the_valid_range(sel):
    with pytest.raises(ArtibusError, match=r"Bus\.mu has elements 1\.\.6 \(valid: Bus\.mu\[1:6\]"):
        expand(sel, "0.5", NAMES, label="Bus." + sel)


def test_star_on_a_scalar_is_an_error():
    with pytest.raises(ArtibusError, match="'v' is not an array variable"):
        expand("v[*]", "1", NAMES)


def test_run_sets_every_element(tmp_path):
    """Issue 15: the wet case needed six --set Bus.mu[a]=0.5."""
    from artibus.runner import Simulation
    with Simulation("Scania18m_OpenLoop", overrides={"Bus.mu[*]": "0.5"}) as sim:
        n = sum(1 for v in sim.units[0].fmu.vars if v.startswith("mu["))
        got = {k: float(v) for k, v in sim.parameters["Bus"].items() if k.startswith("mu[")}
    assert n >= 2 and got == {f"mu[{i}]": 0.5 for i in range(1, n + 1)}
    r = artibus_cli("run", "Scania18m_OpenLoop", "--set", f"Bus.mu[1:{n + 1}]=0.5", "--stop-time", "0.1",
                    "-o", str(tmp_path / "r.csv"), cwd=tmp_path)
    line = one_line_error(r)
    assert f"Bus.mu has elements 1..{n}" in line and not (tmp_path / "r.csv").exists()


def test_o_with_all_is_refused(tmp_path):
    """-o is one results file: --all wrote every bench's results over the same one."""
    line = one_line_error(artibus_cli("run", "--all", "-o", str(tmp_path / "r.csv"), cwd=tmp_path))
    assert line.startswith("artibus: error: -o names one results file") and list(tmp_path.iterdir()) == []
