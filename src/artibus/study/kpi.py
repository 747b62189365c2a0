"""Key performance indicators of a manoeuvre, computed from recorded signals.

Each function takes plain arrays, so it works on any bench's results:

- trace_deviation: how far an axle's trace strays from a reference axle's trace
  (seed 000, Fig. 9: max lateral distance of A4/A6 from the A2 trace);
- swept_path, swept_path_width: the ground swept by the body outlines (its
  envelope and its width along the path) and the largest width;
- overshoot: how far a trace goes beyond its final lateral offset after a lane
  change (seed 001, "initial overshoot" of the rear section);
- oscillation: frequency and damping ratio of a decaying oscillation
  (articulation angle after a manoeuvre), from its successive peaks;
- peak, energy: the largest magnitude of a signal; the work of a torque;
  peak_while_moving: the largest magnitude while the vehicle moves (|v| > 0.1 m/s).
"""
import bisect
import math
from dataclasses import dataclass

import numpy as np


def _polyline(x, y):
    p = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    keep = np.concatenate([[True], np.any(np.diff(p, axis=0) != 0, axis=1)])
    return p[keep]


def _project(ref, pts, chunk=2000):
    """For each point: arc length of its foot on the polyline ``ref``, signed
    lateral offset (left positive), and whether the foot lies within the ends."""
    a, d = ref[:-1], np.diff(ref, axis=0)
    seg = np.hypot(d[:, 0], d[:, 1])
    s0 = np.concatenate([[0.0], np.cumsum(seg)])[:-1]
    seg_len2 = seg ** 2
    s_out, off_out, in_out = [], [], []
    for k in range(0, len(pts), chunk):
        p = pts[k:k + chunk]
        rel = p[:, None, :] - a[None, :, :]                       # [n, m, 2]
        u = np.einsum("nmk,mk->nm", rel, d) / seg_len2
        uc = np.clip(u, 0.0, 1.0)
        e = rel - uc[..., None] * d[None]
        dist2 = np.einsum("nmk,nmk->nm", e, e)
        i = np.argmin(dist2, axis=1)
        n = np.arange(len(p))
        cross = d[i, 0] * rel[n, i, 1] - d[i, 1] * rel[n, i, 0]
        s_out.append(s0[i] + uc[n, i] * seg[i])
        off_out.append(np.copysign(np.sqrt(dist2[n, i]), cross))
        in_out.append(~(((i == 0) & (u[n, i] < 0)) | ((i == len(d) - 1) & (u[n, i] > 1))))
    return np.concatenate(s_out), np.concatenate(off_out), np.concatenate(in_out)


def _project_tracked(ref, pts, window, block=32):
    """As _project, for the points of a trace in time order: the first point's
    foot is the nearest on the whole reference, every later point's the nearest
    within ``window`` m of arc length of the previous point's foot. A reference
    that crosses itself (a circle's exit across its entry straight) does not
    make the foot jump to the other pass and back, a step in the distance that
    is not the trace's.

    The distances of ``block`` points at a time are computed together, to the
    segments within twice the window of the last foot; each point then takes
    the nearest within its own window, in turn (a point whose window reaches
    beyond those segments starts the next block). The same numbers, bit for
    bit, as projecting each point alone on its window (_project), ~9 x faster
    (a sweep computes the KPIs of every case)."""
    a, d = ref[:-1], np.diff(ref, axis=0)
    seg = np.hypot(d[:, 0], d[:, 1])
    s0 = np.concatenate([[0.0], np.cumsum(seg)])
    seg_len2 = seg ** 2
    m, n = len(d), len(pts)
    s_out, off_out, in_out = np.empty(n), np.empty(n), np.empty(n, bool)
    if n == 0:
        return s_out, off_out, in_out
    s, off, inside = _project(ref, pts[:1])          # the first point: anywhere on the reference
    s_out[0], off_out[0], in_out[0] = s0[0] + s[0], off[0], inside[0]
    starts = s0.tolist()
    k = 1
    while k < n:
        s_prev = s_out[k - 1]
        lo_b = max(bisect.bisect_right(starts, s_prev - 2 * window) - 1, 0)
        hi_b = min(bisect.bisect_left(starts, s_prev + 2 * window) + 1, m)
        p = pts[k:k + block]
        rel = p[:, None, :] - a[None, lo_b:hi_b, :]                 # as _project, on these segments
        u = np.einsum("nmk,mk->nm", rel, d[lo_b:hi_b]) / seg_len2[lo_b:hi_b]
        uc = np.clip(u, 0.0, 1.0)
        e = rel - uc[..., None] * d[None, lo_b:hi_b]
        dist2 = np.einsum("nmk,nmk->nm", e, e)
        for j in range(len(p)):
            lo = max(bisect.bisect_right(starts, s_prev - window) - 1, 0)
            hi = min(bisect.bisect_left(starts, s_prev + window) + 1, m)
            if lo < lo_b or hi > hi_b:
                break                                   # a new block from this point
            i_w = int(np.argmin(dist2[j, lo - lo_b:hi - lo_b]))     # in the window
            i, c = lo + i_w, lo + i_w - lo_b
            s_w = float(np.cumsum(seg[lo:i])[-1]) if i_w else 0.0    # the window's own arc length, as _project
            s_k = s_w + float(uc[j, c]) * float(seg[i])
            cross = float(d[i, 0]) * float(rel[j, c, 1]) - float(d[i, 1]) * float(rel[j, c, 0])
            u_k = float(u[j, c])
            inside = not ((i_w == 0 and u_k < 0) or (i == hi - 1 and u_k > 1))
            if not inside and ((s_k > 0 and hi != m) or (s_k == 0 and lo != 0)):
                inside = True         # beyond the window's end, not the reference's: on it
            s_prev = float(s0[lo]) + s_k
            s_out[k], off_out[k], in_out[k] = s_prev, math.copysign(math.sqrt(float(dist2[j, c])), cross), inside
            k += 1
    return s_out, off_out, in_out


