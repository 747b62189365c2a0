"""Results in the formats vehicle engineers open (issue 42): `-o` by its
extension as CSV, Parquet, ASAM MDF 4 (asammdf) or MATLAB (scipy's loadmat),
each read back here by its own reader and compared with the CSV of the same
run; the units and descriptions read independently from the model
description's XML (lxml), never from artibus's writer. An unknown extension is
refused before the run. `--can-log x.mf4` holds the frames of the .blf of the
same run (python-can reads the .blf, asammdf the .mf4)."""
import csv

import numpy as np
import pytest
from lxml import etree

from artibus import ROOT
from artibus.cli import main
from artibus.fmu.result import Result

BENCH, STOP = "Scania18m_LaneChange", "0.3"
RECORD = ["Bus.x[1]", "Bus.psi[1]", "Bus.vy[2]", "Bus.ay[1]", "Bus.FzFromMasses"]


def xml_var(model, name):
    """(unit, description) of a variable as modelDescription/<model>.xml declares
    it: its own unit=, else its declaredType's; "" for none."""
    root = etree.parse(str(ROOT / "modelDescription" / f"{model}.xml"))
    v = root.find(f".//ScalarVariable[@name='{name}']")
    unit = v[0].get("unit")
    if not unit and v[0].get("declaredType"):
        unit = root.find(f".//TypeDefinitions/SimpleType[@name='{v[0].get('declaredType')}']")[0].get("unit")
    return unit or "", v.get("description") or ""


def read_csv(path):
    """{name: column} of a CSV of results, with the csv module and numpy only."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    table = np.array(rows[1:], dtype=float)
    return {n: table[:, i] for i, n in enumerate(rows[0])}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """One bench run written by `artibus run -o` as each format."""
    d = tmp_path_factory.mktemp("formats")
    out = {}
    for ext in ("csv", "mf4", "mat", "parquet"):
        out[ext] = d / f"r.{ext}"
        args = ["run", BENCH, "--stop-time", STOP, "-o", str(out[ext])]
        for r in RECORD:
            args += ["--record", r]
        assert main(args) == 0
    return out


def test_mf4_channels_have_the_csv_values_units_and_descriptions(runs):
    from asammdf import MDF
    ref = read_csv(runs["csv"])
    with MDF(str(runs["mf4"])) as mdf:
        assert len(mdf.groups) == 1                    # one group: every channel on the master's time
        for name in RECORD:
            s = mdf.get(name)
            np.testing.assert_allclose(s.timestamps, ref["time"], rtol=1e-11, atol=1e-12)
            np.testing.assert_allclose(s.samples.astype(float), ref[name], rtol=1e-11, atol=1e-12)
            unit, description = xml_var("BusDynamics", name.split(".", 1)[1])
            assert (s.unit, s.comment) == (unit, description), name
        master = mdf.groups[0].channels[mdf.masters_db[0]]
        assert master.name == "time" and master.unit == "s"
    assert xml_var("BusDynamics", "x[1]")[0] == "m"           # (the reading above is not all "")


def text(x):
    """A text of a struct field as loadmat gives it back ("" comes back as an empty array)."""
    return x if isinstance(x, str) else "".join(np.asarray(x).ravel().tolist())


def test_mat_reads_back_with_the_csv_values_and_units(runs):
    from scipy.io import loadmat
    ref = read_csv(runs["csv"])
    m = loadmat(str(runs["mat"]), simplify_cells=True)
    for name in ["time"] + RECORD:
        key = m["names"][name.replace(".", "_").replace("[", "_").replace("]", "")]
        assert key == name
    np.testing.assert_allclose(m["time"], ref["time"], rtol=1e-11)
    for name in RECORD:
        key = name.replace(".", "_").replace("[", "_").replace("]", "")
        np.testing.assert_allclose(m[key], ref[name], rtol=1e-11, atol=1e-12)
        assert text(m["units"][key]) == xml_var("BusDynamics", name.split(".", 1)[1])[0], name


def test_parquet_reads_back_with_the_csv_values_and_units(runs):
    import pandas as pd
    import pyarrow.parquet as pq
    ref = read_csv(runs["csv"])
    df = pd.read_parquet(runs["parquet"])
    assert list(df.columns) == ["time"] + RECORD
    for name in ["time"] + RECORD:
        np.testing.assert_allclose(df[name].to_numpy(), ref[name], rtol=1e-11, atol=1e-12)
    schema = pq.read_schema(runs["parquet"])
    for name in RECORD:
        unit, description = xml_var("BusDynamics", name.split(".", 1)[1])
        meta = schema.field(name).metadata
        assert (meta[b"unit"].decode(), meta[b"description"].decode()) == (unit, description), name


@pytest.mark.parametrize("verb", [["run", BENCH], ["simulate", "BusKinematics"]])
def test_an_unknown_extension_is_refused_before_the_run(tmp_path, capsys, verb):
    out = tmp_path / "r.xlsx"
    assert main(verb + ["--stop-time", "0.1", "-o", str(out)]) == 1
    cap = capsys.readouterr()
    assert cap.out == ""                                   # nothing ran (a run prints its rows)
    err = cap.err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert str(out) in err and ".xlsx" in err
    assert all(ext in err for ext in (".csv", ".parquet", ".mf4", ".mat")), err
    assert list(tmp_path.iterdir()) == []


def small_result():
    t = np.arange(50) * 0.01
    r = Result.from_array(["time", "A.x", "A.y"], np.column_stack([t, np.sin(t), np.cos(t)]))
    r.units = {"time": "s", "A.x": "m", "A.y": "rad"}
    r.descriptions = {"time": "simulation time", "A.x": "position", "A.y": "angle"}
    return r


def read_any(path):
    """{name: column} of a results file, by its own format's reader."""
    ext = path.suffix
    if ext == ".csv":
        return read_csv(path)
    if ext == ".mat":
        from scipy.io import loadmat
        m = loadmat(str(path), simplify_cells=True)
        return {n: m[k] for k, n in m["names"].items()}
    if ext == ".parquet":
        import pandas as pd
        df = pd.read_parquet(path)
        return {n: df[n].to_numpy() for n in df.columns}
    from asammdf import MDF
    with MDF(str(path)) as mdf:
        out = {n: mdf.get(n).samples for n in ("A.x", "A.y")}
        out["time"] = mdf.get("A.x").timestamps
    return out


