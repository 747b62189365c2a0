"""`artibus run BENCH --input-file in.csv` (issue 38): a bench's free inputs (the end of no
connection) driven by a CSV as `simulate` reads one, columns COMPONENT.VARIABLE.

The bench: two TypesTest FMUs, A.real_out -> B.real_in; A.real_in is free. TypesTest's
real_out = factor real_in (factor 2, its README), computed from the input held over the step
it was set before: the row at t_k holds 2 u(t_{k-1}) for A, 2 * 2 u(t_{k-1}) for B (Gauss-
Seidel: B steps after A, on A's new output); the row at t0 2 u(t0) (the input set in
initialisation). u is the file's ramp, interpolated linearly here with numpy."""
import subprocess
import sys

import numpy as np
import pytest

from artibus import ArtibusError
from artibus.runner import Simulation
from test_runner_types import comp, conn, ins, make_ssp, outs

ARTIBUS = [sys.executable, "-m", "artibus"]
T_IN, U_IN = [0.0, 0.35, 1.0], [1.0, 2.4, -0.6]     # a ramp up, then down (a kink between steps)


def bench(tmp_path):
    elements = comp("A", "TypesTest", outs("real") + ins("real")) + comp("B", "TypesTest", outs("real") + ins("real"))
    return make_ssp(tmp_path, elements, conn("A", "real_out", "B", "real_in"), stop=1.0, name="free")


def csv(tmp_path, header, rows, name="in.csv"):
    path = tmp_path / name
    path.write_text(",".join(header) + "\n" + "".join(",".join(map(str, r)) + "\n" for r in rows))
    return path


def test_a_free_input_follows_the_file(tmp_path):
    path = csv(tmp_path, ["time", '"A.real_in"'], zip(T_IN, U_IN))
    with Simulation(bench(tmp_path), step=0.1, input_file=path) as sim:
        r = sim.run()
    t = np.asarray(r["time"])
    u_before = np.interp(np.r_[t[0], t[:-1]], T_IN, U_IN)      # the input the step to t was taken with
    np.testing.assert_allclose(r["A.real_out"], 2 * u_before, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["B.real_out"], 4 * u_before, rtol=0, atol=1e-12)
    assert len(t) == 11 and np.ptp(r["A.real_out"]) > 1.0


def test_a_connected_or_unknown_column_is_refused_by_name(tmp_path):
    for column in ("B.real_in", "A.nothing"):
        path = csv(tmp_path, ["time", column], [(0, 1), (1, 2)])
        with pytest.raises(ArtibusError, match=rf"in.csv:1: column 2 '{column}' is no input of .*free"):
            Simulation(bench(tmp_path), step=0.1, input_file=path)


def test_a_free_input_of_another_type_is_refused_by_name(tmp_path):
    path = csv(tmp_path, ["time", "A.int_in"], [(0, 1), (1, 2)])
    with pytest.raises(ArtibusError, match=r"in.csv:1: column 'A.int_in': the input is a Integer"):
        Simulation(bench(tmp_path), step=0.1, input_file=path)


def test_run_on_the_command_line_warns_of_the_free_inputs_no_column_gives(tmp_path):
    path = csv(tmp_path, ["time", "A.real_in"], zip(T_IN, U_IN))
    out = tmp_path / "out.csv"
    p = subprocess.run(ARTIBUS + ["run", str(bench(tmp_path)), "--step", "0.1", "--input-file", str(path),
                                  "--set", "B.int_in=3", "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    warned = [line for line in p.stderr.splitlines() if "gives no column" in line]
    assert len(warned) == 1, p.stderr
    named = warned[0].split("free inputs ")[1].split(" of ")[0].split(", ")
    assert sorted(named) == sorted(["A.int_in", "A.bool_in", "A.string_in", "A.enum_in",
                                    "B.bool_in", "B.string_in", "B.enum_in"])      # B.int_in: --set gives it
    got = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    np.testing.assert_allclose(got["A.real_out"][1:], 2 * np.interp(got["time"][:-1], T_IN, U_IN), atol=1e-9)


def test_run_refuses_the_input_file_as_output_and_with_all(tmp_path):
    path = csv(tmp_path, ["time", "A.real_in"], zip(T_IN, U_IN))
    for extra, said in ((["-o", str(path)], f"-o {path} is the --input-file"),
                        (["--all"], "--input-file drives the free inputs of one BENCH, not of --all")):
        args = ([] if extra == ["--all"] else [str(bench(tmp_path))]) + ["--input-file", str(path)] + extra
        p = subprocess.run(ARTIBUS + ["run", *args], capture_output=True, text=True)
        assert p.returncode != 0 and "Traceback" not in p.stderr and said in p.stderr, p.stderr
    assert path.read_text().startswith("time,A.real_in")                  # the input left as it was
