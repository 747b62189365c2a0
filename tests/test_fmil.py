"""Every FMU as the FMI Library (FMIL) reads it (issue 29): FMIL is the C loader under
libcosim, OMSimulator, PyFMI and many commercial importers. Here it is libcosim's, through
libcosimpy from PyPI (which bundles libcosim and FMIL), run by tests/libcosim_run.py in a
process of its own, whose output (libcosim's logger, FMIL's messages in it) is read whole.

- loading an FMU gives no warning or error from FMIL, and FMIL parses every interface the
  model description declares (a ModelExchange after CoSimulation it skips, with an error);
- its default experiment run in libcosim as Co-Simulation ends with every Real output equal
  to FMPy's run of the same FMU at the same step within 1e-9 relative (and 1e-12 absolute
  near zero), every Integer and Boolean output equal (FMPy's result records no String);
  the same with the plants and steering functions moving (start values, MOVING);
- every output reaches libcosim, or the test says which does not and libcosim's message.

Warnings that are not FMIL's: an FMU's own messages (libcosim tags them '[FMI status=...]',
FMPy shows the same) are the model's; libcosim's own must be listed in LIBCOSIM_WARNINGS.
"""
import functools
import json
import os
import re
import subprocess
import sys
import tempfile
import warnings
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description, simulate_fmu

from artibus import fmu_path

pytest.importorskip("libcosimpy", reason="libcosimpy (PyPI) not installed: pip install -e '.[test]'")

ROOT = Path(__file__).resolve().parents[1]
NAMES = sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))
WORKER = Path(__file__).with_name("libcosim_run.py")

#: the step for a default experiment without stepSize (every FMU gives one so far; a run
#: with this step says so as a warning): the ECUs' 10 ms
FALLBACK_STEP = 0.01
RTOL, ATOL = 1e-9, 1e-12

def _enumerations(name, causality=None):
    """the Enumeration variables of modelDescription/<name>.xml (of that causality)"""
    root = ET.parse(ROOT / "modelDescription" / f"{name}.xml").getroot()
    return [sv.get("name") for sv in root.iter("ScalarVariable") if sv.find("Enumeration") is not None
            and causality in (None, sv.get("causality", "local"))]


_IGNORED = "FMI 2.0 Enumeration variable type not supported, variable with name {} will be ignored"
#: libcosim's own warnings (not FMIL's) that are expected, with why; any other fails the test:
#: libcosim ignores every FMI 2.0 Enumeration variable (the choices: tyreModel, road, ...), so a
#: portable pack declares them as Integers (artibus.bench.portable.integer_view)
LIBCOSIM_WARNINGS = {
    n: re.compile(re.escape(_IGNORED).replace(re.escape("{}"), "(" + "|".join(map(re.escape, _enumerations(n))) + ")"))
    for n in NAMES if _enumerations(n)}
#: outputs libcosim cannot read (the comparison leaves them out; test_every_output_reaches_libcosim
#: fails on them, strictly expected)
NOT_IN_LIBCOSIM = {
    n: f"libcosim ignores FMI 2.0 Enumeration variables (its warning: '{_IGNORED.format(_enumerations(n, 'output')[0])}')"
    for n in NAMES if _enumerations(n, "output")}

#: a line of libcosim's console log: [time] [thread] [level] message
LOG_LINE = re.compile(r"^\[[^\]]*\] \[0x[0-9a-fA-F]+\] \[(\w+)\]\s*(.*)$")
PROBLEM_LEVELS = ("warning", "error", "fatal")


class LibcosimRun:
    """what tests/libcosim_run.py reported and logged for one FMU"""

    def __init__(self, fmu, start, stop, step, tmp, initial=()):
        fd, out = tempfile.mkstemp(prefix=f"{Path(fmu).stem}-", suffix=".json", dir=tmp)
        os.close(fd)
        out = Path(out)
        env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
        proc = subprocess.run([sys.executable, str(WORKER), str(fmu), repr(start), repr(stop), repr(step),
                               str(out)] + [f"{vr}={value!r}" for vr, value in initial],
                              capture_output=True, text=True, env=env, timeout=300)
        self.output = proc.stdout + proc.stderr
        assert proc.returncode == 0 and out.is_file(), \
            f"libcosim_run.py {fmu} ended with {proc.returncode}:\n{self.output[-3000:]}"
        self.result = json.loads(out.read_text())
        #: (level, message) of every log line; a message's continuation lines are joined to it
        self.log = []
        for line in self.output.splitlines():
            m = LOG_LINE.match(line)
            if m:
                self.log.append((m.group(1), m.group(2)))
            elif self.log and line.strip():
                self.log[-1] = (self.log[-1][0], self.log[-1][1] + "\n" + line)

    def fmil(self):
        """FMIL's messages: (level, message without the '[FMI Library: <module>]' tag)"""
        return [(lvl, msg) for lvl, msg in self.log if msg.startswith("[FMI Library")]


