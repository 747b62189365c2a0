"""The monolithic reference (issue 44): `artibus run BENCH --reference`, Simulation(reference=True).

Every component that offers Model Exchange integrated together in one CVODE (the ME group,
src/runner_core/me_group.c), the sampled controllers, the driver and the ECUs as they are at the
timing the bench states (artibus.runner.plan.stated_timing). What is held against what:
- the default run, a different algorithm (Co-Simulation builds coupled by sample-and-hold at the
  communication step), converges to the reference as its step halves: each KPI's error at h/2 is
  below its error at h (or both are below FLOOR_PCT, the plants' own integration error: their CS
  builds integrate at rtol 1e-6, the reference at 1e-8), and at h/8 below 0.5 %;
- the reference does not depend on the base step it is recorded at (its sampled units keep their
  timing);
- the stated timing's steps in the plan, worked out by hand;
- bad input: no Model Exchange component, an algebraic loop inside the group, a member that fails.
"""
import subprocess
import sys

import pytest

from artibus.base import ArtibusError
from artibus.bench import script, ssp
from artibus.fmu import Result, SimulationError
from artibus.runner.simulation import Simulation

H = 0.01                 # the benches' default base step
FLOOR_PCT = 0.05         # below this a KPI's error is the plants' integration error, not the stepping's
FINE_PCT = 0.5           # issue 44's acceptance: the error at h/8

# seed 001's transient KPIs of the damping study (the thesis's (4)-(6)): checked beside the graded ones
DAMPING = ("rear axle overshoot beyond the 3.25 m offset after the lane change",
           "max |articulation angle| after the lane change", "max |articulation rate| after the lane change")

CASES = ([("Bus36m_Circle", v) for v in (None, "guided", "guidedAll", "guidedForceMin")]
         + [("Scania18m_Damping", v) for v in ("none", "option1", "option2", "option3", "baseline", "revised",
                                              "floor", "lc60_100")]
         + [("Bus36m_LaneChange", None)])


def kpis(bench, variant, grid=H, **kw):
    """The bench's own KPIs (its bench.py) of one run, on the output grid ``grid`` (every row of a
    run at a finer step than the grid dropped but those at the grid's points: a maximum over rows
    compares like with like)."""
    overrides = ssp.variant_overrides(bench, [variant] if variant else None)
    with Simulation(bench, overrides=overrides, **kw) as sim:
        r = sim.run()
        m = int(round(grid / sim.base_step))
    if m > 1:
        r = Result.from_array(r.names, r.array()[::m])
    return {k.name: k for k in script.load(bench).kpis(r)}


def error_pct(k, ref):
    return abs(k.value - ref.value) / abs(ref.value) * 100


@pytest.mark.parametrize("bench,variant", CASES)
def test_the_default_run_converges_to_the_reference(bench, variant):
    ref = kpis(bench, variant, reference=True)
    runs = {n: kpis(bench, variant, step=H / n) for n in (1, 2, 8)}
    numbers = [n for n, k in ref.items() if isinstance(k.value, (int, float)) and k.value == k.value and k.value]
    # the graded KPIs (and the damping study's); a variant without a graded one: each of its KPIs
    checked = [n for n in numbers if ref[n].passed is not None or n in DAMPING] or numbers
    assert checked, f"{bench} {variant}: no KPI"
    for name in checked:
        e = {n: error_pct(runs[n][name], ref[name]) for n in runs}
        assert e[2] <= e[1] or e[2] < FLOOR_PCT, (bench, variant, name, e)
        assert e[8] < FINE_PCT, (bench, variant, name, e)


def test_the_reference_keeps_its_timing_at_a_finer_base_step():
    """The reference recorded at h/4 (its sampled controllers at the same timing, the group stepped
    more often) gives the KPIs it gives at h: the group is exact between the sampled outputs."""
    a = kpis("Scania18m_Damping", "option2", reference=True)
    b = kpis("Scania18m_Damping", "option2", reference=True, step=H / 4)
    for name in DAMPING + ("energy the damper took out",):
        assert error_pct(b[name], a[name]) < 0.01, (name, a[name].value, b[name].value)


def test_the_reference_groups_the_plant_and_the_damper():
    with Simulation("Scania18m_Damping", reference=True) as sim:
        sim.run(stop_time=1.0)
        group = sim._group
        assert sorted(u.path for u in group.members) == ["Bus", "Damper"]
        inside = {(l.src.path, l.dst.path) for l in group.links}
        assert inside == {("Bus", "Damper"), ("Damper", "Bus")}
        assert group.struct.rtol == 1e-8
        assert group.counts()["steps"] > 0
        # the controllers stay Co-Simulation units
        assert {u.path for u in sim.units if getattr(u.fmu.calls, "facade", None) is None} == {
            "Driver", "Controller", "Baseline"}


