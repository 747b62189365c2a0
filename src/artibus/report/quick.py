"""Plots from files the user already has: a results CSV (``artibus plot``:
``results_plot``, a panel per unit, the units from the sidecar OUT.units.csv)
and a CAN log (``artibus can plot``: ``can_plot``, the frames' timing per message
and the decoded signals chosen)."""
import csv
import difflib
import re
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError


def _select(names, patterns, what):
    """The names matching each pattern: the exact name, else a '*' wildcard
    ('Bus.artAngle[*]'); an unknown one is an error naming it and the closest names."""
    chosen = []
    for pat in patterns:
        if pat in names:
            hits = [pat]
        else:
            rx = re.compile("^" + re.escape(pat).replace(r"\*", ".*") + "$")
            hits = [n for n in names if rx.match(n)]
        if not hits:
            close = difflib.get_close_matches(pat, names, n=3, cutoff=0.5)
            raise ArtibusError(f"{what}: no signal {pat!r}" + (f"; did you mean {' or '.join(close)}?" if close
                                                                 else f" ({len(names)} signals in it)"))
        chosen += [h for h in hits if h not in chosen]
    return chosen


def read_results_csv(path):
    """(names, columns {name: array}, units {name: unit}) of a results CSV (one header line)
    and its units' sidecar OUT.units.csv (empty units where it is missing)."""
    from artibus.runner import read_units, units_path
    path = Path(path)
    if not path.is_file():
        raise ArtibusError(f"{path}: no such file")
    if path.suffix.lower() != ".csv":
        raise ArtibusError(f"{path}: artibus plot reads a results .csv (artibus run -o FILE.csv)")
    with open(path, newline="") as f:
        header = next(csv.reader(f), None)
    if not header or len(header) < 2:
        raise ArtibusError(f"{path}: no header line of signal names")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as e:
        raise ArtibusError(f"{path}: not a results CSV of numbers ({e})") from None
    if data.shape[1] != len(header):
        raise ArtibusError(f"{path}: {data.shape[1]} columns of numbers under {len(header)} names")
    units = read_units(path) if units_path(path).is_file() else {}
    return header, {n: data[:, i] for i, n in enumerate(header)}, units


def _panels(series, units):
    """[(y label, {name: values})]: the signals grouped by unit, a panel per unit."""
    by_unit = {}
    for name, y in series.items():
        by_unit.setdefault(units.get(name, ""), {})[name] = y
    return [(f"[{u}]" if u else "(no unit)", s) for u, s in by_unit.items()]


def results_plot(results, signals, out=None):
    """A PNG of the chosen signals of a results CSV over its first column (time),
    a panel per unit. Returns (the PNG's path, [the signals plotted])."""
    from artibus.report.plots import signals as plot_signals
    results = Path(results)
    names, cols, units = read_results_csv(results)
    chosen = _select(names[1:], signals, str(results))
    out = Path(out) if out else results.with_suffix(".png")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise ArtibusError(f"-o {out}: the plot is a .png (or .pdf, .svg)")
    t = cols[names[0]]
    png = plot_signals(out, t, _panels({n: cols[n] for n in chosen}, units), title=results.name)
    return png, chosen


def can_plot(log, signals=(), dbc=None, out=None):
    """A PNG of a CAN log (.blf, .asc): the time between a message's frames (its timing:
    the cycle and its jitter, a gap where frames were lost) and the chosen decoded signals
    (MESSAGE.SIGNAL or SIGNAL, '*' wildcards), a panel per unit. Frames failing their E2E
    check are marked. Returns (the PNG's path, [the signals plotted], [every signal known])."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from artibus.base import ROOT
    from artibus.can import decode_log
    from artibus.report.plots import colours, save_figure
    log = Path(log)
    rows = decode_log(log, dbc or ROOT / "ssp" / "can" / "Bus36m.dbc")
    if not rows:
        raise ArtibusError(f"{log}: no frame of a message the DBC knows")
    series, frames = {}, {}
    for t, msg, sig, v, unit, e2e in rows:
        series.setdefault(f"{msg}.{sig}", ([], [], [], unit))
        s = series[f"{msg}.{sig}"]
        s[0].append(t), s[1].append(float(v)), s[2].append(e2e == "ok")
        fr = frames.setdefault(msg, [])
        if not fr or fr[-1] != t:
            fr.append(t)
    known = sorted(series)
    short = {k.split(".", 1)[1]: k for k in known}
    wanted = []
    for pat in signals:
        full = short.get(pat, pat)
        wanted += [w for w in _select(known, [full], str(log)) if w not in wanted]
    units = {k: series[k][3] for k in wanted}
    panels = _panels({k: None for k in wanted}, units)
    fig, axes = plt.subplots(1 + len(panels), 1, figsize=(9, 2.6 * (1 + len(panels))), sharex=True,
                             squeeze=False)
    ax = axes[0, 0]
    for (msg, ts), c in zip(sorted(frames.items()), colours() * 4):
        ts = np.asarray(ts)
        if len(ts) > 1:
            ax.plot(ts[1:], np.diff(ts) * 1e3, ".", ms=2, color=c, label=msg)
    ax.set_ylabel("time since the\nlast frame [ms]")
    ax.set_title(f"{log.name}: {sum(len(f) for f in frames.values())} frames of {len(frames)} messages")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=3, loc="upper right")
    for ax, (ylabel, group) in zip(axes[1:, 0], panels):
        for name, c in zip(group, colours() * 3):
            t, v, ok, _ = series[name]
            t, v, ok = np.asarray(t), np.asarray(v), np.asarray(ok)
            ax.plot(t, v, color=c, lw=1.2, label=name)
            if not ok.all():
                ax.plot(t[~ok], v[~ok], "x", color="r", ms=5, label=f"{name}: E2E check failed")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    out = Path(out) if out else log.with_suffix(".png")
    return save_figure(fig, out, dpi=110), wanted, known
