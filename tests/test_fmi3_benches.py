"""Every bench with the FMI 3.0 builds of its FMUs (issue 23, "Runner and benches").

The FMI 3.0 build of an FMU is the same model code as its FMI 2.0 build
(src/fmi/fmu_core.c under both layers; tests/test_fmi3.py), so the bench run
with its FMI 2.0 FMUs is the independent reference of the run with its FMI
3.0 ones:

- every bench of ssp/benches, packed with fmus/fmi3/<Name>.fmu
  (fmus/fmi3/<Bench>.ssp), gives the FMI 2.0 run's KPIs within 1e-12
  relative and the same recorded outputs (the same floating-point operations
  in the same order: bit for bit is expected, 1e-12 relative is the bound),
  through the C stepping core's fmi3 calls where the FMI 2.0 run took the core;
- a CAN bench's network ticked in Python (run(core=False), artibus.can.Network,
  called back by the C core) with FMI 3.0 FMUs gives the table of its network in
  C with FMI 2.0 ones, bit for bit (and a bench without a network, whose run
  core=False does not change, its FMI 2.0 table);
- `artibus run --fmi 3` writes the same results file as `artibus run`;
- a bench whose FMU has no FMI 3.0 build: an error naming the FMU and the
  component's line, no traceback;
- the bench's own choice: an .ssd naming resources/fmi3/<Name>.fmu runs that
  build, and --fmi 2 runs the FMI 2.0 one in its place.
"""
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from artibus import cli, fmu_dir, runner
from artibus.base import ArtibusError
from artibus.bench import script, ssp
from artibus.runner.lsbus_bench import LsBusSteering

BENCHES = ssp.bench_names()
_RUNS = {}


def close(a, b, rtol=1e-12):
    """a == b, or within rtol of the larger magnitude (NaN only against NaN)."""
    if a is None or b is None:
        return a is b
    a, b = float(a), float(b)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b or abs(a - b) <= rtol * max(abs(a), abs(b))


def bench_run(bench, fmi, core=None, variant=None):
    """(table, names, stepping, the FMUs' FMI versions, Result) of the bench's run (its
    default, or a variant), once a session."""
    key = (bench, fmi, core, variant)
    if key not in _RUNS:
        variants = [variant] if variant else None
        overrides = ssp.variant_overrides(bench, variants) if variants else {}
        with runner.Simulation(bench, fmi=fmi, overrides=overrides) as sim:
            r = sim.run(core=core, stop_time=ssp.variant_stop_time(bench, variants) if variants else None)
            _RUNS[key] = (r.array().copy(), list(r.names), sim.stepping, {u.fmu.fmi for u in sim.units}, r)
    return _RUNS[key]


#: the variants that switch on what the default runs leave idle: the steering controllers
#: (TrainGuidance, ForceMinimization), the damping controller and the ACS5-like baseline
VARIANTS = [("Bus36m_Circle", "guidedForceMin"), ("Scania18m_Damping", "option2"),
            ("Scania18m_Damping", "baseline"), ("Bus36m_Circle_CAN", "laneChange")]


@pytest.mark.slow
@pytest.mark.parametrize("bench,variant", [(b, None) for b in BENCHES] + VARIANTS)
def test_bench_with_fmi3_builds_gives_the_fmi2_kpis_and_outputs(bench, variant):
    t2, n2, s2, v2, r2 = bench_run(bench, "2", variant=variant)
    t3, n3, s3, v3, r3 = bench_run(bench, "3", variant=variant)
    assert v2 == {2} and v3 == {3}                     # every FMU in the build asked for
    assert s3 == s2                                    # the C core runs FMI 3.0 where it ran FMI 2.0
    assert n3 == n2 and t3.shape == t2.shape
    bad = [(n2[j], i, t2[i, j], t3[i, j]) for j in range(t2.shape[1]) for i in range(t2.shape[0])
           if not close(t2[i, j], t3[i, j])][:5]
    assert not bad, bad                                # (signal, row, FMI 2.0, FMI 3.0)
    k2, k3 = script.kpis(bench, r2), script.kpis(bench, r3)
    assert [k.name for k in k3] == [k.name for k in k2]
    for a, b in zip(k2, k3):
        assert close(a.value, b.value), (a.name, a.value, b.value)
    if script.load(bench) is not None:                 # a bench with KPIs has numbers to compare
        assert any(isinstance(k.value, (int, float)) and math.isfinite(k.value) for k in k2), bench


