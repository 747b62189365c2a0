"""``artibus run``: benches run one after another, each one's results saved,
with ``--report`` its page (its KPIs against the papers, figures, the CAN
bus's figures), with ``--can-fault`` the fault-free run's KPIs beside the
faulty ones, and with every bench (``--all --report``) the index and seed
000's comparison page (``run_benches``)."""
import sys
from pathlib import Path

from artibus import runner
from artibus.base import ArtibusError
from artibus.bench import ssp
from artibus.files import atomic_dir, bench_inputs, check_not_input, signals_held, write_text
from artibus.runner.results import check_results_file


def run_benches(benches, every=False, variants=None, user=None, stop_time=None, step=None, record=None,
                algorithm="gauss-seidel", can=None, can_log=None, can_faults=None, report=None, output=None,
                progress=False, checked=None, log=print, single_rate=False, fmi=None, inputs=(),
                fmi_type=None, relative_tolerance=None, me_method=None, me_jacobian=False, input_file=None,
                reference=False):
    """Run each bench (names or .ssp paths) with its variants (``variants``: names, as
    ``--variant``), then the user's values (``user``: {"comp.var": value}, from
    --ssv and --set); ``every``: the benches are all of ssp/benches/ (``--all``:
    each writes <bench>.csv, or REPORT/<bench>/ with ``report``). The results
    go to ``output`` (default <bench>.csv, with ``report`` REPORT/results.csv),
    checked before the run (``checked(path)`` is told each, for the partial
    results after a failure); an interrupt leaves OUT.partial.csv
    (runner.save_partial). No output may be an input of the run (the bench,
    the runner's packs and FMUs, ssp/, ``inputs``: [(path, what it is)], e.g.
    the --ssv files): refused before the run (artibus.files.check_not_input).
    A report folder is written whole or not at all (artibus.files.atomic_dir:
    an interrupt leaves the earlier report as it was; _report_run). ``log``:
    print, for what the command line prints (an FMU's warnings go to sys.stderr). ``single_rate``: every component at one
    step (--single-rate). With ``report`` each multi-rate bench is run once
    more single-rate for its page (artibus.report.single_rate). ``fmi``: the
    build of the benches' FMUs, None (as each bench's .ssd names them), "2" or
    "3" (--fmi; artibus.bench.fmi); the extra runs use the same. ``fmi_type`` "me" (--fmi-type):
    every FMU that has Model Exchange runs as ME at ``relative_tolerance`` with CVODE's ``me_method``
    (with ``me_jacobian`` its Jacobian from the FMUs' directional derivatives; runner.Simulation). ``input_file``: a CSV driving the benches' free inputs (--input-file,
    columns COMPONENT.VARIABLE; runner.Simulation). ``reference``: each bench's monolithic reference
    (--reference, artibus.runner.reference). Returns
    [(bench, report directory, KPIs)] of the benches with a report. The drawing
    (artibus.report.pages, comparison: matplotlib) is imported only with ``report``."""
    if report:
        from artibus.report.pages import FAIL, PASS, tally
    if stop_time is None and not every:
        stop_time = ssp.variant_stop_time(benches[0], variants)    # None: the bench's own
    summary = []
    kept = {}
    settings = dict(step=step, record=record, algorithm=algorithm, can=can, fmi=fmi)
    if fmi_type is not None or relative_tolerance is not None or me_method or me_jacobian:   # (Model Exchange)
        settings.update(fmi_type=fmi_type, relative_tolerance=relative_tolerance, me_method=me_method or "bdf",
                        me_jacobian=bool(me_jacobian))
    if input_file is not None:
        settings.update(input_file=input_file)
    if reference:
        settings.update(reference=True)
    for bench in benches:
        overrides = {**ssp.variant_overrides(bench, variants), **(user or {})}
        guard = list(inputs) + bench_inputs(bench)
        _refuse_inputs(guard, None if every else output, can_log, report, every)
        folder = (Path(report) / Path(str(bench)).stem if every else Path(report)) if report else None
        with _ReportNote(folder) as note, runner.Simulation(bench, overrides=overrides, can_log=can_log,
                                                            can_faults=can_faults, single_rate=single_rate,
                                                            **settings) as sim:
            name = sim.bench.name
            run = _Run(sim, stop_time, progress, log, fmi, checked)
            run.variants = list(variants) if variants else None
            if not report:
                out = Path(output or f"{name}.csv")
                check_results_file(out, "-o", guard, results=True)
                run.results(out, out)
                continue
            final = Path(report) / name if every else Path(report)
            out = Path(output) if output and not every else final / "results.csv"
            _check_report(final, out, guard)
            kpis = _report_run(run, final, out,
                               lambda d: _page(run, bench, overrides, d, final, stop_time, can_faults, settings))
            note.state = "complete"
            log(f"{name}: report {final / 'index.html'}")
            summary.append((name, final, kpis))
            if every and _comparison().wanted(name):    # seed 000's comparison page reuses it
                kept[name] = run.result
    if every and report:
        _write_all(Path(report), summary, kept, guard, log, PASS, FAIL, tally)
    return summary


