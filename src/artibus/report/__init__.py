"""The bench reports: the drawings every bench uses (``plots``: the bird's-eye
view with the swept-path envelope, signals over time; ``animation``: the
bird's-eye view animated), a bench run's page and the index of a run of every
bench (``pages``: ``Kpi``, ``write_report``, ``write_html``, ``write_index``),
what several benches' bench.py share (``benchkit``), seed 000's comparison page
(``comparison``) and ``artibus run``'s runs of benches with their reports
(``runs``). A bench's bench.py draws with ``from artibus import report``:
``report.Kpi``, ``report.birds_eye``, ``report.signals``, ...

Every file is written under a temporary name and renamed (artibus.files), so
a report stopped midway never leaves a torn PNG or page under its final name.
"""
import importlib

# imported when first used (PEP 562), so that ``artibus run`` without
# --report, which imports artibus.report.runs, never imports matplotlib
_WHERE = {
    **dict.fromkeys(("animate", "animation_writer", "bench_animation", "result_axle_traces", "result_links",
                     "result_outlines"), "animation"),
    **dict.fromkeys(("CALIBRATED", "FAIL", "NOT_GRADED", "PASS", "STYLE", "Kpi", "Table", "generic", "headline",
                     "run_metadata", "tally", "thumbnail", "write_html", "write_index", "write_kpi_csv",
                     "write_report"), "pages"),
    **dict.fromkeys(("birds_eye", "colours", "draw_bound", "legend_beside", "save_figure", "signals", "swept",
                     "swept_area", "wrapped_title"), "plots"),
}
__all__ = sorted(_WHERE)


def __getattr__(name):
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'artibus.report' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"artibus.report.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_WHERE))
