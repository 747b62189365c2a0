"""Other people's SSPs (issue 40): files written as other SSP tools write them
(tests/ssp_corpus/, each folder an unpacked SSP with its stated result in a
comment), run against that result, computed here from the file's own
statement, not from the runner.

The FMUs are the Modelica Reference-FMUs (.tools/reference-fmus/, made by the
test set-up), some with their ModelStructure's dependencies removed, as many
exporters write them: each output then depends on every input (FMI 2.0 2.2.8,
FMI 3.0 2.4.8)."""
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

from artibus.base import ROOT, ArtibusError
from artibus.runner import Simulation

CORPUS = Path(__file__).parent / "ssp_corpus"
REFERENCE = ROOT / ".tools" / "reference-fmus"
OUT_A, OUT_B = "A.Float64_continuous_output", "B.Float64_continuous_output"


def reference_fmu(name):
    path = REFERENCE / f"{name}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/build_reference_fmus.sh)")
    return path


def without_dependencies(fmu, out):
    """A copy of the FMU whose ModelStructure declares no dependencies (the attributes
    dependencies and dependenciesKind removed, nothing else changed)."""
    with zipfile.ZipFile(fmu) as z, zipfile.ZipFile(out, "w") as o:
        for n in z.namelist():
            data = z.read(n)
            if n == "modelDescription.xml":
                text = data.decode()
                data = re.sub(r'\s(dependencies|dependenciesKind)="[^"]*"', "", text).encode()
                assert "dependencies" not in data.decode()
            o.writestr(n, data)
    return out


def corpus(name, tmp_path, fmus):
    """The corpus folder ``name`` copied to tmp_path with ``fmus`` {resources/...: path}."""
    folder = tmp_path / name
    shutil.copytree(CORPUS / name, folder)
    (folder / "resources").mkdir(exist_ok=True)
    for ref, path in fmus.items():
        shutil.copy(path, folder / ref)
    return folder


def packed(folder):
    """The unpacked SSP folder zipped into an .ssp beside it."""
    ssp = folder.with_suffix(".ssp")
    with zipfile.ZipFile(ssp, "w") as z:
        for f in sorted(folder.rglob("*")):
            if f.is_file():
                z.write(f, f.relative_to(folder).as_posix())
    return ssp


def loop(tmp_path, declared):
    tmp_path.mkdir(parents=True, exist_ok=True)
    fmu = reference_fmu("Feedthrough")
    if not declared:
        fmu = without_dependencies(fmu, tmp_path / "Feedthrough.fmu")
    return corpus("loop_no_dependencies", tmp_path, {"resources/Feedthrough.fmu": fmu})


def stimulus(t):
    return t * (1.0 + t)


