"""The bench reports' pages: a bench run's page (``write_report``: its
bench.py's KPIs, figures and text, artibus.bench.script, or the generic
report; its animation), one HTML page per bench with its KPI table next to
the papers' values (``write_html``; ``Kpi``, and kpis.csv with the units
beside it), a thumbnail, and the index of a run of every bench
(``write_index``): a summary with each bench's headline KPIs, pass/fail
marks, a thumbnail and the run's metadata.

Every file is written under a temporary name and renamed (artibus.files), so
a report stopped midway never leaves a torn PNG or page under its final name.
"""
import csv
import datetime
import html
import io
import math
import platform
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from artibus import files
from artibus.bench import script
from artibus.report.animation import bench_animation
from artibus.report.plots import signals

PASS, FAIL = "✔", "✘"
CALIBRATED = "calibrated"
WITHIN = "within the stepping error"
ERROR_COLUMNS = ("cosim_error", "cosim_error_pct", "cosim_error_method", "within_stepping_error")
NOT_GRADED = "not graded"


@dataclass
class Kpi:
    """One KPI of a run: its value and unit, the paper's figure beside it, and
    its grade. A KPI is graded (``passed`` True or False: ✔ or ✘) only against
    the paper's bound for the configuration that ran; a row the paper gives a
    figure for that is not a bound of this configuration says why it is not
    graded (``ungraded``); a calibration target (the value we calibrated to)
    is ``calibrated``, never ✔. A ✘ carries its explanation (``explain``: why
    it fails, what it depends on, what would change it; ``explain_figure``: a
    PNG beside the page), shown on the page and linked from the index."""
    name: str
    value: float
    unit: str
    paper: str = ""        # the paper's figure, as the paper states it
    source: str = ""       # where in the paper (section, figure, table)
    passed: bool | None = None   # against the paper's bound for this configuration, where it states one
    why: str = ""          # why there is no value (shown instead of it), e.g. "never in fallback"
    ungraded: str = ""     # why the paper's figure beside it is not graded, e.g. "bound of another configuration"
    calibrated: bool = False     # the value is a calibration target (set to the paper's figure, not tested by it)
    explain: str = ""      # a ✘'s explanation: why, what it depends on, what would change it
    explain_figure: str = ""     # a PNG in the page's folder illustrating the explanation
    bound: object = None   # the paper's bound in the KPI's unit: a number or a tuple of them (its edges)
    error: float | None = None   # the co-simulation error, in the KPI's unit (artibus.report.cosim_error)
    error_how: str = ""    # how it was measured: against the reference, h against h/2, the two algorithms
    margin_error: float | None = None   # the same of its distance to the bound (an ordering's other side moves too)

    @property
    def error_pct(self):
        """The co-simulation error in % of the value (None: not measured; inf: a value of 0)."""
        if self.error is None or self.missing or isinstance(self.value, (bool, np.bool_)):
            return None
        v = abs(float(self.value))
        return 100.0 * self.error / v if v > 0 else (0.0 if self.error == 0 else math.inf)

    @property
    def margin(self):
        """The value's distance to the paper's bound (its nearest edge), or None."""
        if self.bound is None or self.missing or isinstance(self.value, (bool, np.bool_)):
            return None
        edges = self.bound if isinstance(self.bound, (tuple, list)) else (self.bound,)
        return min(abs(float(self.value) - float(b)) for b in edges) if edges else None

    @property
    def within_error(self):
        """A graded KPI whose grade the stepping could change (issue 44): its co-simulation
        error above MARK_PCT % of its value (a value below a thousandth of its bound, 0 by
        construction, judged on that thousandth), or larger than its distance to the paper's bound
        (that distance's own error, where measured: a bound that is another run's value moves too)."""
        from artibus.report.cosim_error import MARK_PCT
        if not self.graded or self.error is None:
            return False
        margin = self.margin
        e = max(self.error, self.margin_error or 0.0)
        edges = self.bound if isinstance(self.bound, (tuple, list)) else () if self.bound is None else (self.bound,)
        scale = max([abs(float(self.value))] + [1e-3 * abs(float(b)) for b in edges])   # (0 by construction)
        return self.error > MARK_PCT / 100 * scale or (margin is not None and e > margin)

    def error_cell(self):
        """The co-simulation error as the page and the printout show it: "±0.012 m (1.3 %)"; "" if not measured."""
        if self.error is None:
            return ""
        pct = self.error_pct
        return f"±{self.error:.3g} {self.unit}".rstrip() + (f" ({pct:.3g} %)" if pct is not None else "")

    @property
    def missing(self):
        v = self.value
        return v is None or (isinstance(v, float) and math.isnan(v))

    @property
    def graded(self):
        """Whether the KPI counts in the tally (✔ or ✘)."""
        return self.passed is not None and not self.calibrated and not self.missing

    @property
    def failed(self):
        return self.graded and not bool(self.passed)

    def cell(self):
        if self.missing:
            return f"n/a ({self.why})" if self.why else "n/a"
        if isinstance(self.value, float) and math.isinf(self.value):
            return "inf" if self.value > 0 else "-inf"
        if isinstance(self.value, (bool, np.bool_)):
            return str(bool(self.value))
        return f"{self.value:.4g}"

    @property
    def verdict(self):
        """✔, ✘ (either followed by "within the stepping error" where the stepping could change
        it: within_error), "calibrated", "not graded" (a paper figure beside it, not a bound of
        this run) or ""."""
        if self.calibrated:
            return CALIBRATED
        if self.graded:
            return (PASS if bool(self.passed) else FAIL) + (f" {WITHIN}" if self.within_error else "")
        if self.ungraded:
            return NOT_GRADED
        return ""

    def line(self):
        """The KPI as the console prints it: name, value, unit, its co-simulation error, the
        paper's figure, the grade."""
        paper = f"   (paper: {self.paper}" + (f"; {self.source}" if self.source else "") + ")" if self.paper else ""
        v = self.verdict
        err = f"   co-simulation error {self.error_cell()} ({self.error_how})" if self.error is not None else ""
        return f"{self.name}: {self.cell()} {self.unit}{err}{paper}" + (f"   {v}" if v else "")


