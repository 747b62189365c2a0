"""The bench reports: the drawings every bench uses (bird's-eye view with the
swept-path envelope, signals over time, an animation of the bird's-eye view,
a thumbnail), one HTML page per bench with its KPI table next to the papers'
values (and kpis.csv with the units beside it), and the index of a run of
every bench: a summary with each bench's headline KPIs, pass/fail marks, a
thumbnail and the run's metadata.

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

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from artibus import files  # noqa: E402

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


def _colours():
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
        for (label, (x, y)), c in zip(traces.items(), _colours() * 3):
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
        if n == len(axes) - 1 or tall:
            ax.set_xlabel("x [m]")
    axes[0].set_title(title + (f"\n(split into {len(axes)} panels, each at equal scale)" if len(axes) > 1 else ""),
                      fontsize=10)
    axes[0].legend(loc="best", fontsize=7, ncol=2 if len(traces) > 3 else 1)
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
    return save_figure(fig, path, dpi=110)


# ---- the animation of the bird's-eye view ---------------------------------------

def animation_writer():
    """(writer class, suffix): Pillow's GIF writer, else ffmpeg's MP4, else (None, None)."""
    from matplotlib import animation
    try:
        import PIL  # noqa: F401
        return animation.PillowWriter, ".gif"
    except ImportError:
        pass
    if animation.writers.is_available("ffmpeg"):
        return animation.FFMpegWriter, ".mp4"
    return None, None


def animate(path, t, outlines=None, traces=None, links=None, road=None, title="", frames=100, dpi=50, fps=12):
    """The bird's-eye view as a GIF (Pillow) or, without Pillow, an MP4
    (matplotlib's FFMpegWriter): ``frames`` instants evenly over ``t``;
    outlines [time, corners, 2] (groups of 4 per module) and links [time,
    points, 2] (a polyline per instant, e.g. the axles of a kinematic model)
    move, traces {label: (x, y)} grow. The whole manoeuvre in view when it is
    not long and thin, else a window following the vehicle (with a scale bar).
    The frames are drawn by blitting the moving parts onto a background drawn
    once (a window that follows is drawn whole, without tick labels), which
    keeps 100 frames to about a second. ``path``'s suffix is replaced by the
    writer's; returns the path written, or None when no writer is available."""
    from matplotlib.patches import Polygon
    writer_cls, suffix = animation_writer()
    if writer_cls is None:
        return None
    path = Path(path).with_suffix(suffix)
    t = np.asarray(t, float)
    idx = np.unique(np.linspace(0, len(t) - 1, min(frames, len(t))).astype(int))
    out = None if outlines is None else np.asarray(outlines, float)
    lk = None if links is None else np.asarray(links, float)
    traces = {k: (np.asarray(x, float), np.asarray(y, float)) for k, (x, y) in (traces or {}).items()}
    thin = max(1, len(t) // 1000)         # traces drawn through at most about 1000 points
    body = [a.reshape(len(t), -1, 2) for a in (out, lk) if a is not None]
    pts = np.concatenate(body, axis=1) if body else None
    xs = ([pts[..., 0].ravel()] if pts is not None else []) + [x for x, _ in traces.values()]
    ys = ([pts[..., 1].ravel()] if pts is not None else []) + [y for _, y in traces.values()]
    if not xs:
        return None
    allx, ally = np.concatenate(xs), np.concatenate(ys)
    allx, ally = allx[np.isfinite(allx)], ally[np.isfinite(ally)]
    w, h = np.ptp(allx), np.ptp(ally)
    follow = pts is not None and not (0.3 <= (h / w if w > 0 else 1.0) <= 3.3)
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=dpi)
    scenery = []        # drawn with the moving parts in a window that follows
    if road is not None:
        scenery += ax.plot(road[0], road[1], color="0.8", lw=5, solid_capstyle="round", zorder=0, animated=follow)
    moving = []
    lines = {}
    for (label, (x, y)), c in zip(traces.items(), _colours() * 3):
        scenery += ax.plot(x[::thin], y[::thin], color=c, lw=0.6, alpha=0.3, zorder=1, animated=follow)
        lines[label] = ax.plot([], [], color=c, lw=1.4, label=label, zorder=2, animated=True)[0]
        moving.append(lines[label])
    polys = []
    if out is not None:
        for mo in range(0, out.shape[1], 4):
            p = Polygon(out[0, mo:mo + 4], closed=True, facecolor="tab:blue", alpha=0.4, edgecolor="k", lw=0.8,
                        zorder=3, animated=True)
            ax.add_patch(p)
            polys.append((mo, p))
            moving.append(p)
    link_line = None
    if lk is not None:
        link_line = ax.plot([], [], "k.-", lw=1.5, ms=6, zorder=4, animated=True)[0]
        moving.append(link_line)
    clock = ax.text(0.01, 0.98, "", transform=ax.transAxes, va="top", fontsize=9, animated=True)
    moving.append(clock)
    ax.set_title(title, fontsize=9)
    m = 0.04 * max(w, h, 1.0)
    if follow:
        size = max(np.ptp(pts[0, :, 0]), np.ptp(pts[0, :, 1]), 5.0)
        span = max(2.4 * size, 20.0)
        ax.set_xticks([])
        ax.set_yticks([])
        bar = 10.0 if span < 80 else 20.0
        ax.set_xlabel(f"following the vehicle, x and y at equal scale; the bar is {bar:g} m")
        ax.plot([0.04, 0.04 + bar / span], [0.06, 0.06], color="k", lw=3, transform=ax.transAxes)
    else:
        ax.set_xlim(allx.min() - m, allx.max() + m)
        ax.set_ylim(ally.min() - m, ally.max() + m)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.grid(True, alpha=0.3)
        ax.set_aspect("equal", adjustable="box")
    if traces:
        ax.legend(handles=list(lines.values()), loc="lower right", fontsize=7, ncol=2)
    fig.tight_layout()
    canvas = fig.canvas
    # following: the limits' ratio is the axes box's, so x and y are at equal scale
    box = ax.get_position()
    fw, fh = fig.get_size_inches()
    hw = (box.height * fh) / (box.width * fw)
    images = []
    canvas.draw()
    bg = canvas.copy_from_bbox(fig.bbox)
    for k in idx:
        canvas.restore_region(bg)
        if follow:
            cx, cy = np.nanmean(pts[k, :, 0]), np.nanmean(pts[k, :, 1])
            ax.set_xlim(cx - span / 2, cx + span / 2)
            ax.set_ylim(cy - span * hw / 2, cy + span * hw / 2)
            for a in scenery:
                ax.draw_artist(a)
        for label, (x, y) in traces.items():
            lines[label].set_data(np.append(x[:k:thin], x[k]), np.append(y[:k:thin], y[k]))
        for mo, p in polys:
            p.set_xy(out[k, mo:mo + 4])
        if link_line is not None:
            link_line.set_data(lk[k, :, 0], lk[k, :, 1])
        clock.set_text(f"t = {t[k]:.1f} s")
        for a in moving:
            ax.draw_artist(a)
        images.append(np.asarray(canvas.buffer_rgba())[..., :3].copy())
    plt.close(fig)
    with files.atomic_path(path) as tmp:
        if suffix == ".gif":
            from PIL import Image
            frames_p = [Image.fromarray(a).quantize(colors=64, method=Image.Quantize.FASTOCTREE) for a in images]
            frames_p[0].save(tmp, save_all=True, append_images=frames_p[1:], duration=round(1000 / fps), loop=0,
                             optimize=False)
        else:
            _write_mp4(tmp, images, fps, dpi)
    return path


def _write_mp4(path, images, fps, dpi):
    """Frames (RGB arrays) to an MP4 through matplotlib's FFMpegWriter."""
    from matplotlib import animation
    hgt, wid = images[0].shape[:2]
    fig = plt.figure(figsize=(wid / dpi, hgt / dpi), dpi=dpi)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_axis_off()
    im = ax.imshow(images[0])
    writer = animation.FFMpegWriter(fps=fps)
    with writer.saving(fig, str(path), dpi):
        for a in images:
            im.set_data(a)
            writer.grab_frame()
    plt.close(fig)


def result_outlines(result):
    """The body outlines [time, corners, 2] of a result that recorded a
    BusDynamics' xCorner/yCorner (the component named Bus), or None."""
    names = set(result.names)
    cols = []
    c = 1
    while f"Bus.xCorner[{c}]" in names and f"Bus.yCorner[{c}]" in names:
        cols.append(np.column_stack([result[f"Bus.xCorner[{c}]"], result[f"Bus.yCorner[{c}]"]]))
        c += 1
    if len(cols) < 4:
        return None
    cols = cols[:len(cols) // 4 * 4]
    out = np.stack(cols, axis=1)
    # modules beyond nModules report no outline (zeros or NaN): leave them out
    keep = []
    for mo in range(0, out.shape[1], 4):
        q = out[:, mo:mo + 4]
        if np.all(np.isfinite(q)) and np.ptp(q[0, :, 0]) + np.ptp(q[0, :, 1]) > 0:
            keep.extend(range(mo, mo + 4))
    return out[:, keep] if keep else None


def result_axle_traces(result):
    """{"A1": (x, y), ...} of a result with BusDynamics' xAxle/yAxle (component Bus)."""
    names = set(result.names)
    tr = {}
    a = 1
    while f"Bus.xAxle[{a}]" in names:
        x, y = result[f"Bus.xAxle[{a}]"], result[f"Bus.yAxle[{a}]"]
        if np.all(np.isfinite(x)) and (np.ptp(x) > 0 or np.ptp(y) > 0 or abs(x[0]) + abs(y[0]) > 0):
            tr[f"A{a}"] = (x, y)
        a += 1
    return tr


def result_links(result):
    """A BusKinematics result's axle mid-points P0, P1, ... (component Bus: x[i],
    y[i]) as a polyline per instant [time, points, 2], or None."""
    names = set(result.names)
    pts = []
    i = 0
    while f"Bus.x[{i}]" in names and f"Bus.y[{i}]" in names and f"Bus.theta[{i}]" in names:
        pts.append(np.column_stack([result[f"Bus.x[{i}]"], result[f"Bus.y[{i}]"]]))
        i += 1
    return np.stack(pts, axis=1) if len(pts) >= 2 else None


def bench_animation(result, out, title="", frames=100):
    """The bird's-eye animation of a bench run (outlines of a BusDynamics, or the
    axle points of a BusKinematics), as out/birds_eye.gif (or .mp4); returns
    [(file name, caption)] for the report, [] when the run has no positions or
    no animation writer is available."""
    t = result.time
    outl = result_outlines(result)
    if outl is not None:
        moving = np.ptp(outl[..., 0]) + np.ptp(outl[..., 1]) > 1.0
        if not moving:
            return []
        p = animate(Path(out) / "birds_eye.gif", t, outlines=outl, traces=result_axle_traces(result),
                    title=title, frames=frames)
        what = "body outlines"
    else:
        links = result_links(result)
        if links is None:
            return []
        tr = {f"P{i}": (links[:, i, 0], links[:, i, 1]) for i in range(links.shape[1])}
        p = animate(Path(out) / "birds_eye.gif", t, links=links, traces=tr, title=title, frames=frames)
        what = "the axle mid-points P0, P1, ... joined"
    if p is None:
        return []
    return [(p.name, f"Animation of the bird's-eye view ({what}), {frames} frames over "
                     f"{t[-1] - t[0]:g} s.")]


# ---- pages ---------------------------------------------------------------------

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
        src = pngs[0] if pngs[0].is_absolute() else out_dir / pngs[0]
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
