"""A conformance suite that needs nothing from outside a registry (issue 38): the Modelica
Reference-FMUs built from the sources the crate fmi-sys carries (scripts/build_reference_fmus.sh),
FMI 2.0 and 3.0 Co-Simulation, each run by `artibus simulate` as the FMI cross-check runs
it (the start and stop time and relative tolerance of its <Model>_ref.opt, the inputs of its
<Model>_in.csv) and held against

- FMPy's `simulate_fmu` on the same FMU with the same options (another importer): equal to
  1e-9 relative (the CSV holds 12 significant digits);
- the reference results the sources carry (<Model>_ref.csv) by the cross-check's rule,
  `fmpy.util.validate_signal` (a band around the reference; no point outside it).

Clocks is a Scheduled Execution FMU only (no Co-Simulation): refused by name. Where a reference
result names variables the built FMU does not have (the sources' Feedthrough_ref.csv is of an
older Feedthrough), that comparison is skipped with the names, the comparison with FMPy kept.

An FMU made another way: pythonfmu3 (PyPI, the test extra) builds one from a Python class (an
array output of 4, an input, a state, an Int32 counter), run by `artibus simulate` against FMPy
and against its own equations, and in a one-FMU bench by `artibus run --input-file`."""
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.util import read_csv, validate_signal

from artibus.testing import make_ssp

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / ".tools" / "reference-fmus"
MODELS = ["BouncingBall", "Dahlquist", "Feedthrough", "LinearTransform", "Resource", "Stair", "VanDerPol"]


def options(model):
    """{StartTime, StopTime, StepSize, RelTol} of <model>_ref.opt"""
    path = REFERENCE / "ref" / f"{model}_ref.opt"
    out = {}
    for line in path.read_text().splitlines():
        if "," in line:
            k, v = line.split(",", 1)
            out[k.strip()] = float(v)
    return out


def cases():
    return [pytest.param(m, version, id=f"fmi{version}-{m}") for version in (2, 3) for m in MODELS
            if version == 3 or m != "LinearTransform"]                 # (FMI 3.0 only: arrays)


def fmu_of(model, version):
    path = REFERENCE / ("fmi3" if version == 3 else "") / f"{model}.fmu"
    if not path.is_file() or not (REFERENCE / "ref" / f"{model}_ref.opt").is_file():
        pytest.skip(f"{path} or its reference results not built (scripts/build_reference_fmus.sh; needs cargo)")
    return path


def input_file(model, version, path):
    """The cross-check's <model>_in.csv where its columns are inputs of this build"""
    f = REFERENCE / "ref" / f"{model}_in.csv"
    if not f.is_file():
        return None
    inputs = {v.name for v in fmpy.read_model_description(str(path)).modelVariables if v.causality == "input"}
    header = f.read_text().splitlines()[0].split(",")[1:]
    return f if all(h.strip('" ') in inputs for h in header) else None


def simulated(path, model, version, tmp_path, *args):
    """`artibus simulate` of the FMU with ``args`` and the cross-check's options for the model
    (<model>_ref.opt: start, stop, output interval) and input file: (our CSV, its table as
    numpy reads it, the input file or None)."""
    opt = options(model)
    out = tmp_path / "ours.csv"
    args = [*args, "--start-time", opt["StartTime"], "--stop-time", opt["StopTime"]]
    if opt.get("StepSize"):
        args += ["--output-interval", opt["StepSize"]]
    inp = input_file(model, version, path)
    if inp is not None:
        args += ["--input-file", inp]
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), *map(str, args), "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    return out, np.genfromtxt(out, delimiter=",", names=True, deletechars=""), inp


def assert_64_bit_as_the_input_file(out, inp, name):
    """Feedthrough's 64-bit integer output ``name`` (output = input) in our CSV against the input
    file's own integers, exact, at the first and the last row (the file's two rows, 0 and 1 s).
    FMPy is no reference here: it reads an input file as float64, so 2**63 - 1 becomes 2**63 and
    wraps to -2**63 in an Int64."""
    import csv
    with open(out, newline="") as f:
        ours = list(csv.reader(f))
    with open(inp, newline="") as f:
        given = list(csv.reader(f))
    k, j = ours[0].index(name), given[0].index(name.replace("_output", "_input"))
    assert int(ours[1][k]) == int(given[1][j]), name
    assert int(ours[-1][k]) == int(given[-1][j]), name