def tally(kpis):
    """(number of ✔, number of ✘) over the graded KPIs (calibration targets and
    rows without a bound of their own are not counted)."""
    n_pass = sum(1 for k in kpis if k.graded and bool(k.passed))
    n_fail = sum(1 for k in kpis if k.failed)
    return n_pass, n_fail


def anchor(i):
    """The id of the i-th failing KPI's explanation on its page."""
    return f"why-{i + 1}"


def thumbnail(src, dst, width=240):
    """A small PNG of an image (the index's thumbnails)."""
    from PIL import Image
    with Image.open(src) as im:
        im = im.convert("RGB")
        h = max(1, round(im.height * width / im.width))
        small = im.resize((width, h), Image.LANCZOS)
        buf = io.BytesIO()
        small.save(buf, format="PNG", optimize=True)
    files.write_bytes(dst, buf.getvalue())
    return Path(dst)


def _grade_word(k):
    if k.calibrated:
        return CALIBRATED
    if k.graded:
        return "pass" if bool(k.passed) else "FAIL"
    return NOT_GRADED if k.ungraded else ""


def _error_fields(k):
    """The co-simulation error's CSV fields (ERROR_COLUMNS): in the KPI's unit, in %, how
    measured, and "yes" for a graded KPI within the stepping error of its bound (Kpi.within_error)."""
    if k.error is None:
        return ["", "", "", ""]
    pct = k.error_pct
    return [repr(float(k.error)), "" if pct is None else repr(float(pct)), k.error_how,
            "yes" if k.within_error else ""]


def write_kpi_csv(path, kpis):
    """The KPI table as CSV with its units: kpi, value, unit, paper, source,
    passed (pass, FAIL, calibrated, not graded or empty), why, the note (a ✘'s
    explanation, or why a paper figure is not graded), and the co-simulation error
    (ERROR_COLUMNS): in the KPI's unit, in % of the value, how measured
    (artibus.report.cosim_error; empty where not measured), "yes" where a graded
    KPI is within the stepping error of its bound."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["kpi", "value", "unit", "paper", "source", "passed", "why_no_value", "note", *ERROR_COLUMNS])
    for k in kpis:
        w.writerow([k.name, "" if k.missing else repr(float(k.value)), k.unit, k.paper, k.source,
                    _grade_word(k), k.why, k.explain if k.failed else k.ungraded, *_error_fields(k)])
    return files.write_text(path, buf.getvalue())


STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; padding: 0 1em; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 4px 10px; vertical-align: top; }
th { background: #eee; } td.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.pass { color: #137333; font-weight: bold; text-align: center; }
td.fail { background: #c5221f; font-weight: bold; text-align: center; }
td.fail a { color: #fff; }
td.cal, td.ungraded { color: #555; font-size: 85%; }
span.pass { color: #137333; font-weight: bold; } span.fail { color: #c5221f; font-weight: bold; }
figure { margin: 1.5em 0; } img, video { max-width: 100%; }
figcaption { color: #555; font-size: 90%; }
.meta { color: #555; font-size: 90%; }
table.summary td { font-size: 92%; }
div.why { border-left: 4px solid #c5221f; padding: 0.2em 1em; margin: 1em 0; }
span.within { color: #b06000; font-weight: normal; font-size: 85%; } td.fail span.within { color: #fff; }
"""


