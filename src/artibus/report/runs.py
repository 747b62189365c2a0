"""``artibus run``: benches run one after another, each one's results saved,
with ``--report`` its page (its KPIs against the papers, figures, the CAN
bus's figures), with ``--can-fault`` the fault-free run's KPIs beside the
faulty ones, and with every bench (``--all --report``) the index and seed
000's comparison page (``run_benches``)."""
import sys
from pathlib import Path

from artibus import runner
from artibus.bench import ssp
from artibus.files import check_output, make_dir, write_text


def run_benches(benches, every=False, variants=None, user=None, stop_time=None, step=None, record=None,
                algorithm="gauss-seidel", can=None, can_log=None, can_faults=None, report=None, output=None,
                progress=False, checked=None, log=print, single_rate=False, fmi=None):
    """Run each bench (names or .ssp paths) with its variants (``variants``: names, as
    ``--variant``), then the user's values (``user``: {"comp.var": value}, from
    --ssv and --set); ``every``: the benches are all of ssp/benches/ (``--all``:
    each writes <bench>.csv, or REPORT/<bench>/ with ``report``). The results
    go to ``output`` (default <bench>.csv, with ``report`` REPORT/results.csv),
    checked before the run (``checked(path)`` is told each, for the partial
    results after a failure); an interrupt leaves OUT.partial.csv
    (runner.save_partial). ``log``: print, for what the command line prints (an
    FMU's warnings go to sys.stderr). ``single_rate``: every component at one
    step (--single-rate). With ``report`` each multi-rate bench is run once
    more single-rate for its page (artibus.report.single_rate). ``fmi``: the
    build of the benches' FMUs, None (as each bench's .ssd names them), "2" or
    "3" (--fmi; artibus.bench.fmi); the extra runs use the same. Returns
    [(bench, report directory, KPIs)] of the benches with a report. The drawing
    (artibus.report.pages, comparison: matplotlib) is imported only with ``report``."""
    if report:
        from artibus.report import comparison
        from artibus.report import single_rate as single_rate_report
        from artibus.report.pages import FAIL, PASS, tally, write_index, write_report
    if stop_time is None and not every:
        stop_time = ssp.variant_stop_time(benches[0], variants)    # None: the bench's own
    summary = []
    kept = {}
    for bench in benches:
        overrides = {**ssp.variant_overrides(bench, variants), **(user or {})}
        with runner.Simulation(bench, step=step, overrides=overrides, record=record, algorithm=algorithm,
                               can=can, can_log=can_log, can_faults=can_faults, single_rate=single_rate,
                               fmi=fmi) as sim:
            name = sim.bench.name
            # where the results go, checked before the run (not found unwritable after it)
            if report:
                out_dir = make_dir(Path(report) / name if every else Path(report))
                out = Path(output) if output and not every else out_dir / "results.csv"
            else:
                out_dir = None
                out = Path(output or f"{name}.csv")
            check_output(out, "-o")
            if checked is not None:
                checked(out)
            try:
                result = sim.run(stop_time=stop_time, progress=progress)
            except KeyboardInterrupt as e:      # Ctrl-C, SIGTERM: the results so far as OUT.partial.csv
                runner.save_partial(e, out)
                raise
            result.fmi = fmi     # the build its report's studies (a bench.py's study) run theirs with
            try:
                print_warnings((u.path, u.fmu.log) for u in sim.units)
                if result.terminated is not None:   # an FMU's own end (fmi2Terminated): a normal end, said once
                    log(f"{name}: {result.terminated}")
                can_summary = None
                if sim.can is not None:
                    can_summary = sim.can.summary(result.time[-1] - result.time[0])
                    log(can_summary)
                runner.save(result, out)
            except KeyboardInterrupt as e:      # the run had finished: its results are never discarded
                if getattr(e, "written", None) is None:
                    e.result = result
                    runner.save_partial(e, out)
                raise
            span = result.time[-1] - result.time[0]
            log(f"{name}: {out}: {len(result.rows)} rows, {len(result.names) - 1} signals; "
                f"{span:g} s simulated in {sim.wall:.2f} s (real-time factor {span / sim.wall:.0f})"
                + (f"; the FMUs' FMI {fmi}.0 builds" if fmi else ""))
            if out_dir is not None:
                # the page says how far a master without multi-rate steps is: one more run, single-rate
                sr = single_rate_report.measure(sim, result, lambda: single_rate_report.run_single_rate(
                    bench, overrides, stop_time, step=step, record=record, algorithm=algorithm, can=can, fmi=fmi))
                if sr.multi_rate:
                    log(f"{name}: single-rate at {sr.step:g} s: KPIs within {sr.deviation:.3g} % "
                        f"({sr.worst}); the extra run took {sr.wall:.2f} s")
                kpis = write_report(name, result, out_dir, sim.wall, sections=sr.html())
                if can_summary is not None:
                    write_text(out_dir / "can_bus.txt", can_summary + "\n")
                log(f"{name}: report {out_dir / 'index.html'}")
                for k in kpis:
                    log(f"    {k.line()}")
                n_pass, n_fail = tally(kpis)
                if n_pass + n_fail:
                    log(f"{name}: against the papers' bounds for this configuration: {n_pass} {PASS}, "
                        f"{n_fail} {FAIL}" + (f" (why: {out_dir / 'index.html'})" if n_fail else ""))
                summary.append((name, out_dir, kpis))
                if every and comparison.wanted(name):    # seed 000's comparison page reuses it
                    kept[name] = result
                if can_faults:
                    fault_free_kpis(bench, overrides, out_dir, kpis, can_faults, step=step, record=record,
                                    algorithm=algorithm, can=can, stop_time=stop_time, log=log, fmi=fmi)
    if every and report:
        page = comparison.write(Path(report) / "comparison", kept)
        pages = [("comparison/index.html", comparison.TITLE, "unsteered, guided, guided + force minimisation "
                  "and pathMemory side by side")] if page else []
        from artibus.report import demo
        if (Path(report) / "demo" / "index.html").is_file():     # `artibus demo --report REPORT/demo`
            pages.append(("demo/index.html", demo.TITLE, "BusKinematics alone, its results and plots"))
        index = write_index(Path(report), summary, pages)
        n_pass = sum(tally(k)[0] for _, _, k in summary)
        n_fail = sum(tally(k)[1] for _, _, k in summary)
        log(f"all benches: against the papers' bounds, each for its configuration: {n_pass} {PASS}, {n_fail} {FAIL}")
        log(index)
    return summary