def stated_loop(n, h, algorithm):
    """The corpus file's stated result: x (A's output) and y (B's) at t_0 .. t_n."""
    x, y = np.zeros(n + 1), np.zeros(n + 1)
    for k in range(n):
        x[k + 1] = y[k] + stimulus(k * h)
        y[k + 1] = x[k + 1] if algorithm == "gauss-seidel" else x[k]
    return x, y


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_loop_without_declared_dependencies_runs_with_one_step_of_delay(tmp_path, capfd, algorithm):
    """A two-FMU loop whose outputs declare no dependencies: Jacobi runs it with no order and no
    loop check; Gauss-Seidel breaks it at B -> A (A comes first in the file), warning once with
    that connection named (its file and line); both equal the stated recurrences."""
    ssp = packed(loop(tmp_path, declared=False))
    h, n = 0.1, 10
    with Simulation(ssp, step=h, algorithm=algorithm,
                    stimuli={"A.Float64_continuous_input": stimulus}) as sim:
        r = sim.run()
    x, y = stated_loop(n, h, algorithm)
    np.testing.assert_allclose(r.time, np.arange(n + 1) * h, atol=1e-12)
    np.testing.assert_allclose(r[OUT_A], x, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(r[OUT_B], y, rtol=1e-12, atol=1e-15)
    err = capfd.readouterr().err
    if algorithm == "jacobi":
        assert "loop" not in err, err
    else:
        line = next(k for k, s in enumerate((tmp_path / "loop_no_dependencies" / "SystemStructure.ssd")
                                              .read_text().splitlines(), 1) if 'startElement="B"' in s)
        assert re.search(r"warning: .*loop .*B\.Float64_continuous_output -> A\.Float64_continuous_input", err), err
        assert f"SystemStructure.ssd:{line}: Connection B.Float64_continuous_output -> A.Float64_continuous_input" \
            in err, err
        assert "one step of delay" in err


def test_declared_feedthrough_loop_is_an_error_under_gauss_seidel_and_runs_under_jacobi(tmp_path):
    """The same loop with the Reference-FMUs' own dependencies (output on the input, declared):
    an algebraic loop, refused under Gauss-Seidel naming the file and the loop; Jacobi runs it."""
    ssp = packed(loop(tmp_path, declared=True))
    with pytest.raises(ArtibusError) as e:
        Simulation(ssp, step=0.1)
    msg = str(e.value)
    assert str(ssp) in msg and "algebraic loop" in msg, msg
    assert "A.Float64_continuous_output -> B.Float64_continuous_output -> A.Float64_continuous_output" in msg \
        or "B.Float64_continuous_output -> A.Float64_continuous_output -> B.Float64_continuous_output" in msg, msg
    assert "--algorithm jacobi" in msg
    with Simulation(ssp, step=0.1, algorithm="jacobi", stimuli={"A.Float64_continuous_input": stimulus}) as sim:
        r = sim.run()
    x, y = stated_loop(10, 0.1, "jacobi")
    np.testing.assert_allclose(r[OUT_A], x, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(r[OUT_B], y, rtol=1e-12, atol=1e-15)


def test_check_lists_the_broken_loop_and_refuses_the_algebraic_one(tmp_path):
    """`artibus check` says where Gauss-Seidel breaks the loop (the connection, its line), as
    the run does; the loop of declared feedthrough is its error."""
    from artibus.bench.check import check_bench
    ssp = packed(loop(tmp_path / "assumed", declared=False))
    lines = []
    assert check_bench(str(ssp), lines.append) == 0
    text = "\n".join(lines)
    assert re.search(r"broken at .*SystemStructure\.ssd:\d+: Connection B\.Float64_continuous_output -> "
                     r"A\.Float64_continuous_input, one step of delay", text), text
    with pytest.raises(ArtibusError, match="algebraic loop"):
        check_bench(str(packed(loop(tmp_path / "declared", declared=True))), lines.append)


def omsimulator_style(tmp_path):
    return corpus("omsimulator_style", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})


@pytest.mark.parametrize("given", ["folder", "ssd", "ssp"])
def test_omsimulator_style_system_connectors_run_with_the_stated_result(tmp_path, given):
    """startElement="" is the enclosing system; parameters bound to its connectors reach the
    FMU variables connected to them; one connected to nothing is recorded as the connector's
    value (Bench.system_values), not refused; the unpacked folder, its .ssd and the packed
    .ssp all run, with the stated result."""
    from artibus.bench import ssp as ssp_mod
    folder = omsimulator_style(tmp_path)
    path = {"folder": folder, "ssd": folder / "SystemStructure.ssd", "ssp": None}[given] or packed(folder)
    with Simulation(path, step=0.25, record=[OUT_A, OUT_B, "A.Float64_fixed_parameter"]) as sim:
        r = sim.run()
        assert sim.bench.system_values == {"unused": 42.0}
    np.testing.assert_array_equal(r.time, [0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_array_equal(r[OUT_A], 1.5)
    np.testing.assert_array_equal(r[OUT_B], 1.5)
    np.testing.assert_array_equal(r["A.Float64_fixed_parameter"], 0.25)
    assert ssp_mod.read(ssp_mod.ssp_path(path)).file == (
        str(folder / "SystemStructure.ssd") if given != "ssp" else f"{path}/SystemStructure.ssd")


def test_check_of_an_unpacked_ssp_names_its_own_file_and_the_unconnected_connector(tmp_path):
    from artibus.bench.check import main
    folder = omsimulator_style(tmp_path)
    lines = []
    assert main([str(folder)], out=lines.append) == 0
    text = "\n".join(lines)
    assert lines[0] == f"model: {folder / 'SystemStructure.ssd'}", lines[0]
    assert "system connector unused = 42.0" in text, text


FMI1 = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="1.0" modelName="Old" modelIdentifier="Old" guid="{0}" numberOfContinuousStates="0"
  numberOfEventIndicators="0"><ModelVariables><ScalarVariable name="Float64_continuous_output" valueReference="0"
  causality="output"><Real/></ScalarVariable></ModelVariables>
  <Implementation><CoSimulation_StandAlone><Capabilities/></CoSimulation_StandAlone></Implementation>
</fmiModelDescription>"""


@pytest.mark.parametrize("fault, words", [
    ("connector", ['Connection A.Float64_continuous_output -> z:', "the system' declares no connector 'z'"]),
    ("missing", ['<Component name="A" source="resources/Feedthrough.fmu">', "no such file"]),
    ("fmi1", ["Component 'A'", 'fmiVersion="1.0"']),
])
def test_bad_foreign_files_are_refused_naming_file_line_element(tmp_path, fault, words):
    folder = corpus("errors", tmp_path, {} if fault == "missing" else
                    {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    ssd = folder / "SystemStructure.ssd"
    text = ssd.read_text()
    if fault == "connector":
        text = text.replace('endConnector="y"', 'endConnector="z"')
    ssd.write_text(text)
    if fault == "fmi1":
        with zipfile.ZipFile(folder / "resources" / "Feedthrough.fmu", "w") as z:
            z.writestr("modelDescription.xml", FMI1)
    element = {"connector": "<ssd:Connection ", "missing": "<ssd:Component ", "fmi1": "<ssd:Component "}[fault]
    line = next(k for k, s in enumerate(text.splitlines(), 1) if element in s)
    with pytest.raises(ArtibusError) as e:
        with Simulation(folder, step=0.1) as sim:
            sim.run()
    msg = str(e.value)
    assert f"{ssd}:{line}" in msg, msg
    assert all(w in msg for w in words), msg


def test_empty_element_inside_a_sub_system_is_that_system(tmp_path):
    """endElement="" inside SCSystem names SCSystem's own connector (not a system "SCSystem.")."""
    folder = corpus("omsimulator_nested", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    with Simulation(packed(folder), step=0.5) as sim:
        r = sim.run()
    np.testing.assert_array_equal(r["SCSystem.A.Float64_continuous_output"], 1.5)
    np.testing.assert_array_equal(r[OUT_B], 1.5)


def test_omsimulator3_version_2_on_ssp1_content_reads_as_ssp1_with_a_warning(tmp_path, capfd):
    """version="2.0" on a file of SSP 1.0 content (OMSimulator 3.x): runs with the stated result
    (as omsimulator_style), a warning says it is read as SSP 1.0, `check` says what it is and
    shows no FMI-LS-BUS network."""
    from artibus.bench.check import check_bench
    folder = corpus("omsimulator3_version", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    ssp = packed(folder)
    with Simulation(ssp, step=0.5) as sim:
        r = sim.run()
        assert (sim.bench.version, sim.bench.read_as) == ("2.0", "1.0")
    np.testing.assert_array_equal(r[OUT_B], 1.5)
    assert re.search(r'warning: .*SystemStructure\.ssd:\d+: <SystemStructureDescription version="2\.0">: SSP 1\.0 '
                     r'content only.*read as SSP 1\.0', capfd.readouterr().err)
    lines = []
    check_bench(str(ssp), lines.append)
    text = "\n".join(lines)
    assert 'says version="2.0" but holds SSP 1.0 content only' in text, text
    assert "LS-BUS network" not in text.replace("no FMI-LS-BUS network", ""), text


def test_omsimulator3_version_2_parameter_files_read_as_ssp1_with_a_warning(tmp_path, capfd):
    """.ssv and .ssm files of version="2.0" on SSP 1.0 content (OMSimulator 3.x): bound through
    the mapping with the stated result, a warning naming each file; the same .ssv given to
    --ssv reads too."""
    from artibus.bench.parameters import read_parameters
    folder = corpus("omsimulator3_files", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    ssp = packed(folder)
    with Simulation(ssp, step=0.5, record=[OUT_A, OUT_B, "A.Float64_fixed_parameter"]) as sim:
        r = sim.run()
        assert sim.bench.system_values == {"unused": 42.0}
    np.testing.assert_array_equal(r[OUT_A], 1.5)            # 2 * 0.75, the .ssm's factor on the .ssv's value
    np.testing.assert_array_equal(r[OUT_B], 1.5)
    np.testing.assert_array_equal(r["A.Float64_fixed_parameter"], 0.25)
    err = capfd.readouterr().err
    for member, root in (("parameters.ssv", "ParameterSet"), ("mapping.ssm", "ParameterMapping")):
        assert re.search(rf'warning: .*resources/{re.escape(member)}:\d+: <{root} version="2\.0">: SSP 1\.0 '
                         rf'content only.*read as SSP 1\.0', err), err
    ssv = folder / "resources" / "parameters.ssv"
    assert read_parameters(str(ssv)) == {"in": 0.75, "b": 0.25, "u": 42.0}


def test_version_2_parameter_file_of_ssp2_content_is_refused_naming_file_and_line(tmp_path):
    """A version="2.0" .ssv holding an SSP 2.0 type (ssv:Float32, SSP 2.0 6) is not SSP 1.0
    content: refused, naming the file and the line of the element SSP 1.0 does not know."""
    folder = corpus("omsimulator3_files", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    ssv = folder / "resources" / "parameters.ssv"
    text = ssv.read_text().replace('<ssv:Real value="0.25"/>', '<ssv:Float32 value="0.25"/>')
    ssv.write_text(text)
    line = next(k for k, s in enumerate(text.splitlines(), 1) if "Float32" in s)
    with pytest.raises(ArtibusError) as e:
        with Simulation(packed(folder), step=0.5) as sim:
            sim.run()
    assert re.search(rf"resources/parameters\.ssv:{line}: .*Float32", str(e.value)), str(e.value)