def _verdict_td(k, i=None):
    """The grade's cell: ✔; ✘ linked to its explanation (i: its number); calibrated; not graded, why."""
    if k.calibrated:
        return f'<td class="cal">{CALIBRATED}</td>'
    if k.graded:
        within = f' <span class="within">{WITHIN}</span>' if k.within_error else ""
        if bool(k.passed):
            return f'<td class="pass">{PASS}{within}</td>'
        return f'<td class="fail"><a href="#{anchor(i)}">{FAIL}</a>{within}</td>'
    if k.ungraded:
        return f'<td class="ungraded">{NOT_GRADED}: {html.escape(k.ungraded)}</td>'
    return "<td></td>"


@dataclass
class Table:
    """A table on a bench's page (e.g. the damping functions side by side):
    a title, the column heads, rows of cells (numbers are formatted with fmt)."""
    title: str
    header: list
    rows: list
    note: str = ""
    fmt: str = "{:.3g}"

    def html(self):
        def cell(c):
            if isinstance(c, (int, float, np.integer, np.floating)) and not isinstance(c, bool):
                x = float(c)
                txt = "inf" if math.isinf(x) else ("n/a" if math.isnan(x) else
                                                    (str(int(c)) if isinstance(c, (int, np.integer)) else
                                                     self.fmt.format(x)))
                return f"<td class=n>{html.escape(txt)}</td>"
            return f"<td>{html.escape(str(c))}</td>"
        head = "".join(f"<th>{html.escape(h)}</th>" for h in self.header)
        body = "".join("<tr>" + "".join(cell(c) for c in row) + "</tr>" for row in self.rows)
        note = f"<p class=meta>{html.escape(self.note)}</p>" if self.note else ""
        return f"<h2>{html.escape(self.title)}</h2><table><tr>{head}</tr>{body}</table>{note}"


def _margins_html(kpis):
    """Which grades hold beyond the stepping error (issue 44): each graded KPI with a
    bound and an error, its distance to the bound (for an ordering between two runs,
    e.g. an option against the baseline, the difference between them) against that
    distance's co-simulation error."""
    rows = []
    for k in kpis:
        if not k.graded or k.margin is None or k.error is None:
            continue
        e = max(k.error, k.margin_error or 0.0)
        said = WITHIN if k.within_error else "holds beyond the stepping error"
        rows.append(f"<tr><td>{html.escape(k.name)}</td><td>{PASS if k.passed else FAIL}</td>"
                    f"<td class=n>{k.margin:.4g} {html.escape(k.unit)}</td><td class=n>{e:.3g} "
                    f"{html.escape(k.unit)}</td><td>{said}</td></tr>")
    if not rows:
        return ""
    n_within = sum(1 for k in kpis if k.within_error)
    return (f"<h2>The grades against the stepping error</h2><p>{len(rows) - n_within} of {len(rows)} graded KPIs "
            "with a bound hold beyond the stepping error: the distance to the bound (for an ordering, the "
            "difference from the other run) is larger than its co-simulation error and the error is at most "
            f"2 % of the value.</p><table><tr><th>KPI</th><th>grade</th><th>distance to the bound</th>"
            f"<th>its co-simulation error</th><th></th></tr>{''.join(rows)}</table>")


def _notes_html(notes):
    """notes: a string (a paragraph), or a list of strings and Tables."""
    if isinstance(notes, (str, Table)):
        notes = [notes]
    out = []
    for n in notes or []:
        out.append(n.html() if isinstance(n, Table) else f"<p>{html.escape(n)}</p>")
    return "\n".join(out)


