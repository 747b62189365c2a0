"""The FMI 3.0 build of every FMU (fmus/fmi3/<Name>.fmu, src/fmi/fmi3Functions.c on the
same model code and fmu_core.c as FMI 2.0).

- Both model descriptions describe the same variables, units, ranges and start values:
  each parsed on its own by FMPy (fmpy.read_model_description), compared name by name;
  FMI 3.0 adds exactly the independent variable time and, for Model Exchange, the event
  indicators as variables.
- `fmpy validate` finds nothing in any FMI 3.0 FMU.
- Each FMU's default experiment run as FMI 3.0 equals its FMI 2.0 run within 1e-12
  relative on every output (the same model code: bit for bit is expected), in
  Co-Simulation (also with Event Mode, and with early return allowed) and, where
  offered, Model Exchange: the four modes fmusim would run (fmusim's engine fmi-rs runs them too:
  tests/test_fmirs.py).
- FMU state: get, serialize, deserialize, set, continue: the same outputs bit for bit as
  the uninterrupted run; a corrupted serialized state is refused.
- Misuse: a call in the wrong state, a NaN input, an out-of-range parameter, a Model
  Exchange call to a Co-Simulation-only FMU, an unsupported call: fmi3Error, with a
  message through the logger that names the function and the variable.
"""
import ctypes
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3LogMessageCallback
from fmpy.validation import validate_fmu

from artibus import fmu_dir
import test_win64
from conftest import FMU_NAMES, fmu_file

ROOT = Path(__file__).resolve().parents[1]

FMI3_TYPE = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String",
             "Enumeration": "Enumeration"}


def fmu3_file(name):
    path = fmu_dir() / "fmi3" / f"{name}.fmu"
    assert path.is_file(), f"{path} not built: run the set-up command of the README"
    return path


_MD = {}


def md(name, version):
    key = (name, version)
    if key not in _MD:
        _MD[key] = read_model_description(str(fmu_file(name) if version == 2 else fmu3_file(name)))
    return _MD[key]


def has_me(name):
    return md(name, 2).modelExchange is not None


def _num(x):
    return None if x is None else float(x)


# ---- the two model descriptions agree ------------------------------------------

