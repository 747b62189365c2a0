"""Reports that tell one story (issue 42): `--variant` grades only the variant
run (the others are drawn beside it, not counted); the replay's page shows the
replay's own run (its span, its results.csv); every plot of a report keeps its
text inside the figure and its legends off the plotted points, with units on
its axes."""
import csv
import re
from pathlib import Path

import numpy as np
import pytest

from artibus import ROOT
from artibus.cli import main


def kpi_rows(folder):
    with open(folder / "kpis.csv", newline="") as f:
        return list(csv.DictReader(f))


UNIT = re.compile(r"\[[^\]]+\]")


def layout_problems(fig, name):
    """What of a figure, laid out as it is saved, hides or loses something:
    text (titles, axis labels, the ticks drawn, legends, annotations) reaching
    beyond the figure's edges (cut off in the PNG); a legend box over a point of
    a plotted line of its axes; an axis of plotted lines without a unit
    ("[unit]" in its label; an axis of named categories needs none; axes that
    share one say its unit once)."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    fb = fig.bbox
    out = []

    def outside(b):
        return b is not None and (b.x0 < fb.x0 - 1 or b.y0 < fb.y0 - 1 or b.x1 > fb.x1 + 1 or b.y1 > fb.y1 + 1)

    for ax in fig.axes:
        parts = [(t.get_text(), t.get_window_extent(r)) for t in (ax.title, ax.xaxis.label, ax.yaxis.label, *ax.texts)
                 if t.get_visible() and t.get_text()]
        parts += [("x ticks", ax.xaxis.get_tightbbox(r)), ("y ticks", ax.yaxis.get_tightbbox(r))]
        leg = ax.get_legend()
        if leg is not None and leg.get_visible():
            parts.append(("legend", leg.get_window_extent(r)))
        out += [f"{name}: {what[:50]!r} outside the figure" for what, b in parts if outside(b)]
        lines = [ln for ln in ax.get_lines() if ln.get_visible() and len(ln.get_xydata())]
        if leg is not None and leg.get_visible():
            lb, ab = leg.get_window_extent(r), ax.get_window_extent(r)
            for ln in lines:
                xy = ln.get_transform().transform(ln.get_xydata())
                xy = xy[np.all(np.isfinite(xy), axis=1)]
                if ln.get_clip_on():         # (a point outside the axes is not drawn)
                    xy = xy[(xy[:, 0] >= ab.x0) & (xy[:, 0] <= ab.x1) & (xy[:, 1] >= ab.y0) & (xy[:, 1] <= ab.y1)]
                n = int(((xy[:, 0] > lb.x0) & (xy[:, 0] < lb.x1) & (xy[:, 1] > lb.y0) & (xy[:, 1] < lb.y1)).sum())
                if n:
                    out.append(f"{name}: the legend covers {n} points of {ln.get_label()!r} ({ax.get_ylabel()!r})")
        if lines:
            named = [t for t in ax.get_yticklabels() if t.get_text() and not NUMBER.fullmatch(t.get_text())]
            if not any(UNIT.search(a.get_ylabel()) for a in ax.get_shared_y_axes().get_siblings(ax)) and not named:
                out.append(f"{name}: y axis {ax.get_ylabel()!r} without a unit")
            if not any(UNIT.search(a.get_xlabel()) for a in ax.get_shared_x_axes().get_siblings(ax)):
                out.append(f"{name}: x axis {ax.get_xlabel()!r} without a unit")
    for t in [*fig.texts, *fig.legends]:
        if outside(t.get_window_extent(r)):
            out.append(f"{name}: {str(t)[:50]!r} outside the figure")
    return out


NUMBER = re.compile(r"[\u2212\-0-9.e+]*")


@pytest.fixture(scope="module")
def circle_report(tmp_path_factory):
    """Bus36m_Circle run with --variant guidedForceMin and its report, every
    figure checked (layout_problems) as it is saved: (folder, problems, figures)."""
    from matplotlib.figure import Figure
    problems, names = [], []
    save = Figure.savefig

    def checked(fig, fname, *a, **kw):
        name = Path(str(fname)).name.split(".tmp-")[0]
        names.append(name)
        problems.extend(layout_problems(fig, name))
        return save(fig, fname, *a, **kw)

    out = tmp_path_factory.mktemp("circle") / "b"
    Figure.savefig = checked
    try:
        assert main(["run", "Bus36m_Circle", "--variant", "guidedForceMin", "--report", str(out)]) == 0
    finally:
        Figure.savefig = save
    return out, problems, names


def test_variant_report_grades_only_the_variant_run(circle_report):
    """Bus36m_Circle's report runs every variant for its side-by-side figure;
    run with --variant guidedForceMin, only guidedForceMin's rows that carry a
    paper bound are graded (✔/✘), the other variants' rows are "not graded"."""
    variants = sorted(p.stem for p in (ROOT / "ssp" / "benches" / "Bus36m_Circle" / "variants").glob("*.ssv"))
    assert "guidedForceMin" in variants and len(variants) >= 3
    out = circle_report[0]
    rows = kpi_rows(out)
    graded = [r for r in rows if r["passed"] in ("pass", "FAIL")]
    assert graded and all(r["kpi"].startswith("guidedForceMin: ") for r in graded), graded
    assert {r["kpi"] for r in graded} == {r["kpi"] for r in rows if r["kpi"].startswith("guidedForceMin: ")
                                          and r["paper"]}
    others = [r for r in rows if not r["kpi"].startswith("guidedForceMin: ")]
    assert {r["kpi"].split(":")[0] for r in others} >= set(variants) - {"guidedForceMin"}   # still shown
    assert all(r["passed"] == "not graded" for r in others if r["paper"])
    n_pass = sum(r["passed"] == "pass" for r in graded)
    n_fail = sum(r["passed"] == "FAIL" for r in graded)
    page = (out / "index.html").read_text()
    assert re.search(rf"this configuration: <span class=\"pass\">{n_pass} ✔</span>, "
                     rf"<span class=\"fail\">{n_fail} ✘</span>", page), page[:2000]


