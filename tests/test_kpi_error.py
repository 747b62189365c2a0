"""Every KPI with its co-simulation error (issue 44): the error beside each KPI
in the report's page, its kpis.csv, the index's summary.csv and `run`'s
printout; a graded KPI within its error of the paper's bound (or whose error
exceeds 2 % of its value) says "within the stepping error".

The errors are checked against runs the tests make themselves through the
Python API (a bench whose only continuous component takes ``step``: its h/2 run
is Simulation(step=h/2); the Jacobi run; the monolithic reference), each KPI's
error computed here from the KPIs of those runs."""
import csv
import math

import pytest

from artibus import runner
from artibus.bench import script
from artibus.cli import main
from artibus.report import FAIL, Kpi, PASS
from artibus.report import cosim_error, pages

BENCH = "Bus36m_LaneChange"     # 22 s; one continuous component (Bus, no step annotation), the rest sampled


def kpi_values(result):
    """{name: value} of the bench's numeric KPIs of a run."""
    return {k.name: float(k.value) for k in script.load(BENCH).kpis(result)
            if isinstance(k.value, (int, float)) and not isinstance(k.value, bool) and math.isfinite(k.value)}


def run(**kw):
    with runner.Simulation(BENCH, **kw) as sim:
        return sim.run()


@pytest.fixture(scope="module")
def default():
    return run()


def test_estimate_without_a_reference_is_the_larger_of_h2_and_jacobi(default):
    """Where no reference runs: each KPI's error is max(2 |K(h) - K(h/2)|, |K_GS - K_J|):
    the h/2 run made here with the plant's step halved (Simulation(step=0.005): the
    controllers keep their annotated 10 ms, the driver its 20 ms), the Jacobi run at h."""
    base = kpi_values(default)
    half, jacobi = kpi_values(run(step=0.005)), kpi_values(run(algorithm="jacobi"))
    est = cosim_error.measure(BENCH, default, reference=False)
    kpis = est.apply(script.load(BENCH).kpis(default))
    seen = 0
    for k in kpis:
        if k.name not in base:
            assert k.error is None, k.name
            continue
        e2, ej = 2 * abs(base[k.name] - half[k.name]), abs(base[k.name] - jacobi[k.name])
        assert k.error == pytest.approx(max(e2, ej), rel=1e-9, abs=1e-12), k.name
        assert k.error_how == (cosim_error.HALVED if e2 >= ej else cosim_error.ALGORITHMS)
        if base[k.name]:
            assert k.error_pct == pytest.approx(100 * k.error / abs(base[k.name]))
        seen += 1
    assert seen >= 8
    assert any(k.error > 0 for k in kpis if k.error is not None)


@pytest.mark.skipif(not cosim_error.reference_available(), reason="the runner has no monolithic reference")
def test_error_against_the_reference(default):
    """With the runner's reference: each KPI's error is |K(h) - K(reference)|, the
    reference run here (Simulation(reference=True))."""
    base, ref = kpi_values(default), kpi_values(run(reference=True))
    kpis = cosim_error.measure(BENCH, default).apply(script.load(BENCH).kpis(default))
    for k in kpis:
        if k.name in base:
            assert k.error == pytest.approx(abs(base[k.name] - ref[k.name]), rel=1e-9, abs=1e-12), k.name
            assert k.error_how == cosim_error.REFERENCE


def graded(value, bound, error, passed=True, margin_error=None):
    return Kpi("x", value, "m", "< 1", "paper", passed, bound=bound, error=error, error_how=cosim_error.HALVED,
               margin_error=margin_error, explain="why it fails")