@pytest.mark.parametrize("name", FMU_NAMES)
def test_both_model_descriptions_describe_the_same_variables(name):
    m2, m3 = md(name, 2), md(name, 3)
    assert m2.fmiVersion == "2.0" and m3.fmiVersion == "3.0"
    assert m3.instantiationToken == m2.guid
    v2 = {v.name: v for v in m2.modelVariables}
    v3 = {v.name: v for v in m3.modelVariables}
    nz = m2.numberOfEventIndicators
    added = {"time"} | {f"eventIndicator[{k}]" for k in range(1, nz + 1)}
    assert set(v3) - set(v2) == added and set(v2) <= set(v3)
    assert v3["time"].causality == "independent"
    assert len({v.valueReference for v in m3.modelVariables}) == len(m3.modelVariables), \
        "FMI 3.0 value references must be unique across types"
    for n, a in v2.items():
        b = v3[n]
        where = f"{name}.{n}"
        assert b.type == FMI3_TYPE[a.type], where
        assert (b.causality, b.variability, b.initial) == (a.causality, a.variability, a.initial), where
        assert b.description == a.description, where
        assert (b.unit, b.displayUnit) == (a.unit, a.displayUnit), where
        assert (b.declaredType and b.declaredType.name) == (a.declaredType and a.declaredType.name), where
        if a.type in ("Real", "Integer", "Enumeration"):
            assert (_num(b.min), _num(b.max), _num(b.nominal)) == (_num(a.min), _num(a.max), _num(a.nominal)), where
            assert _num(b.start) == _num(a.start), where
        else:
            assert b.start == a.start, where
        if a.derivative is not None:
            assert b.derivative is not None and b.derivative.name == a.derivative.name, where
    # the enumerations: the same types, items (name, value, description) and type descriptions
    # (FMPy does not read an FMI 2.0 SimpleType's description: compared in the XML)
    def enums(m):
        return {t.name: [(i.name, int(i.value), i.description) for i in t.items]
                for t in m.typeDefinitions if t.type == "Enumeration"}
    assert enums(m3) == enums(m2), name
    assert all(enums(m2).values())
    assert _type_descriptions(fmu_file(name), "SimpleType") == _type_descriptions(fmu3_file(name), "EnumerationType")
    for n, a in v2.items():
        if a.type == "Enumeration":     # a start value is one of its type's items
            assert a.start is None or int(a.start) in [v for _, v, _ in enums(m2)[a.declaredType.name]], n
    # units, display units, the default experiment, the log categories
    def units(m):
        base = ("kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor", "offset")
        return {u.name: (u.baseUnit and tuple(getattr(u.baseUnit, k) for k in base),
                         [(d.name, d.factor, d.offset) for d in u.displayUnits])
                for u in m.unitDefinitions}
    assert units(m3) == units(m2)
    e2, e3 = m2.defaultExperiment, m3.defaultExperiment
    assert (e3.startTime, e3.stopTime, e3.stepSize, e3.tolerance) == \
        (e2.startTime, e2.stopTime, e2.stepSize, e2.tolerance)
    assert [c.name for c in m3.logCategories] == [c.name for c in m2.logCategories]
    # the model structure: the same outputs, states and dependencies, by name
    def deps(unknowns):
        return {u.variable.name: None if u.dependencies is None else sorted(d.name for d in u.dependencies)
                for u in unknowns}
    assert deps(m3.outputs) == deps(m2.outputs)
    assert [u.variable.name for u in m3.derivatives] == [u.variable.name for u in m2.derivatives]
    assert deps(m3.initialUnknowns) == deps(m2.initialUnknowns)
    assert [u.variable.name for u in m3.eventIndicators] == [f"eventIndicator[{k}]" for k in range(1, nz + 1)]
    # the interfaces
    assert (m3.modelExchange is None) == (m2.modelExchange is None)
    assert m3.coSimulation.canHandleVariableCommunicationStepSize
    assert m3.coSimulation.hasEventMode
    for it in (m3.coSimulation, m3.modelExchange):
        if it is not None:
            # FMPy's names (FMI 2.0's spelling) for canGetAndSetFMUState, canSerializeFMUState,
            # providesDirectionalDerivatives
            assert it.canGetAndSetFMUstate and it.canSerializeFMUstate
    # FMPy reads FMI 2.0's providesDirectionalDerivative only (the FMI 3.0 spelling's value is in
    # test_jacobian_stated_and_documented / test_no_jacobian_stated_and_documented)
    for it in (m2.coSimulation, m2.modelExchange):
        if it is not None:
            assert it.providesDirectionalDerivative == (name in JACOBIAN_FMUS)


def _type_descriptions(fmu, tag):
    import xml.etree.ElementTree as ET
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    return {t.get("name"): t.get("description") for t in root.iter(tag)
            if tag == "EnumerationType" or t.find("Enumeration") is not None}


#: the C constants each choice's code compares with (the models' own headers), by enumeration
#: type: the items' values must be these, or the FMU would show one name and do another
C_CHOICES = {
    ("BusDynamics", "TyreModel"): ("src/models/BusDynamics/dynamics.h",
                                   ["TYRE_LINEAR", "TYRE_LINEAR_FRICTION", "TYRE_FIALA", "TYRE_LINEAR_SCALED"]),
    ("ForceMinimization", "SteeringLaw"): ("src/models/ForceMinimization/config.h",
                                           ["LAW_STRAIGHT", "LAW_FORCE_MINIMIZATION", "LAW_LIKE_GUIDED"]),
    ("RoadFollowDriver", "Road"): ("src/models/RoadFollowDriver/roads.h",
                                   ["ROAD_CSV", "ROAD_LANE_CHANGE", "ROAD_CIRCLE", "ROAD_ISO3888"]),
}


def _c_enum(path, names):
    """the values of C enum constants (an enum { A = 0, B, ... } list: implicit ones count on)"""
    text = (ROOT / path).read_text()
    body = next(m.group(1) for m in re.finditer(r"enum\s*\w*\s*\{([^}]*)\}", text) if names[0] in m.group(1))
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    values, k = {}, -1
    for part in body.split(","):
        m = re.match(r"\s*(\w+)\s*(?:=\s*(\d+))?\s*$", part)
        if m:
            k = int(m.group(2)) if m.group(2) else k + 1
            values[m.group(1)] = k
    return [values[n] for n in names]


