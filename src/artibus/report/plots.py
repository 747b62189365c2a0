"""The drawings every bench uses: the bird's-eye view with the swept-path
envelope (``birds_eye``, ``swept``, ``swept_area``) and signals over time
(``signals``); each figure written under a temporary name and renamed
(``save_figure``, artibus.files)."""
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from artibus import files  # noqa: E402


def colours():
    return plt.rcParams["axes.prop_cycle"].by_key()["color"]


def save_figure(fig, path, **kw):
    """fig.savefig, atomically (the format from the suffix); closes the figure."""
    try:
        with files.atomic_path(path) as tmp:
            fig.savefig(tmp, **kw)
    finally:
        plt.close(fig)
    return Path(path)


# ---- the bird's-eye view -------------------------------------------------------

def _longest_corner_trace(outlines, step):
    """The corner whose trace is the longest (the outermost one in a turn):
    the reference of the swept path, as the benches' KPIs take it."""
    out = np.asarray(outlines, float)[::step]
    d = np.diff(out, axis=0)
    lengths = np.hypot(d[..., 0], d[..., 1]).sum(axis=0)
    c = int(np.argmax(lengths))
    return out[:, c, 0], out[:, c, 1]


def swept(outlines, reference=None, target_frames=350, bin_length=0.5, samples_per_edge=4):
    """The swept path of the outlines (kpi.SweptPath) along ``reference`` (x, y)
    or the longest corner trace; the outlines are thinned to about
    ``target_frames`` instants (the benches' KPIs take every 20th of 7001)."""
    from artibus.study import kpi
    out = np.asarray(outlines, float)
    step = max(1, len(out) // target_frames)
    rx, ry = reference if reference is not None else _longest_corner_trace(out, step)
    rx, ry = np.asarray(rx, float), np.asarray(ry, float)
    if reference is not None:
        rx, ry = rx[::step], ry[::step]
    if len(kpi._polyline(rx, ry)) < 2:      # standing still: no path to measure along
        return None
    return kpi.swept_path(rx, ry, out[::step], bin_length=bin_length, samples_per_edge=samples_per_edge)


def swept_area(outlines, resolution=0.1, max_cells=4e6, target_frames=1400):
    """The ground the outlines cover at some instant: a raster (True where
    covered) of cells ``resolution`` m wide (coarser when it would exceed
    max_cells), every polygon of about ``target_frames`` instants filled
    (Pillow). Returns (mask [row = y, column = x], x of column 0, y of row 0, cell size)."""
    from PIL import Image, ImageDraw
    out = np.asarray(outlines, float)
    x0, y0 = np.nanmin(out[..., 0]) - 1.0, np.nanmin(out[..., 1]) - 1.0
    x1, y1 = np.nanmax(out[..., 0]) + 1.0, np.nanmax(out[..., 1]) + 1.0
    res = max(resolution, math.sqrt((x1 - x0) * (y1 - y0) / max_cells))
    W, H = int((x1 - x0) / res) + 2, int((y1 - y0) / res) + 2
    im = Image.new("1", (W, H), 0)
    draw = ImageDraw.Draw(im)
    step = max(1, len(out) // target_frames)
    for k in range(0, len(out), step):
        for mo in range(0, out.shape[1], 4):
            q = out[k, mo:mo + 4]
            if np.all(np.isfinite(q)):
                draw.polygon([((x - x0) / res, (y - y0) / res) for x, y in q], fill=1, outline=1)
    return np.array(im, dtype=bool), x0, y0, res


def _draw_swept_area(ax, area, label=True):
    mask, x0, y0, res = area
    X = x0 + res * np.arange(mask.shape[1])
    Y = y0 + res * np.arange(mask.shape[0])
    m = mask.astype(float)
    ax.contourf(X, Y, m, levels=[0.5, 1.5], colors=["tab:red"], alpha=0.08, zorder=0.5)
    ax.contour(X, Y, m, levels=[0.5], colors=["tab:red"], linewidths=1.0, linestyles="--", zorder=3)
    if label:
        ax.plot([], [], color="tab:red", lw=1.0, ls="--", label="swept-path envelope")


def _panels(xlim, ylim, max_panels=4, min_ratio=0.22):
    """Split the long side of a drawing into up to ``max_panels`` windows so
    that each, drawn at equal scale, is at least ``min_ratio`` as high as wide.
    Returns the x windows (or y windows for a tall drawing) and whether tall."""
    w, h = xlim[1] - xlim[0], ylim[1] - ylim[0]
    tall = h > w
    long_, short = (h, w) if tall else (w, h)
    ratio = short / long_ if long_ > 0 else 1.0
    k = int(min(max_panels, max(1, math.ceil(min_ratio / max(ratio, 1e-9) - 1e-9))))
    lo = ylim[0] if tall else xlim[0]
    edges = lo + long_ * np.arange(k + 1) / k
    overlap = 0.02 * long_ / k
    return [(edges[i] - overlap, edges[i + 1] + overlap) for i in range(k)], tall


def birds_eye(path, traces, outlines=None, road=None, title="", every=10, envelope=True, reference=None):
    """traces: {label: (x, y)}; outlines: array [time, corners, 2] (groups of 4
    corners per module) drawn every ``every`` samples; road: (x, y). With
    outlines (and ``envelope``), the swept-path envelope (kpi.swept_path along
    ``reference`` or the outermost corner's trace) is drawn, and its width over
    the path in a panel below. x and y at equal scale; a long thin drawing is
    split into up to four panels, each a stretch of the long side."""
    out = None if outlines is None else np.asarray(outlines, float)
    sp = swept(out, reference) if (out is not None and envelope and len(out) > 1) else None
    area = swept_area(out) if sp is not None else None
    xs = [np.asarray(x, float) for x, _ in traces.values()]
    ys = [np.asarray(y, float) for _, y in traces.values()]
    if out is not None:
        xs.append(out[..., 0].ravel())
        ys.append(out[..., 1].ravel())
    if road is not None:
        rx, ry = np.asarray(road[0], float), np.asarray(road[1], float)
        # the road only where the vehicle is (a road may run on far beyond)
        if xs:
            x0, x1 = min(np.nanmin(v) for v in xs), max(np.nanmax(v) for v in xs)
            y0, y1 = min(np.nanmin(v) for v in ys), max(np.nanmax(v) for v in ys)
            pad = 0.1 * max(x1 - x0, y1 - y0, 1.0)
            near = (rx > x0 - pad) & (rx < x1 + pad) & (ry > y0 - pad) & (ry < y1 + pad)
            xs.append(rx[near])
            ys.append(ry[near])
        else:
            xs.append(rx)
            ys.append(ry)
    xall = np.concatenate([v[np.isfinite(v)] for v in xs]) if xs else np.array([0.0, 1.0])
    yall = np.concatenate([v[np.isfinite(v)] for v in ys]) if ys else np.array([0.0, 1.0])
    xlim = (float(xall.min()), float(xall.max()))
    ylim = (float(yall.min()), float(yall.max()))
    m = 0.03 * max(xlim[1] - xlim[0], ylim[1] - ylim[0], 1.0)
    xlim, ylim = (xlim[0] - m, xlim[1] + m), (ylim[0] - m, ylim[1] + m)
    windows, tall = _panels(xlim, ylim)
    width_in = 9.0
    if tall:
        pw, ph = (ylim[1] - ylim[0]) / len(windows), xlim[1] - xlim[0]     # each panel: x range wide, a window high
        ratio = pw / ph
        panel_h = min(9.0, width_in / len(windows) * ratio)
        shape = (1, len(windows))
    else:
        ratio = (ylim[1] - ylim[0]) / ((xlim[1] - xlim[0]) / len(windows))
        panel_h = min(8.0, max(1.6, width_in * ratio))
        shape = (len(windows), 1)
    extra = 2.0 if sp is not None else 0.0
    fig_h = (panel_h * shape[0] if not tall else panel_h) + extra + 0.8
    fig = plt.figure(figsize=(width_in, fig_h))
    heights = [panel_h] * shape[0] + ([extra] if sp is not None else [])
    gs = fig.add_gridspec(len(heights), shape[1], height_ratios=heights)
    axes = [fig.add_subplot(gs[i, 0]) for i in range(shape[0])] if not tall else \
        [fig.add_subplot(gs[0, j]) for j in range(shape[1])]
    for n, ax in enumerate(axes):
        if road is not None:
            ax.plot(road[0], road[1], color="0.78", lw=6, solid_capstyle="round", label="road", zorder=0)
        if out is not None:
            for k in range(0, len(out), max(1, every)):
                for mo in range(0, out.shape[1], 4):
                    q = out[k, mo:mo + 4]
                    ax.fill(q[:, 0], q[:, 1], facecolor="none", edgecolor="0.5", lw=0.5, zorder=1)
        if area is not None:
            _draw_swept_area(ax, area)
        for (label, (x, y)), c in zip(traces.items(), colours() * 3):
            ax.plot(x, y, color=c, lw=1.4, label=label, zorder=2)
        ax.set_aspect("equal", adjustable="box")
        if tall:
            ax.set_ylim(*windows[n])
            ax.set_xlim(*xlim)
        else:
            ax.set_xlim(*windows[n])
            ax.set_ylim(*ylim)
        ax.grid(True, alpha=0.3)
        ax.set_ylabel("y [m]")
        ax.set_xlabel("x [m]")              # (each panel a window of its own: each says its unit)
    axes[0].set_title(title + (f"\n(split into {len(axes)} panels, each at equal scale)" if len(axes) > 1 else ""),
                      fontsize=10)
    legend_beside(axes[0], fontsize=7)     # beside the drawing: never over a trace
    if sp is not None:
        axw = fig.add_subplot(gs[-1, :])
        axw.plot(sp.s, sp.width, color="tab:red", lw=0.5, alpha=0.5, label="per 0.5 m of path")
        k = 2                                   # running maximum over 2 m (sparse outline samples)
        padded = np.concatenate([np.full(k, np.nan), sp.width, np.full(k, np.nan)])
        run = np.nanmax(np.stack([padded[i:i + len(sp.width)] for i in range(2 * k + 1)]), axis=0)
        axw.plot(sp.s, run, color="tab:red", lw=1.4, label="running maximum over 2 m")
        axw.set_xlabel("distance along the path of the outermost corner [m]")
        axw.set_ylabel("swept width [m]")
        axw.set_title(f"swept-path width across that path (max {sp.max_width:.2f} m, the KPI's definition: "
                      "kpi.swept_path)", fontsize=9)
        axw.legend(loc="best", fontsize=7)
        axw.grid(True, alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def signals(path, t, panels, title="", bounds=None):
    """panels: [(ylabel, {label: values})], one axis each, shared time axis.
    bounds: [(panel index, value, label)]: the papers' bounds drawn as dashed
    lines, each labelled with its source (draw_bound). Each legend beside its
    panel (legend_beside: never over the data), the title wrapped to the
    figure's width (wrapped_title: never cut at its edges)."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(11, 2.4 * len(panels) + 0.3), sharex=True, squeeze=False)
    for ax, (ylabel, series) in zip(axes[:, 0], panels):
        for (label, y), c in zip(series.items(), colours() * 3):
            ax.plot(t, y, color=c, lw=1.2, label=label)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    for i, value, label in bounds or []:
        draw_bound(axes[i, 0], value, label)
    for ax, _ in zip(axes[:, 0], panels):
        legend_beside(ax, fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    wrapped_title(fig, title)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def legend_beside(ax, width=42, **kw):
    """The axis's legend to the right of it, outside the plotted area, so that it
    never hides a curve (a legend inside, even at matplotlib's "best" place,
    covers some of a panel full of data); tight_layout makes room for it. Its
    labels broken into lines of at most ``width`` characters (a long bound's
    source would otherwise take the plot's width)."""
    import textwrap
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        return None
    labels = [textwrap.fill(label, width) for label in labels]
    return ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kw)


def wrapped_title(fig, title, fontsize=11):
    """The figure's title (suptitle: centred on the figure, not on an axis that a
    legend beside it moves left), broken into lines that fit the figure's width
    (a long one on one line runs past the figure's edges and is cut)."""
    import textwrap
    if not title:
        return None
    # an average glyph is about 0.55 em wide: the characters a line of 90 % of the figure's width holds
    width = max(20, int(fig.get_figwidth() * 72 * 0.9 / (0.55 * fontsize)))
    text = "\n".join(textwrap.fill(line, width) for line in str(title).split("\n"))
    return fig.suptitle(text, fontsize=fontsize)


def draw_bound(ax, value, label, horizontal=True, color="k"):
    """A paper's bound on an axis: a dashed line at value, in the legend as
    label (e.g. "< 1.0 m (seed 000, Fig. 9)"); labels repeated on one axis are shown once."""
    seen = {h.get_label() for h in ax.get_lines()}
    kw = dict(color=color, lw=0.9, ls="--", zorder=1.5, label=label if label not in seen else "_nolegend_")
    return ax.axhline(value, **kw) if horizontal else ax.axvline(value, **kw)
