"""The artibus command line: verbs in the user's words.

  artibus run BENCH [options]          run an SSP bench (a name from `artibus list`, or an .ssp);
                                       --variant NAME selects one of its parameter-set variants
  artibus bode BENCH --input C.V --measure C.V  gain and phase by sine tests through the co-simulation
  artibus calibrate                    the damping controller's gains (seed 001, 5.2.2)
  artibus list [--parameters]          the benches and FMUs, one line each (--parameters: every bound value)
  artibus info BENCH|FMU               a bench's components and connections, or an FMU's variables
  artibus simulate FMU [options]       run one FMU alone, write CSV
  artibus pack [BENCH...]              pack ssp/benches/<BENCH> into fmus/<BENCH>.ssp
  artibus can decode LOG [--csv OUT]   a CAN log (.blf, .asc) decoded through the DBC
  artibus replay LOG --bench BENCH     a recorded log (.csv, .blf, .asc) drives a bench; model against measured
  artibus sweep BENCH --grid C.V=A,B  many cases on Dask (grid, --variant axis, --design CSV/YAML), resumable
  artibus demo [--report DIR]          the main job (for now): the Urbino 18 pusher on an S-curve

Throughout: -o/--output FILE is the results file a command writes (.csv, or
.mat for run), --report DIR a directory of plots and HTML. Files are written
under a temporary name and renamed, so a file under its final name is always
complete. Ctrl-C (SIGINT) or SIGTERM during a run saves the results up to then
as OUT.partial.csv (OUT.partial.mat) and exits with 130 (143).
"""
import argparse
import math
import signal
import sys
from pathlib import Path

from artibus.base import ArtibusError, __version__, fmu_dir, fmu_path, parse_integer, parse_real
from artibus.files import check_output, make_dir


def _seconds(text):
    """--stop-time, --step: a finite number > 0 (a one-line usage error otherwise, never a traceback)."""
    try:
        x = parse_real(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"{text}: expected a finite time > 0 s")
    return x