@pytest.mark.parametrize("name,tname", sorted(C_CHOICES))
def test_enumeration_items_are_the_codes_constants(name, tname):
    path, names = C_CHOICES[(name, tname)]
    (t,) = [t for t in md(name, 2).typeDefinitions if t.name == tname]
    assert [int(i.value) for i in t.items] == _c_enum(path, names)


#: the plants with exact directional derivatives (issue 43: tests/test_directional_derivatives.py)
JACOBIAN_FMUS = {"ArticulationDamper", "BusDynamics", "BusKinematics", "MultiAxle3DOF"}


@pytest.mark.parametrize("name", [n for n in FMU_NAMES if n not in JACOBIAN_FMUS])
def test_no_jacobian_stated_and_documented(name):
    """no model but JACOBIAN_FMUS exports a Jacobian: every interface of the FMI 3.0 description
    states providesDirectionalDerivatives and providesAdjointDerivatives false (FMI 3.0, 2.4.1:
    the calls are then not to be made; ours answer fmi3Error), and the FMU's documentation says
    why, and why its vectors are scalars"""
    import xml.etree.ElementTree as ET
    with zipfile.ZipFile(fmu3_file(name)) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        page = z.read("documentation/index.html").decode()
    interfaces = [e for e in root if e.tag in ("CoSimulation", "ModelExchange")]
    assert interfaces
    for e in interfaces:
        assert e.get("providesDirectionalDerivatives") == "false", e.tag
        assert e.get("providesAdjointDerivatives") == "false", e.tag
    assert not list(root.iter("Dimension"))          # the flat names: no FMI 3.0 array
    assert "<th>derivatives</th><td>providesDirectionalDerivatives and providesAdjointDerivatives are false" in page
    assert "no analytic Jacobian" in page and "<th>arrays</th>" in page


@pytest.mark.parametrize("name", sorted(JACOBIAN_FMUS))
def test_jacobian_stated_and_documented(name):
    """the plants with directional derivatives state both true on both interfaces, and their
    documentation says what the derivatives are"""
    import xml.etree.ElementTree as ET
    with zipfile.ZipFile(fmu3_file(name)) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        page = z.read("documentation/index.html").decode()
    for e in [e for e in root if e.tag in ("CoSimulation", "ModelExchange")]:
        assert e.get("providesDirectionalDerivatives") == "true", e.tag
        assert e.get("providesAdjointDerivatives") == "true", e.tag
    assert "<th>derivatives</th><td>fmi3GetDirectionalDerivative and fmi3GetAdjointDerivative: the exact" in page


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmpy_validate(name):
    assert validate_fmu(str(fmu3_file(name))) == []


FMI3_FUNCTIONS = set(re.findall(r"FMI3_Export\s+\w+TYPE\s+(fmi3\w+);",
                                (ROOT / "include/fmi3/fmi3Functions.h").read_text()))


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmi3_binaries_only_fmi_symbols_exported(name, tmp_path):
    """binaries/x86_64-linux (and x86_64-windows where the win64 build made it): every
    FMI 3.0 function exported, nothing else; the DLL imports only Windows system DLLs
    (checks of the release binaries: not in the sanitizer pass, SANITIZE_SKIP)"""
    with zipfile.ZipFile(fmu3_file(name)) as z:
        names = z.namelist()
        z.extractall(tmp_path)
    assert f"binaries/x86_64-linux/{name}.so" in names
    assert not any(n.startswith(("binaries/linux64", "binaries/win64")) for n in names)
    # sources/ (with sources/buildDescription.xml) exactly where the FMI 2.0 FMU ships its sources
    with zipfile.ZipFile(fmu_file(name)) as z2:
        fmi2_sources = any(n.startswith("sources/") for n in z2.namelist())
    assert ("sources/buildDescription.xml" in names) == fmi2_sources
    nm = subprocess.run(["nm", "-D", "--defined-only", str(tmp_path / f"binaries/x86_64-linux/{name}.so")],
                        capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in nm.splitlines() if line.split()[1:2] == ["T"]}
    assert exported == FMI3_FUNCTIONS, sorted(exported ^ FMI3_FUNCTIONS)
    dll = tmp_path / f"binaries/x86_64-windows/{name}.dll"
    if f"binaries/x86_64-windows/{name}.dll" not in names:
        pytest.skip("no x86_64-windows binary: the win64 build (scripts/build_win64.sh) did not run")
    imports, exports = test_win64.pe_tables(dll)
    assert imports and all(test_win64.SYSTEM_DLLS.match(i) for i in imports), imports
    assert set(exports) == FMI3_FUNCTIONS, sorted(set(exports) ^ FMI3_FUNCTIONS)


