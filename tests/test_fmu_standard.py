"""What every artibus FMU must satisfy, whatever its physics: FMI 2.0 schema
and FMPy's validation, a self-contained binary, the variable table generated
from the XML agreeing with the XML, declared dependencies that hold, state
round trips, and misuse answered with fmi2Error and a message."""
import math
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import FMU_NAMES, ROOT, fmu_file, init

SYSTEM_LIBS = {"linux-vdso.so.1", "libc.so.6", "libm.so.6", "libstdc++.so.6",
               "libgcc_s.so.1", "ld-linux-x86-64.so.2", "libdl.so.2", "libpthread.so.0"}


@pytest.fixture
def so_path(tmp_path):
    """the shared object as shipped inside fmus/<name>.fmu"""
    def extract(name):
        member = f"binaries/linux64/{name}.so"
        with zipfile.ZipFile(fmu_file(name)) as z:
            z.extract(member, tmp_path)
        return tmp_path / member
    return extract


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmpy_validate_and_xsd(name):
    """fmpy validate: the FMI 2.0 XSD, variable names, ModelStructure, start values, units."""
    assert validate_fmu(str(fmu_file(name))) == []


@pytest.mark.parametrize("name", FMU_NAMES)
def test_archive_layout(name):
    with zipfile.ZipFile(fmu_file(name)) as z:
        names = set(z.namelist())
    assert "modelDescription.xml" in names
    assert f"binaries/linux64/{name}.so" in names


@pytest.mark.parametrize("name", FMU_NAMES)
def test_binary_depends_only_on_system_libraries(name, so_path):
    """SUNDIALS is linked statically: ldd lists nothing but libc/libm/libstdc++/libgcc."""
    out = subprocess.run(["ldd", str(so_path(name))], capture_output=True, text=True, check=True).stdout
    libs = {line.split()[0].rsplit("/", 1)[-1] for line in out.splitlines() if line.strip()}
    assert libs <= SYSTEM_LIBS, f"non-system libraries: {libs - SYSTEM_LIBS}"
    assert "sundials" not in out


@pytest.mark.parametrize("name", FMU_NAMES)
def test_only_fmi_symbols_exported(name, so_path):
    out = subprocess.run(["nm", "-D", "--defined-only", str(so_path(name))],
                         capture_output=True, text=True, check=True).stdout
    symbols = [line.split()[-1] for line in out.splitlines() if line.strip()]
    assert symbols and all(s.startswith("fmi2") for s in symbols), \
        [s for s in symbols if not s.startswith("fmi2")]


def _get(fmu, v):
    vr = [v.valueReference]
    if v.type == "Real":
        return fmu.slave.getReal(vr)[0]
    if v.type in ("Integer", "Enumeration"):
        return fmu.slave.getInteger(vr)[0]
    if v.type == "Boolean":
        return bool(fmu.slave.getBoolean(vr)[0])
    return fmu.slave.getString(vr)[0].decode()


def _start(v):
    if v.type == "Real":
        return float(v.start)
    if v.type in ("Integer", "Enumeration"):
        return int(v.start)
    if v.type == "Boolean":
        return v.start in ("true", "1", True)
    return v.start


@pytest.mark.parametrize("name", FMU_NAMES)
def test_generated_table_agrees_with_xml(name, open_fmu):
    """Every parameter and input reads back its XML start value by its XML value
    reference: the C table generated at build time matches the XML."""
    fmu = open_fmu(name)
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    for v in fmu.md.modelVariables:
        if v.causality in ("parameter", "input"):
            assert _get(fmu, v) == _start(v), v.name


@pytest.mark.parametrize("name", FMU_NAMES)
def test_declared_dependencies_hold(name, open_fmu):
    """An output whose value moves when an input moves (no step in between)
    must list that input in ModelStructure/Outputs dependencies."""
    fmu = open_fmu(name)
    md = fmu.md
    init(fmu, **{v.name: 0.0 for v in md.modelVariables if v.name == "testSteerAmp"})
    outputs = {u.variable.name: u for u in md.outputs if u.variable.type == "Real"}
    out_vrs = [fmu.var(n).valueReference for n in outputs]
    base = np.array(fmu.slave.getReal(out_vrs))
    for v in md.modelVariables:
        if v.causality != "input" or v.type != "Real":
            continue
        x0 = float(v.start)
        fmu.set_values({v.name: x0 + 0.05})
        moved = np.array(fmu.slave.getReal(out_vrs))
        fmu.set_values({v.name: x0})
        for (oname, u), a, b in zip(outputs.items(), base, moved):
            if abs(a - b) > 1e-12 * (1 + abs(a)):
                deps = u.dependencies
                assert deps is None or v in deps, f"{oname} depends on {v.name} but does not declare it"


