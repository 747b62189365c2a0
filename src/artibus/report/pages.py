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

from artibus import files
from artibus.bench import script
from artibus.report.animation import bench_animation
from artibus.report.plots import signals

PASS, FAIL = "✔", "✘"


@dataclass
class Kpi:
    name: str
    value: float
    unit: str
    paper: str = ""        # the paper's figure, as the paper states it
    source: str = ""       # where in the paper (section, figure, table)
    passed: bool | None = None   # against the paper's bound, where it states one
    why: str = ""          # why there is no value (shown instead of it), e.g. "never in fallback"

    @property
    def missing(self):
        v = self.value
        return v is None or (isinstance(v, float) and math.isnan(v))

    def cell(self):
        if self.missing:
            return f"n/a ({self.why})" if self.why else "n/a"
        if isinstance(self.value, float) and math.isinf(self.value):
            return "inf" if self.value > 0 else "-inf"
        return f"{self.value:.4g}"

    @property
    def verdict(self):
        return "" if self.passed is None else (PASS if bool(self.passed) else FAIL)


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


def write_kpi_csv(path, kpis):
    """The KPI table as CSV with its units: kpi, value, unit, paper, source, passed, why."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["kpi", "value", "unit", "paper", "source", "passed", "why_no_value"])
    for k in kpis:
        w.writerow([k.name, "" if k.missing else repr(float(k.value)), k.unit, k.paper, k.source,
                    "" if k.passed is None else ("pass" if bool(k.passed) else "FAIL"), k.why])
    return files.write_text(path, buf.getvalue())


STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; padding: 0 1em; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 4px 10px; vertical-align: top; }
th { background: #eee; } td.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.pass { color: #137333; font-weight: bold; text-align: center; }
td.fail { color: #fff; background: #c5221f; font-weight: bold; text-align: center; }
span.pass { color: #137333; font-weight: bold; } span.fail { color: #c5221f; font-weight: bold; }
figure { margin: 1.5em 0; } img, video { max-width: 100%; }
figcaption { color: #555; font-size: 90%; }
.meta { color: #555; font-size: 90%; }
table.summary td { font-size: 92%; }
"""


def _verdict_td(k):
    if k.passed is None:
        return "<td></td>"
    return f'<td class="{"pass" if bool(k.passed) else "fail"}">{k.verdict}</td>'


def write_html(out_dir, title, intro, kpis, images, notes=""):
    """One self-contained page (images next to it) with the KPI table, the KPIs
    as kpis.csv (with units) and thumb.png (the first image, small) for the index.
    A KPI without a value shows why (Kpi.why); one without a value and a reason
    is left out of the table and named below it."""
    out_dir = Path(out_dir)
    rows, dropped = [], []
    for k in kpis:
        if k.missing and not k.why:
            dropped.append(k.name)
            continue
        rows.append(f"<tr><td>{html.escape(k.name)}</td><td class=n>{html.escape(k.cell())}</td>"
                    f"<td>{html.escape(k.unit)}</td><td>{html.escape(k.paper)}</td>"
                    f"<td>{html.escape(k.source)}</td>{_verdict_td(k)}</tr>")
    figs = []
    for i, cap in images:
        name = html.escape(Path(i).name)
        if Path(i).suffix == ".mp4":
            media = f'<video src="{name}" controls loop muted></video>'
        else:
            media = f'<img src="{name}" alt="{html.escape(cap)}">'
        figs.append(f"<figure>{media}<figcaption>{html.escape(cap)}</figcaption></figure>")
    n_fail = sum(1 for k in kpis if k.passed is not None and not bool(k.passed))
    n_pass = sum(1 for k in kpis if k.passed is not None and bool(k.passed))
    marks = (f'<p>Against the papers: <span class="pass">{n_pass} {PASS}</span>, '
             f'<span class="fail">{n_fail} {FAIL}</span>.</p>') if n_pass + n_fail else ""
    drop = (f"<p class=meta>Not computed in this run (no value): {html.escape('; '.join(dropped))}.</p>"
            if dropped else "")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>{STYLE}</style></head><body>
<p><a href="../index.html">all benches</a></p>
<h1>{html.escape(title)}</h1>
<p>{html.escape(intro)}</p>
{marks}
<table><tr><th>KPI</th><th>artibus</th><th>unit</th><th>paper</th><th>source</th><th></th></tr>
{''.join(rows)}
</table>
{drop}
<p class=meta>The table as CSV, with units: <a href="kpis.csv">kpis.csv</a>.</p>
<p>{html.escape(notes)}</p>
{''.join(figs)}
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
    """{date, artibus version, git commit, platform} of this run."""
    from artibus.base import ROOT, __version__
    try:
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