# ---- FMI 3.0 runs as FMI 2.0 -------------------------------------------------------

def _same(name, r2, r3, what):
    outputs = [v.name for v in md(name, 2).modelVariables if v.causality == "output"
               and v.type != "String"]
    assert np.array_equal(r3["time"], r2["time"]), what
    assert outputs, what
    for n in outputs:
        a, b = np.asarray(r2[n], dtype=float), np.asarray(r3[n], dtype=float)
        bad = np.abs(a - b) > 1e-12 * np.maximum(np.abs(a), np.abs(b))
        assert not bad.any(), (f"{what}: {n} differs first at t = {r2['time'][bad.argmax()]}: "
                               f"{a[bad.argmax()]!r} (FMI 2.0) vs {b[bad.argmax()]!r} (FMI 3.0)")


CASES = [(n, "CoSimulation") for n in FMU_NAMES] + \
        [(n, "ModelExchange") for n in FMU_NAMES if n in
         ("ArticulationDamper", "BusDynamics", "BusKinematics", "MultiAxle3DOF")]


@pytest.mark.parametrize("name,interface", CASES)
def test_default_experiment_equals_fmi2(name, interface):
    assert interface == "CoSimulation" or has_me(name)
    r2 = simulate_fmu(str(fmu_file(name)), fmi_type=interface)
    r3 = simulate_fmu(str(fmu3_file(name)), fmi_type=interface)
    _same(name, r2, r3, f"{name} {interface}")


@pytest.mark.parametrize("mode", ["use_event_mode", "early_return_allowed"])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_co_simulation_with_event_mode_and_early_return(name, mode):
    """FMPy's FMI 3.0 Co-Simulation with Event Mode, and with early return allowed (the FMU
    handles its events inside the step and never returns early): the same results"""
    r2 = simulate_fmu(str(fmu_file(name)))
    r3 = simulate_fmu(str(fmu3_file(name)), **{mode: True})
    _same(name, r2, r3, f"{name} CS {mode}")


#: a stimulus where the default experiment has (almost) none: the built-in test steering,
#: or inputs held away from zero (the damper), the driver on its own test vehicle
STIMULUS = {
    "ArticulationDamper": {"Lambda": 0.3, "LambdaDot": 0.2, "pct": 20.0},
    "BusDynamics": {"testSteerAmp": 0.05},
    "BusKinematics": {"testSteerAmp": 0.05},
    "ForceMinimization": {"testSteerAmp": 0.05},
    "MultiAxle3DOF": {"testSteerAmp": 0.05},
    "RoadFollowDriver": {"testVehicle": True},
    "TrainGuidance": {"testSteerAmp": 0.05},
    "ZeroSideslipSteering": {"testSteerAmp": 0.05, "testSpeedRate": 0.5},
}


@pytest.mark.parametrize("name,interface", [c for c in CASES if c[0] in STIMULUS])
def test_stimulated_run_equals_fmi2(name, interface):
    """the same with the outputs moving: at least one output changes over the run"""
    start = STIMULUS[name]
    r2 = simulate_fmu(str(fmu_file(name)), fmi_type=interface, start_values=start)
    r3 = simulate_fmu(str(fmu3_file(name)), fmi_type=interface, start_values=start)
    moving = [v.name for v in md(name, 2).modelVariables if v.causality == "output"
              and v.type == "Real" and np.ptp(r2[v.name]) > 0]
    assert moving, f"{name}: the stimulus moves no output"
    _same(name, r2, r3, f"{name} {interface} with {start}")


def test_model_exchange_plants_listed():
    """CASES' Model Exchange list is every FMU with <ModelExchange>"""
    assert sorted(n for n in FMU_NAMES if has_me(n)) == sorted(n for n, i in CASES if i == "ModelExchange")


