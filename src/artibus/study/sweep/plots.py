"""A sweep's study plot and its worst cases, each with the command that runs it
alone (``study``: study.png, worst.txt)."""
import json
import math
import shlex
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError
from artibus.study.sweep.designs import _variant_list
from artibus.study.sweep.store import MANIFEST, PLOT, STATUS_FAILED, STATUS_OK, STATUS_TERMINATED, TABLE, WORST, _write_text

#: cases with KPIs: those that ran to the stop time and those an FMU ended (fmi2Terminated)
_RAN = (STATUS_OK, STATUS_TERMINATED)


def kpi_columns(table):
    return [n for n in table.column_names if n.endswith("]") and " [" in n]


def _pick_kpi(table, kpi):
    cols = kpi_columns(table)
    if not cols:
        return None
    if kpi is None:
        return cols[0]
    hits = [c for c in cols if c == kpi] or [c for c in cols if kpi.lower() in c.lower()]
    if not hits:
        raise ArtibusError(f"--kpi {kpi}: no such KPI (known: {'; '.join(cols)})")
    return hits[0]


def rerun_command(manifest, row):
    """The command that runs one case alone, with its report."""
    parts = ["artibus", "run", manifest.get("run", manifest["bench"])]
    for v in _variant_list(row.get("variant")):
        parts += ["--variant", v]
    def text(v):
        return str(v).lower() if isinstance(v, bool) else repr(v) if isinstance(v, float) else str(v)
    for name, val in (manifest.get("fixed") or {}).items():
        if name not in row:
            parts += ["--set", f"{name}={text(val)}"]
    for name in manifest["parameters"]:
        if name != "variant" and row.get(name) is not None:
            parts += ["--set", f"{name}={text(row[name])}"]
    if manifest.get("stop_time") is not None:
        parts += ["--stop-time", f"{manifest['stop_time']:g}"]
    if manifest.get("step") is not None:
        parts += ["--step", f"{manifest['step']:g}"]
    parts += ["--report", f"case-{row['key']}"]
    return " ".join(shlex.quote(p) for p in parts)


def _has_values(rows, col):
    return any(r["status"] == STATUS_OK and r.get(col) is not None and math.isfinite(r[col]) for r in rows)


def _short_cases(manifest):
    """Why a KPI may have no value in any case: the cases stop before the bench's own stop
    time (a KPI that needs the whole manoeuvre, the circle or the lane change, has none then)."""
    stop = manifest.get("stop_time")
    if stop is None:
        return ""
    try:
        from artibus.bench import ssp
        own = ssp.read(ssp.ssp_path(manifest.get("run", manifest["bench"]))).stop_time
    except Exception:       # the bench moved or cannot be read: say what is known
        own = None
    if own is not None and stop >= own:
        return ""
    return (f"every case stops at {stop:g} s" + (f", before the bench's own {own:g} s" if own else "")
            + ": a KPI that needs the whole manoeuvre has no value then (give --stop-time "
            + (f">= {own:g}" if own else "longer") + " or --kpi one that has values)")


def study(out, kpi=None, worst=10, largest=True, log=None):
    """study.png (a KPI over two swept parameters, a panel per value of a
    third; or its distribution for Latin hypercube / Monte Carlo) and
    worst.txt (the cases with the largest KPI, and every failed case, each
    with the command that re-runs it alone). A KPI without a value in any case
    is said so (with why, where the cases are shorter than the bench) and the
    plot shows the first KPI that has values instead, or no plot is drawn when
    none has any: never an empty frame. ``log(line)`` is told that note (the
    command line prints it). Returns the files written."""
    import pyarrow.parquet as pq
    out = Path(out)
    manifest = json.loads((out / MANIFEST).read_text())
    table = pq.read_table(out / TABLE)
    rows = table.to_pylist()
    col = _pick_kpi(table, kpi)
    written = []
    lines = [f"Sweep of {manifest['bench']}: {len(rows)} cases, "
             f"{sum(r['status'] == STATUS_FAILED for r in rows)} failed"
             + (f", {sum(r['status'] == STATUS_TERMINATED for r in rows)} ended early by an FMU"
                if any(r['status'] == STATUS_TERMINATED for r in rows) else "") + f" ({out / TABLE})", ""]
    n_ok = sum(r["status"] in _RAN for r in rows)
    if col is not None and n_ok and not _has_values(rows, col):
        why = _short_cases(manifest)
        other = next((c for c in kpi_columns(table) if _has_values(rows, c)), None)
        note = (f"KPI {col!r} has no value in any of the {n_ok} cases" + (f" ({why})" if why else "")
                + (f"; the study plot shows {other!r} instead" if other else "; no KPI has a value: no study plot"))
        lines[1:1] = [note, ""]
        if log is not None:
            log(note)
        col = other
        if col is None and (out / PLOT).exists():
            (out / PLOT).unlink()     # an earlier run's plot is not this run's
    if col is not None:
        ok = [r for r in rows if r["status"] in _RAN and r.get(col) is not None and math.isfinite(r[col])]
        ok.sort(key=lambda r: r[col], reverse=largest)
        lines.append(f"The {min(worst, len(ok))} cases with the {'largest' if largest else 'smallest'} {col}:")
        for r in ok[:worst]:
            lines.append(f"  {col} = {r[col]:.6g}   {rerun_command(manifest, r)}")
        lines.append("")
        if _plot(out / PLOT, manifest, rows, col):
            written.append(out / PLOT)
    bad = [r for r in rows if r["status"] == STATUS_FAILED]
    if bad:
        lines.append(f"Failed cases ({len(bad)}):")
        for r in bad:
            lines.append(f"  {r['error']}\n    {rerun_command(manifest, r)}")
    _write_text(out / WORST, "\n".join(lines) + "\n")
    written.append(out / WORST)
    return written


