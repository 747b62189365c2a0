"""A bench's loop linearised at an amplitude (the describing function, first harmonic), for loops
whose small-signal gain at the operating point says nothing: a damper whose force is zero at zero
piston speed and a controller that only requests damping against the motion and above a floor
(seed 001, 5.1.1) have, at rest, the slope of the damper's regularisation and no control at all.

The plants move in one oscillatory mode of the closed loop, y_p = y0 + Re(Y e^{j theta}), Y = C v
with v the mode's eigenvector scaled so that the signal named has the amplitude given; the loop
(artibus.linear.bench.Opened.loop: every controller and static part, each evaluated from its state
at the operating point) is evaluated over one period, theta = 2 pi k / N; the first harmonic U of
the plants' inputs gives the equivalent gains: each row of K solves K [Re Y, Im Y] = [Re U, Im U]
over the plant outputs the loop reads that move in the mode (least norm where more than two move).
The first mode is the plants' own (the loop open: at rest a friction-like damper's slope may
overdamp it); then A_cl = A + B K C, the mode found again and the gains redone until its eigenvalue settles
(the amplitude held, the frequency and shape of the mode following)."""
import numpy as np

from artibus.base import ArtibusError
from artibus.linear import bench as lb

#: samples of the period
SAMPLES = 64
#: iterations of mode -> gains -> mode at most, and the eigenvalue's relative change that ends them
ITERATIONS = 8
SETTLED = 1e-4


def _mode(A, c_row, near=None):
    """(eigenvalue, eigenvector) of the oscillatory mode of A (Im > 0) the signal with output row
    ``c_row`` shows most (|c v| over the eigenvector's largest component), or the one nearest to
    ``near``."""
    lam, vec = np.linalg.eig(A)
    cands = [k for k in range(len(lam)) if lam[k].imag > 1e-9 * max(1.0, abs(lam[k]))]
    if not cands and near is not None:           # the mode damped beyond critical: a real pair now
        cands = [k for k in range(len(lam)) if abs(lam[k].imag) <= 1e-9 * max(1.0, abs(lam[k]))]
    if not cands:
        raise ArtibusError("no oscillatory mode in the linear model: nothing to take an amplitude of")
    if near is not None:
        k = min(cands, key=lambda k: abs(lam[k] - near))
    else:
        k = max(cands, key=lambda k: abs(c_row @ vec[:, k]) / np.max(np.abs(vec[:, k])))
    return lam[k], vec[:, k]


def harmonic_gains(opened, Y, moving, samples=SAMPLES):
    """K (plant inputs by plant outputs) from the first harmonic of the loop's response to
    y_p = y0 + Re(Y e^{j theta}); only the columns ``moving`` (indices of plant outputs) are non-zero."""
    y0, r0 = opened.operating_point()
    theta = 2 * np.pi * np.arange(samples) / samples
    U = np.array([opened.loop(y0 + np.real(Y * np.exp(1j * t)), r0) for t in theta])
    opened.loop(y0, r0)
    U1 = 2.0 / samples * (U.T @ np.exp(-1j * theta))          # first harmonic, complex per input
    Ym = np.column_stack([Y[moving].real, Y[moving].imag])     # (moving, 2)
    Km = np.column_stack([U1.real, U1.imag]) @ np.linalg.pinv(Ym)
    K = np.zeros((len(U1), len(y0)))
    K[:, moving] = Km
    return K


def linear_at_amplitude(opened, signal, amplitude, steady=False):
    """The BenchLinear of the Opened bench with the loop's gains K_y replaced by its describing
    function at ``amplitude`` of the plant output ``signal`` ("Component.variable") in the mode
    that signal shows most; returns (BenchLinear, eigenvalue of that mode, iterations used)."""
    bl = lb.linear_of(opened, steady)
    outs = [s.name for s in bl.closed.outputs]
    if signal not in outs:
        bl.closed._index(signal, bl.closed.outputs, "output")
    i = outs.index(signal)
    A, B, C, D = lb._blocks(list(bl.plants.values()))
    read = _read_columns(opened)
    Ky, lam, it = np.zeros_like(bl.Ky), None, 0     # the first mode the plants' own, the loop open
    for it in range(1, ITERATIONS + 1):
        A_cl, _, C_cl, _ = lb.close_loop(A, B, C, D, Ky, bl.Kr)
        new, v = _mode(A_cl, C_cl[i], near=lam)
        Y = C_cl @ v
        Y = Y * (amplitude / abs(Y[i]))
        moving = [k for k in read if abs(Y[k]) > 1e-9 * np.max(np.abs(Y[read]))]
        Ky = harmonic_gains(opened, Y, moving)
        done = lam is not None and abs(new - lam) <= SETTLED * abs(new)
        lam = new
        if done:
            break
    A_cl, B_cl, C_cl, D_cl = lb.close_loop(A, B, C, D, Ky, bl.Kr)
    bl.closed.A, bl.closed.B = A_cl, B_cl
    bl.closed.C, bl.closed.D = C_cl, D_cl
    bl.closed.method = (f"closed loop A + B K C, the loop's K the first harmonic at {amplitude:g} "
                        f"{bl.closed.outputs[i].unit} of {signal} in its mode (describing function)")
    bl.Ky = Ky
    return bl, lam, it


def _read_columns(opened):
    """Indices of the plant outputs the loop reads (a connection from them to a kept element)."""
    keys = opened.plant_outputs()
    sources = {src for src, _, _ in opened.feeds.values()}
    return [k for k, key in enumerate(keys) if key in sources]