# ---- a slave with a logger --------------------------------------------------------

class Slave:
    """An FMI 3.0 Co-Simulation (or Model Exchange) instance through FMPy, its log kept."""

    def __init__(self, name, tmp_path, me=False, **kw):
        self.md = md(name, 3)
        unzip = tmp_path / f"{name}-{id(self)}"
        with zipfile.ZipFile(fmu3_file(name)) as z:
            z.extractall(unzip)
        self.unzip = unzip
        self.log = []
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        cls = FMU3Model if me else FMU3Slave
        self.fmu = cls(guid=self.md.instantiationToken, unzipDirectory=str(unzip),
                       modelIdentifier=name, instanceName="i")

        def logger(env, status, category, message):
            self.log.append((status, category.decode(), message.decode()))

        self._cb = fmi3LogMessageCallback(logger)
        if me:
            self.fmu.instantiate(logMessage=logger)
        else:
            self.fmu.instantiate(logMessage=logger, **kw)

    def error(self, call, *args):
        """call(*args) fails with fmi3Error; returns the logged error messages"""
        self.log.clear()
        with pytest.raises(FMICallException) as e:
            call(*args)
        assert "status 3" in str(e.value)
        return " | ".join(m for s, c, m in self.log if s == 3)

    def free(self):
        try:
            self.fmu.freeInstance()
        finally:
            shutil.rmtree(self.unzip, ignore_errors=True)


@pytest.fixture
def slave(tmp_path):
    made = []

    def make(name, **kw):
        s = Slave(name, tmp_path, **kw)
        made.append(s)
        return s

    yield make
    for s in made:
        s.free()


def _outputs(s):
    vrs = [v.valueReference for v in s.md.modelVariables if v.causality == "output" and v.type == "Float64"]
    return np.array(s.fmu.getFloat64(vrs))


@pytest.mark.parametrize("name", FMU_NAMES)
def test_state_round_trip(name, slave):
    """a state got and serialized at t1, deserialized and set after more steps (also into a
    fresh instance): the run continues bit for bit as the uninterrupted one"""
    h = float(md(name, 3).defaultExperiment.stepSize or 0.01)
    s = slave(name)
    s.fmu.enterInitializationMode(startTime=0.0)
    s.fmu.exitInitializationMode()
    t = 0.0
    for _ in range(20):
        s.fmu.doStep(t, h)
        t += h
    state = s.fmu.getFMUState()
    data = s.fmu.serializeFMUState(state)
    s.fmu.freeFMUState(state)
    t1 = t
    ref = []
    for _ in range(20):
        s.fmu.doStep(t, h)
        t += h
        ref.append(_outputs(s))
    for target in (s, slave(name)):
        st = target.fmu.deserializeFMUState(data)
        target.fmu.setFMUState(st)
        target.fmu.freeFMUState(st)
        t = t1
        for k in range(20):
            target.fmu.doStep(t, h)
            t += h
            assert np.array_equal(_outputs(target), ref[k]), f"{name}: step {k} after the restore"
    # a changed byte in the body: refused, the instance unchanged
    bad = bytearray(data)
    bad[-9] ^= 0x10
    msg = s.error(s.fmu.deserializeFMUState, bytes(bad))
    assert "fmi3DeserializeFMUState" in msg and "checksum" in msg


def test_call_order_nan_and_range(slave):
    s = slave("ArticulationDamper")
    msg = s.error(s.fmu.doStep, 0.0, 0.01)
    assert "fmi3DoStep" in msg and "illegal call sequence" in msg and "instantiated" in msg
    s = slave("ArticulationDamper")
    msg = s.error(s.fmu.setFloat64, [s.vr["R"]], [50.0])
    assert "fmi3SetFloat64" in msg and "R = 50" in msg and "maximum 2" in msg
    s = slave("ArticulationDamper")
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    msg = s.error(s.fmu.setFloat64, [s.vr["Lambda"]], [float("nan")])
    assert "fmi3SetFloat64" in msg and "Lambda = nan is not a finite number" in msg
    # in the error state only getters, reset, free: a step is refused
    msg = s.error(s.fmu.doStep, 0.0, 0.01)
    assert "illegal call sequence" in msg and "'error'" in msg
    s = slave("ArticulationDamper")
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    msg = s.error(s.fmu.setFloat64, [s.vr["R"]], [0.3])
    assert "fixed" in msg and "cannot be set in state 'step mode'" in msg