def parameter_units(manifest, names):
    """{COMP.VAR: unit} of swept parameters, from the model descriptions of the
    bench's FMUs (the variable's unit, else its declaredType's); a name without
    one (the variant axis, a unitless variable, a bench that cannot be read) is
    left out."""
    import io
    import zipfile
    from fmpy import read_model_description
    from artibus.bench import ssp
    from artibus.bench.units import unit_of
    out = {}
    try:
        path = ssp.ssp_path(manifest.get("run", manifest["bench"]))
        bench = ssp.read(path)
        with zipfile.ZipFile(path) as z:
            mds = {}
            for n in names:
                comp, _, var = n.partition(".")
                c = bench.components.get(comp)
                if c is None:
                    continue
                if c.source not in mds:
                    mds[c.source] = {v.name: v for v in read_model_description(io.BytesIO(z.read(c.source))).modelVariables}
                v = mds[c.source].get(var)
                if v is not None and unit_of(v):
                    out[n] = unit_of(v)
    except (ArtibusError, OSError, KeyError, zipfile.BadZipFile):
        pass                  # (the plot is drawn without the units it cannot find)
    return out


def _label(name, units):
    return f"{name} [{units[name]}]" if name in units else name


def _plot(path, manifest, rows, col):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ok = [r for r in rows if r["status"] in _RAN and r.get(col) is not None]
    if not ok:
        return False
    axes = [(n, vs) for n, vs in manifest["axes"] if len(vs) > 1]
    units = parameter_units(manifest, [n for n, _ in axes])     # each axis with its unit (the KPI's is in its name)
    if manifest["method"] == "grid" and len(axes) >= 2:
        (xn, _), (yn, _) = axes[0], axes[1]
        third = axes[2][0] if len(axes) > 2 else None
        panels = sorted({str(r.get(third)) for r in ok}, key=_num_key) if third else [None]
        fig, axs = plt.subplots(1, len(panels), figsize=(4.6 * len(panels) + 1, 4.2), squeeze=False)
        xs = sorted({r[xn] for r in ok}, key=_num_key)
        ys = sorted({r[yn] for r in ok}, key=_num_key)
        vals = [r[col] for r in ok if math.isfinite(r[col])]
        vmin, vmax = (min(vals), max(vals)) if vals else (0, 1)
        im = None
        for ax, pv in zip(axs[0], panels):
            z = np.full((len(ys), len(xs)), np.nan)
            for r in ok:
                if third is None or str(r.get(third)) == pv:
                    z[ys.index(r[yn]), xs.index(r[xn])] = r[col]
            im = ax.imshow(z, origin="lower", aspect="auto", cmap="viridis", vmin=vmin, vmax=vmax,
                           extent=None)
            ax.set_xticks(range(len(xs)), [f"{x:g}" if isinstance(x, float) else str(x) for x in xs],
                          rotation=90 if len(xs) > 8 else 0, fontsize=7)
            ax.set_yticks(range(len(ys)), [f"{y:g}" if isinstance(y, float) else str(y) for y in ys], fontsize=7)
            ax.set_xlabel(_label(xn, units))
            ax.set_ylabel(_label(yn, units))
            ax.set_title(f"{third} = {pv} {units.get(third, '')}".rstrip() if third else manifest["bench"], fontsize=9)
        fig.colorbar(im, ax=axs[0].tolist(), label=col)
        fig.suptitle(f"{manifest['bench']}: {col}", fontsize=10)
    elif manifest["method"] == "grid" and len(axes) == 1:
        n = axes[0][0]
        pts = sorted(((r[n], r[col]) for r in ok), key=lambda p: _num_key(p[0]))
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.plot([str(p[0]) if not isinstance(p[0], (int, float)) else p[0] for p in pts], [p[1] for p in pts], "o-")
        ax.set_xlabel(_label(n, units))
        ax.set_ylabel(col)
        ax.grid(True, alpha=0.3)
        ax.set_title(manifest["bench"])
    else:
        v = np.array([r[col] for r in ok], dtype=float)
        v = v[np.isfinite(v)]
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.hist(v, bins=max(5, min(50, int(math.sqrt(len(v))) + 1)), color="#4477aa", edgecolor="white")
        if len(v):
            for q, ls in ((0.5, "-"), (0.95, "--")):
                x = float(np.quantile(v, q))
                ax.axvline(x, color="k", ls=ls, lw=1, label=f"{int(q * 100)} % quantile {x:.4g}")
            ax.legend(fontsize=8)
        ax.set_xlabel(col)
        ax.set_ylabel("cases")
        ax.set_title(f"{manifest['bench']}: {manifest['method']}, {len(v)} cases"
                     + (f", seed {manifest['seed']}" if manifest.get("seed") is not None else ""), fontsize=9)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return True


def _num_key(x):
    try:
        return (0, float(x), "")
    except (TypeError, ValueError):
        return (1, 0.0, str(x))