@pytest.mark.parametrize("model, version", cases())
def test_reference_fmu_as_the_cross_check_runs_it(model, version, tmp_path):
    path = fmu_of(model, version)
    opt = options(model)
    out, ours, inp = simulated(path, model, version, tmp_path, "--relative-tolerance", opt["RelTol"])
    # FMPy on the same FMU with the same options
    kw = dict(start_time=opt["StartTime"], stop_time=opt["StopTime"], relative_tolerance=opt["RelTol"],
              fmi_type="CoSimulation")
    # the same output interval (FMPy's own default doubles the default experiment's step while
    # over 1000 points; artibus keeps it: docs/guide/fmus-alone.md)
    kw["output_interval"] = opt.get("StepSize") or float(ours["time"][1] - ours["time"][0])
    theirs = fmpy.simulate_fmu(str(path), input=read_csv(str(inp)) if inp is not None else None, **kw)
    assert len(ours) == len(theirs)
    np.testing.assert_allclose(ours["time"], theirs["time"], rtol=1e-9, atol=1e-12)
    for name in theirs.dtype.names[1:]:
        if inp is not None and theirs[name].dtype in (np.int64, np.uint64):
            assert_64_bit_as_the_input_file(out, inp, name)
            continue
        y = np.asarray(theirs[name], dtype=float).reshape(len(theirs), -1)
        cols = [name] if y.shape[1] == 1 else [f"{name}[{k + 1}]" for k in range(y.shape[1])]
        for k, c in enumerate(cols):
            scale = max(1.0, float(np.max(np.abs(y[:, k]))))
            np.testing.assert_allclose(ours[c], y[:, k], rtol=1e-9, atol=1e-12 * scale, err_msg=c)
    against_the_reference_results(model, version, path, ours)


def against_the_reference_results(model, version, path, ours):
    """ours against the reference results the sources carry, by the cross-check's rule"""
    ref_path = REFERENCE / "ref" / f"{model}_ref.csv"
    if not ref_path.read_text().strip():
        pytest.skip(f"{ref_path.name} is empty")
    ref = np.genfromtxt(ref_path, delimiter=",", names=True, deletechars="")
    absent = [n for n in ref.dtype.names[1:] if n not in ours.dtype.names]
    if absent:
        pytest.skip(f"{ref_path.name} names {', '.join(absent)}, which {path.name} does not have "
                    "(the sources' reference results are of an older build); compared with FMPy only")
    for n in ref.dtype.names[1:]:
        t_ref, y_ref = ref["time"], ref[n].astype(float)
        if len(t_ref) < 2:
            assert ours[n][0] == y_ref[0]
            continue
        *_, outside = validate_signal(ours["time"], ours[n].astype(float), t_ref, y_ref)
        assert not np.any(outside), f"{model} FMI {version}.0: {n} leaves the reference band"


def me_cases():
    """every Reference-FMU that has Model Exchange, both versions (FMI 2.0 has no LinearTransform)"""
    for version in (2, 3):
        for m in MODELS:
            path = REFERENCE / ("fmi3" if version == 3 else "") / f"{m}.fmu"
            if path.is_file() and fmpy.read_model_description(str(path)).modelExchange is None:
                continue
            if version == 3 or m != "LinearTransform":
                yield pytest.param(m, version, id=f"fmi{version}-{m}-me")


def fmpy_rows_at(ours_t, theirs_t, input_events):
    """Which of FMPy's rows is ours at each of our times. FMPy's simulate_fmu in Model Exchange
    records an event instant twice (its values before and after the event, one time); ours once:
    at an input event (a time of the input file) the values before the inputs are set there, as
    at every communication point (Co-Simulation's), at a time or state event the values after the
    event iteration (the FMU's own, as its Co-Simulation build's step ends there)."""
    rows = []
    for t in ours_t:
        at = np.flatnonzero(np.isclose(theirs_t, t, rtol=1e-12, atol=1e-12))
        assert len(at), f"FMPy has no row at t = {t}"
        rows.append(at[0] if any(np.isclose(t, e, rtol=1e-12, atol=1e-12) for e in input_events) else at[-1])
    return np.array(rows)


