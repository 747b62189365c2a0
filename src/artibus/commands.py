"""What each verb of the command line does (artibus.cli builds the parser and runs them): the
``cmd_<verb>`` functions, each given argparse's namespace; an error is an ArtibusError naming
the file, element and value (artibus.cli.main prints it in one line)."""
import math
import sys
from pathlib import Path

from artibus.base import ArtibusError
from artibus.files import atomic_dir, bench_inputs, given as _given, make_dir
from artibus.inventory import fmu_arg, wrong_kind


def _check_output(path, inputs=(), what="-o", results=False):
    """``path`` a place to write (none of the run's inputs: issue 41); ``results``:
    a run's results, in a format of its extension (artibus.runner.formats)."""
    from artibus.runner.results import check_results_file
    return check_results_file(path, what, inputs, results)


def cmd_pack(args):
    from artibus.bench import ssp
    if args.all_platforms:
        import subprocess
        from artibus.base import ROOT
        # the cross builds and the FMUs with every platform's binaries (scripts/setup.sh)
        r = subprocess.run(["bash", str(ROOT / "scripts" / "setup.sh"), "--all-platforms"])
        if r.returncode:
            raise ArtibusError(f"scripts/setup.sh --all-platforms failed (exit {r.returncode})")
    if not args.portable:
        if args.variant or args.output:
            raise ArtibusError("--variant and -o are for a portable pack (--portable)")
        for name in args.bench or ssp.bench_names():
            print(ssp.pack(name, fmi=args.fmi))
        return 0
    if args.fmi:
        raise ArtibusError("--fmi: a portable pack has the builds the bench's .ssd names")
    from artibus.bench.portable import pack_portable
    benches = args.bench or [b for b in ssp.bench_names()                  # (pack_portable says why not the others)
                             if (r := ssp.read(ssp.ssp_path(b))).can is None and r.read_as == "1.0"]
    if args.output and len(benches) != 1:
        raise ArtibusError("-o names one portable pack: give one BENCH")
    if args.variant and len(benches) != 1:
        raise ArtibusError("--variant selects a variant of one BENCH")
    for name in benches:
        print(pack_portable(name, args.variant, out=args.output and _check_output(args.output, bench_inputs(name))))
    return 0


def cmd_run(args):
    """The benches run (artibus.report.runs.run_benches): their results, reports, the index."""
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set, read_parameters
    from artibus.report.runs import run_benches
    if args.all == bool(args.bench):
        raise ArtibusError("give one BENCH or --all")
    if args.bench:
        wrong_kind("run", args.bench)
    if args.all and args.variant:
        raise ArtibusError("--variant selects a variant of one BENCH, not of --all")
    if args.all and args.input_file:
        raise ArtibusError("--input-file drives the free inputs of one BENCH, not of --all")
    if args.all and args.output:
        raise ArtibusError("-o names one results file: with --all each bench writes <bench>.csv, "
                           "or DIR/<bench>/results.csv with --report DIR")
    user = {}
    for f in args.ssv or []:
        user.update(read_parameters(f, keep_units=True))
    user.update(parse_set(args.set))
    run_benches(ssp.bench_names() if args.all else [args.bench], every=args.all, variants=args.variant,
                user=user, stop_time=args.stop_time, step=args.step, record=args.record,
                algorithm=args.algorithm, can=args.can, can_log=args.can_log, can_faults=args.can_fault,
                report=args.report, output=args.output, progress=sys.stderr.isatty(), single_rate=args.single_rate,
                checked=lambda out: setattr(args, "_out", out), fmi=args.fmi,
                inputs=_given(args.ssv, "an --ssv file") + _given([args.input_file], "the --input-file"),
                fmi_type=_fmi_type(args.fmi_type), relative_tolerance=args.tolerance, me_method=args.me_method,
                me_jacobian=args.me_jacobian, input_file=args.input_file, reference=args.reference)
    return 0


def _fmi_type(text):
    """--fmi-type of `run`: "me" (Model Exchange where an FMU has it), else None (Co-Simulation)."""
    return "me" if text in ("ModelExchange", "me") else None