def fmil_complaints(run, md):
    """What is wrong with how FMIL read the FMU (empty: nothing): every FMIL warning or error
    line, and an interface element of the model description that FMIL did not parse."""
    complaints = [f"FMIL [{lvl}] {msg}" for lvl, msg in run.fmil() if lvl in PROBLEM_LEVELS]
    parsed = {m.group(1) for _, msg in run.fmil() for m in [re.search(r"Parsing XML element (\w+)$", msg)] if m}
    for kind, declared in (("ModelExchange", md.modelExchange), ("CoSimulation", md.coSimulation)):
        if declared is not None and kind not in parsed:
            complaints.append(f"FMIL did not parse the <{kind}> the model description declares")
    if run.result["slave"] < 0:
        complaints.append(f"libcosim could not load the FMU: {run.result['error']}")
    return complaints


def experiment(md):
    """(start, stop, step, note) of the model description's DefaultExperiment"""
    de = md.defaultExperiment
    start = float(de.startTime) if de is not None and de.startTime is not None else 0.0
    stop = float(de.stopTime) if de is not None and de.stopTime is not None else start + 1.0
    if de is not None and de.stepSize is not None:
        return start, stop, float(de.stepSize), None
    return start, stop, FALLBACK_STEP, f"no DefaultExperiment stepSize: step {FALLBACK_STEP} s used"


#: start values that make the plants and steering functions move in their default
#: experiments (at their defaults most of their outputs rest at zero), as
#: tests/test_model_exchange.py's for fmi-sim
MOVING = {"BusKinematics": {"testSteerAmp": 0.2}, "BusDynamics": {"testSteerAmp": 0.05},
          "MultiAxle3DOF": {"testSteerAmp": 0.02}, "TrainGuidance": {"testSteerAmp": 0.2},
          "ForceMinimization": {"testSteerAmp": 0.2}, "ZeroSideslipSteering": {"testSteerAmp": 0.05},
          "ArticulationDamper": {"LambdaDot": 0.2, "pct": 20.0, "tauP": 0.05}}


@functools.cache
def default_run(name, tmp, start_values=()):
    """libcosim's run of the FMU's default experiment (once per FMU, start values and process)"""
    md = read_model_description(str(fmu_path(name)))
    start, stop, step, note = experiment(md)
    if round(start * 1e9) != 0:
        pytest.skip(f"{name}: DefaultExperiment startTime = {start} s: libcosimpy's execution starts at 0")
    if abs((stop - start) / step - round((stop - start) / step)) > 1e-9:
        pytest.skip(f"{name}: ({stop} - {start}) s is no whole number of {step} s steps: "
                    "libcosim steps at a fixed step only")
    vrs = {v.name: v.valueReference for v in md.modelVariables if v.type == "Real"}
    initial = [(vrs[k], v) for k, v in start_values]
    return md, (start, stop, step, note), LibcosimRun(fmu_path(name), start, stop, step, tmp, initial)


@pytest.fixture(scope="module")
def tmp(tmp_path_factory):
    return str(tmp_path_factory.mktemp("libcosim"))


@pytest.mark.parametrize("name", NAMES)
def test_fmil_reads_without_warning_or_error(name, tmp):
    md, _, run = default_run(name, tmp)
    complaints = fmil_complaints(run, md)
    assert not complaints, "\n".join(complaints)
    # and libcosim's own warnings are the expected ones (the FMU's own messages aside)
    expected = LIBCOSIM_WARNINGS.get(name)
    other = [f"[{lvl}] {msg}" for lvl, msg in run.log
             if lvl in PROBLEM_LEVELS and not msg.startswith(("[FMI Library", "[FMI status="))
             and not (expected and expected.search(msg))]
    assert not other, "libcosim: " + "\n".join(other)


@pytest.mark.parametrize("name,start_values", [(n, ()) for n in NAMES]
                         + [(n, tuple(MOVING[n].items())) for n in sorted(MOVING)],
                         ids=NAMES + [f"{n}-moving" for n in sorted(MOVING)])