def test_unsupported_calls_are_errors(slave):
    s = slave("SteeringECU")
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    out = s.vr[next(v.name for v in s.md.modelVariables if v.causality == "output")]
    inp = s.vr[next(v.name for v in s.md.modelVariables if v.causality == "input")]
    msg = s.error(s.fmu.getDirectionalDerivative, [out], [inp], [1.0])
    assert "providesDirectionalDerivatives = false" in msg
    s = slave("SteeringECU")
    msg = s.error(s.fmu.fmi3GetContinuousStates, s.fmu.component,
                  (ctypes.c_double * 1)(), 1)
    assert "fmi3GetContinuousStates" in msg and "Model Exchange" in msg
    s = slave("SteeringECU")
    s.fmu.enterInitializationMode()
    msg = s.error(s.fmu.getFloat32, [0])
    assert "no Float32 variable" in msg


def test_model_exchange_instance_of_a_cs_only_fmu_is_refused(tmp_path):
    with pytest.raises(Exception, match="instantiate"):
        Slave("SteeringECU", tmp_path, me=True)


def test_enumeration_is_int64(slave):
    s = slave("TypesTest")
    s.fmu.enterInitializationMode()
    s.fmu.setInt64([s.vr["enum_in"]], [3])
    s.fmu.exitInitializationMode()
    assert s.fmu.getInt64([s.vr["enum_out"]]) == [3]
    msg = s.error(s.fmu.setInt64, [s.vr["enum_in"]], [4])
    assert "enum_in = 4 is above its maximum 3" in msg


# ---- artibus simulate --fmi 3 ---------------------------------------------------

@pytest.mark.parametrize("name,values", [("BusKinematics", ["--set", "testSteerAmp=0.05"]),
                                         ("TypesTest", []), ("SteeringECU", [])])
def test_artibus_simulate_fmi3_writes_the_fmi2_results(name, values, tmp_path):
    """artibus simulate NAME --fmi 3 (artibus.fmu.Fmu on FMPy's FMU3Slave): the same CSV,
    byte for byte, as the FMI 2.0 build's"""
    from artibus.cli import main
    assert main(["simulate", name, *values, "-o", str(tmp_path / "2.csv")]) == 0
    assert main(["simulate", name, "--fmi", "3", *values, "-o", str(tmp_path / "3.csv")]) == 0
    assert (tmp_path / "3.csv").read_bytes() == (tmp_path / "2.csv").read_bytes()


def test_artibus_simulate_fmi3_error_names_the_fmu_and_the_message():
    from artibus.fmu import SimulationError, simulate
    with pytest.raises(SimulationError) as e:
        simulate(fmu3_file("ArticulationDamper"), inputs={"Lambda": lambda t: float("nan") if t > 0.05 else 0.0},
                 stop_time=0.2)
    assert "ArticulationDamper failed at t = 0.06" in str(e.value)
    assert "fmi3SetFloat64: Lambda = nan is not a finite number" in str(e.value)
    assert abs(e.value.result.rows[-1][0] - 0.06) < 1e-9     # the rows up to the failure kept


# ---- the x86_64-windows binary under Wine ---------------------------------------------

