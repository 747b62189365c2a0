"""The reports an engineer reads (issue 15): the index's summary (every bench,
pass/fail marks, thumbnails, run metadata), seed 000's comparison page linked
from it, pages that render with no missing image (parsed, and screenshot with
headless Chromium), units in the report's CSVs, the swept-path envelope, long
bird's-eye drawings split into readable panels, the Bode plot's phase.

A few benches run shortly (the circle bench of the comparison, its variants
for 30 s, Scania18m_LaneChange's 14 s), as `artibus run --all --report` puts
them together."""
import csv
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from lxml import html as lhtml
from PIL import Image

from artibus import report, runner
from artibus.bench import ssp
from artibus.report import FAIL, Kpi, PASS, comparison, plots
from artibus.study import kpi

BENCHES = {"Bus36m_Circle": 30.0, "Scania18m_LaneChange": None}


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """A report directory as `artibus run --all --report` writes it, for a few short runs."""
    root = tmp_path_factory.mktemp("report")
    summary, kept, extra = [], {}, {}
    for b, stop in BENCHES.items():
        with runner.Simulation(b) as sim:
            r = sim.run(stop_time=stop)
        kpis = report.write_report(b, r, root / b, sim.wall)
        summary.append((b, root / b, kpis))
        if comparison.wanted(b):
            kept[b] = r
    # the comparison's variants, kept by their overrides (the page's rows are checked against them)
    page = comparison.write(root / "comparison", kept, run_extra=lambda bench, o: extra.setdefault(
        (bench, tuple(sorted(o.items()))), runner.run(bench, overrides=o, stop_time=30.0)))
    assert page is not None
    report.write_index(root, summary, [("comparison/index.html", comparison.TITLE, "side by side")])
    return root, summary, {**kept, **extra}


def _doc(path):
    return lhtml.fromstring(Path(path).read_text())


