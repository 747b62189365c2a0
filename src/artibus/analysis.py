"""The analysis verbs of the command line (artibus.cli): `artibus bode` (frequency response
through the co-simulation), `artibus linearize` (one Model Exchange FMU's linear model and modes,
or a bench's with its controllers in the loop), `artibus modes` (stability maps), `artibus calibrate`
(the damping controller's gains, seed 001)."""
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
    """One ME FMU linearised at an operating point (artibus.linear.fmu): the modes printed,
    the matrices to -o FILE.mat|.csv, a Bode plot of --bode IN:OUT to --plot FILE.png."""
    from artibus.linear import fmu as lz
    from artibus.bench import ssp
    from artibus.bench.parameters import parse_set, read_parameters
    if (Path(args.fmu).suffix.lower() in (".ssp", ".ssd") or Path(args.fmu).is_dir()
            or args.fmu in ssp.bench_names()):
        return _linearize_bench(args)
    for flag in ("variant", "exclude", "amplitude"):
        if getattr(args, flag, None):
            raise ArtibusError(f"linearize {args.fmu}: --{flag} is a bench's option; {args.fmu} is one FMU")
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


def _linearize_bench(args):
    """`artibus linearize BENCH`: its ME plants with the rest in the loop (artibus.linear.bench) at its
    start, at --at TIME of its run or --steady; with --amplitude C.V=A the loop's describing function
    there (artibus.linear.describing)."""
    from artibus.linear import fmu as lz
    from artibus.base import parse_real
    from artibus.bench.parameters import parse_set
    from artibus.linear import bench as lb, describing
    if args.at is not None and args.steady:
        raise ArtibusError("linearize: --at TIME or --steady, not both")
    if args.ssv:
        raise ArtibusError(f"linearize {args.fmu}: --ssv is for one FMU; a bench binds its own parameter "
                           "sets (change them with --set Component.variable=VALUE or --variant)")
    out = check_output(args.output, "-o") if args.output else None
    if out is not None and Path(out).suffix not in (".mat", ".csv"):
        raise ArtibusError(f"-o {out}: the matrices are written as FILE.mat or FILE.csv")
    if bool(args.bode) != bool(args.plot):
        raise ArtibusError("linearize: --bode IN:OUT and --plot FILE.png go together")
    names = lambda text: [n.strip() for n in text.split(",") if n.strip()] if text else None   # noqa: E731
    opened = lb.open_bench(args.fmu, args.variant or (), parse_set(args.set), args.exclude or (), args.at)
    try:
        if args.amplitude:
            sig, sep, amp = args.amplitude.partition("=")
            if not sep:
                raise ArtibusError(f"--amplitude {args.amplitude}: expected Component.variable=AMPLITUDE")
            bl, _, _ = describing.linear_at_amplitude(opened, sig.strip(), parse_real(amp.strip()), args.steady)
            bl.closed = lb._select(bl.closed, names(args.inputs), names(args.outputs))
        else:
            bl = lb.linear_of(opened, args.steady, names(args.inputs), names(args.outputs), args.fd_step,
                              args.derivatives)
    finally:
        opened.close()
    print("\n".join(lb.report(bl)))
    if out is not None:
        (lz.write_mat if Path(out).suffix == ".mat" else lz.write_csv)(bl.closed, out)
        print(f"{out}: A {bl.closed.A.shape}, B {bl.closed.B.shape}, C {bl.closed.C.shape}, D {bl.closed.D.shape}")
    if args.bode:
        pair = args.bode.split(":", 1)
        if len(pair) != 2:
            raise ArtibusError(f"--bode {args.bode}: expected INPUT:OUTPUT")
        print(lz.bode_plot(bl.closed, pair[0], pair[1], check_output(args.plot, "--plot")))
    return 0


def cmd_modes(args):
    """`artibus modes -o DIR`: the stability maps' page (artibus.report.modes), the Scania table printed."""
    import math

    import numpy as np

    from artibus.report import modes as page
    parts = args.speeds.split(":")
    try:
        lo, hi, step = (float(x) for x in parts)
    except ValueError:
        raise ArtibusError(f"--speeds {args.speeds}: expected FROM:TO:STEP in km/h, e.g. 50:130:10") from None
    if not (0 < lo <= hi and step > 0 and math.isfinite(hi)):
        raise ArtibusError(f"--speeds {args.speeds}: speeds > 0 km/h, FROM <= TO, STEP > 0")
    speeds = list(np.arange(lo, hi + step / 2, step))
    if not (args.amplitude > 0 and math.isfinite(args.amplitude)):
        raise ArtibusError(f"--amplitude {args.amplitude}: an articulation amplitude > 0 deg")
    where, smap = page.write(args.output, speeds, args.mu_rear, math.radians(args.amplitude),
                             mus=None if args.no_friction else page.MUS)
    print("\n".join(page.text_table(smap)))
    print(where)
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