class _ReportNote:
    """An interrupt outside the report's writing (atomic_dir says what became of
    the report there) told what the report folder holds, for the command line's
    message (artibus.files.report_said): as it was (``state`` "kept" or "none")
    before, "complete" after its swap."""

    def __init__(self, folder):
        self.folder = folder
        self.state = "kept" if folder is not None and folder.is_dir() else "none"

    def __enter__(self):
        return self

    def __exit__(self, kind, e, tb):
        if self.folder is not None and isinstance(e, KeyboardInterrupt) and getattr(e, "report", None) is None:
            e.report = (self.folder, self.state)
        return False


def _comparison():
    from artibus.report import comparison
    return comparison


def _refuse_inputs(guard, output, can_log, report, every):
    """The outputs the user named checked against the run's inputs (``guard``)
    before the bench is set up (a CAN log's writer opens at the set-up)."""
    if can_log:
        from artibus.can.logs import LOG_SUFFIXES
        if Path(can_log).suffix.lower() not in LOG_SUFFIXES:     # (an FMI-LS-BUS bench writes it after the run)
            raise ArtibusError(f"--can-log {can_log}: the log is written as {', '.join(LOG_SUFFIXES)} "
                               f"(by its suffix; .mf4: ASAM MDF 4 CAN bus logging)")
        check_not_input(can_log, "--can-log", guard)
    if report and every:
        for f in ("index.html", "summary.csv"):
            check_not_input(Path(report) / f, "--report", guard)
    elif report:
        _check_report(Path(report), Path(output) if output else Path(report) / "results.csv", guard)
    elif output:
        check_results_file(Path(output), "-o", guard, results=True)


class _Run:
    """One bench's run and its results file (``results``), for run_benches."""

    def __init__(self, sim, stop_time, progress, log, fmi, checked):
        self.sim, self.stop_time, self.progress, self.log, self.fmi = sim, stop_time, progress, log, fmi
        self.checked, self.result, self.can_summary = checked, None, None
        self.variants = None   # the --variant names asked (a report's study grades only those: Result.variants)

    def results(self, out, partial_to, shown=None):
        """Run, then save the results to ``out`` (``shown``: the name it will have,
        printed); an interrupt while running saves the results so far as
        ``runner.partial_path(partial_to)``, one while saving finishes the save
        (a finished run's results are never discarded)."""
        sim, log = self.sim, self.log
        if self.checked is not None:
            self.checked(partial_to)
        try:
            result = sim.run(stop_time=self.stop_time, progress=self.progress)
        except KeyboardInterrupt as e:      # Ctrl-C, SIGTERM: the results so far as OUT.partial.csv
            runner.save_partial(e, partial_to)
            raise
        result.fmi = self.fmi     # the build its report's studies (a bench.py's study) run theirs with
        result.variants = self.variants   # what the user asked to run: a study grades only that, shows the rest
        self.result = result
        try:
            print_warnings((u.path, u.fmu.log) for u in sim.units)
            if result.terminated is not None:   # an FMU's own end (fmi2Terminated): a normal end, said once
                log(f"{sim.bench.name}: {result.terminated}")
            if sim.network is not None:
                self.can_summary = sim.network.summary(result.time[-1] - result.time[0])
                log(self.can_summary)
            runner.save(result, out)
        except KeyboardInterrupt as e:      # the run had finished: its results are never discarded
            if getattr(e, "written", None) is None:
                e.result = result
                runner.save_partial(e, partial_to)
            raise
        span = result.time[-1] - result.time[0]
        log(f"{sim.bench.name}: {shown or out}: {len(result.rows)} rows, {len(result.names) - 1} signals; "
            f"{span:g} s simulated in {sim.wall:.2f} s (real-time factor {span / sim.wall:.0f})"
            + (f"; the FMUs' FMI {self.fmi}.0 builds" if self.fmi else ""))
        return result


def _check_report(final, out, guard):
    """A report folder (replaced whole: none of the inputs in it), the results
    file ``out`` where it is not in the folder, and the results file beside the
    folder (_beside: where the results go when the report is not written),
    checked against the inputs (``guard``) before the run."""
    check_not_input(final, "--report", guard, folder=True)
    if not _inside(out, final):
        check_results_file(out, "-o", guard, results=True)
    b = _beside(final)
    for f in (b, runner.units_path(b), runner.partial_path(b), runner.units_path(runner.partial_path(b))):
        check_not_input(f, "--report", guard, beside=final)


def _inside(out, final):
    import os
    return Path(os.path.abspath(out)).is_relative_to(os.path.abspath(final))


