"""KPIs against closed forms on synthetic traces."""
import math

import numpy as np
import pytest

from artibus.study import kpi


def circle(R, a0=0.0, a1=2 * math.pi, n=2000, cx=0.0, cy=0.0):
    a = np.linspace(a0, a1, n)
    return cx + R * np.sin(a), cy + R - R * np.cos(a)   # starts at (cx, cy) heading +x, turns left


def test_deviation_of_concentric_circles_is_the_radius_difference():
    rx, ry = circle(17.5)
    x, y = circle(16.2)
    assert kpi.trace_deviation(rx, ry, x, y + 1.3) == pytest.approx(1.3, abs=1e-3)
    d, inside = kpi.lateral_distance(rx, ry, x, y + 1.3)
    assert np.all(d[inside] > 0)   # the inner circle is left of a left turn


def test_deviation_counts_only_where_the_reference_has_been():
    """A trace starting 5 m behind the reference's start (on the same line)
    and 2 m to the side: points before the reference's first point are not counted."""
    rx, ry = np.linspace(0, 50, 200), np.zeros(200)
    x = np.linspace(-5, 45, 200)
    y = np.where(x < 0, 10.0, 2.0)           # far away only where the reference has not been
    assert kpi.trace_deviation(rx, ry, x, y) == pytest.approx(2.0)


def test_swept_path_of_a_rigid_body_on_a_circle():
    """Rear axle on a circle of radius R about the turn centre, body width W,
    front overhang a ahead of the rear axle, rear overhang b behind it:
    outer radius sqrt((R + W/2)^2 + a^2), inner radius R - W/2."""
    R, W, a, b = 10.0, 2.55, 9.0, 3.0
    ang = np.linspace(0, 2 * math.pi, 721)
    # rear axle mid-point on the circle (centre at origin), heading tangent
    px, py = R * np.cos(ang), R * np.sin(ang)
    hx, hy = -np.sin(ang), np.cos(ang)            # heading (counter-clockwise)
    nx, ny = np.cos(ang), np.sin(ang)             # outward normal
    corners = np.stack([
        np.column_stack([px + a * hx + W / 2 * nx, py + a * hy + W / 2 * ny]),
        np.column_stack([px + a * hx - W / 2 * nx, py + a * hy - W / 2 * ny]),
        np.column_stack([px - b * hx - W / 2 * nx, py - b * hy - W / 2 * ny]),
        np.column_stack([px - b * hx + W / 2 * nx, py - b * hy + W / 2 * ny]),
    ], axis=1)
    expected = math.hypot(R + W / 2, a) - (R - W / 2)
    width = kpi.swept_path_width(px, py, corners, bin_length=0.5, samples_per_edge=40)
    assert width == pytest.approx(expected, abs=0.03)


@pytest.mark.parametrize("f, zeta", [(0.7, 0.2), (0.4, 0.05), (1.0, 0.35)])
def test_oscillation_recovers_frequency_and_damping(f, zeta):
    wn = 2 * math.pi * f / math.sqrt(1 - zeta ** 2)  # f is the damped frequency
    t = np.arange(0, 20, 0.01)
    x = 0.1 + 0.05 * np.exp(-zeta * wn * t) * np.cos(2 * math.pi * f * t + 0.3)
    o = kpi.oscillation(t, x)
    assert o.frequency == pytest.approx(f, rel=1e-3)
    assert o.damping_ratio == pytest.approx(zeta, rel=1e-2)
    assert o.natural_frequency == pytest.approx(wn / (2 * math.pi), rel=1e-2)


def test_overshoot_peak_energy():
    y = np.array([0, 1, 2, 3.4, 3.6, 3.3, 3.25, 3.25])
    assert kpi.overshoot(y) == pytest.approx(0.35)
    assert kpi.overshoot(-y) == pytest.approx(0.35)
    assert kpi.peak([-3, 2]) == 3
    t = np.linspace(0, 2, 201)
    assert kpi.energy(t, 2 * np.ones_like(t), 0.5 * np.ones_like(t)) == pytest.approx(2.0)


def test_swept_path_along_a_straight_and_a_circle():
    """A 2.5 m wide, 12 m long body drives a straight, a full circle of radius
    15 m tangent to it and the straight on, through the circle's start, its
    reference sampled at the outlines' instants (each instant located near its
    own reference point): the width is the annulus's on the circle
    (sqrt((R + W/2)^2 + (L/2)^2) - (R - W/2) for a body centred on the path)
    and W on the straights."""
    R, W, L = 15.0, 2.5, 12.0
    s = np.arange(-40.0, 2 * math.pi * R + 40.0, 0.1)
    on = (s >= 0) & (s <= 2 * math.pi * R)
    ang = np.where(on, s / R, 0.0)
    x = np.where(s < 0, s, np.where(on, R * np.sin(ang), s - 2 * math.pi * R))
    y = np.where(on, R * (1 - np.cos(ang)), 0.0)
    hx, hy = np.cos(ang), np.sin(ang)
    nx, ny = -hy, hx
    corners = np.stack([np.column_stack([x + a * L / 2 * hx + b * W / 2 * nx, y + a * L / 2 * hy + b * W / 2 * ny])
                        for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1))], axis=1)
    sp = kpi.swept_path(x[::5], y[::5], corners[::5], bin_length=0.5, samples_per_edge=40)
    annulus = math.hypot(R + W / 2, L / 2) - (R - W / 2)
    mid = (sp.s > 0.3 * 2 * math.pi * R + 40) & (sp.s < 0.7 * 2 * math.pi * R + 40)
    assert np.median(sp.width[mid]) == pytest.approx(annulus, abs=0.05)
    assert sp.max_width < annulus + 0.3
    straight = sp.s > 2 * math.pi * R + 40 + L
    assert np.median(sp.width[straight]) == pytest.approx(W, abs=0.02)