def test_index_summary_has_every_bench_with_its_marks(site):
    root, summary, _ = site
    doc = _doc(root / "index.html")
    rows = doc.xpath('//table[@class="summary"]/tr[td]')
    by_name = {r.xpath("string(td[2]//a/b)"): r for r in rows}
    assert set(by_name) == set(BENCHES)
    for name, _, kpis in summary:
        row = by_name[name]
        text = row.text_content()
        n_fail = sum(1 for k in kpis if k.passed is not None and not k.passed)
        n_pass = sum(1 for k in kpis if k.passed is not None and k.passed)
        # the bench's counts, and each failing KPI's mark in the headline (failing ones first)
        assert (f"{n_fail} {FAIL}" in text) == (n_fail > 0), text
        assert (f"{n_pass} {PASS}" in text) == (n_pass > 0), text
        assert len(row.xpath('.//span[@class="fail"]')) == (1 if n_fail else 0) + min(n_fail, 5)
        assert row.xpath(".//img/@src") == [f"{name}/thumb.png"]
    meta = doc.xpath('string(//p[@class="meta"])')
    commit = subprocess.run(["git", "-C", str(Path(report.__file__).parents[2]), "rev-parse", "--short=12", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    from artibus import __version__
    assert f"artibus: {__version__}" in meta and commit in meta and "platform: " in meta and "UTC" in meta


def test_index_links_the_stability_maps_only_when_made(tmp_path):
    """issue 43: ./run.sh makes the stability maps' page into out/modes/ (`artibus modes`); the
    index links it as "Stability maps (linear models)" when OUT/modes/index.html is there, and
    has no such link when it is not (`run --all --report` alone does not make it)."""
    def links():
        return {a.text_content(): a.get("href") for a in _doc(tmp_path / "index.html").xpath("//a")}

    report.write_index(tmp_path, [], metadata={"date": "today"})
    assert "modes/index.html" not in links().values()
    (tmp_path / "modes").mkdir()
    (tmp_path / "modes" / "index.html").write_text("<html><body>maps</body></html>")
    report.write_index(tmp_path, [], [("demo/index.html", "Demo", "the demo")], metadata={"date": "today"})
    got = links()
    assert got.get("Stability maps (linear models)") == "modes/index.html"
    assert got.get("Demo") == "demo/index.html"         # the other pages kept
    assert list(got.values()).count("modes/index.html") == 1


def test_a_failing_kpi_is_marked_on_the_index(tmp_path):
    """A ✘ is counted, shown first and linked from the index to its explanation
    on the bench's page; a calibration target and a paper figure of another
    configuration are shown as such and not counted."""
    d = tmp_path / "B"
    d.mkdir()
    ok = Kpi("fine", 0.5, "m", "< 1.0", "seed 000, Fig. 9", True)
    bad = Kpi("too far", 2.0, "m", "< 1.0", "seed 000, Fig. 9", False, explain="the geometry is estimated")
    cal = Kpi("peak damping", 13.5, "%", "13.5", "seed 001, 5.2.2", True, calibrated=True)
    other = Kpi("hinge force", 50.0, "kN", "> 20", "seed 000", ungraded="a bound of another configuration")
    kpis = [ok, bad, cal, other]
    assert report.tally(kpis) == (1, 1)
    report.write_html(d, "B", "", kpis, [])
    report.write_index(tmp_path, [("B", d, kpis)], metadata={"date": "today"})
    index = _doc(tmp_path / "index.html")
    row = index.xpath('//table[@class="summary"]/tr[td]')[0]
    fails = row.xpath('.//span[@class="fail"]')
    assert [f.text_content() for f in fails] == [f"1 {FAIL}", FAIL]
    assert row.xpath('.//a[span[@class="fail"]]/@href') == ["B/index.html#why-1"]
    assert f"1 {PASS}" in index.text_content() and f"1 {FAIL}" in index.text_content()
    lines = row.xpath("td[3]")[0].text_content()
    assert lines.index("too far") < lines.index("fine")            # the failing KPI first
    page = _doc(d / "index.html")
    assert page.xpath('//td[@class="fail"]//text()') == [FAIL]
    assert page.xpath('//td[@class="fail"]/a/@href') == ["#why-1"]
    assert "the geometry is estimated" in page.xpath('string(//div[@id="why-1"])')
    assert page.xpath('string(//td[@class="cal"])') == "calibrated"
    assert "not graded: a bound of another configuration" in page.xpath('string(//td[@class="ungraded"])')
    assert len(page.xpath('//td[@class="pass"]')) == 1


def test_comparison_page_linked_and_as_the_results(site):
    root, _, kept = site
    doc = _doc(root / "index.html")
    assert "comparison/index.html" in doc.xpath("//a/@href")
    page = _doc(root / "comparison" / "index.html")
    rows = page.xpath("//table/tr[td]")
    labels = [r.xpath("string(td[1])") for r in rows]
    assert labels == ["paper"] + list(comparison.CASES)
    for r, label in zip(rows[1:], comparison.CASES):
        variants, overrides = comparison.CASES[label]
        b = comparison.BENCH
        o = {**ssp.variant_overrides(b, list(variants)), **(overrides or {})}
        res = kept[(b, tuple(sorted(o.items())))] if o else kept[b]
        ax = {a: (res[f"Bus.xAxle[{a}]"][::5], res[f"Bus.yAxle[{a}]"][::5]) for a in (2, 4)}
        d4 = kpi.trace_deviation(*ax[2], *ax[4])
        F1 = np.max(np.abs(res["Bus.FjointY[1]"])) / 1e3
        assert r.xpath("string(td[2])").startswith(f"{d4:.3f} m")
        assert r.xpath("string(td[4])").startswith(f"{F1:.3f} kN")
    for img in page.xpath("//img/@src"):
        assert (root / "comparison" / img).is_file()


def _pages(root):
    return sorted(root.rglob("index.html"))


def test_every_image_exists_and_reads(site):
    root, _, _ = site
    seen = 0
    for p in _pages(root):
        doc = _doc(p)
        for src in doc.xpath("//img/@src"):
            f = p.parent / src
            assert f.is_file(), f"{p}: <img src={src}> missing"
            with Image.open(f) as im:
                im.load()
                assert im.width > 50 and im.height > 50
                if f.suffix == ".gif":
                    assert 50 <= im.n_frames <= 120          # an animation of about 100 frames
                    assert f.stat().st_size < 3e6
            seen += 1
        for href in doc.xpath("//a/@href"):
            if "://" not in href:
                path, _, frag = href.partition("#")
                target = p.parent / path if path else p
                assert target.exists(), f"{p}: link {href} leads nowhere"
                if frag:        # an anchor (a ✘'s explanation) exists on the page it names
                    assert _doc(target).xpath(f'//*[@id="{frag}"]'), f"{p}: link {href}: no such anchor"
    # the circle's 3 figures, its variants' and its animation; the comparison's 2; a thumbnail a bench
    assert seen >= 5 + 2 + len(BENCHES)


def test_the_circle_page_shows_every_variant(site):
    """Bus36m_Circle's report is a study: the KPIs of the default (unsteered) and of
    each variant, with the paper's bounds (guidedForceMin's hinge force < 4 kN)."""
    root, summary, _ = site
    kpis = {k.name: k for name, _, ks in summary if name == "Bus36m_Circle" for k in ks}
    text = _doc(root / "Bus36m_Circle" / "index.html").text_content()
    for v in ("unsteered", "guided", "guidedAll", "guidedForceMin"):
        assert f"{v}: max deviation of A4 from the A2 trace" in kpis
        assert f"{v}: max |lateral force| hinge 1" in text
    assert kpis["guidedForceMin: max |lateral force| hinge 1"].paper == "< 4 (force minimisation)"
    assert kpis["guidedForceMin: max |lateral force| hinge 1"].graded
    # the > 20 kN is graded on guidedAll only (inaccurate A3/A5 angles), shown beside guided, not graded
    assert kpis["guidedAll: max |lateral force| hinge 1"].graded
    assert not kpis["guided: max |lateral force| hinge 1"].graded
    assert "guidedAll" in kpis["guided: max |lateral force| hinge 1"].ungraded
    assert not kpis["unsteered: max deviation of A4 from the A2 trace"].graded
    assert kpis["unsteered: max deviation of A6 from the A2 trace"].paper.startswith("about 6")


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.parametrize("page", ["index.html", "comparison/index.html", "Bus36m_Circle/index.html"])
def test_screenshot_with_headless_chromium(site, page, tmp_path):
    exe = _chromium()
    if exe is None:
        pytest.skip("chromium not installed (scripts/setup_test.sh installs Debian's chromium)")
    root, _, _ = site
    shot = tmp_path / "shot.png"
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", f"--screenshot={shot}", "--window-size=1280,2000",
           (root / page).resolve().as_uri()]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)   # (a failure bound only)
    assert shot.is_file(), r.stderr[-2000:]
    a = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert a.shape[:2] == (2000, 1280)
    ink = np.any(a < 200, axis=2)
    assert ink.mean() > 0.01, "the screenshot is blank"
    # colour: the plots' lines and the marks, not only black text on white
    colourful = (a.max(axis=2) - a.min(axis=2)) > 60
    assert colourful.mean() > 0.001


