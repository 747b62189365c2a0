"""The command line's parser (``Parser``: an unknown option answered with the nearest one) and
`artibus simulate`'s options, with FMPy's and fmusim's names for them as aliases (issue 38):
a user of `fmpy simulate` (FMPy's command line) or of the Reference-FMUs' `fmusim` keeps the
words they know. Ours first, then theirs:

  -o/--output          FMPy --output-file, fmusim --output-file
  --step               FMPy --step-size (FMPy's fixed solver step in Model Exchange; here the
                       communication step; FMPy and fmusim step a Co-Simulation FMU at the
                       output interval, as --output-interval without --step does here)
  --start-time         FMPy, fmusim --start-time
  --stop-time          FMPy, fmusim --stop-time
  --output-interval    FMPy, fmusim: the results every so many seconds (without --step: the
                       communication step, as both take it in Co-Simulation)
  --relative-tolerance FMPy; fmusim --tolerance: told to the FMU (setupExperiment / fmi3
                       EnterInitializationMode)
  --set NAME=VALUE     FMPy --start-values NAME VALUE [NAME VALUE ...]; fmusim --start-value
                       NAME VALUE (again for each)
  --input-file FILE    FMPy, fmusim: a CSV of the inputs (artibus.fmu.inputs)
  --fmi-type           FMPy CoSimulation|ModelExchange; fmusim --interface-type cs|me
  --fmi-logging        FMPy --fmi-logging and --debug-logging, fmusim --log-fmi-calls: the FMU
                       logs (loggingOn) and its messages are printed to stderr
  --record NAME ...    FMPy --output-variables: the variables recorded (default: every output
                       but Binary and Clock ones; a Binary as hex text)
"""
import argparse
import sys

from artibus.base import ArtibusError, arg_seconds


def _positive(text):
    x = arg_seconds(text)
    if not x > 0:
        raise argparse.ArgumentTypeError(f"{text}: expected a number > 0")
    return x


def _real(text):
    from artibus.base import parse_real
    try:
        return parse_real(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text}: not a number") from None


def _finite(text):
    import math
    x = _real(text)
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{text}: expected a finite number of seconds")
    return x


def add_simulate_options(s):
    """The options of `artibus simulate` on its parser ``s`` (the FMU and --fmi are the caller's)."""
    s.add_argument("--ssv", help="parameter set: name in ssp/parameters or path of an .ssv")
    s.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a parameter or an input's start value")
    s.add_argument("--start-values", nargs="+", metavar="NAME VALUE",
                   help="FMPy's form of --set: NAME VALUE pairs")
    s.add_argument("--start-value", nargs=2, action="append", metavar=("NAME", "VALUE"),
                   help="fmusim's form of --set")
    s.add_argument("--start-time", type=_finite, default=0.0, help="s (default 0)")
    s.add_argument("--stop-time", type=arg_seconds, help="s (default: the FMU's default experiment)")
    s.add_argument("--step", "--step-size", type=_positive, dest="step",
                   help="communication step, s (default: the default experiment's, else (stop - start) / 500)")
    s.add_argument("--output-interval", type=_positive,
                   help="results every so many s, a whole number of steps (without --step: the step)")
    s.add_argument("--relative-tolerance", "--tolerance", type=_real, dest="tolerance",
                   help="the relative tolerance the FMU is told (its own solver's)")
    s.add_argument("--input-file", metavar="CSV",
                   help="inputs: a time column, a column per input (FMPy's and the cross-check's CSV)")
    s.add_argument("--fmi-type", "--interface-type", dest="fmi_type",
                   choices=["CoSimulation", "ModelExchange", "cs", "me"], default=None,
                   help="the FMU's interface: Co-Simulation, or Model Exchange integrated with CVODE "
                        "(default: Co-Simulation where the FMU has it)")
    s.add_argument("--me-method", choices=["bdf", "adams"], default=None,
                   help="Model Exchange: CVODE's BDF (default, stiff-safe) or Adams")
    s.add_argument("--me-jacobian", action="store_true",
                   help="Model Exchange: CVODE's Jacobian from the FMU's directional derivatives "
                        "(default: its difference quotients)")
    s.add_argument("--fmi-logging", "--debug-logging", "--log-fmi-calls", action="store_true", dest="fmi_logging",
                   help="the FMU logs (loggingOn): its messages printed to stderr")
    s.add_argument("-o", "--output", "--output-file", metavar="FILE", dest="output",
                   help="results: .csv, .parquet, .mf4 or .mat, by the extension (default: <FMU>.csv)")
    s.add_argument("--record", "--output-variables", action="extend", nargs="+", metavar="NAME", dest="record",
                   help="the variables recorded (default: every output but Binary and Clock ones); a Binary "
                        "as hex text, a clocked variable at its clock's ticks")


