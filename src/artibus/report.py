"""The bench report: PNG plots and one HTML page with the KPI table next to
the papers' values."""
import html
import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


@dataclass
class Kpi:
    name: str
    value: float
    unit: str
    paper: str = ""        # the paper's figure, as the paper states it
    source: str = ""       # where in the paper
    passed: bool | None = None   # against the paper's bound, where it states one

    def cell(self):
        if self.value is None or (isinstance(self.value, float) and math.isnan(self.value)):
            return "n/a"
        return f"{self.value:.4g}"


def _colours():
    return plt.rcParams["axes.prop_cycle"].by_key()["color"]


def birds_eye(path, traces, outlines=None, road=None, title="", every=10):
    """traces: {label: (x, y)}; outlines: array [time, corners, 2] (groups of 4
    corners per module) drawn every ``every`` samples; road: (x, y)."""
    fig, ax = plt.subplots(figsize=(9, 8))
    if road is not None:
        ax.plot(road[0], road[1], color="0.75", lw=6, solid_capstyle="round", label="road", zorder=0)
    if outlines is not None:
        out = np.asarray(outlines)
        for k in range(0, len(out), every):
            for m in range(0, out.shape[1], 4):
                q = out[k, m:m + 4]
                ax.fill(q[:, 0], q[:, 1], facecolor="none", edgecolor="0.45", lw=0.5)
    for (label, (x, y)), c in zip(traces.items(), _colours() * 3):
        ax.plot(x, y, color=c, lw=1.4, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def signals(path, t, panels, title=""):
    """panels: [(ylabel, {label: values})], one axis each, shared time axis."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.4 * len(panels)), sharex=True, squeeze=False)
    for ax, (ylabel, series) in zip(axes[:, 0], panels):
        for (label, y), c in zip(series.items(), _colours() * 3):
            ax.plot(t, y, color=c, lw=1.2, label=label)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_html(out_dir, title, intro, kpis, images, notes=""):
    """One self-contained page (images next to it) with the KPI table."""
    out_dir = Path(out_dir)
    rows = []
    for k in kpis:
        verdict = "" if k.passed is None else ("✔" if k.passed else "✘")
        rows.append(f"<tr><td>{html.escape(k.name)}</td><td class=n>{k.cell()}</td>"
                    f"<td>{html.escape(k.unit)}</td><td>{html.escape(k.paper)}</td>"
                    f"<td>{html.escape(k.source)}</td><td>{verdict}</td></tr>")
    imgs = "\n".join(f'<figure><img src="{html.escape(Path(i).name)}" alt="{html.escape(cap)}">'
                     f"<figcaption>{html.escape(cap)}</figcaption></figure>" for i, cap in images)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>
body {{ font-family: sans-serif; max-width: 1000px; margin: 2em auto; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 4px 10px; }}
th {{ background: #eee; }} td.n {{ text-align: right; font-variant-numeric: tabular-nums; }}
figure {{ margin: 1.5em 0; }} img {{ max-width: 100%; }}
figcaption {{ color: #555; font-size: 90%; }}
</style></head><body>
<h1>{html.escape(title)}</h1>
<p>{html.escape(intro)}</p>
<table><tr><th>KPI</th><th>artibus</th><th>unit</th><th>paper</th><th>source</th><th></th></tr>
{''.join(rows)}
</table>
<p>{html.escape(notes)}</p>
{imgs}
</body></html>
"""
    path = out_dir / "index.html"
    path.write_text(page)
    return path


def write_index(out_dir, summary):
    """out_dir/index.html: every bench's KPI table, linking to its page."""
    parts = []
    for name, d, kpis in summary:
        rows = "".join(f"<tr><td>{html.escape(k.name)}</td><td class=n>{k.cell()}</td>"
                       f"<td>{html.escape(k.unit)}</td><td>{html.escape(k.paper)}</td></tr>" for k in kpis)
        rel = Path(d).relative_to(out_dir) / "index.html"
        parts.append(f'<h2><a href="{html.escape(str(rel))}">{html.escape(name)}</a></h2>'
                     f"<table><tr><th>KPI</th><th>artibus</th><th>unit</th><th>paper</th></tr>{rows}</table>")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>artibus benches</title>
<style>
body {{ font-family: sans-serif; max-width: 1000px; margin: 2em auto; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 4px 10px; }} th {{ background: #eee; }}
td.n {{ text-align: right; }}
</style></head><body><h1>artibus benches</h1>
{''.join(parts)}
</body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path
