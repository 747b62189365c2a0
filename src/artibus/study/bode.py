"""Frequency responses measured through the co-simulation: for each
frequency, a sine on one input of a bench (added to what drives it), run
until the transient has died away, then gain and phase of each output from a
least-squares fit of  y = c + a sin(wt) + b cos(wt)  over whole periods."""
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError
from artibus import runner


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
                       overrides=None, step=None, fmi=None):
    """{output: [Point]} for each frequency (Hz). ``settle`` (s) is how long
    the transient is given before the fit (default: 3 periods, at least 5 s).
    ``fmi``: the build of the bench's FMUs (--fmi, artibus.bench.fmi.fmi_choice)."""
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
                       stimuli={input: lambda t, w=w: amplitude * math.sin(w * t)}, fmi=fmi)
        t = r.time
        h = t[1] - t[0]
        sel = t >= stop - periods / f - 1e-9
        # the input is held over each step: as applied, the sine is delayed by h/2
        for o in outputs:
            a, b = _fit(t[sel], r[o][sel], w)
            result[o].append(Point(f, math.hypot(a, b) / amplitude, math.atan2(b, a) + w * h / 2))
    return result


def unwrapped_phase_deg(points):
    """The phase of measured points in degrees, unwrapped over frequency (the
    lowest frequency's phase in (-180, 180])."""
    ph = np.unwrap([p.phase for p in points])
    if len(ph):
        ph = ph - 2 * math.pi * round(ph[0] / (2 * math.pi))
    return np.degrees(ph)


def plot(path, responses, title, units=None, reference=None, input_unit="", marks=None):
    """Bode plot: a column per output (gain on a log axis in the output's unit
    per the input's, a dB axis beside it; unwrapped phase below).
    responses: {output: [Point]} or {output: {series label: [Point]}} (several
    runs of one output, e.g. two steering laws); units: {output: unit};
    reference: {output: (label, frequencies Hz, complex G)} drawn as a line
    (e.g. a closed form the measured points are checked against); marks:
    [(frequency Hz, label)] a paper's figure, a dashed vertical line on every axis."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from artibus.report import save_figure
    groups = {o: (v if isinstance(v, dict) else {"measured": v}) for o, v in responses.items()}
    units = units or {}
    reference = reference or {}
    n = len(groups)
    fig, axes = plt.subplots(2, n, figsize=(max(8.0, 5.2 * n), 6.5), sharex="col", squeeze=False)
    for j, (out, series) in enumerate(groups.items()):
        ax1, ax2 = axes[0, j], axes[1, j]
        if out in reference:
            label, fr, G = reference[out]
            fr, G = np.asarray(fr, float), np.asarray(G, complex)
            ax1.loglog(fr, np.abs(G), "g-", label=label)
            ph = np.unwrap(np.angle(G))
            ph = ph - 2 * math.pi * round(ph[0] / (2 * math.pi))
            ax2.semilogx(fr, np.degrees(ph), "g-", label=label)
        for label, pts in series.items():
            f = [p.frequency for p in pts]
            ax1.loglog(f, [max(p.gain, 1e-300) for p in pts], "o-", ms=3, label=label)
            ax2.semilogx(f, unwrapped_phase_deg(pts), "o-", ms=3, label=label)
        u = units.get(out, "")
        per = f" [{u} / {input_unit}]" if (u or input_unit) else ""
        ax1.set_ylabel(f"gain |{out.split('.')[-1]}|{per}")
        lo, hi = ax1.get_ylim()             # the same axis in dB on the right (log gain is linear in dB)
        db = ax1.twinx()
        db.set_ylim(20 * math.log10(lo), 20 * math.log10(hi))
        db.set_ylabel("gain [dB]")
        ax2.set_ylabel("phase [deg]")
        ax2.set_xlabel("frequency [Hz]")
        ax1.set_title(out, fontsize=9)
        for ax in (ax1, ax2):
            ax.grid(True, which="both", alpha=0.3)
            for f_mark, label in marks or []:
                ax.axvline(f_mark, color="k", lw=0.9, ls="--", label=label)
        ax1.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def output_units(bench, names):
    """{"comp.var": unit} of outputs of a bench, from its FMUs' model descriptions."""
    import zipfile
    from fmpy import read_model_description
    from artibus.bench import ssp
    b = ssp.read(ssp.ssp_path(bench))
    units = {}
    with zipfile.ZipFile(ssp.ssp_path(bench)) as z:
        import tempfile
        with tempfile.TemporaryDirectory(prefix="artibus-units-") as tmp:
            for name in names:
                comp, _, var = name.rpartition(".")
                c = b.components.get(comp)
                if c is None:
                    continue
                z.extract(c.source, tmp)
                md = read_model_description(str(Path(tmp) / c.source))
                v = {x.name: x for x in md.modelVariables}.get(var)
                if v is not None:
                    u = v.unit or (getattr(v.declaredType, "unit", None) if v.declaredType is not None else None)
                    units[name] = u or "-"
    return units


def csv_rows(frequencies, responses, outputs, input, units):
    """The lines of ``artibus bode``'s CSV: a header (each output's gain in its
    unit per the input's, its phase in deg as the plot shows it), then a row per frequency."""
    per = lambda o: f"{units.get(o, '-')} per {units.get(input, '-')}"    # noqa: E731 (gain's unit)
    rows = ["frequency [Hz]," + ",".join(f"{o} gain [{per(o)}],{o} phase [deg]" for o in outputs)]
    for k, f in enumerate(frequencies):
        rows.append(f"{f:.6g}," + ",".join(f"{responses[o][k].gain:.8g},{math.degrees(responses[o][k].phase):.8g}"
                                           for o in outputs))
    return rows


def measure(bench, input, outputs, fmin, fmax, n, amplitude, periods=4, settle=None, overrides=None,
            step=None, out=None, plot_path=None, log=print, fmi=None):
    """`artibus bode`: the frequency response of ``outputs`` to ``input`` at ``n``
    frequencies from ``fmin`` to ``fmax`` (log-spaced), the table written to
    ``out`` (CSV, only when given) and printed, the plot to ``plot_path``.
    Returns the table's rows."""
    from artibus.files import write_text
    freqs = np.geomspace(fmin, fmax, n) if n > 1 else [fmin]
    resp = frequency_response(bench, input, outputs, freqs, amplitude, periods=periods, settle=settle,
                              overrides=overrides, step=step, fmi=fmi)
    units = output_units(bench, list(outputs) + [input])
    rows = csv_rows(freqs, resp, outputs, input, units)
    if out is not None:
        write_text(out, "\n".join(rows) + "\n")
        log(f"{out}: {len(freqs)} frequencies")
    for line in rows:
        log("  " + line)
    if plot_path:
        plot(plot_path, resp, f"{bench}: {', '.join(outputs)} / {input}", units=units,
             input_unit=units.get(input, ""))
        log(plot_path)
    return rows
