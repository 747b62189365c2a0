"""A bench's KPIs, figures and text live with the bench, in its folder:
``ssp/benches/<Bench>/bench.py``, loaded here by path. It declares

- ``kpis(result) -> list[Kpi]``: the KPIs of one run, a function of the result
  alone (no drawing): each with its unit, the paper's value and the pass rule
  (``Kpi.passed``); a sweep computes them for every case;
- ``figures(result, out) -> [(png name, caption)]``: the report's drawings,
  written into the folder ``out``;
- ``TEXT``: the report's notes;
- optionally ``study(result, out) -> (kpis, images, text[, shown])``: a report
  that runs further cases of the bench (the damping functions side by side,
  frequency responses); the report then shows the study's KPIs and figures,
  and a sweep still takes ``kpis(result)``. ``shown``: a run of the study's own
  that the page shows instead of ``result`` (its span, animation and
  results.csv: a replay). A study that runs other variants than the one run
  grades only those the user asked for (``result.variants``, the --variant
  names, None without).

A bench without a bench.py gets the generic report (the first recorded signals
over time, artibus.report.pages.generic) and no KPIs; the report of a run is
artibus.report.pages.write_report. The bench's variants are its ``variants/*.ssv``
(artibus.bench.ssp)."""
import importlib.util
import sys
from pathlib import Path

from artibus.base import ArtibusError

FILE = "bench.py"


def bench_file(bench):
    """ssp/benches/<bench>/bench.py (bench: a name, or an .ssp path named after its folder)."""
    from artibus.bench import ssp
    return ssp.BENCH_DIR / Path(str(bench)).stem / FILE


def load(bench):
    """The module of the bench's bench.py, or None when it has none (loaded once a process)."""
    path = bench_file(bench)
    key = f"artibus_bench_{Path(str(bench)).stem}"
    mod = sys.modules.get(key)
    if mod is not None and getattr(mod, "__file__", None) == str(path):
        return mod
    if not path.is_file():
        return None
    spec = importlib.util.spec_from_file_location(key, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[key] = mod
    try:
        spec.loader.exec_module(mod)
    except Exception:
        del sys.modules[key]
        raise
    for name in ("kpis", "figures"):
        if not callable(getattr(mod, name, None)):
            raise ArtibusError(f"{path}: defines no function {name}(result{', out' if name == 'figures' else ''})")
    return mod


def kpis(bench, result):
    """The bench's KPIs of one run (the result alone); [] for a bench without a bench.py."""
    mod = load(bench)
    return [] if mod is None else list(mod.kpis(result))