def _report_run(run, final, out, page):
    """The bench run with its report written whole into a folder beside
    ``final`` and swapped in at the end (atomic_dir): the results file ``out``
    (inside ``final``: in the new folder), then ``page(folder)``. An interrupt
    leaves the earlier report as it was; the finished run's results are then
    kept beside it as FINAL.csv (also after an error in the page), the
    partial ones as FINAL.partial.csv."""
    import os
    beside = _beside(final)
    inside = _inside(out, final)
    with atomic_dir(final) as tmp:
        target = tmp / Path(os.path.abspath(out)).relative_to(os.path.abspath(final)) if inside else out
        try:
            if inside:
                target.parent.mkdir(parents=True, exist_ok=True)
            run.results(target, beside if inside else out, shown=out)
            return page(tmp)
        except BaseException as e:
            if inside and target.is_file():       # complete (written whole): kept, not removed with the folder
                with signals_held():
                    os.replace(target, beside)
                    if runner.units_path(target).is_file():
                        os.replace(runner.units_path(target), runner.units_path(beside))
                if isinstance(e, KeyboardInterrupt):
                    e.written = beside
                elif isinstance(e, ArtibusError) and e.args:
                    e.args = (f"{e.args[0]} (the finished run's results: {beside})", *e.args[1:])
            raise


def _beside(final):
    """Where a report's results go when the report is not written: REPORT.csv."""
    return final.with_name(f"{final.name}.csv")


def _page(run, bench, overrides, out_dir, final, stop_time, can_faults, settings):
    """A bench run's page in ``out_dir`` (the new folder of the report ``final``):
    the single-rate comparison, the KPIs with their co-simulation errors
    (artibus.report.cosim_error), the CAN bus's figures, the fault-free KPIs; printed."""
    from artibus.report import cosim_error, single_rate as single_rate_report
    from artibus.report.pages import FAIL, PASS, tally, write_report
    sim, result, log, name = run.sim, run.result, run.log, run.sim.bench.name
    # the page says how far a master without multi-rate steps is: one more run, single-rate
    sr = single_rate_report.measure(sim, result, lambda: single_rate_report.run_single_rate(
        bench, overrides, stop_time, **settings))
    if sr.multi_rate:
        log(f"{name}: single-rate at {sr.step:g} s: KPIs within {sr.deviation:.3g} % "
            f"({sr.worst}); the extra run took {sr.wall:.2f} s")
    if settings.get("reference"):            # (this run is the reference: nothing to measure it against)
        errors = cosim_error.Estimate(why="this run is the monolithic reference")
    else:
        errors = cosim_error.measure(bench, result, overrides, stop_time,
                                     {**settings, "can_faults": can_faults, "single_rate": sim.single_rate})
    log(f"{name}: co-simulation errors: {errors.said()}; the extra runs took {errors.wall:.2f} s")
    results_file = out_dir / "results.csv"      # (the page's own results: a study's run may replace them)
    kpis = write_report(name, result, out_dir, sim.wall, sections=sr.html(),
                        results_file=results_file if results_file.is_file() else None, errors=errors)
    if run.can_summary is not None:
        write_text(out_dir / "can_bus.txt", run.can_summary + "\n")
    for k in kpis:
        log(f"    {k.line()}")
    n_pass, n_fail = tally(kpis)
    if n_pass + n_fail:
        log(f"{name}: against the papers' bounds for this configuration: {n_pass} {PASS}, "
            f"{n_fail} {FAIL}" + (f" (why: {final / 'index.html'})" if n_fail else ""))
    if can_faults:
        fault_free_kpis(bench, overrides, out_dir, kpis, can_faults, stop_time=stop_time, log=log, **settings)
    return kpis


def _write_all(report, summary, kept, guard, log, PASS, FAIL, tally):
    """``--all --report REPORT``: seed 000's comparison page (its folder swapped in
    whole, as each bench's), the links to the pages beside, the index."""
    from artibus.report import demo
    from artibus.report.pages import write_index
    comparison, pages = _comparison(), []
    if comparison.BENCHES <= set(kept):      # (else no page: an earlier one is left as it was)
        check_not_input(report / "comparison", "--report", guard, folder=True)
        with atomic_dir(report / "comparison") as tmp:
            comparison.write(tmp, kept)
        pages.append(("comparison/index.html", comparison.TITLE, "unsteered, guided, guided + force "
                      "minimisation and pathMemory side by side"))
    if (report / "demo" / "index.html").is_file():     # `artibus demo --report REPORT/demo`
        pages.append(("demo/index.html", demo.TITLE, "BusKinematics alone, its results and plots"))
    index = write_index(report, summary, pages)
    n_pass = sum(tally(k)[0] for _, _, k in summary)
    n_fail = sum(tally(k)[1] for _, _, k in summary)
    log(f"all benches: against the papers' bounds, each for its configuration: {n_pass} {PASS}, {n_fail} {FAIL}")
    log(index)


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
                    can=None, stop_time=None, log=print, fmi=None, **more):
    """The same bench without the faults: its KPIs next to the faulty run's,
    printed and written to OUT/kpi_faults.csv (its own report in OUT/fault-free;
    ``more``: the run's other settings, as Simulation takes them)."""
    from artibus.report.pages import write_report
    with runner.Simulation(bench, step=step, overrides=overrides, record=record,
                           algorithm=algorithm, can=can, fmi=fmi, **more) as sim:
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