@pytest.mark.parametrize("ext", ["csv", "parquet", "mf4", "mat"])
def test_partial_results_in_the_format_asked(tmp_path, ext):
    """A run stopped midway (the runner's KeyboardInterrupt carrying the results
    so far): OUT.partial.EXT, in EXT's format; only a CSV has a units sidecar
    (the others hold their units)."""
    from artibus.runner import save_partial
    e = KeyboardInterrupt()
    e.result = small_result()
    out = tmp_path / f"r.{ext}"
    save_partial(e, out)
    assert e.partial == tmp_path / f"r.partial.{ext}" and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [f"r.partial.{ext}"] + (["r.partial.units.csv"] if ext == "csv" else []))
    back = read_any(e.partial)
    for n in ("time", "A.x", "A.y"):
        np.testing.assert_allclose(back[n], e.result[n], rtol=1e-11, atol=1e-15)


def test_mat_names_long_and_alike_all_kept(tmp_path):
    """MATLAB's names: at most 63 characters, a letter first; two signals whose
    MATLAB-safe names would be the same, or a name beyond 31 characters (a struct
    field), each kept under a name of its own, the original in `names`."""
    from scipy.io import loadmat
    from artibus.runner import save
    names = ["time", "Ctrl.x[1]", "Ctrl.x_1", "9Lead.v", "Steering.aVeryLongOutputNameOfTheController[1]",
             "Steering.aVeryLongOutputNameOfTheController[1]_and_more_text_to_go_past_63_chars",
             "Steering.aVeryLongOutputNameOfTheController[1]_and_more_text_to_go_past_63_chars_too"]
    t = np.arange(4.0)
    r = Result.from_array(names, np.column_stack([t] + [t * (i + 2) for i in range(len(names) - 1)]))
    r.units = {n: f"u{i}" for i, n in enumerate(names)}
    m = loadmat(str(save(r, tmp_path / "r.mat")), simplify_cells=True)
    back = {n: k for k, n in m["names"].items()}
    assert sorted(back) == sorted(names)
    for i, n in enumerate(names):
        k = back[n]
        assert len(k) <= 63 and k[0].isalpha() and (k.replace("_", "a").isalnum()), k
        np.testing.assert_array_equal(m[k], r[n])
        assert m["units"][k] == f"u{i}"