def cmd_replay(args):
    from artibus import runner
    from artibus.bench.parameters import parse_set
    from artibus.can import replay
    out = args._out = _check_output(Path(args.output or f"{Path(args.log).stem}_replay.csv"), _given([args.log, args.dbc, args.steering_map], "a file replay reads") + bench_inputs(args.bench), results=True)
    rep = replay.replay(args.log, args.bench, maps=args.map, dbc=args.dbc, stop_time=args.stop_time,
                        overrides=parse_set(args.set), steering_map_name=args.steering_map,
                        variants=args.variant, fmi=args.fmi)
    r = rep.result
    for w in rep.warnings:
        print(f"artibus: warning: {w}", file=sys.stderr)
    runner.save(r, out)
    print(f"replay of {args.log} into {args.bench}: {out}: {len(r.rows)} rows, {r.time[-1] - r.time[0]:g} s")
    for inp, (sig, unit) in rep.drive.items():
        print(f"    {inp} <- {sig}" + (" (seed 003 App. A steering map)" if rep.profile.steering
                                         and inp == rep.profile.steering[0] else ""))
    for name, _, errors in replay.runs(rep):
        if errors:
            print(f"{name} against measured (RMS, max):")
            for label, rms, mx, unit in errors:
                print(f"    {label}: {rms:.3f} {unit} RMS, {mx:.3f} {unit} max")
    if args.report:
        title = f"{Path(args.log).name} replayed into {args.bench}"
        with atomic_dir(args.report) as tmp:         # whole or not at all (artibus.files)
            replay.report_page(rep, tmp, title, f"{args.log} replayed into the bench {args.bench}.")
        for i in sorted(p.name for p in Path(args.report).iterdir() if p.suffix in (".png", ".csv", ".html")):
            print(f"    {Path(args.report) / i}")
    return 0


def cmd_can_decode(args):
    from artibus.base import ROOT
    from artibus import can
    if args.csv:
        _check_output(args.csv, _given([args.log, args.dbc], "a file decode reads"), "--csv")
    unknown = {}
    rows = can.decode_log(args.log, args.dbc or ROOT / "ssp" / "can" / "Bus36m.dbc", unknown)
    if unknown:
        print(f"artibus: warning: {sum(unknown.values())} frame(s) with an identifier the DBC does not know, "
              f"skipped: {', '.join(f'0x{i:03X} ({n})' for i, n in sorted(unknown.items()))}", file=sys.stderr)
    header = "time_s,message,signal,value,unit,e2e"
    lines = [f"{t:.6f},{m},{s},{v!r},{u},{e}" for t, m, s, v, u, e in rows]
    if args.csv:
        from artibus.files import write_text
        out = write_text(Path(args.csv), header + "\n" + "\n".join(lines) + "\n")
        print(f"{out}: {len(rows)} signal values")
    else:
        print(header)
        print("\n".join(lines))
    bad = sum(1 for r in rows if r[5] != "ok")
    if bad:
        print(f"artibus: {bad} signal values from frames failing their CRC or counter (e2e column)", file=sys.stderr)
    return 0


def cmd_plot(args):
    """artibus plot RESULTS.csv SIGNAL...: a PNG, a panel per unit (artibus.report.quick)."""
    from artibus.report import quick
    if args.output:
        _check_output(args.output, _given([args.results], "the results plotted"))
    png, chosen = quick.results_plot(args.results, args.signal, args.output)
    print(f"{png}: {len(chosen)} signals ({', '.join(chosen)})")
    return 0


def cmd_can_plot(args):
    """artibus can plot LOG [--signal MSG.SIG]...: frame timing and decoded signals as a PNG."""
    from artibus.report import quick
    if args.output:
        _check_output(args.output, _given([args.log, args.dbc], "a file the plot reads"))
    png, chosen, known = quick.can_plot(args.log, args.signal or (), dbc=args.dbc, out=args.output)
    print(f"{png}: the frames' timing" + (f" and {', '.join(chosen)}" if chosen else ""))
    if not chosen:
        print(f"(--signal NAME adds a decoded signal; this log has {len(known)}: {', '.join(known[:8])}"
              + (", ..." if len(known) > 8 else "") + ")")
    return 0