@pytest.mark.parametrize("model, version", list(me_cases()))
def test_reference_fmu_in_model_exchange_as_fmpy_integrates_it(model, version, tmp_path):
    """`artibus simulate --fmi-type me` (CVODE, rtol 1e-8) against FMPy's simulate_fmu(fmi_type=
    "ModelExchange", solver="CVode", relative_tolerance=1e-8) on the same output grid: each signal
    within 1e-6 of its peak magnitude (|ours - FMPy| <= 1e-6 max|FMPy|, an integer or Boolean
    exactly), at the rows of fmpy_rows_at; then the sources' reference results by the
    cross-check's rule. A run the FMU ends itself (Stair: terminateSimulation at its counter's
    10th event) ends at FMPy's time; there FMPy records only the values before that event,
    ours the event's own: that last row is held against the reference results only."""
    path = fmu_of(model, version)
    opt = options(model)
    out, ours, inp = simulated(path, model, version, tmp_path, "--fmi-type", "me", "--relative-tolerance", 1e-8)
    table = read_csv(str(inp)) if inp is not None else None
    theirs = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                               start_time=opt["StartTime"], stop_time=opt["StopTime"], input=table,
                               output_interval=opt.get("StepSize") or float(ours["time"][1] - ours["time"][0]))
    assert ours["time"][-1] == pytest.approx(theirs["time"][-1], rel=1e-12)
    ended = ours["time"][-1] < opt["StopTime"] - 1e-9          # (the FMU ended the run itself)
    rows = fmpy_rows_at(ours["time"], theirs["time"], table["time"] if table is not None else ())
    mine = ours[:-1] if ended else ours
    rows = rows[:-1] if ended else rows
    for name in theirs.dtype.names[1:]:
        y = np.asarray(theirs[name], dtype=float).reshape(len(theirs), -1)[rows]
        if table is not None and theirs[name].dtype in (np.int64, np.uint64):
            assert_64_bit_as_the_input_file(out, inp, name)
            continue
        cols = [name] if y.shape[1] == 1 else [f"{name}[{k + 1}]" for k in range(y.shape[1])]
        for k, c in enumerate(cols):
            if theirs[name].dtype.kind in "iub":
                np.testing.assert_array_equal(mine[c], y[:, k], err_msg=c)
            else:
                peak = float(np.max(np.abs(y[:, k])))
                assert np.max(np.abs(mine[c] - y[:, k])) <= 1e-6 * peak + 1e-300, c
    against_the_reference_results(model, version, path, ours)


def test_a_discrete_input_of_an_me_fmu_in_a_bench_is_set_in_event_mode(tmp_path):
    """TypesTest's count (the steps taken: k at t_k) into FMI 3.0 Feedthrough's Int32_input, the
    Feedthrough run as Model Exchange: a discrete input changes in Event Mode only (FMI 3.0
    3.2.1, "State: Continuous-Time Mode": there only continuous-time inputs are set; the
    Reference-FMUs refuse it, "Illegal call sequence"): Int32_output = count = k at every point"""

    from artibus.base import fmu_dir
    feed, types = REFERENCE / "fmi3" / "Feedthrough.fmu", fmu_dir() / "TypesTest.fmu"
    if not feed.is_file() or not types.is_file():
        pytest.skip(f"{feed} or {types} not built")
    elements = ('<ssd:Component name="T" source="resources/TypesTest.fmu"><ssd:Connectors>'
                '<ssd:Connector name="count" kind="output"/></ssd:Connectors></ssd:Component>'
                '<ssd:Component name="F" source="resources/Feedthrough.fmu"><ssd:Connectors>'
                '<ssd:Connector name="Int32_input" kind="input"/><ssd:Connector name="Int32_output" kind="output"/>'
                '</ssd:Connectors></ssd:Component>')
    bench = make_ssp(tmp_path, elements, '<ssd:Connection startElement="T" startConnector="count" endElement="F" '
                     'endConnector="Int32_input"/>', 1, name="me", fmu=False, fmus=[feed, types], system_name="me")
    out = tmp_path / "me.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(bench), "--fmi-type", "me", "--step", "0.25",
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    ours = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    assert list(ours["T.count"]) == list(ours["F.Int32_output"]) == [0, 1, 2, 3, 4]


