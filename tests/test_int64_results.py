"""FMI 3.0's 64-bit integers (Int64, UInt64; FMI 3.0 2.4.7.4) kept exact in a result: a float64
holds 53 bits, so 2**63 - 1 read into one is 2**63 and 2**53 + 1 is 2**53. FMPy's simulate_fmu
keeps such an output in an int64 or uint64 field; `artibus simulate` keeps it too, in the Result
and in every format -o writes (CSV, Parquet, MDF 4, MATLAB), also in the rows kept when the FMU
crashes (artibus.fmu.isolated).

The values are checked as Python integers read back by each format's own reader (the csv module,
pyarrow, scipy.io.loadmat, asammdf), against the values set or against FMPy's own run of the FMU:
every one of them is beyond 2**53, where a float64 on the way loses it."""
import csv
import subprocess
import sys

import pytest

from artibus import cli
from artibus.fmu import simulate
from test_reference_fmus import reference_fmu

#: (Int64, UInt64) pairs a float64 does not hold: each rounds to another number
CASES = [(2**63 - 1, 2**64 - 1), (-2**63, 2**53 + 1), (-(2**53) - 1, 2**63 + 1)]


def test_the_cases_are_beyond_a_float64():
    for a, b in CASES:
        assert int(float(a)) != a or int(float(b)) != b


@pytest.mark.parametrize("int64,uint64", CASES)
def test_a_result_keeps_feedthroughs_64_bit_outputs_as_fmpy_does(int64, uint64):
    """FMI 3.0 Feedthrough (Reference-FMUs): its outputs are its inputs; our Result's Int64 and
    UInt64 columns hold the set values exactly in every row, as FMPy's simulate_fmu does"""
    import fmpy
    fmu = reference_fmu("Feedthrough", 3)
    sets = {"Int64_input": int64, "UInt64_input": uint64}
    ours = simulate(fmu, parameters=sets, stop_time=0.01)
    theirs = fmpy.simulate_fmu(str(fmu), stop_time=0.01, start_values=sets)
    for name, value in (("Int64_output", int64), ("UInt64_output", uint64)):
        column = [int(x) for x in ours[name]]
        assert column == [value] * len(column), name
        assert {int(x) for x in theirs[name]} == {value}, name        # (FMPy: its own output interval)


def _read(path, name):
    """Column ``name`` of a results file as Python integers, read by its format's own reader."""
    suffix = path.suffix
    if suffix == ".csv":
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        k = rows[0].index(name)
        return [int(r[k]) for r in rows[1:]]
    if suffix == ".parquet":
        import pyarrow.parquet as pq
        return pq.read_table(path).column(name).to_pylist()
    if suffix == ".mat":
        from scipy.io import loadmat
        x = loadmat(path)[name]
        assert x.dtype.kind in "iu", x.dtype          # (a float here would have rounded)
        return [int(v) for v in x.ravel()]
    from asammdf import MDF
    with MDF(path) as mdf:
        x = mdf.get(name).samples
    assert x.dtype.kind in "iu", x.dtype
    return [int(v) for v in x]


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".mat", ".mf4"])
def test_every_results_format_holds_them_exactly(suffix, tmp_path):
    fmu = reference_fmu("Feedthrough", 3)
    int64, uint64 = CASES[0]
    out = tmp_path / f"f{suffix}"
    assert cli.main(["simulate", str(fmu), "--stop-time", "0.01", "-o", str(out),
                     f"--set=Int64_input={int64}", f"--set=UInt64_input={uint64}"]) == 0
    for name, value in (("Int64_output", int64), ("UInt64_output", uint64)):
        column = _read(out, name)
        assert column and column == [value] * len(column), (suffix, name, column[:3])


WIDE_FMU = '''
import ctypes
from pythonfmu3 import Fmi3Causality, Fmi3Slave, Fmi3Variability, Float64, Int64, String, UInt64


class Wide(Fmi3Slave):
    """after step k: n = 2**62 + 2 k + 1, u = 2**64 - 1 - 2 k (odd, beyond 2**53), s = "step k";
    a read of address 0 on the step past 0.45 s"""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.time, self.n, self.u, self.s, self.k = 0.0, 2**62 + 1, 2**64 - 1, "step 0", 0
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous))
        self.register_variable(Int64("n", causality=Fmi3Causality.output, variability=Fmi3Variability.discrete))
        self.register_variable(UInt64("u", causality=Fmi3Causality.output, variability=Fmi3Variability.discrete))
        self.register_variable(String("s", causality=Fmi3Causality.output, variability=Fmi3Variability.discrete))

    def do_step(self, current_time, step_size):
        if current_time + step_size > 0.45:
            ctypes.string_at(0)
        self.k += 1
        self.n, self.u, self.s = 2**62 + 2 * self.k + 1, 2**64 - 1 - 2 * self.k, f"step {self.k}"
        return True
'''


def test_a_crashing_fmus_kept_rows_hold_them_exactly(tmp_path):
    """An FMU made another way (pythonfmu3) with Int64, UInt64 and String outputs that crashes
    after t = 0.4 s: OUT.partial.csv has every row up to 0.4 s, each value exact, each text (the
    row at 0.4 s was lost with a String output before: its texts were written with the next row)"""
    pytest.importorskip("pythonfmu3", reason="pythonfmu3 (pyproject's test extra) is not installed")
    (tmp_path / "Wide.py").write_text(WIDE_FMU)
    p = subprocess.run([sys.executable, "-m", "pythonfmu3", "build", "-f", "Wide.py", "-d", "."],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0 and (tmp_path / "Wide.fmu").is_file(), p.stderr
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", "Wide.fmu", "--stop-time", "1",
                        "--step", "0.1", "-o", "w.csv"], capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 1 and "SIGSEGV after t = 0.4 s" in p.stderr, p.stderr
    partial = tmp_path / "w.partial.csv"
    assert _read(partial, "n") == [2**62 + 2 * k + 1 for k in range(5)]
    assert _read(partial, "u") == [2**64 - 1 - 2 * k for k in range(5)]
    with open(partial, newline="") as f:
        rows = list(csv.reader(f))
    assert [r[rows[0].index("s")] for r in rows[1:]] == [f"step {k}" for k in range(5)]
