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
from artibus.report.animation import (animate, animation_writer, bench_animation, result_axle_traces,  # noqa: F401
                                      result_links, result_outlines)
from artibus.report.pages import (CALIBRATED, FAIL, NOT_GRADED, PASS, STYLE, Kpi, Table, generic,  # noqa: F401
                                  headline, run_metadata, tally, thumbnail, write_html, write_index,
                                  write_kpi_csv, write_report)
from artibus.report.plots import birds_eye, colours, draw_bound, save_figure, signals, swept, swept_area  # noqa: F401