def lateral_distance(ref_x, ref_y, x, y, window=5.0):
    """Signed distance of each point (x, y) from the reference polyline (left of
    the reference's direction of travel positive), and a mask that is True
    where the point's foot lies on the reference, not beyond its ends.

    The distance is to the polyline through the reference's samples (its
    segments, not its nearest sample: a coarsely sampled straight trace gives
    0 for a point on it). (x, y) is a trace in time order: each point's foot is
    looked for within ``window`` m of arc length of the previous point's
    (_project_tracked); window=None: anywhere on the reference."""
    ref = _polyline(ref_x, ref_y)
    if len(ref) < 2:
        raise ValueError("the reference trace needs at least 2 distinct points")
    pts = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    if window is None:
        _, dist, inside = _project(ref, pts)
    else:
        _, dist, inside = _project_tracked(ref, pts, window)
    return dist, inside


def trace_deviation(ref_x, ref_y, x, y, window=5.0):
    """Largest lateral distance of a trace from a reference trace, counting only
    the part of the trace that lies where the reference has been (the rear axles
    start behind the reference's first point). The distance to the reference's
    polyline, each point's foot near the previous one's (lateral_distance): no
    step where the reference crosses itself."""
    dist, inside = lateral_distance(ref_x, ref_y, x, y, window)
    if not inside.any():
        return float("nan")
    return float(np.max(np.abs(dist[inside])))


@dataclass
class SweptPath:
    """The ground swept by the body outlines, located along a reference path:
    per bin of arc length ``s`` (m, bin centres) the outermost offsets to the
    left and right of the reference (m, left positive), their difference
    ``width`` (m), and the envelope's two edges in the plane (``left_xy``,
    ``right_xy``: arrays [bin, 2]). Bins no outline point fell into are left out."""
    s: np.ndarray
    left: np.ndarray
    right: np.ndarray
    width: np.ndarray
    left_xy: np.ndarray
    right_xy: np.ndarray

    @property
    def max_width(self):
        return float(np.max(self.width)) if len(self.width) else float("nan")


def _outline_points(outlines, samples_per_edge):
    out = np.asarray(outlines, float)
    pts = []
    for m in range(0, out.shape[1], 4):
        quad = out[:, m:m + 4]
        for c in range(4):
            p0, p1 = quad[:, c], quad[:, (c + 1) % 4]
            for f in np.linspace(0, 1, samples_per_edge, endpoint=False):
                pts.append(p0 + f * (p1 - p0))
    return np.concatenate(pts)


