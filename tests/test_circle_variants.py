"""Bus36m_Circle's variants (issue 13): one bench, seed 000's steering system
built in and switched by parameter sets (TrainGuidance.guided,
ForceMinimization.law), instead of four copies of its .ssd.

- the variants are listed by name, and an old bench name points to its variant;
- the default (unsteered): the controllers send exactly 0 to A3..A6, and the
  run equals, bit for bit, the same bench with the controllers taken out
  (built here from the packed .ssd);
- guided: A3/A5 exactly 0, A4/A6 what the guidance sends; guidedAll: A3 = A4
  and A5 = A6 sample for sample; guidedForceMin: A3/A5 neither 0 nor A4/A6;
  the bench's KPIs tell each run's variant from the recorded signals;
- the switches on the FMUs alone: guided = false gives 0 while the guidance
  runs on (gamma4ss), law 0/1/2 gives 0 / the force minimisation / the inputs.
"""
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from lxml import etree

from artibus import ArtibusError, fmu_path, report, runner
from artibus.bench import script, ssp

BENCH = "Bus36m_Circle"
VARIANTS = ["guided", "guidedAll", "guidedForceMin"]
DELTA = [f"Bus.delta[{a}]" for a in (3, 4, 5, 6)]
CTRL = ["Guidance.gamma4", "Guidance.gamma6", "ForceMin.gamma3", "ForceMin.gamma5"]
STOP = 40.0        # the bus is on the circle (entry at s = 25 m, 3 m/s) and well round it


def _record():
    """Every output the bench records by default, plus the plant's steering inputs."""
    with runner.Simulation(BENCH) as sim:
        names = [n for n in sim.names if n != "time"]
    return names + DELTA


@pytest.fixture(scope="module")
def runs():
    rec = _record()
    out = {None: runner.run(BENCH, stop_time=STOP, record=rec)}
    for v in VARIANTS:
        out[v] = runner.run(BENCH, stop_time=STOP, record=rec, overrides=ssp.variant_overrides(BENCH, [v]))
    return out


def test_the_variants_are_listed_and_old_names_point_to_them(monkeypatch, tmp_path):
    assert ssp.variants(ssp.ssp_path(BENCH)) == VARIANTS
    assert not any(n.startswith("Bus36m_Circle_Guided") for n in ssp.bench_names())
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(tmp_path))     # no stale pack of an old bench there
    for old, v in (("Bus36m_Circle_GuidedForceMin", "guidedForceMin"), ("Bus36m_Circle_GuidedAll", "guidedAll"),
                   ("Bus36m_Circle_Guided", "guided")):
        with pytest.raises(ArtibusError) as e:
            ssp.ssp_path(old)
        assert f"did you mean {BENCH} --variant {v}" in str(e.value)


def _without_controllers(tmp_path):
    """The packed bench with Guidance and ForceMin and their connections taken out."""
    src = ssp.ssp_path(BENCH)
    ns = {"ssd": ssp.NS["ssd"]}
    with zipfile.ZipFile(src) as z:
        tree = etree.fromstring(z.read("SystemStructure.ssd"))
        gone = {"Guidance", "ForceMin"}
        for c in tree.iterfind(".//ssd:Component", ns):
            if c.get("name") in gone:
                c.getparent().remove(c)
        for c in tree.iterfind(".//ssd:Connection", ns):
            if c.get("startElement") in gone or c.get("endElement") in gone:
                c.getparent().remove(c)
        out = tmp_path / f"{BENCH}.ssp"
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zo:
            for n in z.namelist():
                data = etree.tostring(tree, xml_declaration=True, encoding="UTF-8") if n == "SystemStructure.ssd" \
                    else z.read(n)
                zo.writestr(n, data)
    return out


def test_unsteered_default_is_the_bus_without_controllers(runs, tmp_path):
    r = runs[None]
    for n in CTRL + DELTA:
        assert not np.any(r[n]), n                    # exactly 0, every sample
    bare = _without_controllers(tmp_path)
    with runner.Simulation(str(bare)) as sim:
        assert set(sim.bench.components) == {"Bus", "Driver"}
    b = runner.run(str(bare), stop_time=STOP, record=[n for n in r.names[1:] if not n.startswith(("Guidance.",
                                                                                                    "ForceMin."))])
    assert len(b.names) > 50 and set(b.names) <= set(r.names)
    for n in b.names:
        assert np.array_equal(b[n], r[n]), n
    assert script.load(BENCH).variant_of(r) == "unsteered"


def test_the_bus_stops_without_rolling_back_and_nothing_warns():
    """Unsteered, at the end of the road the driver brakes to a stop (a brake,
    -Kp v, not the PI on zero speed whose wound-up integral rolled the bus back,
    v < 0, the guidance's fault flag 2): the speed decays to zero without
    changing sign and no FMU warns. (That an idle guidance stays silent at v < 0:
    test_train_guidance_warns_only_where_it_steers.)"""
    with runner.Simulation(BENCH, record=["Guidance.v", "Guidance.fault", "Driver.finished"]) as sim:
        r = sim.run()
        logs = {u.path: u.fmu.log for u in sim.units}
    stopped = r["Driver.finished"] > 0.5
    assert stopped.any()
    v = r["Guidance.v"]
    assert np.min(v) >= 0 and np.all(r["Guidance.fault"] != 2)
    assert v[-1] < 0.02 * v[np.argmax(stopped)]           # it has come (almost) to a stop
    assert np.all(np.diff(v[stopped]) <= 1e-9)             # braking only: the speed never rises again
    for c, log in logs.items():
        assert not [m for m in log if m.startswith("[Warning]")], (c, log)


