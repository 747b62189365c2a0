"""Portable packs (artibus pack --portable, artibus.bench.portable): each
component's parameters resolved into one inline set named "bench", the rest
of the bench unchanged, valid against the SSP 1.0 XSDs; our runner gives the
same results on the portable pack as on the bench with its bindings, files,
mappings and variant, bit for bit (the same values reach the same FMUs)."""
import zipfile
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from artibus import cli
from artibus.base import ArtibusError
from artibus.bench import ssp
from artibus.bench.portable import PARAMETER_SET, pack_portable
from artibus.runner import Simulation

NS = ssp.NS


def _sets(pack):
    root = etree.fromstring(zipfile.ZipFile(pack).read("SystemStructure.ssd"))
    out = {}
    for c in root.iter(f"{{{NS['ssd']}}}Component"):
        bindings = c.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS)
        out[c.get("name")] = bindings
    return root, out


@pytest.mark.parametrize("bench, variants, stop", [
    ("Scania18m_Damping", [], 2.0),                  # .ssv files, an .ssm mapping, several bindings
    ("Bus36m_Circle", ["guidedForceMin"], 2.0),       # a variant on top of the vehicle's .ssv
    ("Scania18m_Damping", ["heavyRear"], 2.0),        # a variant that rebinds a parameter set
])
def test_our_runner_gives_the_same_results_on_the_portable_pack(bench, variants, stop, tmp_path):
    pack = pack_portable(bench, variants, out=tmp_path / "p.ssp")
    names = zipfile.ZipFile(pack).namelist()
    assert not [n for n in names if n.endswith((".ssv", ".ssm")) or n.startswith("variants/")]
    root, bindings = _sets(pack)
    for comp, bs in bindings.items():                 # at most one binding, one inline set named "bench"
        assert len(bs) <= 1, comp
        for b in bs:
            assert b.get("source") is None
            psets = b.findall("ssd:ParameterValues/ssv:ParameterSet", NS)
            assert [p.get("name") for p in psets] == [PARAMETER_SET]
    assert root.find(".//ssd:System/ssd:ParameterBindings", NS) is None
    # the prefixes libcosim's reader expects, as written
    assert {"ssd", "ssc", "ssv", "osp"} <= set(root.nsmap)
    ssp.read(pack)                                    # FMPy's reader: valid against the SSP 1.0 XSDs
    overrides = ssp.variant_overrides(bench, variants)
    with Simulation(bench, overrides=overrides) as a:
        ra = a.run(stop_time=stop)
        pa = a.parameters
    with Simulation(pack) as b:
        rb = b.run(stop_time=stop)
        pb = b.parameters
    assert {c: dict(v) for c, v in pa.items()} == {c: dict(v) for c, v in pb.items()}
    assert ra.names == rb.names
    np.testing.assert_array_equal(ra.array(), rb.array())


def test_the_connections_and_connectors_are_the_benchs(tmp_path):
    pack = pack_portable("Bus36m_Circle", ["guidedForceMin"], out=tmp_path / "p.ssp")
    a, b = ssp.read(ssp.ssp_path("Bus36m_Circle")), ssp.read(pack)
    assert [(c.start, c.end, c.factor, c.offset) for c in a.connections] == \
           [(c.start, c.end, c.factor, c.offset) for c in b.connections]
    assert {p: c.connectors for p, c in a.components.items()} == {p: c.connectors for p, c in b.components.items()}
    # the steps: the bench's annotation, else (read from the pack's osp:StepSizeHint) its FMU's default experiment's
    steps = {p: c.step or float(ssp.model_description(ssp.ssp_path("Bus36m_Circle"), c.source).defaultExperiment.stepSize)
             for p, c in a.components.items()}
    assert steps == {p: c.step for p, c in b.components.items()}
    # the variant's values are in: Guidance.guided true, ForceMin.law 1
    assert b.components["Guidance"].parameters["guided"] is True
    assert b.components["ForceMin"].parameters["law"] == 1
    # the vehicle's .ssv (which ecos never applied) is in the Bus's one set
    assert b.components["Bus"].parameters["nModules"] == a.components["Bus"].parameters["nModules"] == 3


def test_cli_pack_portable_and_its_errors(tmp_path, capsys):
    out = tmp_path / "u.portable.ssp"
    assert cli.main(["pack", "--portable", "Urbino18_Circle", "-o", str(out)]) == 0
    assert out.is_file() and str(out) in capsys.readouterr().out
    assert cli.main(["pack", "--portable", "Bus36m_Circle", "--variant", "nosuch", "-o", str(out)]) == 1
    assert "no such variant" in capsys.readouterr().err
    assert cli.main(["pack", "Urbino18_Circle", "--variant", "x"]) == 1
    assert "--portable" in capsys.readouterr().err
    with pytest.raises(ArtibusError, match="CAN"):
        pack_portable("Bus36m_Circle_CAN", out=tmp_path / "c.ssp")