def test_units_in_the_report_csvs(site):
    root, summary, _ = site
    rows = list(csv.DictReader((root / "summary.csv").open()))
    assert {r["bench"] for r in rows} == set(BENCHES)
    for name, d, kpis in summary:
        own = list(csv.DictReader((d / "kpis.csv").open()))
        assert [(r["kpi"], r["unit"]) for r in own] == [(k.name, k.unit) for k in kpis]
        for r, k in zip(own, kpis):
            if not k.missing:
                assert float(r["value"]) == pytest.approx(float(k.value))
            want = ("calibrated" if k.calibrated else ("pass" if k.passed else "FAIL") if k.graded
                    else "not graded" if k.ungraded else "")
            assert r["passed"] == want


def test_kpi_without_a_value_shows_why_or_is_named(tmp_path):
    report.write_html(tmp_path, "t", "", [Kpi("entered at", math.nan, "s", why="never in fallback"),
                                          Kpi("damping ratio", math.nan, "-"), Kpi("peak", 1.0, "m")], [])
    doc = _doc(tmp_path / "index.html")
    cells = [r.xpath("string(td[1])") + "|" + r.xpath("string(td[2])") for r in doc.xpath("//table/tr[td]")]
    assert cells == ["entered at|n/a (never in fallback)", "peak|1"]
    assert "Not computed in this run (no value): damping ratio" in doc.text_content()


