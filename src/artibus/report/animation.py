"""The animation of the bird's-eye view (``animate``, a GIF or an MP4) and a
bench run's (``bench_animation``: the body outlines of a BusDynamics, or the
axle points of a BusKinematics)."""
from pathlib import Path

import numpy as np

from artibus import files
from artibus.report.plots import colours, plt


def animation_writer():
    """(writer class, suffix): ffmpeg's MP4 through matplotlib (where ffmpeg is installed:
    small files, full colour), else Pillow's GIF, else (None, None)."""
    from matplotlib import animation
    if animation.writers.is_available("ffmpeg"):
        return animation.FFMpegWriter, ".mp4"
    try:
        import PIL  # noqa: F401
        return animation.PillowWriter, ".gif"
    except ImportError:
        return None, None


#: the animation's size: 8 x 5.5 in at 100 dpi, 800 x 550 px (title, legend and clock readable)
FIGSIZE, DPI = (8.0, 5.5), 100


def animate(path, t, outlines=None, traces=None, links=None, road=None, title="", frames=100, dpi=DPI, fps=12):
    """The bird's-eye view, 800 px wide, as an MP4 (matplotlib's FFMpegWriter, where
    ffmpeg is installed) or a GIF (Pillow): ``frames`` instants evenly over ``t``;
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
    fig, ax = plt.subplots(figsize=FIGSIZE, dpi=dpi)
    scenery = []        # drawn with the moving parts in a window that follows
    if road is not None:
        scenery += ax.plot(road[0], road[1], color="0.8", lw=5, solid_capstyle="round", zorder=0, animated=follow)
    moving = []
    lines = {}
    for (label, (x, y)), c in zip(traces.items(), colours() * 3):
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
    clock = ax.text(0.01, 0.98, "", transform=ax.transAxes, va="top", fontsize=11, animated=True)
    moving.append(clock)
    ax.set_title(title, fontsize=11)
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
        ax.legend(handles=list(lines.values()), loc="lower right", fontsize=9, ncol=2)
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
