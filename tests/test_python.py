"""The Python side: parameter files, the CLI, and the build-time generator.
User errors name the file, element and value, exit non-zero, no traceback."""
import subprocess
import sys

import pytest

from artibus import ArtibusError, fmu_path
from artibus.bench.parameters import read_parameters
from conftest import ROOT

SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
                  version="1.0" name="t"><ssv:Parameters>{}</ssv:Parameters></ssv:ParameterSet>
"""


def ssv(tmp_path, body):
    p = tmp_path / "t.ssv"
    p.write_text(SSV.format(body))
    return p


def test_unknown_parameter_names_file_element_value(tmp_path):
    p = ssv(tmp_path, '<ssv:Parameter name="Lzero"><ssv:Real value="5.9"/></ssv:Parameter>')
    with pytest.raises(ArtibusError) as e:
        read_parameters(p, fmu_path("BusKinematics"))
    assert str(p) in str(e.value) and "Lzero" in str(e.value) and "5.9" in str(e.value)


def test_out_of_range_and_output_parameters(tmp_path):
    p = ssv(tmp_path, '<ssv:Parameter name="N"><ssv:Integer value="7"/></ssv:Parameter>')
    with pytest.raises(ArtibusError, match=r"'N' = 7 is outside \[1, 4\]"):
        read_parameters(p, fmu_path("BusKinematics"))
    p = ssv(tmp_path, '<ssv:Parameter name="x[0]"><ssv:Real value="1"/></ssv:Parameter>')
    with pytest.raises(ArtibusError, match="output"):
        read_parameters(p, fmu_path("BusKinematics"))


def test_invalid_ssv_is_reported_with_its_file(tmp_path):
    p = ssv(tmp_path, '<ssv:Parameter name="N"><ssv:Bogus value="1"/></ssv:Parameter>')
    with pytest.raises(ArtibusError) as e:
        read_parameters(p)
    assert str(p) in str(e.value)


def artibus(*args, cwd):
    return subprocess.run([sys.executable, "-m", "artibus", *args], capture_output=True,
                          text=True, cwd=cwd)


def test_demo_writes_results_and_plot(tmp_path):
    r = artibus("demo", "--report", str(tmp_path / "out"), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    csv = tmp_path / "out" / "BusKinematics_Urbino18_SCurve.csv"
    png = tmp_path / "out" / "BusKinematics_Urbino18_SCurve.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(csv.read_text().splitlines()) == 802       # header + 0..40 s at 0.05 s


def test_cli_user_error_has_no_traceback(tmp_path):
    r = artibus("simulate", "BusKinematics", "--set", "N=9", "-o", str(tmp_path / "r.csv"), cwd=tmp_path)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr and "'N' = '9'" in r.stderr


def test_cli_keeps_partial_results_when_the_fmu_fails(tmp_path):
    out = tmp_path / "r.csv"
    r = artibus("simulate", "BusKinematics", "--ssv", "Urbino18", "--set", "testSteerAmp=0.5",
                "--set", "testSteerPeriod=200", "--set", "v=-3", "--stop-time", "60",
                "-o", str(out), cwd=tmp_path)
    assert r.returncode == 1 and "jack-knife" in r.stderr and "Traceback" not in r.stderr
    partial = tmp_path / "r.partial.csv"         # OUT.partial.csv, as after an interrupt
    rows = partial.read_text().splitlines()
    assert len(rows) > 2


def test_generator_refuses_duplicate_value_references(tmp_path):
    xml = (ROOT / "modelDescription" / "BusKinematics.xml").read_text()
    bad = xml.replace('name="L0" valueReference="3"', 'name="L0" valueReference="4"')
    assert bad != xml
    (tmp_path / "m.xml").write_text(bad)
    r = subprocess.run([sys.executable, str(ROOT / "src" / "fmi" / "gen_vars.py"),
                        str(tmp_path / "m.xml"), str(tmp_path / "gen")], capture_output=True, text=True)
    assert r.returncode == 1 and "valueReference 4" in r.stderr