def start_values(args):
    """{name: text} of --start-values and --start-value (FMPy's and fmusim's --set)."""
    out = {}
    pairs = list(args.start_values or [])
    if len(pairs) % 2:
        raise ArtibusError(f"--start-values {' '.join(pairs)}: expected NAME VALUE pairs")
    for name, value in zip(pairs[::2], pairs[1::2]):
        out[name] = value
    for name, value in args.start_value or []:
        out[name] = value
    return out


def check_interface(args, model, path):
    """--fmi-type: the interface the FMU runs in, "cs" or "me" (Model Exchange: integrated by
    the stepping core's ME facade, artibus.fmu.me); without it Co-Simulation where the FMU has
    it, else Model Exchange (as FMPy chooses). An interface the FMU lacks is refused by name."""
    if args.fmi_type is None:        # (neither: Co-Simulation, which artibus.fmu.Fmu refuses by name)
        return "me" if model.coSimulation is None and model.modelExchange is not None else "cs"
    want = "me" if args.fmi_type in ("ModelExchange", "me") else "cs"
    if want == "me" and model.modelExchange is None:
        raise ArtibusError(f"{path}: --fmi-type {args.fmi_type}: {model.modelName} has no Model Exchange "
                           "interface (it runs in Co-Simulation: --fmi-type CoSimulation)")
    if want == "cs" and model.coSimulation is None:
        raise ArtibusError(f"{path}: --fmi-type {args.fmi_type}: {model.modelName} has no Co-Simulation "
                           "interface (it runs in Model Exchange: --fmi-type ModelExchange)")
    return want


def input_file(path, model, given):
    """The InputTable of --input-file (artibus.fmu.inputs), or None; the inputs neither it nor
    ``given`` (--set) gives warned of."""
    if path is None:
        return None
    from artibus.fmu.inputs import read_input_file
    table = read_input_file(path, model)
    table.missing = [n for n in table.missing if n not in given]
    if table.missing:
        print(f"artibus: warning: --input-file {path} gives no column for the input"
              f"{'s' if len(table.missing) > 1 else ''} {', '.join(table.missing)} of {model.modelName}: "
              f"{'they keep their' if len(table.missing) > 1 else 'it keeps its'} start value", file=sys.stderr)
    return table


class Parser(argparse.ArgumentParser):
    """argparse's parser; an unknown option answered with the nearest option of the verb
    given (`simulate --output-fil`: did you mean --output-file?)."""

    def parse_args(self, args=None, namespace=None):
        self._argv = list(sys.argv[1:] if args is None else args)
        return super().parse_args(args, namespace)

    def error(self, message):
        if message.startswith("unrecognized arguments: "):
            message += _nearest_options(self, getattr(self, "_argv", []), message.split(": ", 1)[1].split())
        super().error(message)


def _nearest_options(parser, argv, unknown):
    """"; did you mean ...?" for the unknown options, from the options of the verb in argv."""
    import difflib
    verbs = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})
    verb = next((verbs[w] for w in argv if w in verbs), parser)
    known = [o for a in verb._actions for o in a.option_strings]
    said = []
    for u in unknown:
        close = difflib.get_close_matches(u.split("=", 1)[0], known, n=1, cutoff=0.6) if u.startswith("-") else []
        if close:
            said.append(f"{u}: did you mean {close[0]}?")
    return f" ({'; '.join(said)})" if said else ""