def test_swept_area_of_a_rigid_body_on_a_circle():
    """A body (width W, front overhang a ahead of its rear axle, rear b behind)
    with its rear axle on a circle of radius R sweeps the annulus between
    R - W/2 and sqrt((R + W/2)^2 + a^2) (the rear corners stay inside it)."""
    R, W, a, b = 10.0, 2.55, 9.0, 3.0
    ang = np.linspace(0, 2 * math.pi, 1441)
    px, py = R * np.cos(ang), R * np.sin(ang)
    hx, hy, nx, ny = -np.sin(ang), np.cos(ang), np.cos(ang), np.sin(ang)
    corners = np.stack([np.column_stack([px + s * hx + t * W / 2 * nx, py + s * hy + t * W / 2 * ny])
                        for s, t in ((a, 1), (a, -1), (-b, -1), (-b, 1))], axis=1)
    mask, x0, y0, res = report.swept_area(corners, resolution=0.05)
    ro, ri = math.hypot(R + W / 2, a), R - W / 2
    assert mask.sum() * res ** 2 == pytest.approx(math.pi * (ro ** 2 - ri ** 2), rel=0.02)
    # the centre of the turn is not swept, a point just inside the outer radius is
    j, i = int(round((0 - x0) / res)), int(round((0 - y0) / res))
    assert not mask[i, j]
    assert mask[int(round((0 - y0) / res)), int(round((ro - 0.2 - x0) / res))]


def test_long_birds_eye_drawing_is_split_into_readable_panels(tmp_path):
    # the Scania lane change: 455 m long, 16 m wide
    windows, tall = plots._panels((-15.0, 440.0), (-2.0, 14.0))
    assert not tall and 3 <= len(windows) <= 4
    assert windows[0][0] == pytest.approx(-15.0, abs=3) and windows[-1][1] == pytest.approx(440.0, abs=3)
    x = np.linspace(0, 450, 900)
    y = 3.25 / (1 + np.exp(-(x - 60) / 8))
    t = np.linspace(0, 16, 900)
    body = np.stack([np.column_stack([x + dx, y + dy]) for dx, dy in ((0, 1.3), (0, -1.3), (-12, -1.3), (-12, 1.3))],
                    axis=1)
    report.birds_eye(tmp_path / "long.png", {"A1": (x, y)}, outlines=body, title="long")
    with Image.open(tmp_path / "long.png") as im:
        assert im.height / im.width > 0.5          # a page, not a strip
    # its animation follows the body (a window of the vehicle's size, not the whole strip)
    p = report.animate(tmp_path / "a.gif", t, outlines=body, traces={"A1": (x, y)}, frames=40)
    with Image.open(p) as im:
        assert im.n_frames == 40


def test_bode_phase_unwrapped_over_frequency(tmp_path):
    """A third-order lag 1/(1 + s/w0)^3: its phase falls through -180 deg to
    -270 deg; the plot's phase follows it without a jump."""
    from artibus.study import bode
    w0 = 2 * math.pi * 1.0
    f = np.geomspace(0.05, 30, 40)
    G = 1 / (1 + 1j * 2 * math.pi * f / w0) ** 3
    pts = [bode.Point(fi, abs(g), math.atan2(g.imag, g.real)) for fi, g in zip(f, G)]
    ph = bode.unwrapped_phase_deg(pts)
    expected = -3 * np.degrees(np.arctan(2 * math.pi * f / w0))
    assert np.allclose(ph, expected, atol=1e-9)
    assert np.all(np.diff(ph) < 0) and ph[-1] < -250
    out = bode.plot(tmp_path / "b.png", {"V.y": {"lag": pts}, "V.z": pts}, "t", units={"V.y": "m", "V.z": "rad"},
                    input_unit="rad", reference={"V.y": ("closed form", f, G)})
    with Image.open(out) as im:
        assert im.width > im.height                  # two columns, one per output
