"""Frequency responses measured through the co-simulation: for each
frequency, a sine on one input of a bench (added to what drives it), run
until the transient has died away, then gain and phase of each output from a
least-squares fit of  y = c + a sin(wt) + b cos(wt)  over whole periods."""
import math
from dataclasses import dataclass

import numpy as np

from artibus import ArtibusError, runner


@dataclass
class Point:
    frequency: float     # Hz
    gain: float          # output amplitude / input amplitude
    phase: float         # rad, output relative to input


def _fit(t, y, w):
    A = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    (c, a, b), *_ = np.linalg.lstsq(A, y, rcond=None)
    return a, b


def frequency_response(bench, input, outputs, frequencies, amplitude, periods=4, settle=None,
                       overrides=None, step=None):
    """{output: [Point]} for each frequency (Hz). ``settle`` (s) is how long
    the transient is given before the fit (default: 3 periods, at least 5 s)."""
    if not amplitude > 0:
        raise ArtibusError(f"--amplitude {amplitude}: must be > 0")
    result = {o: [] for o in outputs}
    for f in frequencies:
        if not f > 0:
            raise ArtibusError(f"frequency {f} Hz: must be > 0")
        w = 2 * math.pi * f
        t_settle = settle if settle is not None else max(5.0, 3.0 / f)
        stop = t_settle + periods / f
        r = runner.run(bench, stop_time=stop, step=step, overrides=overrides, record=list(outputs),
                       stimuli={input: lambda t, w=w: amplitude * math.sin(w * t)})
        t = r.time
        h = t[1] - t[0]
        sel = t >= stop - periods / f - 1e-9
        # the input is held over each step: as applied, the sine is delayed by h/2
        for o in outputs:
            a, b = _fit(t[sel], r[o][sel], w)
            result[o].append(Point(f, math.hypot(a, b) / amplitude, math.atan2(b, a) + w * h / 2))
    return result


def plot(path, responses, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, pts in responses.items():
        f = [p.frequency for p in pts]
        ax1.semilogx(f, [20 * math.log10(max(p.gain, 1e-300)) for p in pts], "o-", label=name)
        ax2.semilogx(f, np.degrees(np.unwrap([p.phase for p in pts])), "o-", label=name)
    ax1.set_ylabel("gain [dB]")
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax1.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
