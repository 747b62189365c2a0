"""Each bench's page states its multi-rate steps and how far a single-rate
run (every component at one step, as ecos, libcosim and FMPy run a bench) is
from ours on its KPIs, measured (issue 31): the figure is on the page and
finite. A short run of every bench (2 s, the KPIs of so short a run may be
n/a: then the recorded signals are compared), and one whole `artibus run
--report` of a short bench for the page as the command writes it."""
import math
import re

import pytest
from lxml import html as lhtml

from artibus import runner
from artibus.bench import ssp
from artibus.report import pages, single_rate
from artibus.report.runs import run_benches


def _figure(page):
    doc = lhtml.fromstring(page.read_text())
    spans = doc.xpath('//span[@class="srdev"]')
    assert len(spans) == 1, page.read_text()[:2000]
    return float(spans[0].text_content())


@pytest.mark.parametrize("bench", ssp.bench_names())
def test_every_bench_page_shows_a_finite_single_rate_deviation(tmp_path, bench):
    with runner.Simulation(bench) as sim:
        r = sim.run(stop_time=2.0)
        sr = single_rate.measure(sim, r, lambda: single_rate.run_single_rate(bench, {}, 2.0))
    steps = {u.step for u in sim.units}      # the annotation's, else the FMU's default experiment's
    assert sr.multi_rate == (len(steps) > 1)
    pages.write_html(tmp_path, bench, "short run", [], [], "", sr.html())
    d = _figure(tmp_path / "index.html")
    assert math.isfinite(d) and d >= 0
    if not sr.multi_rate:
        assert d == 0                     # already single-rate: the same run
    else:
        text = (tmp_path / "index.html").read_text()
        assert all(f"{s:g} s" in text for s in steps)      # the multi-rate steps are named


def test_the_report_of_a_multi_rate_bench_carries_it(tmp_path, capsys):
    out = tmp_path / "report"
    run_benches(["Scania18m_LaneChange"], report=out, stop_time=3.0)
    d = _figure(out / "index.html")
    assert math.isfinite(d)
    log = capsys.readouterr().out
    assert re.search(r"single-rate at 0\.01 s: KPIs within [0-9.e+-]+ %", log), log
