"""`artibus simulate` as a user of FMPy or fmusim drives it (issue 38): their option names,
an input file, a start time, an output interval, a tolerance; each checked against FMPy's
`simulate_fmu` on the same FMU (another master, not our code) and against the input table's
own values; bad input files refused naming file, line and column."""
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.util import read_csv

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / ".tools" / "reference-fmus"


def reference(name, version=2):
    path = REFERENCE / ("fmi3" if version == 3 else "") / f"{name}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/build_reference_fmus.sh; needs cargo)")
    return path


def artibus(*args, cwd=None):
    p = subprocess.run([sys.executable, "-m", "artibus", *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert "Traceback" not in p.stderr, p.stderr
    return p


def table(path):
    return np.genfromtxt(path, delimiter=",", names=True, deletechars="")


# the breakpoints (0.25 twice: a jump; 0.85) lie between the communication points
FEEDTHROUGH_IN = """time,Float64_continuous_input,Float64_discrete_input,Int32_input,Boolean_input
0,0,0,0,0
0.25,3,1,2,1
0.25,-1,5,7,0
0.85,6,2,-3,1
"""
OUTPUTS = ["Float64_continuous_output", "Float64_discrete_output", "Int32_output", "Boolean_output"]


@pytest.mark.parametrize("version", [2, 3])
def test_an_input_file_drives_the_fmu_as_fmpy_applies_it(version, tmp_path):
    fmu = reference("Feedthrough", version)
    inp = tmp_path / "in.csv"
    inp.write_text(FEEDTHROUGH_IN)
    out = tmp_path / "out.csv"
    p = artibus("simulate", fmu, "--input-file", inp, "--stop-time", "1.2", "--output-interval", "0.1",
                "--output-file", out)
    assert p.returncode == 0, p.stderr
    ours = table(out)
    theirs = fmpy.simulate_fmu(str(fmu), input=read_csv(str(inp)), output_interval=0.1, stop_time=1.2)
    # 13 regular points and the two input events (0.25, 0.85) the steps are cut at, as FMPy cuts them
    assert len(ours) == len(theirs) == 15
    np.testing.assert_allclose(ours["time"], theirs["time"], rtol=1e-9, atol=1e-12)
    for n in OUTPUTS:        # (the CSV holds 12 significant digits)
        np.testing.assert_allclose(ours[n], np.asarray(theirs[n], dtype=float), rtol=1e-9, atol=1e-12, err_msg=n)
    # the table's own values, independently: the continuous input interpolated (between 0.25 and
    # 0.85 from -1 to 6), each output one point behind its input (Co-Simulation: set, then step);
    # at 0.25 the values after the jump, from 0.85 the last row's
    t = ours["time"]
    k = np.flatnonzero(np.isclose(t, 0.6))[0]
    assert ours["Float64_continuous_output"][k] == pytest.approx(-1 + 7 * (0.5 - 0.25) / 0.6, abs=1e-9)
    k = np.flatnonzero(np.isclose(t, 0.3))[0]
    assert ours["Float64_continuous_output"][k] == -1 and ours["Int32_output"][k] == 7
    assert ours["Int32_output"][k - 1] == 0 and t[k - 1] == pytest.approx(0.25)
    assert ours["Int32_output"][-1] == -3 and ours["Boolean_output"][-1] == 1


def test_fmpy_option_names_give_fmpys_table(tmp_path):
    """--start-time, --stop-time, --output-interval, --start-values, --relative-tolerance,
    --fmi-type, --output-file, as `fmpy simulate` takes them: Dahlquist (x' = -k x) from t = 1"""
    fmu = reference("Dahlquist")
    out = tmp_path / "d.csv"
    p = artibus("simulate", fmu, "--start-time", "1", "--stop-time", "3", "--output-interval", "0.5",
                "--start-values", "k", "2", "--relative-tolerance", "1e-6", "--fmi-type", "CoSimulation",
                "--output-file", out)
    assert p.returncode == 0, p.stderr
    theirs = fmpy.simulate_fmu(str(fmu), start_time=1, stop_time=3, output_interval=0.5, start_values={"k": 2},
                               relative_tolerance=1e-6)
    ours = table(out)
    np.testing.assert_array_equal(ours["time"], theirs["time"])
    np.testing.assert_allclose(ours["x"], theirs["x"], rtol=1e-9)       # (the CSV: 12 digits)
    # fmusim's names for the same: --start-value, --interface-type, --tolerance
    out2 = tmp_path / "d2.csv"
    p = artibus("simulate", fmu, "--start-time", "1", "--stop-time", "3", "--output-interval", "0.5",
                "--start-value", "k", "2", "--tolerance", "1e-6", "--interface-type", "cs", "-o", out2)
    assert p.returncode == 0, p.stderr
    assert out2.read_text() == out.read_text()


def test_output_interval_records_every_kth_step(tmp_path):
    """--step 0.1 --output-interval 0.5: the results of a run at 0.1, every fifth point"""
    fmu = reference("Dahlquist")
    fine, coarse = tmp_path / "f.csv", tmp_path / "c.csv"
    assert artibus("simulate", fmu, "--step", "0.1", "-o", fine).returncode == 0
    assert artibus("simulate", fmu, "--step", "0.1", "--output-interval", "0.5", "-o", coarse).returncode == 0
    f, c = table(fine), table(coarse)
    np.testing.assert_array_equal(c["x"], f["x"][::5])
    p = artibus("simulate", fmu, "--step", "0.1", "--output-interval", "0.25", "-o", tmp_path / "x.csv")
    assert p.returncode == 1 and "output interval 0.25 s is not a whole number of steps of 0.1 s" in p.stderr


def test_an_input_no_column_gives_is_named_in_a_warning(tmp_path):
    fmu = reference("Feedthrough")
    inp = tmp_path / "in.csv"
    inp.write_text('"time","Float64_continuous_input"\n0,1\n1,2\n')
    p = artibus("simulate", fmu, "--input-file", inp, "-o", tmp_path / "o.csv")
    assert p.returncode == 0
    assert "warning" in p.stderr and "Int32_input" in p.stderr and "Boolean_input" in p.stderr
    assert "Float64_continuous_input" not in p.stderr.split("warning", 1)[1].split(" of ")[0]
    p = artibus("simulate", fmu, "--input-file", inp, "--set", "Int32_input=3", "--set", "Boolean_input=true",
                "--set", "Float64_discrete_input=1", "-o", tmp_path / "o.csv")
    assert p.returncode == 0 and "warning" not in p.stderr, p.stderr


@pytest.mark.parametrize("text, words", [
    ("time,Float64_continuous_input,nope\n0,1,2\n", [":1:", "column 3 'nope' is no input of Feedthrough"]),
    ("time,Float64_continuous_input\n0,1\n0.5,abc\n", [":3:", "'abc' is not a number"]),
    ("time,Float64_continuous_input\n0,1\n0.5,2\n0.4,3\n", [":4:", "time 0.4 s goes back from 0.5 s"]),
    ("Time,Int32_output\n0,1\n", [":1:", "'Int32_output' is no input"]),
    ("x,Float64_continuous_input\n0,1\n", [":1:", "the first column is 'x', expected 'time'"]),
    ("time,Float64_continuous_input\n0,1,2\n", [":2:", "3 cells, the header has 2 columns"]),
    ("", ["empty"]),
])
def test_a_bad_input_file_is_an_error_naming_file_line_and_column(text, words, tmp_path):
    fmu = reference("Feedthrough")
    inp = tmp_path / "in.csv"
    inp.write_text(text)
    p = artibus("simulate", fmu, "--input-file", inp, "-o", tmp_path / "o.csv")
    assert p.returncode == 1 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert str(inp) in p.stderr and all(w in p.stderr for w in words), p.stderr
    assert not (tmp_path / "o.csv").exists()


def test_an_array_input_from_its_element_columns(tmp_path):
    """LinearTransform (FMI 3.0): u[1], u[2] columns fill the array input u; y = A u with A = I"""
    fmu = reference("LinearTransform", 3)
    inp = tmp_path / "in.csv"
    inp.write_text('"time","u[1]","u[2]"\n0,1,2\n1,3,6\n')
    out = tmp_path / "o.csv"
    p = artibus("simulate", fmu, "--input-file", inp, "--stop-time", "1", "--step", "0.25", "-o", out)
    assert p.returncode == 0, p.stderr
    r = table(out)
    # y at t is u at t - 0.25 (set before the step), u linear from [1, 2] to [3, 6]
    for t, y1, y2 in zip(r["time"][1:], r["y[1]"][1:], r["y[2]"][1:]):
        s = t - 0.25
        assert (y1, y2) == pytest.approx((1 + 2 * s, 2 + 4 * s), abs=1e-12)
    inp.write_text('"time","u[1]","u[3]"\n0,1,2\n')
    p = artibus("simulate", fmu, "--input-file", inp, "-o", out)
    assert p.returncode == 1 and "u[3]" in p.stderr and "no such element" in p.stderr


def test_model_exchange_asked_of_an_fmu_without_it_is_refused_naming_what_runs(tmp_path):
    """(Model Exchange runs since issue 38's ME facade: tests/test_me_facade.py.) An FMU with
    Co-Simulation only: --fmi-type ModelExchange refused, naming the interface it has."""
    from conftest import fmu_file
    p = artibus("simulate", fmu_file("SteeringECU"), "--fmi-type", "ModelExchange", "-o", tmp_path / "o.csv")
    assert p.returncode == 1 and "no Model Exchange" in p.stderr and "--fmi-type CoSimulation" in p.stderr


def test_an_unknown_option_suggests_the_nearest_of_its_verb():
    p = artibus("simulate", "Dahlquist", "--output-flie", "x.csv")
    assert p.returncode == 2 and "did you mean --output-file?" in p.stderr
    p = artibus("run", "Bus36m_Circle", "--stop-tme", "1")
    assert p.returncode == 2 and "did you mean --stop-time?" in p.stderr
