"""Units carried into the results (issue 15): a CSV keeps its one header line of
names and gets the sidecar OUT.units.csv (name,unit); a .mat a struct `units`
with a field per signal. The units are the model descriptions' (unit=, else
the declaredType's), read here from the XML independently of the runner."""
import csv
from types import SimpleNamespace

import numpy as np
import pytest
from lxml import etree

from artibus import ROOT
from artibus.bench.units import unit_of
from artibus.cli import main
from artibus.runner import read_units, run, save, units_path

RECORD = ["Bus.x[1]", "Bus.psi[1]", "Bus.vy[2]", "Bus.FzFromMasses"]


def xml_unit(model, name):
    """The unit= of a variable as its modelDescription/<model>.xml declares it ("" for none)."""
    root = etree.parse(str(ROOT / "modelDescription" / f"{model}.xml"))
    v = root.find(f".//ScalarVariable[@name='{name}']")
    return v[0].get("unit") or ""


@pytest.fixture(scope="module")
def lane_change():
    return run("Scania18m_LaneChange", stop_time=0.2, record=RECORD)


def test_recorded_bus_units_in_the_csv_sidecar(lane_change, tmp_path):
    out = save(lane_change, tmp_path / "r.csv")
    units = read_units(out)
    assert list(units) == lane_change.names            # a row per column, in the CSV's order
    assert units["time"] == "s"
    for name in RECORD:
        assert units[name] == xml_unit("BusDynamics", name.split(".", 1)[1]), name
    assert (units["Bus.x[1]"], units["Bus.psi[1]"], units["Bus.vy[2]"]) == ("m", "rad", "m/s")
    assert units["Bus.FzFromMasses"] == ""             # a Boolean without a unit
    assert units_path(out).name == "r.units.csv"


def test_csv_reads_back_identically(lane_change, tmp_path):
    """The results file is what Result.to_csv writes (one header line of names,
    the data bit for bit): numpy, Arrow and the csv module read it as before."""
    out = save(lane_change, tmp_path / "r.csv")
    plain = tmp_path / "plain.csv"
    lane_change.to_csv(plain)
    assert out.read_bytes() == plain.read_bytes()
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(f'"{n}"' for n in lane_change.names)
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table, np.array([[float(f"{x:.12g}") for x in row] for row in lane_change.array()]))
    d = np.genfromtxt(out, delimiter=",", names=True)
    assert len(d) == len(lane_change.rows)
    from pyarrow import csv as pacsv                     # (pandas' reader is Arrow's in the sweep)
    t = pacsv.read_csv(out)
    assert t.column_names == lane_change.names
    np.testing.assert_array_equal(np.column_stack([t[n].to_numpy() for n in t.column_names]), table)
    with open(units_path(out), newline="") as f:         # the sidecar is a plain CSV too
        rows = list(csv.reader(f))
    assert rows[0] == ["name", "unit"] and ["Bus.x[1]", "m"] in rows


def test_mat_units_struct(lane_change, tmp_path):
    from scipy.io import loadmat
    m = loadmat(str(save(lane_change, tmp_path / "r.mat")), simplify_cells=True)
    assert m["units"]["Bus_x_1"] == "m" and m["units"]["Bus_psi_1"] == "rad" and m["units"]["time"] == "s"
    np.testing.assert_array_equal(m["Bus_x_1"], lane_change["Bus.x[1]"])    # the data bit for bit
    assert not (tmp_path / "r.units.csv").exists()


def test_run_and_simulate_cli_write_units(tmp_path):
    out = tmp_path / "run.csv"
    assert main(["run", "Scania18m_LaneChange", "--stop-time", "0.1", "--record", "Bus.ay[1]", "-o", str(out)]) == 0
    assert read_units(out) == {"time": "s", "Bus.ay[1]": "m/s2"}
    out = tmp_path / "sim.csv"
    assert main(["simulate", "BusKinematics", "--stop-time", "0.1", "-o", str(out)]) == 0
    units = read_units(out)
    header = out.read_text().splitlines()[0].replace('"', "").split(",")
    assert list(units) == header
    for name in header[1:]:
        assert units[name] == xml_unit("BusKinematics", name), name
    assert "m" in units.values()


def test_unit_of_declared_type():
    assert unit_of(SimpleNamespace(unit="N", declaredType=SimpleNamespace(unit="kN"))) == "N"
    assert unit_of(SimpleNamespace(unit=None, declaredType=SimpleNamespace(unit="rad"))) == "rad"
    assert unit_of(SimpleNamespace(unit=None, declaredType=None)) == ""