def _real(text):
    """a number option (artibus.base.parse_real's syntax: no "1_5", no hex)"""
    try:
        return parse_real(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a decimal number") from None


def _integer(text):
    try:
        return parse_integer(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a decimal integer") from None


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, as Ctrl-C raises KeyboardInterrupt:
    the same clean-up (temporary directories, partial results) runs for both."""
    signum = signal.SIGTERM


def _on_sigterm(signum, frame):
    raise Terminated()


def _check_output(path):
    return check_output(path, "-o")


def _fmu_arg(text):
    p = Path(text)
    return p if p.suffix == ".fmu" else fmu_path(text)


def _fmu_names():
    return sorted(p.stem for p in fmu_dir().glob("*.fmu"))


def cmd_info(args):
    from fmpy import read_model_description
    from artibus.bench import ssp
    name = str(args.fmu)
    if name.endswith(".ssp") or name in ssp.bench_names():
        return _info_ssp(name)
    p = Path(name)
    if p.suffix == ".fmu":
        if not p.is_file():
            raise ArtibusError(f"{p}: no such file")
        path = p
    elif (fmu_dir() / f"{name}.fmu").is_file():
        path = fmu_dir() / f"{name}.fmu"
    else:
        import difflib
        known = ssp.bench_names() + _fmu_names()
        close = difflib.get_close_matches(name, known, n=3, cutoff=0.6)
        hint = f"; did you mean {' or '.join(close)}?" if close else f" (see `artibus list`)"
        raise ArtibusError(f"{name}: no such bench or FMU{hint}")
    try:
        md = read_model_description(str(path))
    except Exception as e:  # a corrupt or foreign file: name it
        raise ArtibusError(f"{path}: not a readable FMU ({e})") from None
    print(f"{md.modelName}: {md.description}")
    de = md.defaultExperiment
    if de:
        print(f"default experiment: {de.startTime} .. {de.stopTime} s, step {de.stepSize} s")
    for caus in ("parameter", "input", "output"):
        vs = [v for v in md.modelVariables if v.causality == caus]
        print(f"\n{caus}s ({len(vs)}):")
        for v in vs:
            start = f" = {v.start}" if v.start is not None else ""
            print(f"  {v.name:18s} {v.type:8s}{start:>12s}  {v.description or ''}")
    return 0


def _info_ssp(path):
    from artibus.bench import ssp
    bench = ssp.read(ssp.ssp_path(path))
    print(f"{bench.name}: {bench.file}")
    print(f"default experiment: {bench.start_time} .. {bench.stop_time} s")
    print("\ncomponents:")
    for c in bench.components.values():
        step = f", step {c.step} s" if c.step else ""
        print(f"  {c.path}: {c.source}{step}, {len(c.parameters)} parameters bound")
    print("\nconnections:")
    for c in bench.connections:
        tr = f"  (x {c.factor:g} + {c.offset:g})" if (c.factor, c.offset) != (1.0, 0.0) else ""
        print(f"  {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}{tr}")
    return 0


def cmd_list(args):
    """One line per bench and per FMU; --parameters: every bench's bound parameters too."""
    from artibus.bench import ssp
    names = ssp.bench_names()
    print(f"benches ({len(names)}; `artibus info BENCH` for one, `artibus run BENCH` to run it):"
          if names else "no benches in ssp/benches/")
    for name in names:
        try:
            bench = ssp.read(ssp.ssp_path(name))
        except Exception as e:  # an unpacked or broken bench is still listed
            print(f"  {name}: ({e})")
            continue
        variants = ssp.variants(ssp.ssp_path(name))
        more = f"; variants: {', '.join(variants)}" if variants else ""
        print(f"  {name}: {', '.join(bench.components)}; {bench.stop_time:g} s{more}")
        if args.parameters:
            for c in bench.components.values():
                for k, v in sorted(c.parameters.items()):
                    print(f"      {c.path}.{k} = {v}")
    fmus = _fmu_names()
    if fmus:
        from fmpy import read_model_description
        print(f"\nFMUs ({len(fmus)} in {fmu_dir()}; `artibus info FMU` for its variables):")
        for f in fmus:
            try:
                d = read_model_description(str(fmu_dir() / f"{f}.fmu")).description or ""
            except Exception as e:
                d = f"(unreadable: {e})"
            print(f"  {f}: {d[:100] + ('...' if len(d) > 100 else '')}")
    if not args.parameters:
        print("\n(`artibus list --parameters` adds every bench's parameter values)")
    return 0


def cmd_pack(args):
    from artibus.bench import ssp
    for name in args.bench or ssp.bench_names():
        print(ssp.pack(name))
    return 0


def cmd_run(args):
    """The benches run (artibus.report.runs.run_benches): their results, reports, the index."""
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set, read_parameters
    from artibus.report.runs import run_benches
    if args.all == bool(args.bench):
        raise ArtibusError("give one BENCH or --all")
    if args.all and args.variant:
        raise ArtibusError("--variant selects a variant of one BENCH, not of --all")
    if args.all and args.output:
        raise ArtibusError("-o names one results file: with --all each bench writes <bench>.csv, "
                           "or DIR/<bench>/results.csv with --report DIR")
    user = {}
    for f in args.ssv or []:
        user.update(read_parameters(f))
    user.update(parse_set(args.set))
    run_benches(ssp.bench_names() if args.all else [args.bench], every=args.all, variants=args.variant,
                user=user, stop_time=args.stop_time, step=args.step, record=args.record,
                algorithm=args.algorithm, can=args.can, can_log=args.can_log, can_faults=args.can_fault,
                report=args.report, output=args.output, progress=sys.stderr.isatty(),
                checked=lambda out: setattr(args, "_out", out))
    return 0


def cmd_replay(args):
    from artibus import runner
    from artibus.bench.parameters import parse_set
    from artibus.can import replay
    out = args._out = _check_output(Path(args.output or f"{Path(args.log).stem}_replay.csv"))
    rep = replay.replay(args.log, args.bench, maps=args.map, dbc=args.dbc, stop_time=args.stop_time,
                        overrides=parse_set(args.set), steering_map_name=args.steering_map,
                        variants=args.variant)
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
        imgs = replay.write_report(rep, args.report, f"{Path(args.log).name} replayed into {args.bench}")
        for i in imgs + ["errors.csv"]:
            print(f"    {Path(args.report) / i}")
    return 0


def cmd_can_decode(args):
    from artibus.base import ROOT
    from artibus import can
    if args.csv:
        check_output(args.csv, "--csv")
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


def cmd_bode(args):
    import numpy as np
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set
    from artibus.files import write_text
    from artibus.study import bode
    if not args.measure:
        hint = (f" (-o/--output is the results file now, as in every command: "
                f"--measure {args.output} names the output to measure)"
                if args.output and not args.output.endswith(".csv") else "")
        raise ArtibusError("bode: give the output to measure, --measure COMP.VAR" + hint)
    out = _check_output(Path(args.output or "bode.csv"))
    if args.plot:
        check_output(args.plot, "--plot")
    overrides = {**ssp.variant_overrides(args.bench, args.variant), **parse_set(args.set)}
    freqs = np.geomspace(args.fmin, args.fmax, args.n) if args.n > 1 else [args.fmin]
    resp = bode.frequency_response(args.bench, args.input, args.measure, freqs, args.amplitude,
                                   periods=args.periods, settle=args.settle, overrides=overrides,
                                   step=args.step)
    units = bode.output_units(args.bench, list(args.measure) + [args.input])
    rows = bode.csv_rows(freqs, resp, args.measure, args.input, units)
    write_text(out, "\n".join(rows) + "\n")
    print(f"{out}: {len(freqs)} frequencies")
    for line in rows:
        print("  " + line)
    if args.plot:
        bode.plot(args.plot, resp, f"{args.bench}: {', '.join(args.measure)} / {args.input}", units=units,
                  input_unit=units.get(args.input, ""))
        print(args.plot)
    return 0


def cmd_calibrate(args):
    """seed 001, 5.2.2: each damping option's gain for a peak damping of 13.5 %
    on the 200 m / 100 km/h / rear-friction-0.2 lane change."""
    from artibus.study import damping
    gains, reached = damping.calibrate(target=args.target)
    print(f"\n{'gain':6s} {'artibus':>10s} {'thesis':>8s} {'ratio':>7s}  peak damping on lc200_100")
    for name, value in gains.items():
        thesis = damping.THESIS_GAINS.get(name)
        ratio = f"{value / thesis:7.3f}" if thesis else "      -"
        print(f"{name:6s} {value:10.4g} {thesis if thesis else 'n/a':>8} {ratio}  {reached.get(name, float('nan')):.3f} %")
    if args.dry_run:
        return 0
    notes = "Made by `artibus calibrate`; " + ", ".join(f"{n}: {reached[n]:.3f} %" for n in reached) + "."
    print(damping.write_gains(gains, notes=notes))
    return 0


def cmd_simulate(args):
    from artibus.bench.parameters import check_against, parse_set, read_parameters
    from artibus.fmu import simulate
    from artibus.runner import save_partial
    fmu = _fmu_arg(args.fmu)
    out = args._out = _check_output(Path(args.output or f"{fmu.stem}.csv"))
    params = read_parameters(args.ssv, fmu) if args.ssv else {}
    extra = parse_set(args.set)
    if any("[" in k for k in extra):          # mu[*], mu[1:6]: each element
        from fmpy import read_model_description
        from artibus.bench.names import expand_all
        names = [v.name for v in read_model_description(str(fmu)).modelVariables]
        extra = expand_all(extra, lambda full: ("", names))
    check_against(extra, fmu, "--set")
    params.update(extra)
    try:
        result = simulate(fmu, parameters=params, stop_time=args.stop_time, step=args.step)
    except KeyboardInterrupt as e:      # Ctrl-C, SIGTERM: the results so far as OUT.partial.csv
        save_partial(e, out)
        raise
    from artibus.runner import save
    save(result, out)
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
    _check_output(csv)
    png, bmax = demo.s_curve(out, csv)
    print(f"demo: {csv}\ndemo: {png}\nmax |beta[1]| = {math.degrees(bmax):.1f} deg "
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
                retry_failed=args.retry_failed,
                argv=sys.argv)
    n = res.table.num_rows
    print(f"sweep {Path(args.bench).stem}: {n} cases, {res.ran} run now ({res.failed} failed), "
          f"{res.skipped} done before" + (f"; {res.rate:.1f} cases/min" if res.ran else ""))
    for f in (TABLE, PLOT, WORST):
        if (Path(out) / f).is_file():
            print(f"    {Path(out) / f}")
    return 0


def build_parser():
    p = argparse.ArgumentParser(prog="artibus", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"artibus {__version__}")
    sub = p.add_subparsers(dest="verb", required=True)
    s = sub.add_parser("run", help="run an SSP bench")
    s.add_argument("bench", nargs="?", help="a bench name (see `artibus list`) or the path of an .ssp")
    s.add_argument("--all", action="store_true", help="run every bench")
    s.add_argument("--report", metavar="DIR", help="write plots and an HTML page with the KPIs to DIR")
    s.add_argument("--stop-time", type=_seconds, help="default: the bench's DefaultExperiment")
    s.add_argument("--step", type=_seconds, help="base communication step, s")
    s.add_argument("--ssv", action="append", help="parameter file with names COMPONENT.VARIABLE")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE", help="set a parameter")
    s.add_argument("--variant", action="append", metavar="NAME",
                   help="a variant of the bench (its parameter set variants/NAME.ssv; see `artibus list`); "
                        "repeatable, later ones win; applied before --ssv and --set")
    s.add_argument("--record", action="append", metavar="COMP.VAR",
                   help="record this variable (default: every connected output)")
    s.add_argument("--algorithm", default="gauss-seidel", choices=["gauss-seidel", "jacobi"])
    s.add_argument("-o", "--output", metavar="FILE",
                   help="results: .csv or .mat (default: <bench>.csv, with --report DIR/results.csv); "
                        "checked before the run; a run stopped by Ctrl-C/SIGTERM leaves FILE.partial.csv")
    s.add_argument("--can", metavar="virtual|INTERFACE:CHANNEL",
                   help="for a bench that routes connections over CAN: python-can's virtual bus "
                        "(the default) or a real interface, e.g. socketcan:vcan0")
    s.add_argument("--can-log", metavar="FILE.blf|FILE.asc", help="write the CAN traffic (simulated time)")
    s.add_argument("--can-fault", action="append", metavar="SPEC",
                   help="inject a fault into the CAN network (repeatable): loss:MSG|NODE:RATE[:seed=N], "
                        "latency:MSG|NODE:DELAY_S[:jitter=S][:seed=N], corrupt:MSG|NODE:crc|repeat|skip[:rate=R], "
                        "silent:NODE, busoff:NODE[:recover[=DELAY_S]]; each may end in @T0 or @T0-T1 (s). "
                        "With --report, the fault-free run's KPIs are printed and written beside the faulty ones")
    s.set_defaults(func=cmd_run)
    s = sub.add_parser("can", help="CAN tools: decode a log")
    can_sub = s.add_subparsers(dest="can_verb", required=True)
    c = can_sub.add_parser("decode", help="print or export (CSV) the signals of a .blf/.asc log")
    c.add_argument("log", help="a .blf or .asc file")
    c.add_argument("--dbc", help="default: ssp/can/Bus36m.dbc")
    c.add_argument("--csv", metavar="OUT", help="write CSV instead of printing")
    c.set_defaults(func=cmd_can_decode)
    s = sub.add_parser("replay", help="drive a bench from a recorded log, compare with measured responses")
    s.add_argument("log", help="a .csv (time_s and signal columns) or a CAN log (.blf, .asc)")
    s.add_argument("--bench", required=True,
                   help="the bench to drive (e.g. Urbino18_Replay; a CAN log into a bench with routes over CAN "
                        "feeds every routed input); a driven input the bench connects is cut from its source")
    s.add_argument("--variant", action="append", metavar="NAME", help="a variant of the bench (as for run)")
    s.add_argument("--map", action="append", metavar="SIGNAL[unit]=COMP.INPUT",
                   help="feed a log signal to an input (repeatable; adds to or replaces the bench's replay profile; "
                        "a CAN signal as MESSAGE.SIGNAL, e.g. SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1])")
    s.add_argument("--dbc", help="for a CAN log: default the bench's DBC, else ssp/can/Bus36m.dbc")
    s.add_argument("--steering-map", help="a parameter set c[0..3] (seed 003 App. A), default the bench's")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE")
    s.add_argument("--stop-time", type=_seconds, help="default: the end of the driving signals")
    s.add_argument("-o", "--output", metavar="FILE", help="results CSV (default <log>_replay.csv)")
    s.add_argument("--report", metavar="DIR", help="plots of model against measured and errors.csv")
    s.set_defaults(func=cmd_replay)
    s = sub.add_parser("bode", help="frequency response through the co-simulation (sine tests)")
    s.add_argument("bench", help="a bench name or the path of an .ssp")
    s.add_argument("--input", required=True, metavar="COMP.VAR", help="the input the sine is added to")
    s.add_argument("--measure", action="append", metavar="COMP.VAR",
                   help="an output to measure (repeatable)")
    s.add_argument("--fmin", type=_real, default=0.05, help="lowest frequency, Hz")
    s.add_argument("--fmax", type=_real, default=5.0, help="highest frequency, Hz")
    s.add_argument("--n", type=_integer, default=12, help="frequencies, log-spaced")
    s.add_argument("--amplitude", type=_real, default=0.01, help="sine amplitude, in the input's unit")
    s.add_argument("--periods", type=_integer, default=4, help="periods fitted after the transient")
    s.add_argument("--settle", type=_real, help="time given to the transient, s")
    s.add_argument("--step", type=_seconds)
    s.add_argument("--variant", action="append", metavar="NAME", help="a variant of the bench (repeatable)")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE")
    s.add_argument("-o", "--output", "--output-file", metavar="FILE", help="results CSV (default bode.csv)")
    s.add_argument("--plot", help="PNG with gain and phase")
    s.set_defaults(func=cmd_bode)
    s = sub.add_parser("calibrate", help="the damping controller's gains (seed 001, 5.2.2), "
                                         "written to ssp/parameters/DampingGains.ssv")
    s.add_argument("--target", type=_real, default=13.5, help="peak damping on the 200 m / 100 km/h case, %%")
    s.add_argument("--dry-run", action="store_true", help="print the gains, write nothing")
    s.set_defaults(func=cmd_calibrate)
    s = sub.add_parser("list", help="the benches and FMUs, one line each")
    s.add_argument("--parameters", action="store_true", help="every bench's bound parameter values too")
    s.set_defaults(func=cmd_list)
    s = sub.add_parser("pack", help="pack benches into self-contained .ssp files")
    s.add_argument("bench", nargs="*", help="default: every bench in ssp/benches")
    s.set_defaults(func=cmd_pack)
    s = sub.add_parser("info", help="show an FMU's variables or a bench's structure")
    s.add_argument("fmu", metavar="BENCH|FMU", help="a bench name, the name of a built FMU, or the path of an .ssp or .fmu")
    s.set_defaults(func=cmd_info)
    s = sub.add_parser("simulate", help="run one FMU alone")
    s.add_argument("fmu", help="path of an .fmu, or the name of a built FMU")
    s.add_argument("--ssv", help="parameter set: name in ssp/parameters or path of an .ssv")
    s.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a parameter")
    s.add_argument("--stop-time", type=_seconds)
    s.add_argument("--step", type=_seconds)
    s.add_argument("-o", "--output", metavar="FILE", help="results CSV (default: <FMU>.csv)")
    s.set_defaults(func=cmd_simulate)
    s = sub.add_parser("check", help="check a vehicle parameter set's consistency (axles, hinges, loads, inertia)")
    s.add_argument("ssv", nargs="+", help="a parameter set: path of an .ssv or a name in ssp/parameters")
    s.add_argument("--model", choices=["BusDynamics", "BusKinematics"], help="default: from the names in the set")
    s.set_defaults(func=cmd_check)
    s = sub.add_parser("demo", help="the main job: a demo run with results and a plot")
    s.add_argument("--report", metavar="DIR", default="out", help="directory of results and plots (default: out)")
    s.add_argument("-o", "--output", metavar="FILE", help="results CSV (default: DIR/BusKinematics_Urbino18_SCurve.csv)")
    s.set_defaults(func=cmd_demo)
    s = sub.add_parser("sweep", help="run many cases of a bench on Dask (grid, design file), resumable")
    s.add_argument("bench", help="a bench name (see `artibus list`) or the path of an .ssp")
    s.add_argument("--grid", nargs="+", action="extend", metavar="COMP.VAR=VALUES",
                   help="an axis: COMP.VAR=V1,V2,... or COMP.VAR=START:STOP:STEP (stop included)")
    s.add_argument("--variant", action="append", metavar="A,B,...",
                   help="an axis of the bench's variants (repeatable: each one more axis)")
    s.add_argument("--design", metavar="FILE", help="the cases from a .csv (a case a row) or .yaml "
                                                    "(grid, lhs or montecarlo with a seed)")
    s.add_argument("-o", "--out", default=None, help="output folder (default: sweep-<BENCH>)")
    s.add_argument("--stop-time", type=_seconds, help="every case's stop time (default: the bench's)")
    s.add_argument("--step", type=_seconds, help="base communication step, s")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE", help="a parameter of every case")
    s.add_argument("--keep-series", action="store_true", help="keep each case's time series (series/<key>.parquet)")
    s.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler (tcp://host:8786)")
    s.add_argument("--workers", type=_integer, help="local worker processes (default: one per core)")
    s.add_argument("--retry-failed", action="store_true", help="run the cases recorded as failed again")
    s.add_argument("--kpi", help="the KPI of the study plot and the worst cases (default: the bench's first)")
    s.set_defaults(func=cmd_sweep)
    return p


def main(argv=None):
    args = build_parser().parse_args(argv)
    import threading
    previous = previous_int = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _on_sigterm)   # SIGTERM unwinds as Ctrl-C does
        # Ctrl-C stops a run even where the shell started us with SIGINT ignored
        # (a background job of a script: Python then installs no handler of its own)
        previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return args.func(args)
    except KeyboardInterrupt as e:     # Ctrl-C (SIGINT) or SIGTERM: one line, 130 or 143
        sig = signal.Signals(getattr(e, "signum", signal.SIGINT))
        partial = getattr(e, "partial", None)
        if getattr(e, "written", None) is not None:
            what = f"the finished run's results are complete in {e.written}"
        elif partial is not None:
            what = f"partial results up to t = {e.partial_time:g} s in {partial}"
        elif getattr(e, "partial_error", None):
            what = f"partial results not saved: {e.partial_error}"
        else:
            what = "nothing written"
        print(f"artibus: stopped by {sig.name}; {what}", file=sys.stderr)
        return 128 + sig.value
    except ArtibusError as e:
        print(f"artibus: error: {e}", file=sys.stderr)
        log = getattr(e, "log", None)
        if log:
            print("FMU log:\n  " + "\n  ".join(log[-10:]), file=sys.stderr)
        result = getattr(e, "result", None)
        out = getattr(args, "_out", None)
        if result is not None and result.rows and out is not None:
            from artibus import runner
            partial = runner.partial_path(out)
            try:
                runner.save(result, partial)
                print(f"artibus: partial results up to the failure: {partial}", file=sys.stderr)
            except (ArtibusError, OSError) as err:
                print(f"artibus: partial results not saved: {err}", file=sys.stderr)
        return 1
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
        if previous_int is not None:
            signal.signal(signal.SIGINT, previous_int)
