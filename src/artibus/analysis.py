"""The analysis verbs of the command line (artibus.cli): `artibus bode` (frequency response
through the co-simulation), `artibus linearize` (one Model Exchange FMU's linear model and modes),
`artibus calibrate` (the damping controller's gains, seed 001)."""
from pathlib import Path

from artibus.base import ArtibusError
from artibus.files import bench_inputs, check_output
from artibus.inventory import fmu_arg


def _check_output(path, inputs=(), what="-o"):
    """``path`` a place to write, none of the run's inputs (artibus.files)"""
    from artibus.runner.results import check_results_file
    return check_results_file(path, what, inputs, False)


def cmd_bode(args):
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set
    from artibus.study import bode
    if not args.measure:
        hint = (f" (-o/--output is the results file now, as in every command: "
                f"--measure {args.output} names the output to measure)"
                if args.output and not args.output.endswith(".csv") else "")
        raise ArtibusError("bode: give the output to measure, --measure COMP.VAR" + hint)
    if not args.output and not args.plot:
        raise ArtibusError("bode: say where the results go: -o FILE.csv (the table) and/or --plot FILE.png")
    out = _check_output(Path(args.output), bench_inputs(args.bench)) if args.output else None
    if args.plot:
        _check_output(args.plot, bench_inputs(args.bench), "--plot")
    overrides = {**ssp.variant_overrides(args.bench, args.variant), **parse_set(args.set)}
    bode.measure(args.bench, args.input, args.measure, args.fmin, args.fmax, args.n, args.amplitude,
                 periods=args.periods, settle=args.settle, overrides=overrides, step=args.step,
                 out=out, plot_path=args.plot, log=print, fmi=args.fmi)
    return 0


def cmd_linearize(args):
    """One ME FMU linearised at an operating point (artibus.linearize): the modes printed,
    the matrices to -o FILE.mat|.csv, a Bode plot of --bode IN:OUT to --plot FILE.png."""
    from artibus import linearize as lz
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set, read_parameters
    if Path(args.fmu).suffix.lower() == ".ssp" or args.fmu in ssp.bench_names():
        raise ArtibusError(f"linearize {args.fmu}: a bench; the linear model of a whole bench (its Model "
                           "Exchange plants with their controllers) is to come (issue 43): give one FMU")
    fmu = fmu_arg(args.fmu)
    out = check_output(args.output, "-o") if args.output else None
    if out is not None and Path(out).suffix not in (".mat", ".csv"):
        raise ArtibusError(f"-o {out}: the matrices are written as FILE.mat or FILE.csv")
    if bool(args.bode) != bool(args.plot):
        raise ArtibusError("linearize: --bode IN:OUT and --plot FILE.png go together")
    if args.plot:
        check_output(args.plot, "--plot")
    pair = args.bode.split(":", 1) if args.bode else None
    if pair is not None and len(pair) != 2:
        raise ArtibusError(f"--bode {args.bode}: expected INPUT:OUTPUT")
    params = read_parameters(args.ssv, fmu) if args.ssv else {}
    params.update(parse_set(args.set))
    names = lambda text: [n.strip() for n in text.split(",") if n.strip()] if text else None   # noqa: E731
    lin = lz.linearize(fmu, at=args.at, steady=args.steady, parameters=params, inputs=names(args.inputs),
                       outputs=names(args.outputs), step=args.fd_step, derivatives=args.derivatives)
    print("\n".join(lz.report(lin)))
    if out is not None:
        (lz.write_mat if Path(out).suffix == ".mat" else lz.write_csv)(lin, out)
        print(f"{out}: A {lin.A.shape}, B {lin.B.shape}, C {lin.C.shape}, D {lin.D.shape}")
    if pair is not None:
        print(lz.bode_plot(lin, pair[0], pair[1], args.plot))
    return 0


def cmd_calibrate(args):
    """seed 001, 5.2.2: each damping option's gain for a peak damping of 13.5 %
    on the 200 m / 100 km/h / rear-friction-0.2 lane change; printed, and
    written as a parameter set only to -o FILE (the benches' own gains:
    -o ssp/parameters/DampingGains.ssv)."""
    from artibus.study import damping
    out = check_output(args.output, "-o") if args.output else None
    if out is not None and Path(out).suffix != ".ssv":
        raise ArtibusError(f"-o {out}: the gains are written as a parameter set, FILE.ssv")
    gains, reached = damping.calibrate(target=args.target)
    print("\n" + damping.gains_table(gains, reached))
    if out is None or args.dry_run:
        print("\n(written nowhere: -o FILE.ssv writes them; -o ssp/parameters/DampingGains.ssv is the benches' set)")
        return 0
    notes = "Made by `artibus calibrate`; " + ", ".join(f"{n}: {reached[n]:.3f} %" for n in reached) + "."
    print(f"gains written to {damping.write_gains(gains, path=out, notes=notes)}")
    return 0