def test_a_scheduled_execution_only_fmu_is_refused_by_name(tmp_path):
    path = REFERENCE / "fmi3" / "Clocks.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built")
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "-o", str(tmp_path / "c.csv")],
                       capture_output=True, text=True)
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "Clocks has no Co-Simulation interface" in p.stderr


# -- FMUs made another way: pythonfmu3 (PyPI) builds an FMI 3.0 Co-Simulation FMU from a Python
# class, its binary embedding the Python that loads it. Its conventions: outputs computed in
# do_step only (at t0 they hold their start values), no default experiment, arrays as numpy arrays.
PYTHON_FMU = '''
import numpy as np
from pythonfmu3 import Dimension, Fmi3Causality, Fmi3Slave, Fmi3Variability, Float64, Int32


class Scaled(Fmi3Slave):
    """y[i] = gain[i] u (an array output of 4), x' = u by explicit Euler, n the steps taken"""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.time, self.u, self.x, self.n = 0.0, 0.0, 0.0, 0
        self.gain = np.array(GAIN)
        self.y = np.zeros(4)
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous))
        self.register_variable(Float64("u", causality=Fmi3Causality.input, variability=Fmi3Variability.continuous,
                                       start=0.0))
        self.register_variable(Float64("gain", causality=Fmi3Causality.parameter, variability=Fmi3Variability.tunable,
                                       dimensions=[Dimension(start="4")], start=self.gain))
        self.register_variable(Float64("y", causality=Fmi3Causality.output, variability=Fmi3Variability.continuous,
                                       dimensions=[Dimension(start="4")]))
        self.register_variable(Float64("x", causality=Fmi3Causality.output, variability=Fmi3Variability.continuous))
        self.register_variable(Int32("n", causality=Fmi3Causality.output, variability=Fmi3Variability.discrete))

    def do_step(self, current_time, step_size):
        self.x += self.u * step_size
        self.n += 1
        self.y = self.gain * self.u
        return True
'''
GAIN = [1.0, -2.0, 0.5, 3.0]
U_T, U = [0.0, 0.45, 1.0], [1.0, 3.0, -1.0]          # the input: a ramp up, then down
H = 0.1


@pytest.fixture(scope="module")
def python_fmu(tmp_path_factory):
    """Scaled.fmu built by pythonfmu3 (the test extra; skipped without it)"""
    pytest.importorskip("pythonfmu3", reason="pythonfmu3 (pyproject's test extra) is not installed")
    d = tmp_path_factory.mktemp("pythonfmu3")
    (d / "Scaled.py").write_text(PYTHON_FMU.replace("GAIN", repr(GAIN)))
    p = subprocess.run([sys.executable, "-m", "pythonfmu3", "build", "-f", str(d / "Scaled.py"), "-d", str(d)],
                       capture_output=True, text=True, cwd=d)
    assert p.returncode == 0 and (d / "Scaled.fmu").is_file(), p.stderr
    return d / "Scaled.fmu"


def python_fmu_expected(t):
    """Scaled's outputs at the points t by its own equations, u from the input table held over
    each step (the value at the step's start): y(t_k) = gain u(t_{k-1}), x(t_k) = H sum_{j<k} u(t_j),
    n(t_k) = k; at t0 the start values (0)."""
    u_prev = np.interp(t[:-1], U_T, U)
    y = np.vstack([np.zeros(4), np.outer(u_prev, GAIN)])
    x = np.r_[0.0, H * np.cumsum(u_prev)]
    return y, x, np.arange(len(t))


