"""The artibus command line: verbs in the user's words.

  artibus info FMU                     variables, defaults and the default experiment
  artibus simulate FMU [options]       run one FMU alone, write CSV (and a plot)
  artibus demo [-o DIR]                the main job (for now): the Urbino 18 pusher on an S-curve
"""
import argparse
import math
import sys
from pathlib import Path

from artibus import ArtibusError, fmu_path


def _fmu_arg(text):
    p = Path(text)
    return p if p.suffix == ".fmu" else fmu_path(text)


def _parse_set(items):
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep:
            raise ArtibusError(f"--set {item}: expected NAME=VALUE")
        values[name.strip()] = value.strip()
    return values


def cmd_info(args):
    from fmpy import read_model_description
    md = read_model_description(str(_fmu_arg(args.fmu)))
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


def cmd_simulate(args):
    from artibus.parameters import read_parameters, check_against
    from artibus.simulation import simulate
    fmu = _fmu_arg(args.fmu)
    params = read_parameters(args.ssv, fmu) if args.ssv else {}
    extra = _parse_set(args.set)
    check_against(extra, fmu, "--set")
    params.update(extra)
    result = simulate(fmu, parameters=params, stop_time=args.stop_time, step=args.step)
    out = Path(args.output or f"{fmu.stem}.csv")
    result.to_csv(out)
    print(f"{out}: {len(result.rows)} rows")
    return 0


def cmd_demo(args):
    """Urbino 18 Electric (seed 003, Table I) pushed at 3 m/s through an
    S-curve: 25 deg left, 25 deg right, straight; results and a plot."""
    from artibus.parameters import read_parameters
    from artibus.plots import plot_path
    from artibus.simulation import simulate
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    fmu = fmu_path("BusKinematics")
    params = read_parameters("Urbino18", fmu)
    params["testSteerAmp"] = 0.0
    amp, period = math.radians(25.0), 24.0

    def gammaF(t):
        return amp * math.sin(2 * math.pi * t / period) if t < period else 0.0

    result = simulate(fmu, parameters=params, inputs={"gammaF": gammaF, "v": lambda t: 3.0},
                      stop_time=40.0, step=0.05)
    csv = out / "BusKinematics_Urbino18_SCurve.csv"
    png = out / "BusKinematics_Urbino18_SCurve.png"
    result.to_csv(csv)
    plot_path(result, 1, png, "Urbino 18 pusher, S-curve at 3 m/s (seed 003 model)")
    bmax = max(abs(result["beta[1]"]))
    print(f"demo: {csv}\ndemo: {png}\nmax |beta[1]| = {math.degrees(bmax):.1f} deg "
          f"(Urbino 18 mechanical limit 54 deg, seed 003 Table I)")
    return 0


def build_parser():
    p = argparse.ArgumentParser(prog="artibus", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="verb", required=True)
    s = sub.add_parser("info", help="show an FMU's variables")
    s.add_argument("fmu", help="path of an .fmu, or the name of a built FMU")
    s.set_defaults(func=cmd_info)
    s = sub.add_parser("simulate", help="run one FMU alone")
    s.add_argument("fmu", help="path of an .fmu, or the name of a built FMU")
    s.add_argument("--ssv", help="parameter set: name in ssp/parameters or path of an .ssv")
    s.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a parameter")
    s.add_argument("--stop-time", type=float)
    s.add_argument("--step", type=float)
    s.add_argument("-o", "--output", help="CSV file (default: <FMU>.csv)")
    s.set_defaults(func=cmd_simulate)
    s = sub.add_parser("demo", help="the main job: a demo run with results and a plot")
    s.add_argument("-o", "--output", default="out", help="output directory (default: out)")
    s.set_defaults(func=cmd_demo)
    return p


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except ArtibusError as e:
        print(f"artibus: error: {e}", file=sys.stderr)
        log = getattr(e, "log", None)
        if log:
            print("FMU log:\n  " + "\n  ".join(log[-10:]), file=sys.stderr)
        result = getattr(e, "result", None)
        if result is not None and result.rows and getattr(args, "output", None):
            partial = Path(str(args.output) + ".partial.csv")
            result.to_csv(partial)
            print(f"artibus: partial results up to the failure: {partial}", file=sys.stderr)
        return 1