def _project_local(ref, frames, centre, window, batch=6):
    """_project for the outline samples of each instant (frames [time, n, 2])
    onto only the part of the reference within ``window`` m of arc length of
    that instant's reference point (centre: its segment index): a path that
    crosses itself (a full circle and the straight through it) does not mix
    one pass's outlines into another's.

    ``batch`` instants at a time, each on its own window of segments (padded to
    the batch's longest, the padding never the nearest): the same operations on
    each element as _project on ref[lo:hi + 1] (the window's arc length summed
    from its start, then its start's added), the same numbers bit for bit, ~2 x
    faster than an instant at a time (a sweep computes the KPIs of every case;
    a few instants at a time keep the temporaries small: fresh large ones cost
    page faults)."""
    a, d = ref[:-1], np.diff(ref, axis=0)
    seg = np.hypot(d[:, 0], d[:, 1])
    s0 = np.concatenate([[0.0], np.cumsum(seg)])[:-1]
    seg_len2 = seg ** 2
    m = len(seg)
    sc = s0[centre]
    lo = np.maximum(0, np.searchsorted(s0, sc - window) - 1)
    hi = np.minimum(m, np.maximum(np.searchsorted(s0, sc + window, side="right"), lo + 1))
    n_f, n_p = frames.shape[:2]
    s_out, off_out, in_out = np.empty((n_f, n_p)), np.empty((n_f, n_p)), np.empty((n_f, n_p), bool)
    for b in range(0, n_f, batch):
        fl, fh, p = lo[b:b + batch], hi[b:b + batch], frames[b:b + batch]
        f = len(fl)
        idx = fl[:, None] + np.arange(int((fh - fl).max()))[None, :]     # [f, w]: each instant's segments
        valid = idx < fh[:, None]
        idx = np.minimum(idx, m - 1)
        da, db = d[idx, 0][:, None, :], d[idx, 1][:, None, :]            # [f, 1, w]
        r0 = p[:, :, 0, None] - a[idx, 0][:, None, :]                    # [f, n, w]: rel = p - a
        r1 = p[:, :, 1, None] - a[idx, 1][:, None, :]
        u = (r0 * da + r1 * db) / seg_len2[idx][:, None, :]
        uc = np.clip(u, 0.0, 1.0)
        e0, e1 = r0 - uc * da, r1 - uc * db
        dist2 = e0 * e0 + e1 * e1
        dist2[~np.broadcast_to(valid[:, None, :], dist2.shape)] = np.inf
        i = np.argmin(dist2, axis=2)                                     # [f, n]
        F, P = np.arange(f)[:, None], np.arange(n_p)[None, :]
        local_s0 = np.zeros(idx.shape)                                   # the window's own arc length
        local_s0[:, 1:] = np.cumsum(np.where(valid, seg[idx], 0.0)[:, :-1], axis=1)
        g = idx[F, i]
        cross = d[g, 0] * r1[F, P, i] - d[g, 1] * r0[F, P, i]
        s_out[b:b + batch] = (local_s0[F, i] + uc[F, P, i] * seg[g]) + s0[fl][:, None]
        off_out[b:b + batch] = np.copysign(np.sqrt(dist2[F, P, i]), cross)
        u_i = u[F, P, i]
        in_out[b:b + batch] = ~(((i == 0) & (u_i < 0)) | ((i == (fh - fl - 1)[:, None]) & (u_i > 1)))
    return s_out.ravel(), off_out.ravel(), in_out.ravel()


def swept_path(ref_x, ref_y, outlines, bin_length=0.25, samples_per_edge=8, window=None):
    """The swept path (SweptPath): the body outlines (an array [time, corner, 2]
    of polygon corners, any number of modules stacked along the corner axis in
    groups of 4) are sampled along their edges, each sample is located along the
    reference path (arc length) and across it (signed lateral offset); only
    samples beside the reference (not beyond its ends) count. When the reference
    is sampled at the outlines' instants (as many points), each instant's samples
    are located on the reference only within ``window`` m of arc length of its
    own reference point (default: 1.5 times the vehicle's reach from it, plus
    5 m), so a path crossing itself does not mix its passes."""
    rx, ry = np.asarray(ref_x, float), np.asarray(ref_y, float)
    ref = _polyline(rx, ry)
    if len(ref) < 2:
        raise ValueError("the reference path needs at least 2 distinct points")
    out = np.asarray(outlines, float)
    if len(rx) == len(out):
        full = np.column_stack([rx, ry])
        keep = np.concatenate([[True], np.any(np.diff(full, axis=0) != 0, axis=1)])
        centre = np.clip(np.cumsum(keep) - 1, 0, len(ref) - 2)
        frames = _outline_points(out, samples_per_edge).reshape(-1, len(out), 2).transpose(1, 0, 2)
        if window is None:
            reach = np.max(np.hypot(frames[..., 0] - rx[:, None], frames[..., 1] - ry[:, None]))
            window = 1.5 * reach + 5.0
        s_all, off_all, inside = _project_local(ref, frames, centre, window)
    else:
        s_all, off_all, inside = _project(ref, _outline_points(out, samples_per_edge))
    s_all, off_all = s_all[inside], off_all[inside]   # only beside the reference path
    bins = np.floor(s_all / bin_length).astype(int)
    order = np.argsort(bins, kind="stable")
    bins, off_all = bins[order], off_all[order]
    edges = np.flatnonzero(np.diff(bins)) + 1
    keys = bins[np.concatenate([[0], edges])] if len(bins) else np.array([], int)
    groups = np.split(off_all, edges) if len(bins) else []
    left = np.array([g.max() for g in groups])
    right = np.array([g.min() for g in groups])
    s = (keys + 0.5) * bin_length
    # the edges in the plane: the reference point at s, moved along its left normal
    seg = np.diff(ref, axis=0)
    seg_len = np.hypot(seg[:, 0], seg[:, 1])
    s0 = np.concatenate([[0.0], np.cumsum(seg_len)])
    i = np.clip(np.searchsorted(s0, s, side="right") - 1, 0, len(seg) - 1)
    u = (s - s0[i]) / seg_len[i]
    base = ref[i] + u[:, None] * seg[i]
    tangent = seg[i] / seg_len[i][:, None]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    return SweptPath(s, left, right, left - right, base + left[:, None] * normal, base + right[:, None] * normal)