def write_html(out_dir, title, intro, kpis, images, notes="", sections="", error_note="not measured"):
    """One self-contained page (images next to it) with the KPI table, the KPIs
    as kpis.csv (with units) and thumb.png (the first image, small) for the index.
    A KPI without a value shows why (Kpi.why); one without a value and a reason
    is left out of the table and named below it. Each ✘ links to its
    explanation below the table (Kpi.explain, with its figure). notes: a
    paragraph, or a list of paragraphs and Tables. error_note: how the KPIs'
    co-simulation errors (Kpi.error) were measured, said under the table."""
    out_dir = Path(out_dir)
    rows, dropped, whys = [], [], []
    for k in kpis:
        if k.missing and not k.why:
            dropped.append(k.name)
            continue
        i = None
        if k.failed:
            i = len(whys)
            whys.append(k)
        rows.append(f"<tr><td>{html.escape(k.name)}</td><td class=n>{html.escape(k.cell())}</td>"
                    f"<td>{html.escape(k.unit)}</td><td>{html.escape(k.paper)}</td>"
                    f"<td>{html.escape(k.source)}</td>{_verdict_td(k, i)}"
                    f"<td class=n>{html.escape(k.error_cell())}</td></tr>")
    figs = []
    for i, cap in images:
        name = html.escape(Path(i).name)
        if Path(i).suffix == ".mp4":
            media = f'<video src="{name}" controls loop muted></video>'
        else:
            media = f'<img src="{name}" alt="{html.escape(cap)}">'
        figs.append(f"<figure>{media}<figcaption>{html.escape(cap)}</figcaption></figure>")
    n_pass, n_fail = tally(kpis)
    n_cal = sum(1 for k in kpis if k.calibrated)
    n_ungraded = sum(1 for k in kpis if not k.graded and not k.calibrated and k.ungraded)
    marks = (f'<p>Against the papers\' bounds for this configuration: <span class="pass">{n_pass} {PASS}</span>, '
             f'<span class="fail">{n_fail} {FAIL}</span>'
             + (f"; {n_cal} calibration target{'s' if n_cal != 1 else ''} (not counted)" if n_cal else "")
             + (f"; {n_ungraded} paper figure{'s' if n_ungraded != 1 else ''} not graded (the reason beside each)"
                if n_ungraded else "") + ".</p>") if n_pass + n_fail + n_cal + n_ungraded else ""
    drop = (f"<p class=meta>Not computed in this run (no value): {html.escape('; '.join(dropped))}.</p>"
            if dropped else "")
    expl = []
    for i, k in enumerate(whys):
        text = k.explain.strip() or "No explanation given."
        fig = (f'<figure><img src="{html.escape(k.explain_figure)}" alt="{html.escape(k.name)}"></figure>'
               if k.explain_figure else "")
        expl.append(f'<div class="why" id="{anchor(i)}"><p><b>{FAIL} {html.escape(k.name)}</b>: '
                    f'{html.escape(k.cell())} {html.escape(k.unit)} against the paper\'s {html.escape(k.paper)} '
                    f'({html.escape(k.source)}).</p><p>{html.escape(text)}</p>{fig}</div>')
    why_html = f"<h2>Why each {FAIL} fails</h2>\n" + "\n".join(expl) if expl else ""
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>{STYLE}</style></head><body>
<p><a href="../index.html">all benches</a></p>
<h1>{html.escape(title)}</h1>
<p>{html.escape(intro)}</p>
{marks}
<table><tr><th>KPI</th><th>artibus</th><th>unit</th><th>paper</th><th>source</th><th>grade</th>
<th>co-simulation error</th></tr>
{''.join(rows)}
</table>
{drop}
<p class=meta>The table as CSV, with units: <a href="kpis.csv">kpis.csv</a>. {PASS}/{FAIL}: against the paper's
bound for the configuration that ran; "calibrated": the value we calibrated to the paper's figure (not a test);
"not graded": the paper gives a figure, but not a bound for this configuration (the reason beside it).
Co-simulation error: {html.escape(error_note)} ("{WITHIN}": a graded KPI whose error exceeds 2 % of its value or its
distance to the paper's bound; how it is measured: docs/guide/cosim-error.md).</p>
{why_html}
{_margins_html(kpis)}
{_notes_html(notes)}
{sections}
{''.join(figs)}
<p class=meta>{html.escape(meta_line())}</p>
</body></html>
"""
    write_kpi_csv(out_dir / "kpis.csv", kpis)
    pngs = [Path(i) for i, _ in images if Path(i).suffix == ".png"]
    if pngs:
        # an image is named as given (relative to the working directory, as write_report
        # names them) or relative to the page's folder
        src = pngs[0] if pngs[0].is_absolute() or pngs[0].is_file() else out_dir / pngs[0]
        if src.is_file():
            thumbnail(src, out_dir / "thumb.png")
    return files.write_text(out_dir / "index.html", page)


def run_metadata():
    """{date, artibus version, git commit, platform} of this run (the commit of the clone
    artibus runs from; none from an installed wheel, whose folder may lie in another repository)."""
    from artibus.base import ROOT, __version__
    try:
        if not (ROOT / ".git").exists():
            raise OSError("not a git checkout")
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                                text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        if commit and dirty:
            commit += " (with uncommitted changes)"
    except (OSError, subprocess.SubprocessError):
        commit = ""
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "artibus": __version__,
        "commit": commit or "unknown (not a git checkout)",
        "platform": f"{platform.platform()}, Python {platform.python_version()}",
    }


def meta_line():
    """The run's metadata in one line, at the foot of every bench's page: the artibus version above all."""
    return "; ".join(f"{k}: {v}" for k, v in run_metadata().items())


def headline(kpis, n=5):
    """The KPIs the summary shows: those the paper gives a figure or a bound
    for (failing ones first), then the first others, at most n."""
    judged = [k for k in kpis if k.graded]
    judged.sort(key=lambda k: bool(k.passed))
    paper = [k for k in kpis if not k.graded and k.paper and not k.missing]
    rest = [k for k in kpis if not k.graded and not k.paper and not k.missing]
    return (judged + paper + rest)[:max(n, sum(1 for k in judged if not k.passed))]


MODES_PAGE = "modes/index.html"     # issue 43: `artibus modes -o OUT/modes` (artibus.report.modes)
MODES_TITLE = "Stability maps (linear models)"
MODES_WHAT = ("seed 001's sway mode over speed with each damping function (damping ratio, root locus), "
              "seed 004's Fig. 4 checks: FWS against zero side-slip MAS")


def write_index(out_dir, summary, pages=(), metadata=None):
    """out_dir/index.html: a summary of every bench (headline KPIs against the
    paper with pass/fail, a thumbnail, a link to its page), links to further
    pages ([(relative href, title, what)], e.g. the comparison page), the run's
    metadata; summary.csv beside it (every KPI with its unit and its co-simulation error).
    The stability maps' page is linked when out_dir/modes/index.html is there (``artibus modes
    -o OUT/modes``, made by ./run.sh; `run --all` does not make it, being slow enough)."""
    out_dir = Path(out_dir)
    meta = metadata or run_metadata()
    if (out_dir / MODES_PAGE).is_file() and MODES_PAGE not in (h for h, _, _ in pages):
        pages = [*pages, (MODES_PAGE, MODES_TITLE, MODES_WHAT)]
    rows, csv_rows = [], []
    total_pass = total_fail = 0
    for name, d, kpis in summary:
        rel = Path(d).relative_to(out_dir)
        href = html.escape(str(rel / "index.html"))
        thumb = Path(d) / "thumb.png"
        img = (f'<a href="{href}"><img src="{html.escape(str(rel / "thumb.png"))}" alt="{html.escape(name)}" '
               f'width="200"></a>') if thumb.is_file() else ""
        n_pass, n_fail = tally(kpis)
        fails = {id(k): i for i, k in enumerate(k for k in kpis if k.failed and not (k.missing and not k.why))}
        total_pass += n_pass
        total_fail += n_fail
        status = (f'<span class="fail">{n_fail} {FAIL}</span> ' if n_fail else "") + \
                 (f'<span class="pass">{n_pass} {PASS}</span>' if n_pass else "") or "no bound in the papers"
        lines = []
        for k in headline(kpis):
            if k.failed:        # linked to its explanation on the bench's page
                why = html.escape(f"{rel / 'index.html'}#{anchor(fails[id(k)])}")
                mark = f' <a href="{why}"><span class="fail">{FAIL}</span></a>'
            elif k.graded:
                mark = f' <span class="pass">{PASS}</span>'
            else:
                mark = f" <i>({k.verdict})</i>" if k.verdict else ""
            paper = f" <i>(paper: {html.escape(k.paper)}" + (f"; {html.escape(k.source)}" if k.source else "") + \
                ")</i>" if k.paper else ""
            if k.within_error:
                mark += f' <span class="within">{WITHIN}</span>'
            err = f" (co-sim. error {html.escape(k.error_cell())})" if k.error is not None else ""
            lines.append(f"{html.escape(k.name)}: <b>{html.escape(k.cell())}</b> {html.escape(k.unit)}{err}"
                         f"{paper}{mark}")
        more = len([k for k in kpis if not (k.missing and not k.why)]) - len(lines)
        if more > 0:
            lines.append(f'<a href="{href}">{more} more KPIs</a>')
        rows.append(f'<tr><td>{img}</td><td><a href="{href}"><b>{html.escape(name)}</b></a><br>{status}</td>'
                    f'<td>{"<br>".join(lines) or "no KPIs"}</td></tr>')
        for k in kpis:
            csv_rows.append([name, k.name, "" if k.missing else repr(float(k.value)), k.unit, k.paper, k.source,
                             _grade_word(k), *_error_fields(k)])
    links = "".join(f'<li><a href="{html.escape(h)}">{html.escape(t)}</a>: {html.escape(w)}</li>'
                    for h, t, w in pages)
    meta_html = "<br>".join(f"{html.escape(k)}: {html.escape(str(v))}" for k, v in meta.items())
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>artibus benches</title>
<style>{STYLE}</style></head><body><h1>artibus benches</h1>
<p class=meta>{meta_html}</p>
<h2>Summary</h2>
<p>{len(summary)} benches; graded against the papers' bounds, each for the configuration it belongs to:
<span class="pass">{total_pass} {PASS}</span>, <span class="fail">{total_fail} {FAIL}</span>
(each {FAIL} links to its explanation on the bench's page; calibration targets and paper figures that are not
a bound of the run's configuration are not counted).
Every KPI with its unit: <a href="summary.csv">summary.csv</a>.</p>
{f"<ul>{links}</ul>" if links else ""}
<table class="summary"><tr><th></th><th>bench</th><th>headline KPIs (paper; {PASS} within the paper's bound,
{FAIL} not, linked to why)</th></tr>
{''.join(rows)}
</table>
</body></html>
"""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["bench", "kpi", "value", "unit", "paper", "source", "passed", *ERROR_COLUMNS])
    w.writerows(csv_rows)
    files.write_text(out_dir / "summary.csv", buf.getvalue())
    return files.write_text(out_dir / "index.html", page)


