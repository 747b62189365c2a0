"""Every fmiVersion the FMI 3.0 standard allows runs as FMI 3.0 (issue 38's first point).

The FMI 3.0 schema (fmi3ModelDescription.xsd, attribute fmiVersion) takes "3" "." a
minor, optionally "." a patch and "-" a pre-release suffix: Dymola's FMI 3.0 exports say
"3.0.1", the standard's current release is 3.0.2. The versions below are the standard's
own release names, written here, not derived from artibus's pattern. An FMU that differs
from our FMI 3.0 build only in fmiVersion must give the same results, bit for bit, alone
and in a bench; FMI 1.0 and a later major version are refused by name."""
import re
import zipfile

import numpy as np
import pytest

from artibus import ArtibusError, fmu_dir
from artibus.fmu import simulate
from artibus.runner import Simulation
from artibus.testing import pack_ssp, ssd_text

NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"')
SOURCE = "BusKinematics"                 # moves from its start values with testSteerAmp (an S-curve)
MOVING = {"testSteerAmp": 0.2}


def with_version(tmp_path, version):
    """fmus/fmi3/BusKinematics.fmu with fmiVersion="<version>" in its modelDescription.xml."""
    src = fmu_dir() / "fmi3" / f"{SOURCE}.fmu"
    out = tmp_path / f"{SOURCE}_{version}.fmu"
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as b:
        for info in a.infolist():
            data = a.read(info)
            if info.filename == "modelDescription.xml":
                data, n = re.subn(rb'fmiVersion="3\.0"', f'fmiVersion="{version}"'.encode(), data, count=1)
                assert n == 1
            b.writestr(info, data)
    return out


def one_fmu_bench(tmp_path, fmu):
    """an SSP 1.0 bench of the one FMU (outputs x[0], y[0] recorded), 10 s"""
    bus = (f'<ssd:Component name="Bus" source="resources/fmi3/{SOURCE}.fmu"><ssd:Connectors>'
           '<ssd:Connector name="x[0]" kind="output"/><ssd:Connector name="y[0]" kind="output"/>'
           '</ssd:Connectors></ssd:Component>')
    return pack_ssp(tmp_path / f"one-{fmu.stem}.ssp", ssd_text(bus, None, 10, "one", system_name="one"),
                    {f"resources/fmi3/{SOURCE}.fmu": fmu})


@pytest.mark.parametrize("version", ["3.0.1", "3.0.2", "3.1"])
def test_an_fmu_of_any_fmi_3_version_runs_as_our_3_0_build(tmp_path, version):
    ref = simulate(fmu_dir() / "fmi3" / f"{SOURCE}.fmu", parameters=MOVING, stop_time=10.0, step=0.05)
    got = simulate(with_version(tmp_path, version), parameters=MOVING, stop_time=10.0, step=0.05)
    assert got.names == ref.names
    assert np.ptp(ref["y[0]"]) > 0.1                      # it moves: the comparison compares something
    np.testing.assert_array_equal(got.array(), ref.array())


@pytest.mark.parametrize("version", ["3.0.1", "3.0.2"])
def test_in_a_bench_too(tmp_path, version):
    runs = []
    for fmu in (fmu_dir() / "fmi3" / f"{SOURCE}.fmu", with_version(tmp_path, version)):
        with Simulation(one_fmu_bench(tmp_path, fmu), step=0.05, overrides={"Bus.testSteerAmp": 0.2}) as sim:
            runs.append(sim.run())
            assert {u.fmu.fmi for u in sim.units} == {3}
    assert np.ptp(runs[0]["Bus.y[0]"]) > 0.1
    np.testing.assert_array_equal(runs[1].array(), runs[0].array())


@pytest.mark.parametrize("version", ["4.0", "1.0"])
def test_another_major_version_is_refused_by_name(tmp_path, version):
    with pytest.raises(ArtibusError, match=rf'fmiVersion[=: "]+{re.escape(version)}'):
        simulate(with_version(tmp_path, version), stop_time=1.0, step=0.05)