@pytest.fixture(scope="module")
def fmi3_run(tmp_path_factory):
    """tests/c/fmi3_run.c built for linux (cc) and win64 (mingw-w64): (linux exe, win exe)"""
    d = tmp_path_factory.mktemp("fmi3_run")
    src, inc = ROOT / "tests/c/fmi3_run.c", f"-I{ROOT / 'include/fmi3'}"
    subprocess.run(["cc", "-O1", "-std=gnu11", "-Wall", "-Wextra", "-Werror", inc, str(src),
                    "-o", str(d / "fmi3_run"), "-ldl"], check=True)
    mingw = shutil.which("x86_64-w64-mingw32-gcc")
    if mingw:
        subprocess.run([mingw, "-O1", "-std=gnu11", "-Wall", "-Wextra", "-Werror", inc, str(src),
                        "-o", str(d / "fmi3_run.exe"), "-static"], check=True)
    return d / "fmi3_run", (d / "fmi3_run.exe" if mingw else None)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmi3_win64_cosimulation_equals_x86_64_linux(name, fmi3_run, tmp_path):
    """the x86_64-windows DLL, run under Wine by a small FMI 3.0 importer (tests/c/fmi3_run.c
    cross-compiled), ends at least 200 steps of the default experiment where the x86_64-linux
    binary does (the same importer, native), within 1e-12 relative on every Float64 output"""
    linux_exe, win_exe = fmi3_run
    wine = test_win64._wine()
    if win_exe is None:
        pytest.skip("no mingw-w64 compiler (apt package mingw-w64)")
    m = md(name, 3)
    with zipfile.ZipFile(fmu3_file(name)) as z:
        if f"binaries/x86_64-windows/{name}.dll" not in z.namelist():
            pytest.skip("no x86_64-windows binary: the win64 build (scripts/build_win64.sh) did not run")
        z.extractall(tmp_path)
    (tmp_path / "resources").mkdir(exist_ok=True)
    h = float(m.defaultExperiment.stepSize)
    n = min(200, int(round(float(m.defaultExperiment.stopTime) / h)))
    outs = [f"{v.valueReference}={v.name}" for v in m.modelVariables
            if v.causality == "output" and v.type == "Float64"]

    def run(cmd, binary, resources, under_wine=False):
        full = cmd + [str(binary), m.instantiationToken, resources, repr(h), str(n), *outs]
        p = (test_win64._wine_run(full) if under_wine  # (Wine's own hiccups made again: _wine_run)
             else subprocess.run(full, capture_output=True, text=True, timeout=300))
        assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
        return {k: float(x) for k, x in (line.split() for line in p.stdout.splitlines())}

    lin = run([str(linux_exe)], tmp_path / f"binaries/x86_64-linux/{name}.so", str(tmp_path / "resources") + "/")
    win = run([wine, str(win_exe)], tmp_path / f"binaries/x86_64-windows/{name}.dll",
              str(tmp_path / "resources") + "\\", under_wine=True)
    assert set(win) == set(lin) == {o.split("=", 1)[1] for o in outs}
    for k, a in lin.items():
        assert abs(win[k] - a) <= 1e-12 * max(abs(a), abs(win[k])), f"{name}.{k}: {a!r} (linux) vs {win[k]!r} (win64)"


def test_restored_state_parameters_checked_as_model_init_does(slave):
    """fmu_core.c runs model_check_parameters on every restored state for FMI 3.0 too
    (tests/test_state_fuzzer.py's probe, through fmi3DeserializeFMUState): a
    RoadFollowDriver state whose lookFar0 = -1e308 (inside its declared range
    [-inf, 1000], behind the near look-ahead point) with a recomputed checksum
    (FNV-1a over the GUID field and the body) is refused, naming lookFar0"""
    import struct
    from test_state_fuzzer import HEADER, with_checksum
    s = slave("RoadFollowDriver")
    vr = s.vr["lookFar0"]
    v = next(x for x in s.md.modelVariables if x.name == "lookFar0")
    start = float(v.start)

    def serialized():
        st = s.fmu.getFMUState()
        data = bytes(s.fmu.serializeFMUState(st))
        s.fmu.freeFMUState(st)
        return data

    base = np.frombuffer(serialized(), dtype=np.uint8)
    s.fmu.setFloat64([vr], [start - 0.4375])
    moved = np.frombuffer(serialized(), dtype=np.uint8)
    s.fmu.setFloat64([vr], [start])
    off = HEADER + int(np.flatnonzero(base[HEADER:] != moved[HEADER:])[0]) // 8 * 8
    s.fmu.enterInitializationMode(startTime=0.0)
    s.fmu.exitInitializationMode()
    h = float(s.md.defaultExperiment.stepSize or 0.01)
    for k in range(10):
        s.fmu.doStep(k * h, h)
    bad = bytearray(serialized())
    struct.pack_into("<d", bad, off, -1e308)
    msg = s.error(s.fmu.deserializeFMUState, with_checksum(bad))
    assert "fmi3DeserializeFMUState" in msg and "parameters are not valid" in msg and "lookFar0" in msg, msg