def test_deviation_from_a_coarsely_sampled_straight_trace_has_no_step():
    """The distance is to the reference's polyline, not to its nearest sample:
    a straight reference of three samples 50 m apart gives 0 for points on it
    and exactly 1 m for points 1 m beside it (the nearest sample would be up
    to sqrt(25^2 + 1) m away)."""
    rx, ry = np.array([0.0, 50.0, 100.0]), np.zeros(3)
    x = np.linspace(0.0, 100.0, 101)
    assert kpi.trace_deviation(rx, ry, x, np.zeros_like(x)) == pytest.approx(0.0, abs=1e-12)
    d, inside = kpi.lateral_distance(rx, ry, x, np.full_like(x, -1.0))
    assert inside.all() and np.allclose(d, -1.0, atol=1e-12)     # right of the direction of travel


def self_crossing(offset, ds=0.05):
    """A straight (y = offset, x from -20 to 0), a left arc of radius 10 - offset
    about (0, 10) over 270 deg, a straight down x = -10 + offset to y = -20:
    the exit crosses the entry at x = -10 (offset = 0), and the path offset to the
    left by ``offset`` stays exactly ``offset`` from the one with 0."""
    R = 10.0 - offset
    x1 = np.arange(-20.0, 0.0, ds)
    a = np.arange(0.0, 1.5 * math.pi, ds / 10.0)
    y3 = np.arange(10.0, -20.0 - ds / 2, -ds)
    x = np.concatenate([x1, R * np.sin(a), np.full_like(y3, -R)])
    y = np.concatenate([np.full_like(x1, offset), 10.0 - R * np.cos(a), y3])
    return x, y


def test_deviation_where_the_reference_crosses_itself_has_no_step():
    """A circle's exit crossing its entry straight (as on the 17.5 m circle): a
    trace 0.5 m left of the reference all along is 0.5 m from it at every point.
    The foot on the reference nearest anywhere jumps to the other pass near the
    crossing (distance down to 0); each point's foot near the previous one's does not."""
    rx, ry = self_crossing(0.0)
    x, y = self_crossing(0.5)
    d, inside = kpi.lateral_distance(rx, ry, x, y)
    assert inside.all()
    np.testing.assert_allclose(d, 0.5, atol=2e-4)                 # chord error of the arc: 1.3e-5 m
    assert kpi.trace_deviation(rx, ry, x, y) == pytest.approx(0.5, abs=2e-4)
    anywhere, _ = kpi.lateral_distance(rx, ry, x, y, window=None)
    assert np.min(np.abs(anywhere)) < 0.05                        # the step the tracked foot avoids


def test_hinge_force_peak_only_while_moving():
    """A spike of 5 kN while standing (|v| <= 0.1 m/s: the start-up transient)
    is not the manoeuvre's peak; the 3 kN sine while moving, forwards or
    backwards (v < 0), is."""
    t = np.linspace(0.0, 20.0, 2001)
    v = np.where(t < 2.0, 0.05, np.where(t < 11.0, 3.0, -2.0))
    F = np.where(t < 1.0, 5000.0, 0.0) + np.where(t >= 2.0, 3000.0 * np.sin(2 * math.pi * 0.25 * t), 0.0)
    assert kpi.peak(F) == 5000.0
    assert kpi.peak_while_moving(F, v) == pytest.approx(3000.0, rel=1e-9)
    assert kpi.peak_while_moving(np.where(t > 11.0, F, 0.0), v) == pytest.approx(3000.0, rel=1e-3)   # backwards
    assert math.isnan(kpi.peak_while_moving(F, np.zeros_like(t)))
    assert kpi.peak_while_moving([7.0, 1.0], [0.1, 0.2]) == 1.0   # |v| = 0.1 is standing still


def test_swept_path_projection_a_few_instants_at_a_time_is_each_instant_alone():
    """kpi._project_local projects several instants at a time, each on its own
    window of the reference (padded to the longest): the same numbers, bit for
    bit, as _project on each instant's window alone (its arc length from the
    window's start, plus the start's), on random references, outlines, windows
    that clip at either end and batch sizes."""
    rng = np.random.default_rng(7)
    for _ in range(40):
        n = int(rng.integers(3, 60))
        ref = np.cumsum(rng.normal(size=(n, 2)), axis=0)
        frames = rng.normal(scale=3.0, size=(int(rng.integers(1, 20)), int(rng.integers(1, 9)), 2)) \
            + ref[rng.integers(0, n - 1)]
        centre, window = rng.integers(0, n - 1, size=len(frames)), float(rng.uniform(0.1, 20.0))
        seg = np.hypot(*np.diff(ref, axis=0).T)
        s0 = np.concatenate([[0.0], np.cumsum(seg)])[:-1]
        alone = []
        for k in range(len(frames)):
            lo = max(0, int(np.searchsorted(s0, s0[centre[k]] - window)) - 1)
            hi = min(len(seg), max(int(np.searchsorted(s0, s0[centre[k]] + window, side="right")), lo + 1))
            s, off, inside = kpi._project(ref[lo:hi + 1], frames[k])
            alone.append((s + s0[lo], off, inside))
        expected = [np.concatenate(x) for x in zip(*alone)]
        got = kpi._project_local(ref, frames, centre, window, batch=int(rng.integers(1, 7)))
        for e, g in zip(expected, got):
            assert e.dtype == g.dtype and e.tobytes() == g.tobytes()