@pytest.mark.parametrize("guided", [True, False])
def test_train_guidance_warns_only_where_it_steers(guided):
    msgs = []
    simulate_fmu(str(fmu_path("TrainGuidance")), stop_time=0.1, start_values={"v": -1.0, "guided": guided},
                 logger=lambda env, name, status, cat, msg: msgs.append(msg.decode()))
    assert any("v = -1 m/s < 0" in m for m in msgs) == guided


def test_guided_steers_a4_a6_only(runs):
    r = runs["guided"]
    assert not np.any(r["Bus.delta[3]"]) and not np.any(r["Bus.delta[5]"])
    assert np.array_equal(r["Bus.delta[4]"], r["Guidance.gamma4"])
    assert np.array_equal(r["Bus.delta[6]"], r["Guidance.gamma6"])
    # A4, A6 steer opposite to A1 on the left-hand circle (seed 000, eq. 34)
    on = r["Driver.s"] > 60
    assert np.all(r["Bus.delta[4]"][on] < -0.05) and np.all(r["Bus.delta[6]"][on] < -0.05)


def test_guided_all_steers_a3_like_a4_and_a5_like_a6(runs):
    r = runs["guidedAll"]
    assert np.array_equal(r["Bus.delta[3]"], r["Bus.delta[4]"])
    assert np.array_equal(r["Bus.delta[5]"], r["Bus.delta[6]"])
    assert np.max(np.abs(r["Bus.delta[3]"])) > 0.05
    assert np.array_equal(r["ForceMin.gamma3"], r["Guidance.gamma4"])


def test_guided_force_min_steers_a3_a5_its_own_way(runs):
    r = runs["guidedForceMin"]
    on = r["Driver.s"] > 60
    for a, b in ((3, 4), (5, 6)):
        d = r[f"Bus.delta[{a}]"][on]
        assert np.all(d != 0) and np.max(np.abs(d - r[f"Bus.delta[{b}]"][on])) > 0.02
    # the hinge's lateral force: force minimisation against wrong A3/A5 angles (seed 000, Fig. 10)
    while_moving = r["Bus.v"] > 0.1
    F = {v: np.max(np.abs(runs[v]["Bus.FjointY[1]"][while_moving])) for v in VARIANTS}
    assert F["guidedForceMin"] < 4e3 < 20e3 < min(F["guided"], F["guidedAll"])


def test_the_kpis_tell_the_variant_that_ran(runs):
    mod = script.load(BENCH)
    for v in VARIANTS:
        assert mod.variant_of(runs[v]) == v
        k = {x.name: x for x in mod.kpis(runs[v])}
        assert k["max |lateral force| hinge 1"].paper == mod.paper_of(v, "F1")


def test_a_run_that_is_none_of_the_variants_has_kpis_without_bounds(tmp_path):
    """A3/A5 force-minimising with A4/A6 straight is no variant: its KPIs carry no
    paper value or verdict, and its report sets the four variants beside it."""
    r = runner.run(BENCH, stop_time=30.0, overrides={"ForceMin.law": 1})
    mod = script.load(BENCH)
    assert mod.variant_of(r) is None and np.any(r["ForceMin.gamma3"])
    k = mod.kpis(r)
    assert len(k) == 9 and all(x.passed is None and x.paper == "" for x in k)
    kpis = report.write_report(BENCH, r, tmp_path)
    names = [x.name for x in kpis]
    assert names[:9] == [f"this run: {x.name}" for x in k]
    assert [n.split(":")[0] for n in names[9::9]] == ["unsteered", *VARIANTS]


# --- the switches on the FMUs alone ---------------------------------------------------

def test_train_guidance_not_guided_sends_zero_and_runs_on():
    on = simulate_fmu(str(fmu_path("TrainGuidance")), stop_time=2.0, output_interval=0.01)
    off = simulate_fmu(str(fmu_path("TrainGuidance")), stop_time=2.0, output_interval=0.01,
                       start_values={"guided": False})
    assert not np.any(off["gamma4"]) and not np.any(off["gamma6"])
    assert np.array_equal(off["gamma4ss"], on["gamma4ss"]) and np.all(on["gamma4ss"] < -0.01)
    assert np.array_equal(on["gamma4"], on["gamma4ss"])     # steady state at the start: no lag left


@pytest.mark.parametrize("law", [0, 1, 2])
def test_force_minimization_law(law):
    g4, g6 = 0.05, -0.03
    default = simulate_fmu(str(fmu_path("ForceMinimization")), stop_time=1.0, output_interval=0.01,
                           start_values={"gamma4": g4, "gamma6": g6})
    r = simulate_fmu(str(fmu_path("ForceMinimization")), stop_time=1.0, output_interval=0.01,
                     start_values={"gamma4": g4, "gamma6": g6, "law": law})
    want = {0: (0.0, 0.0), 1: (default["gamma3"], default["gamma5"]), 2: (g4, g6)}[law]
    assert np.all(r["gamma3"] == want[0]) and np.all(r["gamma5"] == want[1])
    assert np.array_equal(r["fault"], default["fault"])
    assert abs(default["gamma3"][-1]) > 0.01 and default["gamma3"][-1] != g4


@pytest.mark.parametrize("law", [0, 1, 2])
def test_force_minimization_warns_only_where_its_angles_go_out(law):
    """A jack-knifed hinge (dPsi[1] beyond 90 deg: no instantaneous centre ahead) is flagged
    with any law, warned about with law 1 only."""
    msgs = []
    r = simulate_fmu(str(fmu_path("ForceMinimization")), stop_time=0.1, start_values={"dPsi[1]": 1.7, "law": law},
                     logger=lambda env, name, status, cat, msg: msgs.append(msg.decode()))
    assert np.all(r["fault"][1:].astype(int) & 4)
    assert any("dPsi[1] = 1.7" in m for m in msgs) == (law == 1)