def test_enumerations_are_integers_in_the_pack(tmp_path):
    """The choices (Enumeration variables) reach the other masters as Integers: in the pack's
    FMUs each is an Integer with the same value reference, min/max its items' smallest and
    largest value and the items in its description; the bench's item (Driver.road =
    fullCircle in Bus36m_Circle) is the ssv:Integer of that item's value; every other entry
    of the FMU is byte for byte the built FMU's (the binary is the same)."""
    from fmpy import read_model_description
    from artibus import fmu_path
    pack = pack_portable("Bus36m_Circle", [], out=tmp_path / "p.ssp")
    root, sets = _sets(pack)
    road = [p for p in root.iter(f"{{{NS['ssv']}}}Parameter") if p.get("name") == "road"]
    (value,) = [c for r in road for c in r]
    assert etree.QName(value).localname == "Integer" and value.get("value") == "2"   # fullCircle
    assert not list(root.iter(f"{{{NS['ssv']}}}Enumeration"))
    with zipfile.ZipFile(pack) as z:
        (entry,) = [n for n in z.namelist() if n.endswith("RoadFollowDriver.fmu")]
        (tmp_path / "d.fmu").write_bytes(z.read(entry))
    built = read_model_description(str(fmu_path("RoadFollowDriver")))
    packed = read_model_description(str(tmp_path / "d.fmu"))
    b = {v.name: v for v in built.modelVariables}
    enums = [v for v in built.modelVariables if v.type == "Enumeration"]
    assert {v.name for v in enums} == {"road", "method"}
    for v in packed.modelVariables:
        if v.name in ("road", "method"):
            items = [int(i.value) for i in b[v.name].declaredType.items]
            assert v.type == "Integer" and v.valueReference == b[v.name].valueReference
            assert (int(v.min), int(v.max)) == (min(items), max(items))
            assert all(i.name in v.description for i in b[v.name].declaredType.items)
        else:
            assert (v.type, v.valueReference, v.description) == \
                (b[v.name].type, b[v.name].valueReference, b[v.name].description)
    with zipfile.ZipFile(fmu_path("RoadFollowDriver")) as a, zipfile.ZipFile(tmp_path / "d.fmu") as c:
        assert a.namelist() == c.namelist()
        for n in a.namelist():
            if n != "modelDescription.xml":
                assert a.read(n) == c.read(n), n


def _road_deviation(x, y, road):
    """(the largest |y - road's y at x| over the road's extent, the largest |y|) of a path"""
    inside = (x > road[0, 0]) & (x < road[-1, 0])
    assert inside.sum() > 100, "the front axle never drove along the road"
    return float(np.max(np.abs(y[inside] - np.interp(x[inside], road[:, 0], road[:, 1])))), float(np.max(np.abs(y)))


@pytest.mark.parametrize("master", ["ecos", "libcosim"])
def test_road_file_goes_into_the_drivers_resources_and_other_masters_follow_it(master, tmp_path):
    """Bus36m_Slalom's road (a String parameter "resources/Bus36m_Slalom.csv" in the bench) is in
    the pack's RoadFollowDriver.fmu as resources/Bus36m_Slalom.csv, byte for byte the road of
    ssp/roads/, and the value is the bare file name (a master hands it to the FMU as written; the
    FMU reads a relative name in its own resources/). Run in ecos or libcosim (where installed),
    the front axle A1 follows the road's slalom (±1.5 m, read from the CSV here) within 0.1 m."""
    import json
    import subprocess
    import sys
    from artibus.base import ROOT
    road_file = ROOT / "ssp" / "roads" / "Bus36m_Slalom.csv"
    pack = pack_portable("Bus36m_Slalom", [], out=tmp_path / "p.ssp")
    with zipfile.ZipFile(pack) as z:
        assert not [n for n in z.namelist() if n.endswith(".csv")]      # not beside the FMUs any more
        with zipfile.ZipFile(z.open("resources/RoadFollowDriver.fmu")) as fmu:
            assert fmu.read("resources/Bus36m_Slalom.csv") == road_file.read_bytes()
    root, _ = _sets(pack)
    files = {p.get("name"): s.get("value") for p in root.iter(f"{{{NS['ssv']}}}Parameter")
             for s in p.findall("ssv:String", NS)}
    assert files == {"roadFile": "Bus36m_Slalom.csv"}
    module = {"ecos": "ecospy", "libcosim": "libcosimpy"}[master]
    pytest.importorskip(module)
    out = tmp_path / "run.json"
    names = ["Bus.xAxle[1]", "Bus.yAxle[1]"]
    p = subprocess.run([sys.executable, str(Path(__file__).parent / "masters_run.py"), master, str(pack), "0.01",
                        "42.0", str(out), *names], capture_output=True, text=True, timeout=600)
    assert out.is_file(), f"{master} died (exit {p.returncode}): {p.stderr[-2000:]}"
    d = json.loads(out.read_text())
    assert d["ok"], d["error"]
    rows = np.array(d["rows"])
    road = np.loadtxt(road_file, delimiter=",", skiprows=1)
    deviation, swing = _road_deviation(rows[:, 1], rows[:, 2], road)
    assert swing > 1.4 and deviation < 0.1, (deviation, swing)