@pytest.mark.slow
def test_the_benches_run_every_fmu_but_the_types_test():
    """The runs above cover every FMU's FMI 3.0 build (TypesTest: tests/test_fmi3.py)."""
    used = set()
    for bench in BENCHES:
        with runner.Simulation(bench, fmi="3") as sim:
            used |= {u.fmu.md.modelName for u in sim.units}
            if isinstance(sim.lsbus, LsBusSteering):             # an LS-BUS network's FMUs
                used |= {p.stem for p, _ in sim.lsbus.nodes.values()} | {sim.lsbus.bus_path.stem}
    built = {f.stem for f in (fmu_dir() / "fmi3").glob("*.fmu")}
    # FMI 3.0 only: the FMI-LS-BUS bus and nodes, run by Bus36m_Circle_LSBUS's network
    lsbus = {"CanBus", "SteeringECU_LSBUS", "SteeringActuator_LSBUS", "SteeringSensors_LSBUS"}
    assert lsbus <= built and not any((fmu_dir() / f"{n}.fmu").exists() for n in lsbus)
    assert built - used == {"TypesTest"}


@pytest.mark.slow
@pytest.mark.parametrize("bench, in_python", [("Urbino18_Circle", ""),
                                              ("Bus36m_Circle_CAN", "; in Python: the network, switched off (core=False)")])
def test_fmi3_with_the_network_in_python_equals_fmi2_with_it_in_c(bench, in_python):
    """The FMI 3.0 builds through the core's fmi3 calls with the CAN network ticked in Python
    (artibus.can.Network, the reference) against the FMI 2.0 builds with the network in C,
    bit for bit; a bench without a network: the FMI 3.0 builds against the FMI 2.0 ones."""
    t2, _, s2, _, _ = bench_run(bench, "2")
    t3, _, s3, _, _ = bench_run(bench, "3", core=False)
    assert s2 == "C core" and s3 == "C core" + in_python
    np.testing.assert_array_equal(t3, t2)