def headline(kpis, n=5):
    """The KPIs the summary shows: those the paper gives a figure or a bound
    for (failing ones first), then the first others, at most n."""
    judged = [k for k in kpis if k.passed is not None]
    judged.sort(key=lambda k: bool(k.passed))
    paper = [k for k in kpis if k.passed is None and k.paper and not k.missing]
    rest = [k for k in kpis if k.passed is None and not k.paper and not k.missing]
    return (judged + paper + rest)[:n]


def write_index(out_dir, summary, pages=(), metadata=None):
    """out_dir/index.html: a summary of every bench (headline KPIs against the
    paper with pass/fail, a thumbnail, a link to its page), links to further
    pages ([(relative href, title, what)], e.g. the comparison page), the run's
    metadata; summary.csv beside it (every KPI with its unit)."""
    out_dir = Path(out_dir)
    meta = metadata or run_metadata()
    rows, csv_rows = [], []
    total_pass = total_fail = 0
    for name, d, kpis in summary:
        rel = Path(d).relative_to(out_dir)
        href = html.escape(str(rel / "index.html"))
        thumb = Path(d) / "thumb.png"
        img = (f'<a href="{href}"><img src="{html.escape(str(rel / "thumb.png"))}" alt="{html.escape(name)}" '
               f'width="200"></a>') if thumb.is_file() else ""
        n_pass = sum(1 for k in kpis if k.passed is not None and bool(k.passed))
        n_fail = sum(1 for k in kpis if k.passed is not None and not bool(k.passed))
        total_pass += n_pass
        total_fail += n_fail
        status = (f'<span class="fail">{n_fail} {FAIL}</span> ' if n_fail else "") + \
                 (f'<span class="pass">{n_pass} {PASS}</span>' if n_pass else "") or "no bound in the papers"
        lines = []
        for k in headline(kpis):
            mark = f' <span class="{"pass" if bool(k.passed) else "fail"}">{k.verdict}</span>' if k.verdict else ""
            paper = f" <i>(paper: {html.escape(k.paper)}" + (f"; {html.escape(k.source)}" if k.source else "") + \
                ")</i>" if k.paper else ""
            lines.append(f"{html.escape(k.name)}: <b>{html.escape(k.cell())}</b> {html.escape(k.unit)}{paper}{mark}")
        more = len([k for k in kpis if not (k.missing and not k.why)]) - len(lines)
        if more > 0:
            lines.append(f'<a href="{href}">{more} more KPIs</a>')
        rows.append(f'<tr><td>{img}</td><td><a href="{href}"><b>{html.escape(name)}</b></a><br>{status}</td>'
                    f'<td>{"<br>".join(lines) or "no KPIs"}</td></tr>')
        for k in kpis:
            csv_rows.append([name, k.name, "" if k.missing else repr(float(k.value)), k.unit, k.paper, k.source,
                             "" if k.passed is None else ("pass" if bool(k.passed) else "FAIL")])
    links = "".join(f'<li><a href="{html.escape(h)}">{html.escape(t)}</a>: {html.escape(w)}</li>'
                    for h, t, w in pages)
    meta_html = "<br>".join(f"{html.escape(k)}: {html.escape(str(v))}" for k, v in meta.items())
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>artibus benches</title>
<style>{STYLE}</style></head><body><h1>artibus benches</h1>
<p class=meta>{meta_html}</p>
<h2>Summary</h2>
<p>{len(summary)} benches; against the papers' figures and bounds:
<span class="pass">{total_pass} {PASS}</span>, <span class="fail">{total_fail} {FAIL}</span>.
Every KPI with its unit: <a href="summary.csv">summary.csv</a>.</p>
{f"<ul>{links}</ul>" if links else ""}
<table class="summary"><tr><th></th><th>bench</th><th>headline KPIs (paper; {PASS} within the paper's bound,
{FAIL} not)</th></tr>
{''.join(rows)}
</table>
</body></html>
"""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["bench", "kpi", "value", "unit", "paper", "source", "passed"])
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
    mod = script.load(bench)
    if mod is None:
        return generic(result, out)
    if callable(getattr(mod, "study", None)):
        return mod.study(result, out)
    return mod.kpis(result), mod.figures(result, out), getattr(mod, "TEXT", "")


def write_report(bench, result, out_dir, wall=None):
    """PNGs and index.html for one bench run; returns the KPIs."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    kpis, images, notes = _report(bench, result, out)
    images = list(images) + bench_animation(result, out, title=f"{bench}, bird's-eye view")
    span = result.time[-1] - result.time[0]
    intro = f"Bench {bench}: {span:g} s simulated" + (f" in {wall:.2f} s." if wall else ".")
    write_html(out, bench, intro, kpis, [(out / i, c) for i, c in images], notes)
    return kpis