def test_a_pythonfmu3_fmu_with_an_array_output_as_fmpy_runs_it(python_fmu, tmp_path):
    inp = tmp_path / "in.csv"
    inp.write_text("time,u\n" + "".join(f"{a},{b}\n" for a, b in zip(U_T, U)))
    out = tmp_path / "ours.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(python_fmu), "--stop-time", "1",
                        "--output-interval", str(H), "--input-file", str(inp), "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    ours = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    theirs = fmpy.simulate_fmu(str(python_fmu), stop_time=1.0, output_interval=H, input=read_csv(str(inp)),
                               output=["y", "x", "n"])
    assert len(ours) == len(theirs) == 11
    y, x, n = python_fmu_expected(ours["time"])
    for k in range(4):
        np.testing.assert_allclose(ours[f"y[{k + 1}]"], theirs["y"][:, k], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ours[f"y[{k + 1}]"], y[:, k], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours["x"], theirs["x"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours["x"], x, rtol=1e-9, atol=1e-12)
    assert list(ours["n"]) == list(theirs["n"]) == list(n)


def test_a_pythonfmu3_fmu_in_a_bench_driven_by_an_input_file(python_fmu, tmp_path):
    scaled = ('<ssd:Component name="P" source="resources/Scaled.fmu"><ssd:Connectors>'
              '<ssd:Connector name="u" kind="input"/><ssd:Connector name="x" kind="output"/>'
              '<ssd:Connector name="n" kind="output"/></ssd:Connectors></ssd:Component>')
    bench = make_ssp(tmp_path, scaled, None, 1, name="py", fmu=False, fmus=[python_fmu], system_name="py")
    inp = tmp_path / "in.csv"
    inp.write_text("time,P.u\n" + "".join(f"{a},{b}\n" for a, b in zip(U_T, U)))
    out = tmp_path / "bench.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(bench), "--step", str(H), "--input-file", str(inp),
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    ours = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    _, x, n = python_fmu_expected(ours["time"])
    assert len(ours) == 11
    np.testing.assert_allclose(ours["P.x"], x, rtol=1e-9, atol=1e-12)
    assert list(ours["P.n"]) == list(n)


def test_a_pythonfmu3_array_output_drives_linear_transform_in_a_bench(python_fmu, tmp_path):
    """Scaled's y (4 elements, gain u) connected whole to LinearTransform's u, its n = 4 set in
    the bench (an .ssv: a structural parameter, FMI 3.0 2.3 Configuration Mode): L.y = A (gain u)
    element by element (u = 2 held; Scaled's y is its start value 0 until its first step)."""
    lt = REFERENCE / "fmi3" / "LinearTransform.fmu"
    if not lt.is_file():
        pytest.skip(f"{lt} not built")
    ns = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
          'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
          'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')
    ssv = (f'<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet {ns} version="1.0" name="n"><ssv:Parameters>'
           '<ssv:Parameter name="n"><ssv:Integer value="4"/></ssv:Parameter></ssv:Parameters></ssv:ParameterSet>')
    elements = ('<ssd:Component name="P" source="resources/Scaled.fmu"><ssd:Connectors>'
                '<ssd:Connector name="y" kind="output"/></ssd:Connectors></ssd:Component>'
                '<ssd:Component name="L" source="resources/LinearTransform.fmu"><ssd:Connectors>'
                '<ssd:Connector name="u" kind="input"/><ssd:Connector name="y" kind="output"/></ssd:Connectors>'
                '<ssd:ParameterBindings><ssd:ParameterBinding source="resources/n.ssv"/></ssd:ParameterBindings>'
                '</ssd:Component>')
    bench = make_ssp(tmp_path, elements, '<ssd:Connection startElement="P" startConnector="y" endElement="L" '
                     'endConnector="u"/>', 0.5, ssv={"n.ssv": ssv}, name="py", fmu=False, fmus=[python_fmu, lt],
                     system_name="py")
    a = np.array([[1.0, 0.0, 2.0, -1.0], [0.5, 1.0, 0.0, 3.0]])
    out = tmp_path / "bench.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(bench), "--step", str(H), "--set", "P.u=2",
                        "--set", "L.A=" + " ".join(map(str, a.ravel())), "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    ours = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    y = 2.0 * np.array(GAIN)
    for k in range(4):
        assert ours[f"P.y[{k + 1}]"][0] == 0.0
        np.testing.assert_array_equal(ours[f"P.y[{k + 1}]"][1:], y[k])
    for k in range(2):
        np.testing.assert_allclose(ours[f"L.y[{k + 1}]"][2:], (a @ y)[k], rtol=1e-15)