@pytest.mark.slow
def test_artibus_run_fmi3_writes_the_fmi2_results(tmp_path, capsys):
    a, b = tmp_path / "fmi2.csv", tmp_path / "fmi3.csv"
    assert cli.main(["run", "Urbino18_Circle", "-o", str(a)]) == 0
    assert cli.main(["run", "Urbino18_Circle", "--fmi", "3", "-o", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()
    said = capsys.readouterr().out
    assert "the FMUs' FMI 3.0 builds" in said
    assert (fmu_dir() / "fmi3" / "Urbino18_Circle.ssp").is_file()


def _fmu_dir_copy(tmp_path, monkeypatch, leave_out=()):
    """ARTIBUS_FMU_DIR: tmp_path/fmus with links to the built FMUs (FMI 2.0 and 3.0), but leave_out's FMI 3.0 ones."""
    built = fmu_dir()
    d = tmp_path / "fmus"
    (d / "fmi3").mkdir(parents=True)
    for f in built.glob("*.fmu"):
        (d / f.name).symlink_to(f)
    for f in (built / "fmi3").glob("*.fmu"):
        if f.stem not in leave_out:
            (d / "fmi3" / f.name).symlink_to(f)
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(d))
    return d


def test_a_missing_fmi3_build_is_named(tmp_path, monkeypatch, capsys):
    _fmu_dir_copy(tmp_path, monkeypatch, leave_out={"RoadFollowDriver"})
    with pytest.raises(ArtibusError) as e:
        runner.Simulation("Urbino18_Circle", fmi="3")
    text = str(e.value)
    assert "RoadFollowDriver has no FMI 3.0 build" in text
    assert "resources/RoadFollowDriver.fmu" in text and "SystemStructure.ssd:" in text
    assert str(tmp_path / "fmus" / "fmi3" / "RoadFollowDriver.fmu") in text
    # on the command line: one line, exit 1, no traceback
    assert cli.main(["run", "Urbino18_Circle", "--fmi", "3", "-o", str(tmp_path / "x.csv")]) == 1
    err = capsys.readouterr().err
    assert "RoadFollowDriver has no FMI 3.0 build" in err and "Traceback" not in err
    # the FMI 2.0 run does not need it
    with runner.Simulation("Urbino18_Circle", fmi="2") as sim:
        assert {u.fmu.fmi for u in sim.units} == {2}


def test_fmi_takes_2_or_3_and_a_bench_by_name():
    with pytest.raises(ArtibusError, match=r"--fmi 4: expected 2 or 3"):
        ssp.ssp_path("Urbino18_Circle", "4")
    packed = ssp.ssp_path("Urbino18_Circle")
    with pytest.raises(ArtibusError, match=r"is a pack, run with the FMUs inside it"):
        ssp.ssp_path(str(packed), "3")


def test_the_bench_chooses_fmi3_in_its_ssd(tmp_path, monkeypatch):
    """A component's source resources/fmi3/<Name>.fmu: that build, as the .ssd says;
    --fmi 2 puts the FMI 2.0 build in its place (fmus/fmi2/<Bench>.ssp)."""
    d = _fmu_dir_copy(tmp_path, monkeypatch)
    benches = tmp_path / "benches"
    shutil.copytree(ssp.BENCH_DIR / "Urbino18_Circle", benches / "Urbino18_Circle")
    ssd = benches / "Urbino18_Circle" / "SystemStructure.ssd"
    text = ssd.read_text()
    assert 'source="resources/BusKinematics.fmu"' in text
    ssd.write_text(text.replace('source="resources/BusKinematics.fmu"', 'source="resources/fmi3/BusKinematics.fmu"'))
    monkeypatch.setattr(ssp, "BENCH_DIR", benches)
    with runner.Simulation("Urbino18_Circle") as sim:
        versions = {u.path: u.fmu.fmi for u in sim.units}
        mixed = sim.run().array()
        assert sim.ssp == d / "Urbino18_Circle.ssp"
    assert {v for p, v in versions.items() if sim.bench.components[p].source.endswith("BusKinematics.fmu")} == {3}
    assert sorted(versions.values()) == [2, 3]       # the driver stays FMI 2.0
    with runner.Simulation("Urbino18_Circle", fmi="2") as sim:
        assert {u.fmu.fmi for u in sim.units} == {2}
        assert sim.ssp == d / "fmi2" / "Urbino18_Circle.ssp"
        np.testing.assert_array_equal(sim.run().array(), mixed)


def test_pack_fmi3_holds_the_fmi3_builds_under_the_same_names(tmp_path, monkeypatch):
    import zipfile
    d = _fmu_dir_copy(tmp_path, monkeypatch)
    out = ssp.pack("Urbino18_Circle", fmi="3")
    assert out == d / "fmi3" / "Urbino18_Circle.ssp"
    with zipfile.ZipFile(out) as z:
        fmus = sorted(n for n in z.namelist() if n.endswith(".fmu"))
        assert fmus == ["resources/BusKinematics.fmu", "resources/RoadFollowDriver.fmu"]
        for n in fmus:
            assert z.read(n) == (d / "fmi3" / Path(n).name).read_bytes()
    assert os.path.isfile(out)


@pytest.mark.slow
def test_sweep_fmi3_gives_the_fmi2_kpis_as_other_cases(tmp_path):
    """`artibus sweep --fmi 3`: the pack with the FMI 3.0 builds runs on the workers; its
    cases are keyed apart from the FMI 2.0 ones (the FMUs differ) and give their KPIs."""
    import logging

    import artibus
    from dask.distributed import Client, LocalCluster
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}, silence_logs=logging.CRITICAL)
    client = Client(cluster)
    try:
        kw = dict(grid={"Driver.vSet": "3,5"}, fixed={"Driver.roadBefore": 2.0}, stop_time=3.0,
                  client=client, progress=None, plot=False)
        a = artibus.sweep("Bus36m_Circle", out=tmp_path / "s", fmi="2", **kw)
        b = artibus.sweep("Bus36m_Circle", out=tmp_path / "s", fmi="3", **kw)   # the same folder
    finally:
        client.close()
        cluster.close()
    assert a.ran == 2 and b.ran == 2 and a.failed == b.failed == 0     # not taken for the FMI 2.0 cases
    ta, tb = a.table.to_pylist(), b.table.to_pylist()
    kpis = [c for c in a.table.column_names if c.endswith("]") and not c.startswith("Driver.")]
    assert kpis
    for ra, rb in zip(ta, tb):
        assert ra["key"] != rb["key"]
        for c in kpis:
            assert close(ra[c], rb[c]), (c, ra[c], rb[c])