@pytest.mark.parametrize("name", FMU_NAMES)
def test_default_experiment_runs_in_fmpy(name):
    """`fmpy simulate fmus/<Name>.fmu` on its default experiment."""
    result = simulate_fmu(str(fmu_file(name)))
    md = read_model_description(str(fmu_file(name)))
    assert result["time"][-1] == pytest.approx(float(md.defaultExperiment.stopTime))
    for n in result.dtype.names:
        assert np.all(np.isfinite(result[n])), n


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("serialize", [False, True])
def test_fmu_state_round_trip(name, serialize, open_fmu):
    """simulate, save, continue, restore, continue again: identical outputs.
    The Real inputs move along a slow ramp from their start values (within
    their ranges), so an FMU without a built-in stimulus moves too."""
    fmu = open_fmu(name)
    init(fmu)
    outs = [v.valueReference for v in fmu.md.modelVariables if v.causality == "output" and v.type == "Real"]
    inputs = [v for v in fmu.md.modelVariables if v.causality == "input" and v.type == "Real"]
    h = 0.05

    def drive(t):
        for v in inputs:
            x0 = float(v.start)
            span = min(1.0, float(v.max) - x0) if v.max is not None else 1.0
            fmu.slave.setReal([v.valueReference], [x0 + 0.1 * span * t])

    def advance(t0, n=40):
        rows = []
        for i in range(n):
            drive(t0 + i * h)
            fmu.slave.doStep(t0 + i * h, h)
            rows.append(fmu.slave.getReal(outs))
        return rows

    advance(0.0)
    state = fmu.slave.getFMUstate()
    if serialize:
        state = fmu.slave.deSerializeFMUstate(fmu.slave.serializeFMUstate(state))
    first = advance(40 * h)
    fmu.slave.setFMUstate(state)
    second = advance(40 * h)
    fmu.slave.freeFMUstate(state)
    assert np.array_equal(np.array(first), np.array(second))
    assert not np.array_equal(np.array(first[0]), np.array(first[-1])), "nothing moved: the test cannot fail"


def _expect_error(fmu, call, *words):
    fmu.log.clear()
    with pytest.raises(FMICallException):
        call()
    text = " ".join(fmu.log)
    for w in words:
        assert w in text, f"{w!r} not in log: {text}"


@pytest.mark.parametrize("name", FMU_NAMES)
def test_misuse_is_an_error_with_a_message(name, open_fmu):
    fmu = open_fmu(name)
    md = fmu.md
    _expect_error(fmu, lambda: fmu.slave.doStep(0.0, 0.1), "fmi2DoStep", "illegal call sequence")
    fmu.slave.reset()
    out = next(v for v in md.modelVariables if v.causality == "output")
    init(fmu)
    _expect_error(fmu, lambda: fmu.slave.setReal([out.valueReference], [1.0]), out.name, "cannot be set")
    fmu.slave.reset()
    fixed = next(v for v in md.modelVariables if v.causality == "parameter" and v.variability == "fixed")
    init(fmu)
    _expect_error(fmu, lambda: fmu.set_values({fixed.name: _start(fixed)}), fixed.name, "step complete")
    fmu.slave.reset()
    init(fmu)
    _expect_error(fmu, lambda: fmu.slave.doStep(1.0, 0.1), "currentCommunicationPoint")
    fmu.slave.reset()
    for v in md.modelVariables:
        if v.causality == "input" and v.type == "Real":
            for bad in (math.nan, math.inf, -math.inf):
                init(fmu)
                _expect_error(fmu, lambda: fmu.set_values({v.name: bad}), v.name, str(bad))
                fmu.slave.reset()


def _fmi_sim():
    import shutil
    local = ROOT / ".tools" / "bin" / "fmi-sim"
    return str(local) if local.is_file() else shutil.which("fmi-sim")


@pytest.mark.skipif(_fmi_sim() is None, reason="fmi-sim (crates.io) not installed: scripts/setup_test.sh builds it when cargo is present")
@pytest.mark.parametrize("name", FMU_NAMES)
def test_runs_in_fmi_sim_like_in_fmpy(name, tmp_path):
    """A second importer (fmi-sim, Rust) on the default experiment gives FMPy's results."""
    out = tmp_path / "fmi-sim.csv"
    md = read_model_description(str(fmu_file(name)))
    step = float(md.defaultExperiment.stepSize)
    r = subprocess.run([_fmi_sim(), "-q", "--model", str(fmu_file(name)), "-o", str(out),
                        "co-simulation", "--step", repr(step), "-n", "0"],
                       capture_output=True, text=True, env={"RUST_BACKTRACE": "0", "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr[-2000:]
    import csv
    with open(out) as f:
        rows = list(csv.DictReader(f))
    ours = simulate_fmu(str(fmu_file(name)), step_size=step, output_interval=step)
    last = {k: {"true": 1.0, "false": 0.0}.get(v, None) if v in ("true", "false") else float(v)
            for k, v in rows[-1].items() if k in ours.dtype.names}   # FMPy records no String
    assert len(rows) == len(ours)
    assert last["time"] == pytest.approx(ours["time"][-1])
    for n in ours.dtype.names[1:]:   # to the integrators' tolerance, on the signal's scale
        scale = float(np.max(np.abs(ours[n].astype(float))))
        assert last[n] == pytest.approx(float(ours[n][-1]), rel=1e-5, abs=1e-6 * scale + 1e-9), n