def cmd_simulate(args):
    from artibus.bench.parameters import check_against, parse_set, read_parameters
    from artibus.fmu.isolated import simulate     # the FMU in a process of its own: its crash ends only that
    from artibus.runner import save_partial
    from artibus.bench.fmi import simulated_fmu
    fmu = fmu_arg(args.fmu)
    run = simulated_fmu(fmu, args.fmu, args.fmi)     # --fmi 3: its FMI 3.0 build, checked as FMI 2.0's
    out = args._out = _check_output(Path(args.output or f"{fmu.stem}.csv"), _given([fmu, args.ssv], "a file simulate reads") + bench_inputs(fmu), results=True)
    from artibus.options import check_interface, input_file, start_values
    from artibus.fmu.instance import read_model
    model = read_model(run)
    interface = check_interface(args, model, run)     # "cs" or "me" (--fmi-type)
    params = read_parameters(args.ssv, fmu) if args.ssv else {}
    extra = {**start_values(args), **parse_set(args.set)}
    if any("[" in k for k in extra):          # mu[*], mu[1:6]: each element
        from artibus.bench.names import expand_all
        names = [v.name for v in model.modelVariables]
        extra = expand_all(extra, lambda full: ("", names))
    check_against(extra, fmu, "--set")
    params.update(extra)
    table = input_file(args.input_file, model, params)
    inputs, events = (table.functions(), table.events()) if table is not None else (None, ())
    messages = [] if args.fmi_logging else None
    try:
        result = simulate(run, parameters=params, inputs=inputs, stop_time=args.stop_time, step=args.step,
                          outputs=args.record,
                          start_time=args.start_time, output_interval=args.output_interval,
                          tolerance=args.tolerance, logging=args.fmi_logging, messages=messages,
                          events=events, interface=interface, me_method=args.me_method or "bdf",
                          me_jacobian=args.me_jacobian)
    except KeyboardInterrupt as e:      # Ctrl-C, SIGTERM: the results so far as OUT.partial.csv
        save_partial(e, out)
        raise
    finally:
        for m in messages or []:
            print(f"{run.stem if hasattr(run, 'stem') else run}: {m}", file=sys.stderr)
    from artibus.runner import save
    save(result, out)
    if result.terminated is not None:     # the FMU's own end (fmi2Terminated): a normal end, exit 0
        print(f"{result.terminated}")
    print(f"{out}: {len(result.rows)} rows")
    return 0


def cmd_demo(args):
    """Urbino 18 Electric (seed 003, Table I) pushed at 3 m/s through an
    S-curve: 25 deg left, 25 deg right, straight; results and a plot (artibus.report.demo)."""
    from artibus.report import demo
    out = make_dir(args.report)
    csv = out / "BusKinematics_Urbino18_SCurve.csv"
    if args.output:
        if Path(args.output).is_dir() or not Path(args.output).suffix:
            raise ArtibusError(f"-o {args.output}: -o is the results file (.csv); the directory of "
                               f"results and plots is --report DIR")
        csv = Path(args.output)
    _check_output(csv, results=True)
    png, bmax = demo.s_curve(out, csv)
    html_page = demo.page(out, csv, [png, demo.signals_png(out)], bmax)
    print(f"demo: {csv}\ndemo: {png}\ndemo: {html_page}\nmax |beta[1]| = {math.degrees(bmax):.1f} deg "
          f"(Urbino 18 mechanical limit 54 deg, seed 003 Table I)")
    return 0


def cmd_check(args):
    """A vehicle parameter set's consistency (artibus.bench.check)."""
    from artibus.bench import check
    return check.main(args.ssv, args.model)


def cmd_sweep(args):
    """artibus sweep: the cases of a bench on Dask (artibus.study.sweep)."""
    from artibus.bench.parameters import parse_set
    from artibus.study.sweep import PLOT, TABLE, WORST, parse_grid, sweep
    variants = [v.split(",") for v in args.variant] if args.variant else None
    if variants and any(not x.strip() for vs in variants for x in vs):
        raise ArtibusError(f"--variant {','.join(args.variant)}: an empty variant name")
    if args.workers is not None and args.workers < 1:
        raise ArtibusError(f"--workers {args.workers}: at least 1")
    out = args.out or f"sweep-{Path(args.bench).stem}"
    res = sweep(args.bench, grid=parse_grid(args.grid) if args.grid else None, variants=variants,
                design=args.design, out=out, stop_time=args.stop_time, step=args.step,
                fixed=parse_set(args.set),
                keep_series=args.keep_series, scheduler=args.scheduler, workers=args.workers, kpi=args.kpi,
                retry_failed=args.retry_failed, argv=sys.argv, fmi=args.fmi, error_every=args.error_every)
    n = res.table.num_rows
    print(f"sweep {Path(args.bench).stem}: {n} cases, {res.ran} run now ({res.failed} failed), "
          f"{res.skipped} done before" + (f"; {res.rate:.1f} cases/min" if res.ran else ""))
    for f in (TABLE, PLOT, WORST):
        if (Path(out) / f).is_file():
            print(f"    {Path(out) / f}")
    return 0