def test_marking_rule():
    """Marked "within the stepping error": a graded KPI whose error is at least its
    distance to the bound, or above 2 % of its value; not a KPI with a smaller error,
    nor an ungraded one; a bound that is another run's value counts its own error."""
    W = pages.WITHIN
    assert graded(0.97, 1.0, 0.019).verdict == PASS                   # 1.96 %, 0.03 from the bound
    assert graded(0.97, 1.0, 0.031).verdict == f"{PASS} {W}"          # beyond the bound
    assert graded(34.0, 34.0, 0.0).verdict == PASS                    # on the bound, exactly: no error
    assert graded(1e-12, (-1e-6, 1e-6), 1e-12).verdict == PASS        # 0 by construction: the bound's scale
    assert graded(0.50, 1.0, 0.011).verdict == f"{PASS} {W}"          # 2.2 % of the value
    assert graded(1.02, 1.0, 0.005, passed=False).verdict == FAIL
    assert graded(1.02, 1.0, 0.021, passed=False).verdict == f"{FAIL} {W}"
    assert graded(0.95, (0.9, 1.0), 0.015).verdict == PASS            # nearest edge 0.05 away, 1.6 %
    assert graded(0.95, (0.9, 1.0), 0.01, margin_error=0.06).verdict == f"{PASS} {W}"
    assert graded(0.97, None, 0.019).verdict == PASS                  # no bound: the 2 % alone
    assert graded(0.97, 1.0, None).verdict == PASS                    # not measured: not marked
    free = Kpi("y", 1.0, "m", "< 1", "paper", ungraded="another configuration's", error=0.5)
    assert not free.within_error and "within" not in free.verdict


def test_page_and_csvs_carry_the_error(tmp_path):
    """The page's table shows each error (unit and %) and the mark; a marked ✘ keeps
    its explanation; kpis.csv and summary.csv have the error columns."""
    kpis = [graded(0.97, 1.0, 0.031), graded(1.5, 1.0, 0.6, passed=False),
            Kpi("z", 2.0, "s", error=0.01, error_how=cosim_error.REFERENCE), Kpi("n", 3.0, "-")]
    kpis[1].name, kpis[2].name = "x2", "z"
    (tmp_path / "b").mkdir()
    pages.write_html(tmp_path / "b", "b", "", kpis, [], error_note="measured here")
    page = (tmp_path / "b" / "index.html").read_text()
    assert "±0.031 m (3.2 %)" in page and "±0.01 s (0.5 %)" in page
    assert page.count(pages.WITHIN) >= 3 and "why it fails" in page and "Why each" in page and "measured here" in page
    rows = list(csv.DictReader((tmp_path / "b" / "kpis.csv").open()))
    assert [r["cosim_error"] for r in rows] == ["0.031", "0.6", "0.01", ""]
    assert float(rows[0]["cosim_error_pct"]) == pytest.approx(100 * 0.031 / 0.97)
    assert [r["cosim_error_method"] for r in rows] == [cosim_error.HALVED, cosim_error.HALVED,
                                                      cosim_error.REFERENCE, ""]
    assert [r["within_stepping_error"] for r in rows] == ["yes", "yes", "", ""]   # the ✘: 0.5 beyond, error 0.6
    assert [r["passed"] for r in rows] == ["pass", "FAIL", "", ""]
    pages.write_index(tmp_path, [("b", tmp_path / "b", kpis)])
    rows = list(csv.DictReader((tmp_path / "summary.csv").open()))
    assert [r["cosim_error"] for r in rows] == ["0.031", "0.6", "0.01", ""]
    assert rows[0]["within_stepping_error"] == "yes"