def swept_path_width(ref_x, ref_y, outlines, bin_length=0.25, samples_per_edge=8):
    """Width of the swept path (see swept_path): per ``bin_length`` of arc
    length along the reference the spread of the outlines' lateral offsets;
    the result is the largest width over the path."""
    sp = swept_path(ref_x, ref_y, outlines, bin_length, samples_per_edge)
    return float(np.max(sp.width)) if len(sp.width) else 0.0


def overshoot(y, y_final=None):
    """How far a lateral trace goes beyond its final value, in the direction it
    moved (a lane change to the left: the largest y above the final y)."""
    y = np.asarray(y, float)
    y_final = y[-1] if y_final is None else y_final
    direction = math.copysign(1.0, y_final - y[0]) if y_final != y[0] else 1.0
    return float(max(0.0, np.max(direction * (y - y_final))))


@dataclass
class Oscillation:
    frequency: float          # damped (observed) frequency, Hz
    damping_ratio: float      # -
    natural_frequency: float  # undamped, Hz: frequency / sqrt(1 - zeta^2)
    periods: int              # periods the estimate used


def oscillation(t, x, t_from=None):
    """Frequency and damping ratio of a decaying oscillation about its final
    value, from successive extrema after ``t_from``: the period from the
    spacing of the extrema, the damping from the logarithmic decrement of
    successive peak-to-peak swings (delta per half period):
    zeta = delta / sqrt(pi^2 + delta^2)."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    if t_from is not None:
        keep = t >= t_from
        t, x = t[keep], x[keep]
    x = x - x[-1]
    dx = np.diff(x)
    idx = np.where(np.sign(dx[1:]) != np.sign(dx[:-1]))[0] + 1
    idx = [i for i in idx if 0 < i < len(x) - 1 and abs(x[i]) > 1e-3 * np.max(np.abs(x))]
    if len(idx) < 3:
        return Oscillation(float("nan"), float("nan"), float("nan"), 0)
    # refine each extremum with a parabola through its neighbours
    te, xe = [], []
    for i in idx:
        y0, y1, y2 = x[i - 1], x[i], x[i + 1]
        den = y0 - 2 * y1 + y2
        off = 0.5 * (y0 - y2) / den if den != 0 else 0.0
        h = t[i + 1] - t[i]
        te.append(t[i] + off * h)
        xe.append(y1 - 0.25 * (y0 - y2) * off)
    te, xe = np.array(te), np.array(xe)
    period = 2 * float(np.median(np.diff(te)))
    # successive peak-to-peak swings decay like the amplitude and do not depend
    # on where the oscillation settles
    pp = np.abs(np.diff(xe))
    delta = float(np.median(np.log(pp[:-1] / pp[1:])))
    zeta = delta / math.sqrt(math.pi ** 2 + delta ** 2)
    # the extrema of a damped sinusoid are exactly half a damped period apart
    return Oscillation(1 / period, zeta, 1 / period / math.sqrt(1 - zeta ** 2), len(te) // 2)


def peak(x):
    """max |x|; NaN with no sample (a run too short for the stretch the KPI looks at)."""
    x = np.asarray(x, float)
    return float(np.max(np.abs(x))) if x.size else float("nan")


#: below this speed, m/s, the bus stands (peak_while_moving)
STANDSTILL = 0.1


def peak_while_moving(x, v, v_min=STANDSTILL):
    """The largest |x| over the samples where |v| > v_min (m/s): a hinge force's
    peak in the manoeuvre, not the start-up transient at standstill (a tyre's
    low-speed blend, the settling of a bus pulling away); NaN if it never moves."""
    x, v = np.asarray(x, float), np.asarray(v, float)
    moving = np.abs(v) > v_min
    return float(np.max(np.abs(x[moving]))) if moving.any() else float("nan")


def energy(t, torque, rate):
    """Work done by a torque against a rotation rate, J (trapezoidal rule)."""
    p = np.asarray(torque, float) * np.asarray(rate, float)
    return float(np.trapezoid(p, np.asarray(t, float)))