def test_stated_timing_by_hand():
    """A 20 ms controller of a bench whose default base step is 10 ms is seen 10 ms after its
    sample: at a 2.5 ms base step (ratio 8) the plan steps it in the 5th base step of its period
    (k % 8 == 4), early = 3; a 10 ms one is seen at its sample (k % 4 == 0), early = 3."""
    from types import SimpleNamespace as U

    from artibus.runner.plan import _Plan, stated_timing
    slow = U(path="C", step=0.02, ratio=8, sampled=True)
    fast = U(path="B", step=0.01, ratio=4, sampled=True)
    plant = U(path="P", step=0.0025, ratio=1, sampled=False)
    stated_timing([slow, fast, plant], 0.01, 0.0025)
    assert (slow.early, fast.early, plant.early) == (3, 3, 0)
    plan = _Plan([slow, fast, plant], 16)
    stepped = {u.path: [k for k in range(16) if u in plan[k][1]] for u in (slow, fast, plant)}
    assert stepped == {"C": [4, 12], "B": [0, 4, 8, 12], "P": list(range(16))}


# --- bad input ---------------------------------------------------------------------------------

def _ssp(tmp_path, elements, connections, fmus):
    from artibus.testing import make_ssp
    return make_ssp(tmp_path, elements, connections or None, 0.1, name="b", fmu=False, fmus=fmus)


def _component(name, fmu, connectors):
    conns = "".join(f'<ssd:Connector name="{n}" kind="{k}"><ssc:Real/></ssd:Connector>' for n, k in connectors)
    return (f'<ssd:Component name="{name}" source="resources/{fmu}.fmu" type="application/x-fmu-sharedlibrary">'
            f'<ssd:Connectors>{conns}</ssd:Connectors></ssd:Component>')


def test_a_bench_without_model_exchange_is_refused(tmp_path):
    path = _ssp(tmp_path, _component("C", "DampingController", [("pct", "output")]), "", ["DampingController"])
    p = subprocess.run([sys.executable, "-m", "artibus", "run", str(path), "--reference", "-o",
                        str(tmp_path / "r.csv")], capture_output=True, text=True)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert "--reference: no component offers Model Exchange" in p.stderr
    assert "C (DampingController)" in p.stderr
    assert not (tmp_path / "r.csv").exists()


def test_an_algebraic_loop_inside_the_group_is_refused(tmp_path):
    """Two dampers, each one's moment into the other's angle: each Mjoint depends directly on its
    Lambda (declared), so the group cannot evaluate its connections (Jacobi: the Gauss-Seidel order,
    which refuses the loop itself, is not asked)."""
    ends = [("Lambda", "input"), ("Mjoint", "output")]
    link = ('<ssd:Connection startElement="{a}" startConnector="Mjoint" endElement="{b}" endConnector="Lambda">'
            '<ssc:LinearTransformation factor="1e-6"/></ssd:Connection>')
    path = _ssp(tmp_path, _component("D1", "ArticulationDamper", ends) + _component("D2", "ArticulationDamper", ends),
                link.format(a="D1", b="D2") + link.format(a="D2", b="D1"), ["ArticulationDamper"])
    with pytest.raises(ArtibusError, match=r"algebraic loop inside the Model Exchange group .*D1\.Mjoint -> D2\.Mjoint"):
        Simulation(path, reference=True, algorithm="jacobi")


def test_a_failing_member_stops_the_reference_with_the_time_and_its_message():
    """The damper's valve lag made 1e-300 s: its pressure's derivative overflows when the lane change
    moves the hinge (about 1.15 s); the run stops there, the rows before kept."""
    overrides = {**ssp.variant_overrides("Scania18m_Damping", ["option2"]), "Damper.tauP": 1e-300}
    with Simulation("Scania18m_Damping", overrides=overrides, reference=True) as sim:
        with pytest.raises(SimulationError) as e:
            sim.run()
    text = str(e.value)
    assert "failed at t = 1.15 s" in text and "Model Exchange group (the reference), member '" in text
    assert e.value.result is not None and abs(e.value.result.time[-1] - 1.15) < 1e-9


def test_every_graded_kpi_of_the_main_job_is_within_one_percent_of_the_reference():
    """issue 44's acceptance: with the benches' default steps, every graded KPI of the main job
    (`artibus run --all --report`: each bench at its default) within 1 % of the reference run's,
    both computed here by the bench's own KPI code (not read from the report's error column)"""
    checked = []
    for bench in ssp.bench_names():
        ref = kpis(bench, None, reference=True)
        default = kpis(bench, None)
        for name, k in ref.items():
            if k.passed is None or not isinstance(k.value, (int, float)) or k.value != k.value:
                continue
            e = error_pct(default[name], k) if k.value else abs(default[name].value)
            checked.append((bench, name, e))
    assert len(checked) >= 20, checked                 # the main job grades some two dozen KPIs
    worst = max(checked, key=lambda c: c[2])
    assert worst[2] < 1.0, worst