def test_run_prints_each_error_and_writes_it(tmp_path, capsys, default):
    """`artibus run BENCH --report`: every numeric KPI's error printed and in kpis.csv,
    the numbers those of the runs made here (the reference where the runner has one,
    else the h/2 and Jacobi estimate)."""
    assert main(["run", BENCH, "--report", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    base = kpi_values(default)
    if cosim_error.reference_available():
        ref = kpi_values(run(reference=True))
        want = {n: abs(v - ref[n]) for n, v in base.items()}
    else:
        half, jac = kpi_values(run(step=0.005)), kpi_values(run(algorithm="jacobi"))
        want = {n: max(2 * abs(v - half[n]), abs(v - jac[n])) for n, v in base.items()}
    rows = {r["kpi"]: r for r in csv.DictReader((tmp_path / "r" / "kpis.csv").open())}
    for name, e in want.items():
        assert float(rows[name]["cosim_error"]) == pytest.approx(e, rel=1e-9, abs=1e-12), name
        line = next(ln for ln in out.splitlines() if ln.strip().startswith(f"{name}:"))
        assert f"co-simulation error ±{e:.3g}" in line, line
    assert f"{BENCH}: co-simulation errors: " in out


def test_sweep_records_the_error_on_a_sample_of_cases(tmp_path):
    """`sweep(..., error_every=2)`: cases 0 and 2 of 3 carry "KPI [unit] cosim error" =
    2 |K(h) - K(h/2)|, the runs made here (the case's overrides, Simulation(step=0.005));
    case 1 has none."""
    import artibus
    from dask.distributed import Client, LocalCluster
    speeds = [12.0, 13.0, 14.0]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        res = artibus.sweep(BENCH, grid={"Driver.vSet": speeds}, out=tmp_path / "s", client=client, progress=None,
                            plot=False, error_every=2)
    rows = sorted(res.table.to_pylist(), key=lambda r: r["case"])
    assert [r["Driver.vSet"] for r in rows] == speeds
    for i, r in enumerate(rows):
        errors = {c[:-len(" cosim error")]: v for c, v in r.items() if c.endswith("] cosim error")}
        if i % 2:
            assert all(v is None for v in errors.values()), r
            continue
        o = {"Driver.vSet": speeds[i]}
        base, half = kpi_values(run(overrides=o)), kpi_values(run(step=0.005, overrides=o))
        checked = 0
        for k in script.load(BENCH).kpis(run(overrides=o)):
            col = f"{k.name} [{k.unit}]"
            if k.name in base:
                assert errors[col] == pytest.approx(2 * abs(base[k.name] - half[k.name]), rel=1e-9, abs=1e-12), col
                checked += 1
        assert checked >= 8


def test_page_says_which_grades_hold_beyond_the_stepping_error(tmp_path):
    """The page's section on the grades: a KPI whose distance to its bound exceeds its
    error holds beyond it; one whose error (or its bound's: another run's value) reaches
    the distance, or exceeds 2 %, is within it."""
    from lxml import html as lhtml
    kpis = [graded(0.5, 1.0, 0.001), graded(0.97, 1.0, 0.031), graded(0.9, 1.0, 0.001, margin_error=0.2)]
    for k, name in zip(kpis, "abc"):
        k.name = name
    pages.write_html(tmp_path, "t", "", kpis, [])
    doc = lhtml.fromstring((tmp_path / "index.html").read_text())
    h2 = next(h for h in doc.iter("h2") if h.text_content() == "The grades against the stepping error")
    table = h2.getnext().getnext()
    said = {tr[0].text_content(): tr[-1].text_content() for tr in table.iter("tr") if tr[0].tag == "td"}
    assert said == {"a": "holds beyond the stepping error", "b": pages.WITHIN, "c": pages.WITHIN}
    assert "1 of 3 graded KPIs" in h2.getnext().text_content()


def test_sweep_error_every_must_be_a_count(tmp_path, capsys):
    """`sweep --error-every -1`: one line naming the option and the value, no traceback, nothing run."""
    code = main(["sweep", BENCH, "--grid", "Driver.vSet=12", "--error-every", "-1", "-o", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert code != 0 and "--error-every -1: a whole number >= 0" in err and "Traceback" not in err, err
    assert not (tmp_path / "s").exists()


@pytest.mark.slow
def test_the_main_jobs_graded_kpis_are_within_one_percent_of_the_reference(tmp_path):
    """issue 44's acceptance over the main job's own summary (`artibus run --all --report`, as
    ./run.sh runs it; the studies' variants included): every graded KPI's error measured against
    the monolithic reference and below 1 % of its value; a KPI that is 0 by construction (the
    zero side-slip steering's side-slip, ~1e-12 rad against its bound 0: a percentage of it says
    nothing) below 1e-9 in its unit"""
    assert main(["run", "--all", "--report", str(tmp_path / "out")]) == 0
    rows = [r for r in csv.DictReader((tmp_path / "out" / "summary.csv").open()) if r["passed"] in ("pass", "FAIL")]
    assert len(rows) >= 40, len(rows)                    # the main job grades 45 KPIs
    for r in rows:
        where = (r["bench"], r["kpi"], r["value"], r["cosim_error"])
        assert r["cosim_error_method"] == cosim_error.REFERENCE, where
        value, error = abs(float(r["value"])), float(r["cosim_error"])
        assert error < 0.01 * value or (value < 1e-9 and error < 1e-9), where