@pytest.mark.parametrize("bench", ["Bus36m_Circle_CAN", "Bus36m_Circle_LSBUS"])
def test_can_log_mf4_holds_the_frames_of_the_blf(tmp_path, bench):
    """A CAN bench (python-can's network; an FMI-LS-BUS one) logged twice: .blf
    (python-can reads it) and .mf4 (asammdf's CAN bus logging: CAN_DataFrame
    channels): the same identifiers, bytes and times (to the .blf's
    nanosecond)."""
    import can as pycan
    from asammdf import MDF
    logs = {}
    for ext in ("blf", "mf4"):
        logs[ext] = tmp_path / f"traffic.{ext}"
        assert main(["run", bench, "--stop-time", "0.3", "-o", str(tmp_path / f"{ext}.csv"),
                     "--can-log", str(logs[ext])]) == 0
    blf = list(pycan.BLFReader(str(logs["blf"])))
    assert len(blf) > 50
    with MDF(str(logs["mf4"])) as mdf:
        ids = mdf.get("CAN_DataFrame.ID")
        length = mdf.get("CAN_DataFrame.DataLength").samples
        data = mdf.get("CAN_DataFrame.DataBytes").samples
        assert mdf.groups[0].channel_group.acq_source.bus_type == 2          # BUS_TYPE_CAN (MDF 4.1 SI block)
    assert list(ids.samples) == [m.arbitration_id for m in blf]
    assert [bytes(d[:n]) for d, n in zip(data, length)] == [bytes(m.data) for m in blf]
    np.testing.assert_allclose(ids.timestamps, [m.timestamp for m in blf], rtol=0, atol=2e-9)
    assert not (tmp_path / "traffic.mf4.part").exists()


# --- wrong-kind arguments: the verb that takes them -----------------------------------------------

@pytest.mark.parametrize("argv, verb", [
    (["simulate", "Bus36m_Circle"], "artibus run Bus36m_Circle"),
    (["simulate", str(ROOT / "fmus" / "Bus36m_Circle.ssp")], "artibus run"),
    (["run", str(ROOT / "fmus" / "BusDynamics.fmu")], "artibus simulate"),
    (["run", "BusDynamics"], "artibus simulate BusDynamics"),
])
def test_a_bench_to_simulate_or_an_fmu_to_run_names_the_verb(tmp_path, capsys, monkeypatch, argv, verb):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    cap = capsys.readouterr()
    err = cap.err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err and cap.out == ""
    assert verb in err and argv[1] in err, err
    assert "not built" not in err and "no such bench" not in err
    assert list(tmp_path.iterdir()) == []


def test_the_readers_of_these_formats_come_with_the_package():
    """asammdf (.mf4) and pandas (the sweep's results.parquet, a run's .parquet)
    are dependencies of the package (the set-up installs pyproject.toml's
    dependencies, scripts/setup.sh), and present in this environment."""
    import importlib.util
    import re
    import tomllib
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    names = {re.match(r"[A-Za-z0-9_.-]+", d).group(0).lower() for d in deps}
    assert {"asammdf", "pandas", "scipy", "pyarrow"} <= names, names
    assert all(importlib.util.find_spec(m) for m in ("asammdf", "pandas", "scipy", "pyarrow"))


def test_simulate_writes_mf4_with_the_fmus_units_and_descriptions(tmp_path):
    """`artibus simulate FMU -o x.mf4`: each output a channel with the unit and
    description its model description declares (read here with lxml)."""
    from asammdf import MDF
    out = tmp_path / "k.mf4"
    assert main(["simulate", "BusKinematics", "--stop-time", "0.2", "-o", str(out)]) == 0
    with MDF(str(out)) as mdf:
        channels = {c.name: c for c in mdf.groups[0].channels}
    outputs = [n for n in channels if n != "time"]
    assert len(outputs) >= 3
    for n in outputs:
        unit, description = xml_var("BusKinematics", n)
        assert (channels[n].unit, channels[n].comment) == (unit, description), n
    assert any(channels[n].comment for n in outputs)