def test_every_figure_of_a_report_keeps_its_text_and_data_visible(circle_report):
    out, problems, names = circle_report
    pngs = sorted(p.name for p in out.glob("*.png") if p.name != "thumb.png")
    assert set(pngs) <= set(names) and "variants.png" in pngs and len(pngs) >= 4   # every figure was checked
    assert problems == []


def test_replay_page_shows_the_replays_own_run(tmp_path):
    """Urbino18_Replay's page is the shipped log replayed: its header's span and
    its results.csv are the replay's (the log's time span, read here from the
    log), not the bench's own run of 10 s standing still."""
    log = ROOT / "ssp" / "logs" / "Urbino18_test.csv"
    with open(log, newline="") as f:
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    span = float(rows[-1][rows[0].index("time_s")]) - float(rows[1][rows[0].index("time_s")])
    assert span > 20
    out = tmp_path / "r"
    assert main(["run", "Urbino18_Replay", "--report", str(out)]) == 0
    page = (out / "index.html").read_text()
    assert f"{span:g} s simulated" in page and "10 s simulated" not in page
    t = np.loadtxt(out / "results.csv", delimiter=",", skiprows=1, usecols=0)
    assert t[-1] - t[0] == pytest.approx(span)
    header = (out / "results.csv").read_text().splitlines()[0]
    assert '"Bus.x[1]"' in header


def xml_unit(model, name):
    """A variable's unit= as modelDescription/<model>.xml declares it (lxml), "" for none."""
    from lxml import etree
    v = etree.parse(str(ROOT / "modelDescription" / f"{model}.xml")).find(f".//ScalarVariable[@name='{name}']")
    return v[0].get("unit") or ""


@pytest.mark.parametrize("axes", [2, 1])
def test_sweep_study_plot_axes_have_units(tmp_path, monkeypatch, axes):
    """The sweep's study.png: each swept parameter's axis with its unit (from the
    FMU's model description), the KPI's with its own."""
    from matplotlib.figure import Figure
    from artibus.study.sweep import plots
    kpi = "max deviation of A4 from the A2 trace [m]"
    grid = [("Driver.vSet", [3.0, 4.0]), ("Driver.R", [15.0, 20.0])][:axes]
    rows = [{"status": "ok", "key": f"k{i}{j}", kpi: 0.1 * (i + j), **dict(zip([n for n, _ in grid], vs))}
            for i, vs in enumerate([(a, b) for a in grid[0][1] for b in (grid[1][1] if axes == 2 else [None])])
            for j in [0]]
    manifest = {"bench": "Bus36m_Circle", "method": "grid", "axes": [[n, [str(v) for v in vs]] for n, vs in grid]}
    labels = []
    save = Figure.savefig

    def checked(fig, fname, *a, **kw):
        labels.extend(t for ax in fig.axes for t in (ax.get_xlabel(), ax.get_ylabel()) if t)
        return save(fig, fname, *a, **kw)

    monkeypatch.setattr(Figure, "savefig", checked)
    assert plots._plot(tmp_path / "study.png", manifest, rows, kpi)
    want = {f"Driver.vSet [{xml_unit('RoadFollowDriver', 'vSet')}]", kpi}
    if axes == 2:
        want.add(f"Driver.R [{xml_unit('RoadFollowDriver', 'R')}]")
    assert "Driver.vSet [m/s]" in want
    assert want <= set(labels), labels