def print_warnings(logs):
    """An FMU's warnings (e.g. a parameter that does not act in its
    configuration) printed once each to sys.stderr, naming the component.
    logs: [(component, its FMU's log)]."""
    for name, log in logs:
        seen = set()
        for m in log:
            if m.startswith("[Warning]") and m not in seen:
                seen.add(m)
                text = m[len("[Warning]"):].strip()
                text = text.split(": ", 1)[1] if text.startswith("log") and ": " in text else text
                print(f"warning: {name}: {text}", file=sys.stderr)


def fault_free_kpis(bench, overrides, out_dir, kpis, can_faults, step=None, record=None, algorithm="gauss-seidel",
                    can=None, stop_time=None, log=print, fmi=None):
    """The same bench without the faults: its KPIs next to the faulty run's,
    printed and written to OUT/kpi_faults.csv (its own report in OUT/fault-free)."""
    from artibus.report.pages import write_report
    with runner.Simulation(bench, step=step, overrides=overrides, record=record,
                           algorithm=algorithm, can=can, fmi=fmi) as sim:
        result = sim.run(stop_time=stop_time)
        free = write_report(sim.bench.name, result, out_dir / "fault-free", sim.wall)
    faults = "; ".join(can_faults)
    log(f"{sim.bench.name}: KPIs with faults ({faults}) against the fault-free run:")
    rows = ["kpi,unit,fault_free,with_faults,difference"]
    for a, b in zip(free, kpis):
        diff = (b.value - a.value) if isinstance(a.value, (int, float)) and isinstance(b.value, (int, float)) else float("nan")
        log(f"    {b.name}: {a.cell()} -> {b.cell()} {b.unit} (difference {diff:+.4g})")
        rows.append(f'"{b.name}",{b.unit},{a.value!r},{b.value!r},{diff!r}')
    out = out_dir / "kpi_faults.csv"
    write_text(out, "\n".join(rows) + "\n")
    log(f"{sim.bench.name}: {out}")
