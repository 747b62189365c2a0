"""A sweep whose KPI has no value in any case says so, and why, instead of drawing an
empty frame (artibus.study.sweep.plots.study):

- Bus36m_Circle's first KPI, the deviation of A4 from the A2 trace, needs the bus on
  the circle: cases cut to 3 s (the bench's own stop time is 70 s) have no value for it;
  the sweep names the KPI and the short stop time, and study.png shows the first KPI
  that has values;
- with no KPI having a value in any case, no study.png is written (an earlier one is
  removed) and worst.txt says so."""
import math

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import artibus
from artibus.bench import ssp
from artibus.study.sweep.plots import kpi_columns, study
from artibus.study.sweep.store import PLOT, TABLE, WORST

BENCH = "Bus36m_Circle"
FIRST = "max deviation of A4 from the A2 trace [m]"


@pytest.fixture(scope="module")
def short_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "s"
    notes = []

    class Log:
        def write(self, s):
            notes.append(s)

        def flush(self):
            pass

    res = artibus.sweep(ssp.ssp_path(BENCH), grid={"Driver.vSet": "3,4"}, stop_time=3.0, out=out,
                        workers=1, progress=Log())
    return out, res, "".join(notes)


def test_a_kpi_without_values_is_named_with_why_and_another_is_plotted(short_sweep):
    out, res, printed = short_sweep
    rows = res.table.to_pylist()
    assert len(rows) == 2 and all(r["status"] == "ok" for r in rows)
    cols = kpi_columns(res.table)
    assert cols[0] == FIRST
    assert all(math.isnan(r[FIRST]) for r in rows), "the premise: the A4 deviation needs the circle"
    other = next(c for c in cols if all(math.isfinite(r[c]) for r in rows))
    worst = (out / WORST).read_text()
    for text in (worst, printed):
        assert f"KPI {FIRST!r} has no value in any of the 2 cases" in text, text
        assert "every case stops at 3 s, before the bench's own 70 s" in text, text
        assert f"the study plot shows {other!r} instead" in text, text
    assert (out / PLOT).is_file()
    assert f"with the largest {other}" in worst


def test_no_kpi_with_a_value_no_plot(short_sweep):
    out, res, _ = short_sweep
    t = res.table
    for c in kpi_columns(t):
        t = t.set_column(t.column_names.index(c), c, pa.array([math.nan] * t.num_rows))
    pq.write_table(t, out / TABLE)
    assert (out / PLOT).is_file()       # the earlier run's
    written = study(out)
    assert out / PLOT not in written and not (out / PLOT).exists()
    assert "no KPI has a value: no study plot" in (out / WORST).read_text()