# ---- a bench run's page ----------------------------------------------------------

def generic(r, out):
    """The report of a bench without a bench.py: its first recorded signals over time, no KPIs."""
    series = {n: r[n] for n in r.names[1:]}
    panels = [(n, {n: v}) for n, v in list(series.items())[:8]]
    signals(out / "signals.png", r.time, panels, title="recorded signals")
    return [], [("signals.png", "The first recorded signals over time.")], ""


def _report(bench, result, out):
    """(KPIs, images, notes, the run the page shows): a study may return a run of
    its own as a fourth item (a replay: the bench's own run stands still)."""
    mod = script.load(bench)
    if mod is None:
        return (*generic(result, out), result)
    if callable(getattr(mod, "study", None)):
        parts = tuple(mod.study(result, out))
        return parts if len(parts) == 4 else (*parts, result)
    return mod.kpis(result), mod.figures(result, out), getattr(mod, "TEXT", ""), result


def write_report(bench, result, out_dir, wall=None, sections="", results_file=None, errors=None):
    """PNGs and index.html for one bench run (``sections``: more of the page,
    HTML, after the KPI table); returns the KPIs. Where the bench's study
    shows a run of its own (_report), the page is that run's: its span in the
    header, its animation, and its results saved as ``results_file`` (the
    page's results.csv) in place of the bench's run. ``errors``: the KPIs'
    co-simulation errors (artibus.report.cosim_error.Estimate), beside each."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    kpis, images, notes, shown = _report(bench, result, out)
    if errors is not None:
        errors.apply(kpis)
    if shown is not result:
        wall = None                         # (the bench's run's wall time is not the shown run's)
        if results_file is not None:
            from artibus.runner import save
            save(shown, results_file)
    images = list(images) + bench_animation(shown, out, title=f"{bench}, bird's-eye view")
    span = shown.time[-1] - shown.time[0]
    intro = (f"Bench {bench}: {span:g} s simulated" + (f" in {wall:.2f} s." if wall else ".")
             + (" The page shows the run of its study (results.csv), not the bench's run alone."
                if shown is not result else ""))
    write_html(out, bench, intro, kpis, [(out / i, c) for i, c in images], notes, sections,
               error_note=errors.said() if errors is not None else "not measured")
    return kpis