def test_default_experiment_in_libcosim_equals_fmpy(name, start_values, tmp):
    md, (start, stop, step, note), run = default_run(name, tmp, start_values)
    if note:
        warnings.warn(f"{name}: {note}")
    res = run.result
    assert res["slave"] >= 0, f"libcosim could not load {name}: {res['error']}"
    assert res["ok"], f"libcosim's run of {name} failed: {res['error']}"
    assert res["time"] == pytest.approx(stop, abs=1e-9)
    ref = simulate_fmu(str(fmu_path(name)), fmi_type="CoSimulation", start_time=start, stop_time=stop,
                       output_interval=step, start_values=dict(start_values))
    assert ref["time"][-1] == pytest.approx(stop, abs=1e-9)
    by_vr = {(v.type, str(v.valueReference)): v.name for v in md.modelVariables if v.causality == "output"}
    compared, bad = 0, []
    for tname, values in res["values"].items():
        for vr, value in values.items():
            vname = by_vr[(tname, vr)]
            fmpy_value = ref[vname][-1]
            if tname == "Real":
                ok = abs(value - fmpy_value) <= RTOL * max(abs(value), abs(fmpy_value)) + ATOL
            else:
                ok = value == fmpy_value
            compared += 1
            if not ok:
                bad.append(f"{vname}: libcosim {value!r}, FMPy {fmpy_value!r}")
    assert compared, f"{name}: no output to compare"
    assert not bad, f"{len(bad)} of {compared} outputs differ at t = {stop} s:\n" + "\n".join(bad)
    n_real = sum(1 for v in md.modelVariables if v.causality == "output" and v.type == "Real")
    assert len(res["values"].get("Real", {})) == n_real, "libcosim did not give every Real output"


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(reason=NOT_IN_LIBCOSIM[n], strict=True))
                                  if n in NOT_IN_LIBCOSIM else n for n in NAMES])
def test_every_output_reaches_libcosim(name, tmp):
    """the outputs libcosim lists (read through FMIL) are the model description's, by name,
    value reference and type"""
    md, _, run = default_run(name, tmp)
    kinds = {"Real": "REAL", "Integer": "INTEGER", "Boolean": "BOOLEAN", "String": "STRING"}
    ours = {(v.name, v.valueReference, kinds.get(v.type, v.type)) for v in md.modelVariables
            if v.causality == "output"}
    theirs = {(n, vr, t) for n, vr, t, c in run.result["variables"] if c == "OUTPUT"}
    missing = sorted(ours - theirs)
    said = [msg for lvl, msg in run.log if lvl in PROBLEM_LEVELS and any(m[0] in msg for m in missing)]
    assert not missing, f"not in libcosim: {missing}; libcosim said: {said}"
    assert theirs <= ours


def _with_cosimulation_first(src, dst):
    """a copy of the FMU whose modelDescription.xml declares <CoSimulation> before
    <ModelExchange> (the order of the model descriptions before issue 29)"""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                md = ET.fromstring(data)
                me, cs = md.find("ModelExchange"), md.find("CoSimulation")
                md.remove(me)
                md.insert(list(md).index(cs) + 1, me)
                data = ET.tostring(md, encoding="UTF-8", xml_declaration=True)
            zout.writestr(item, data)


def test_checker_flags_cosimulation_before_model_exchange(tmp_path):
    """the check above fails on the old order: FMIL's error, and Model Exchange not parsed"""
    old = tmp_path / "BusKinematics.fmu"
    _with_cosimulation_first(fmu_path("BusKinematics"), old)
    md = read_model_description(str(old))       # FMPy reads it, both interfaces
    assert md.modelExchange is not None and md.coSimulation is not None
    run = LibcosimRun(old, 0.0, 0.0, 0.05, tmp_path)
    complaints = fmil_complaints(run, md)
    assert any("XML element 'ModelExchange' cannot be placed after element 'CoSimulation'" in c
               for c in complaints), complaints
    assert "FMIL did not parse the <ModelExchange> the model description declares" in complaints
    # and the shipped FMU loads clean through the same check, load only
    shipped = LibcosimRun(fmu_path("BusKinematics"), 0.0, 0.0, 0.05, tmp_path)
    assert fmil_complaints(shipped, read_model_description(str(fmu_path("BusKinematics")))) == []