# ---- the other bench commands: bode and replay with --fmi 3 ------------------------------

@pytest.fixture
def packs_run(monkeypatch):
    """the .ssp files the Simulations of a test ran (so a test sees the FMI 3.0 pack was taken)"""
    from artibus.runner.simulation import Simulation
    seen, init = [], Simulation.__init__

    def spy(self, *a, **k):
        init(self, *a, **k)
        seen.append(Path(self.ssp))

    monkeypatch.setattr(Simulation, "__init__", spy)
    return seen


def test_bode_with_fmi3_writes_the_fmi2_table(tmp_path, packs_run):
    """`artibus bode --fmi 3`: the same sine runs on the FMI 3.0 builds, the same table byte for byte"""
    tables = {}
    for fmi in ("2", "3"):
        packs_run.clear()
        out = tmp_path / f"b{fmi}.csv"
        assert cli.main(["bode", "MultiAxle_StepSteer", "--input", "Steering.delta1", "--measure", "Vehicle.w_r",
                         "--set", "Steering.delta1=0", "--fmin", "0.2", "--fmax", "1", "--n", "2",
                         "-o", str(out), "--fmi", fmi]) == 0
        tables[fmi] = out.read_text()
        assert packs_run and all((p.parent.name == "fmi3") == (fmi == "3") for p in packs_run), packs_run
    assert len(tables["3"].splitlines()) == 3
    assert tables["3"] == tables["2"]


def test_replay_with_fmi3_equals_fmi2(packs_run):
    """`artibus replay --fmi 3` (artibus.can.replay.replay(fmi="3")): the shipped log into the bench's
    FMI 3.0 builds, every recorded column and every error figure as with FMI 2.0"""
    from artibus.base import ROOT
    from artibus.can import replay
    log = ROOT / "ssp" / "logs" / "Urbino18_test.csv"
    r2 = replay.replay(log, "Urbino18_Replay", fmi="2")
    assert packs_run and all(p.parent.name != "fmi3" for p in packs_run)
    packs_run.clear()
    r3 = replay.replay(log, "Urbino18_Replay", fmi="3")
    assert packs_run and all(p == fmu_dir() / "fmi3" / "Urbino18_Replay.ssp" for p in packs_run), packs_run
    assert r3.result.names == r2.result.names and len(r3.result.time) > 100
    np.testing.assert_array_equal(r3.result.array(), r2.result.array())
    assert r3.errors == r2.errors


def test_a_report_with_fmi3_runs_its_studies_on_fmi3(tmp_path, packs_run):
    """`artibus run MultiAxle_StepSteer --report DIR --fmi 3`: the bench's study (its other speeds and
    steering laws, the sine tests) runs on the FMI 3.0 builds too, as the run itself"""
    assert cli.main(["run", "MultiAxle_StepSteer", "--report", str(tmp_path / "rep"), "--fmi", "3"]) == 0
    assert len(packs_run) > 2 and all(p.parent.name == "fmi3" for p in packs_run), packs_run
    assert (tmp_path / "rep" / "index.html").is_file()
