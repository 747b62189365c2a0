"""The artibus command line: verbs in the user's words.

  artibus run BENCH [options]          run an SSP bench (a name from `artibus list`, or an .ssp);
                                       --variant NAME selects one of its parameter-set variants
  artibus list [--parameters]          the benches and FMUs, one line each (--parameters: every bound value)
  artibus info BENCH|FMU               a bench's components and connections, or an FMU's variables
  artibus simulate FMU [options]       run one FMU alone, write CSV
  artibus check SSV...                 a vehicle parameter set's consistency (axles, hinges, loads, inertia)
  artibus sweep BENCH --grid C.V=A,B   many cases on Dask (grid, --variant axis, --design CSV/YAML), resumable
  artibus plot RESULTS.csv SIGNAL...   a PNG of signals of a results file, a panel per unit
  artibus bode BENCH --input C.V --measure C.V  gain and phase by sine tests through the co-simulation
  artibus calibrate [-o FILE.ssv]      the damping controller's gains (seed 001, 5.2.2)
  artibus linearize FMU [--steady]     A, B, C, D of one Model Exchange FMU at an operating point (--at T,
                                       --steady); its modes: frequency, damping ratio, dominant state
  artibus linearize BENCH [--variant V] a bench's ME plants with its controllers in the loop (--at T: at a
                                       time of its run, --steady, --exclude C, --amplitude C.V=A: the
                                       loop's describing function)
  artibus modes -o DIR                 stability maps over speed (seed 001's sway, seed 004's FWS/MAS), a page
  artibus can decode LOG [--csv OUT]   a CAN log (.blf, .asc) decoded through the DBC
  artibus can plot LOG [--signal S]    a CAN log's frame timing and decoded signals as a PNG
  artibus replay LOG --bench BENCH     a recorded log (.csv, .blf, .asc) drives a bench; model against measured
  artibus pack [BENCH...]              pack ssp/benches/<BENCH> into fmus/<BENCH>.ssp (--all-platforms:
                                       build every platform's binaries into the FMUs first); --portable
                                       [--variant V]: a pack other SSP masters run as we do
  artibus demo [--report DIR]          the kinematic demo: the Urbino 18 pusher on an S-curve

Throughout: -o/--output FILE is the results file a command writes (run,
simulate, replay: .csv, .parquet, .mf4 or .mat by the extension), --report DIR
a directory of plots and HTML. Files are written
under a temporary name and renamed, so a file under its final name is always
complete. Ctrl-C (SIGINT) or SIGTERM during a run saves the results up to then
as OUT.partial.EXT (OUT.partial.csv, OUT.partial.mf4, ...) and exits with 130 (143).
"""
# (the docstring above is `artibus --help`'s.) Here: the parser, a function per verb, and main;
# what each verb does is a cmd_<verb> of artibus.commands, artibus.analysis or artibus.inventory.
import argparse
import signal
import sys

from artibus.console import path_error, quiet_exit, stdout_gone
from artibus.base import ArtibusError, __version__, arg_integer, arg_real, arg_seconds
from artibus import files
from artibus.files import report_said
from artibus.bench.fmi import add_fmi_option
from artibus.analysis import cmd_bode, cmd_calibrate, cmd_linearize, cmd_modes
from artibus.commands import (cmd_can_decode, cmd_can_plot, cmd_check, cmd_demo, cmd_pack, cmd_plot, cmd_replay,
                              cmd_run, cmd_simulate, cmd_sweep)
from artibus.inventory import cmd_info, cmd_list
from artibus.options import Parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, as Ctrl-C raises KeyboardInterrupt:
    the same clean-up (temporary directories, partial results) runs for both."""
    signum = signal.SIGTERM


def _on_sigterm(signum, frame):
    raise Terminated()


def build_parser():
    """The command line: a sub-command a verb (``_verb_<name>``: its arguments)."""
    p = Parser(prog="artibus", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"artibus {__version__}")
    sub = p.add_subparsers(dest="verb", required=True)
    _verb_run(sub)
    _verb_plot(sub)
    _verb_can(sub)
    _verb_replay(sub)
    _verb_bode(sub)
    _verb_linearize(sub)
    _verb_modes(sub)
    _verb_calibrate(sub)
    _verb_list(sub)
    _verb_pack(sub)
    _verb_info(sub)
    _verb_simulate(sub)
    _verb_check(sub)
    _verb_demo(sub)
    _verb_sweep(sub)
    return p


def _verb_run(sub):
    """`artibus run`: a bench (or every bench), its report, results, CAN, Model Exchange and reference options"""
    s = sub.add_parser("run", help="run an SSP bench")
    s.add_argument("bench", nargs="?", help="a bench name (see `artibus list`) or the path of an .ssp")
    s.add_argument("--all", action="store_true", help="run every bench")
    s.add_argument("--report", metavar="DIR", help="write plots and an HTML page with the KPIs to DIR")
    s.add_argument("--stop-time", type=arg_seconds, help="default: the bench's DefaultExperiment")
    s.add_argument("--step", "--step-size", type=arg_seconds, dest="step",
                   help="base communication step, s (--step-size: FMPy's name)")
    s.add_argument("--single-rate", action="store_true",
                   help="every component at the one (base) step, as a master without multi-rate steps runs it")
    s.add_argument("--ssv", action="append", help="parameter file with names COMPONENT.VARIABLE")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE", help="set a parameter")
    s.add_argument("--variant", action="append", metavar="NAME",
                   help="a variant of the bench (its parameter set variants/NAME.ssv; see `artibus list`); "
                        "repeatable, later ones win; applied before --ssv and --set")
    s.add_argument("--record", action="append", metavar="COMP.VAR",
                   help="record this variable (default: every connected output)")
    s.add_argument("--algorithm", default="gauss-seidel", choices=["gauss-seidel", "jacobi"])
    s.add_argument("-o", "--output", "--output-file", metavar="FILE", dest="output",
                   help="results: .csv, .parquet, .mf4 (ASAM MDF 4) or .mat, by the extension (default: "
                        "<bench>.csv, with --report DIR/results.csv); checked before the run; a run stopped by "
                        "Ctrl-C/SIGTERM leaves FILE.partial.EXT")
    s.add_argument("--can", metavar="virtual|INTERFACE:CHANNEL",
                   help="for a bench that routes connections over CAN: python-can's virtual bus "
                        "(the default) or a real interface, e.g. socketcan:vcan0")
    s.add_argument("--can-log", metavar="FILE.blf|FILE.asc|FILE.mf4",
                   help="write the CAN traffic (simulated time; .mf4: ASAM MDF 4 CAN bus logging)")
    s.add_argument("--can-fault", action="append", metavar="SPEC",
                   help="inject a fault into the CAN network (repeatable): loss:MSG|NODE:RATE[:seed=N], "
                        "latency:MSG|NODE:DELAY_S[:jitter=S][:seed=N], corrupt:MSG|NODE:crc|repeat|skip[:rate=R], "
                        "silent:NODE, busoff:NODE[:recover[=DELAY_S]]; each may end in @T0 or @T0-T1 (s). "
                        "With --report, the fault-free run's KPIs are printed and written beside the faulty ones")
    s.add_argument("--fmi-type", "--interface-type", dest="fmi_type",
                   choices=["CoSimulation", "ModelExchange", "cs", "me"], default=None,
                   help="ModelExchange|me: every FMU that has Model Exchange runs as ME, integrated with CVODE "
                        "by the stepping core (default: Co-Simulation)")
    s.add_argument("--relative-tolerance", "--tolerance", type=float, dest="tolerance",
                   help="the Model Exchange FMUs' integrator's relative tolerance (default: their default "
                        "experiment's, else 1e-6)")
    s.add_argument("--reference", action="store_true",
                   help="the bench's monolithic reference (issue 44): every component that has Model Exchange "
                        "integrated together in one CVODE (relative tolerance 1e-8 unless given), the sampled "
                        "controllers, the driver, the ECUs and the network as they are")
    s.add_argument("--me-method", choices=["bdf", "adams"], default=None,
                   help="the Model Exchange FMUs' integrator: CVODE's BDF (default, stiff-safe) or Adams")
    s.add_argument("--me-jacobian", action="store_true",
                   help="the Model Exchange FMUs' Jacobian from their directional derivatives where they "
                        "provide them (default: CVODE's difference quotients)")
    s.add_argument("--input-file", metavar="CSV",
                   help="drive the bench's free (unconnected) inputs: a time column, a column per input "
                        "COMPONENT.VARIABLE (as simulate's --input-file)")
    add_fmi_option(s, "run")
    s.set_defaults(func=cmd_run)


def _verb_plot(sub):
    """`artibus plot`: signals of a results file as a PNG"""
    s = sub.add_parser("plot", help="a PNG of signals of a results CSV, a panel per unit")
    s.add_argument("results", metavar="RESULTS.csv", help="a results file of artibus run or simulate")
    s.add_argument("signal", nargs="+", metavar="SIGNAL",
                   help="a column name, e.g. Bus.artAngle[1]; '*' matches any text (Bus.artAngle[*])")
    s.add_argument("-o", "--output", metavar="FILE.png", help="default: RESULTS with .png")
    s.set_defaults(func=cmd_plot)


def _verb_can(sub):
    """`artibus can decode|plot`: a CAN log's signals"""
    s = sub.add_parser("can", help="CAN tools: decode or plot a log")
    can_sub = s.add_subparsers(dest="can_verb", required=True)
    c = can_sub.add_parser("decode", help="print or export (CSV) the signals of a .blf/.asc log")
    c.add_argument("log", help="a .blf or .asc file")
    c.add_argument("--dbc", help="default: ssp/can/Bus36m.dbc")
    c.add_argument("--csv", metavar="OUT", help="write CSV instead of printing")
    c.set_defaults(func=cmd_can_decode)
    c = can_sub.add_parser("plot", help="a .blf/.asc log's frame timing and decoded signals as a PNG")
    c.add_argument("log", help="a .blf or .asc file")
    c.add_argument("--signal", action="append", metavar="MESSAGE.SIGNAL",
                   help="a decoded signal to plot (repeatable; SIGNAL alone where unique; '*' matches any text)")
    c.add_argument("--dbc", help="default: ssp/can/Bus36m.dbc")
    c.add_argument("-o", "--output", metavar="FILE.png", help="default: LOG with .png")
    c.set_defaults(func=cmd_can_plot)


def _verb_replay(sub):
    """`artibus replay`: a bench driven by a recorded log"""
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
    s.add_argument("--stop-time", type=arg_seconds, help="default: the end of the driving signals")
    s.add_argument("-o", "--output", metavar="FILE",
                   help="results: .csv, .parquet, .mf4 or .mat (default <log>_replay.csv)")
    s.add_argument("--report", metavar="DIR", help="plots of model against measured and errors.csv")
    add_fmi_option(s, "replay")
    s.set_defaults(func=cmd_replay)


def _verb_bode(sub):
    """`artibus bode`: a frequency response through the co-simulation"""
    s = sub.add_parser("bode", help="frequency response through the co-simulation (sine tests)")
    s.add_argument("bench", help="a bench name or the path of an .ssp")
    s.add_argument("--input", required=True, metavar="COMP.VAR", help="the input the sine is added to")
    s.add_argument("--measure", action="append", metavar="COMP.VAR", help="an output to measure (repeatable)")
    s.add_argument("--fmin", type=arg_real, default=0.05, help="lowest frequency, Hz")
    s.add_argument("--fmax", type=arg_real, default=5.0, help="highest frequency, Hz")
    s.add_argument("--n", type=arg_integer, default=12, help="frequencies, log-spaced")
    s.add_argument("--amplitude", type=arg_real, default=0.01, help="sine amplitude, in the input's unit")
    s.add_argument("--periods", type=arg_integer, default=4, help="periods fitted after the transient")
    s.add_argument("--settle", type=arg_real, help="time given to the transient, s")
    s.add_argument("--step", type=arg_seconds)
    s.add_argument("--variant", action="append", metavar="NAME", help="a variant of the bench (repeatable)")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE")
    s.add_argument("-o", "--output", "--output-file", metavar="FILE",
                   help="results CSV (gain, phase in deg); written only when given")
    s.add_argument("--plot", metavar="FILE.png", help="PNG with gain and phase")
    add_fmi_option(s, "bode")
    s.set_defaults(func=cmd_bode)


def _verb_linearize(sub):
    """`artibus linearize`: the linear model of an FMU or a bench at an operating point"""
    s = sub.add_parser("linearize", help="A, B, C, D of one Model Exchange FMU at an operating point, "
                                         "its modes (frequency, damping ratio, dominant state)")
    s.add_argument("fmu", help="path of an .fmu, or the name of a built FMU (it needs Model Exchange), "
                               "or a bench (its ME plants with the rest of the bench in the loop)")
    s.add_argument("--variant", action="append", metavar="NAME", help="a bench's variant (repeatable)")
    s.add_argument("--exclude", action="append", metavar="COMPONENT",
                   help="a bench's component left out: what it drives becomes an open input (repeatable)")
    s.add_argument("--amplitude", metavar="C.V=A",
                   help="a bench's loop linearised by its first harmonic at amplitude A of plant output C.V")
    # (--at and --steady exclude each other: said in one line by cmd_linearize, not by argparse's usage)
    s.add_argument("--at", type=arg_real, metavar="TIME",
                   help="simulate to TIME first, s (one FMU: ME, inputs held; a bench: its run)")
    s.add_argument("--steady", action="store_true", help="simulate until the dynamic states are at rest")
    s.add_argument("--ssv", help="a parameter set (.ssv, or a name in ssp/parameters) for the FMU")
    s.add_argument("--set", action="append", metavar="NAME=VALUE", help="a parameter or an input's held value")
    s.add_argument("--inputs", metavar="A,B", help="the inputs (default: every continuous Real input)")
    s.add_argument("--outputs", metavar="Y,Z", help="the outputs (default: every continuous Real output)")
    s.add_argument("--derivatives", choices=["auto", "fd", "exact"], default="auto",
                   help="auto: the FMU's directional derivatives where it provides them, else finite differences")
    s.add_argument("--fd-step", type=arg_seconds, default=1e-5, metavar="H",
                   help="finite differences' step, times each state's and input's nominal (default 1e-5)")
    s.add_argument("-o", "--output", metavar="FILE", help="the matrices: FILE.mat (MATLAB) or FILE.csv")
    s.add_argument("--bode", metavar="IN:OUT", help="the linear model's Bode plot from IN to OUT (with --plot)")
    s.add_argument("--plot", metavar="FILE.png", help="where the Bode plot goes")
    s.set_defaults(func=cmd_linearize)


def _verb_modes(sub):
    """`artibus modes`: the stability maps"""
    s = sub.add_parser("modes", help="stability maps: seed 001's sway mode with each damping function and "
                                     "seed 004's FWS/MAS over speed, a page with plots")
    s.add_argument("-o", "--output", required=True, metavar="DIR", help="where the page and its PNGs go")
    s.add_argument("--speeds", default="50:130:10", metavar="FROM:TO:STEP", help="km/h (default 50:130:10)")
    s.add_argument("--mu-rear", type=arg_real, default=1.0, help="the Scania's rear axle friction (default 1)")
    s.add_argument("--amplitude", type=arg_real, default=2.0, metavar="DEG",
                   help="articulation amplitude of the hinge's describing function, deg (default 2)")
    s.add_argument("--no-friction", action="store_true",
                   help="leave out the map over rear friction at 100 km/h (30 linearisations)")
    s.set_defaults(func=cmd_modes)


def _verb_calibrate(sub):
    """`artibus calibrate`: the damping controller's gains"""
    s = sub.add_parser("calibrate", help="the damping controller's gains (seed 001, 5.2.2), printed; "
                                         "-o FILE.ssv writes them")
    s.add_argument("--target", type=arg_real, default=13.5, help="peak damping on the 200 m / 100 km/h case, %%")
    s.add_argument("-o", "--output", metavar="FILE.ssv",
                   help="write the gains as a parameter set (the benches': ssp/parameters/DampingGains.ssv)")
    s.add_argument("--dry-run", action="store_true", help="print the gains, write nothing (also without -o)")
    s.set_defaults(func=cmd_calibrate)


def _verb_list(sub):
    """`artibus list`"""
    s = sub.add_parser("list", help="the benches and FMUs, one line each")
    s.add_argument("--parameters", action="store_true", help="every bench's bound parameter values too")
    s.set_defaults(func=cmd_list)


def _verb_pack(sub):
    """`artibus pack`: self-contained and portable .ssp files"""
    s = sub.add_parser("pack", help="pack benches into self-contained .ssp files")
    s.add_argument("bench", nargs="*", help="default: every bench in ssp/benches (with --portable: every CAN-free one)")
    s.add_argument("--portable", action="store_true",
                   help="a pack other SSP masters run as we do (ecos, libcosim, FMPy): each component's parameters "
                        "resolved into one inline parameter set 'bench'; fmus/<BENCH>[_<VARIANT>].portable.ssp")
    s.add_argument("--variant", action="append", metavar="NAME",
                   help="with --portable: a variant of the bench resolved into the pack (repeatable, later ones win)")
    s.add_argument("-o", "--output", metavar="FILE", help="with --portable and one BENCH: the pack's path")
    s.add_argument("--all-platforms", action="store_true",
                   help="first build every platform's binaries (win64 with mingw-w64) into the FMUs "
                        "(scripts/setup.sh --all-platforms, a few minutes the first time)")
    add_fmi_option(s, "pack")
    s.set_defaults(func=cmd_pack)


def _verb_info(sub):
    """`artibus info`"""
    s = sub.add_parser("info", help="show an FMU's variables or a bench's structure")
    s.add_argument("fmu", metavar="BENCH|FMU", help="a bench name, the name of a built FMU, or the path of an .ssp or .fmu")
    s.set_defaults(func=cmd_info)


def _verb_simulate(sub):
    """`artibus simulate`: one FMU alone (FMPy's and fmusim's option names too)"""
    s = sub.add_parser("simulate", help="run one FMU alone")
    s.add_argument("fmu", help="path of an .fmu, or the name of a built FMU")
    from artibus.options import add_simulate_options      # (with FMPy's and fmusim's names)
    add_simulate_options(s)
    add_fmi_option(s, "simulate")
    s.set_defaults(func=cmd_simulate)


def _verb_check(sub):
    """`artibus check`: a parameter set's consistency, or a bench's portability"""
    s = sub.add_parser("check", help="check a vehicle parameter set's consistency (axles, hinges, loads, inertia), "
                                     "or what of a bench other SSP masters run differently")
    s.add_argument("ssv", nargs="+", help="a parameter set (path of an .ssv or a name in ssp/parameters) "
                                          "or a bench (a name or an .ssp)")
    s.add_argument("--model", choices=["BusDynamics", "BusKinematics"], help="default: from the names in the set")
    s.set_defaults(func=cmd_check)


def _verb_demo(sub):
    """`artibus demo`"""
    s = sub.add_parser("demo", help="the kinematic demo (Urbino 18 on an S-curve): results, plots and a page")
    s.add_argument("--report", metavar="DIR", default="out", help="directory of results and plots (default: out)")
    s.add_argument("-o", "--output", metavar="FILE", help="results CSV (default: DIR/BusKinematics_Urbino18_SCurve.csv)")
    s.set_defaults(func=cmd_demo)


def _verb_sweep(sub):
    """`artibus sweep`: many cases of a bench on Dask"""
    s = sub.add_parser("sweep", help="run many cases of a bench on Dask (grid, design file), resumable")
    s.add_argument("bench", help="a bench name (see `artibus list`) or the path of an .ssp")
    s.add_argument("--grid", nargs="+", action="extend", metavar="COMP.VAR=VALUES",
                   help="an axis: COMP.VAR=V1,V2,... or COMP.VAR=START:STOP:STEP (stop included)")
    s.add_argument("--variant", action="append", metavar="A,B,...",
                   help="an axis of the bench's variants (repeatable: each one more axis)")
    s.add_argument("--design", metavar="FILE", help="the cases from a .csv (a case a row) or .yaml "
                                                    "(grid, lhs or montecarlo with a seed)")
    s.add_argument("-o", "--out", default=None, help="output folder (default: sweep-<BENCH>)")
    s.add_argument("--stop-time", type=arg_seconds, help="every case's stop time (default: the bench's)")
    s.add_argument("--step", type=arg_seconds, help="base communication step, s")
    s.add_argument("--set", action="append", metavar="COMP.VAR=VALUE", help="a parameter of every case")
    s.add_argument("--keep-series", action="store_true", help="keep each case's time series (series/<key>.parquet)")
    s.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler (tcp://host:8786)")
    s.add_argument("--workers", type=arg_integer, help="local worker processes (default: one per core)")
    s.add_argument("--retry-failed", action="store_true", help="run the cases recorded as failed again")
    s.add_argument("--kpi", help="the KPI of the study plot and the worst cases (default: the bench's first)")
    s.add_argument("--error-every", type=arg_integer, default=0, metavar="N",
                   help="every N-th case run again at half the continuous components' step: each KPI's "
                        "co-simulation error, a column 'KPI [unit] cosim error' (issue 44; default 0: none)")
    add_fmi_option(s, "sweep")
    s.set_defaults(func=cmd_sweep)


def main(argv=None):
    args = build_parser().parse_args(argv)
    files.REPORTS_DONE.clear()
    import threading
    previous = previous_int = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _on_sigterm)   # SIGTERM unwinds as Ctrl-C does
        # Ctrl-C stops a run even where the shell started us with SIGINT ignored
        # (a background job of a script: Python then installs no handler of its own)
        previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code = args.func(args)
        sys.stdout.flush()             # (a reader gone: the BrokenPipeError here, not at the exit)
        return code
    except BrokenPipeError:            # `artibus list | head -1`: the reader has all it wanted
        if not stdout_gone():
            raise
        return quiet_exit()
    except OSError as e:               # a name longer than the file system allows: one line
        if path_error(e) is None:
            raise
        print(f"artibus: error: {path_error(e)}", file=sys.stderr)
        return 1
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
        print(f"artibus: stopped by {sig.name}; {report_said(e, what)}", file=sys.stderr)
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


def console():
    """The program's entry (`artibus`, `python -m artibus`): main's exit status as the process's.
    After an interrupt main has handled (130, 143: its results, partial results and report said
    and in place), the process ends with that status at once: CPython ends a process whose
    interpreter once saw a KeyboardInterrupt leave code it ran itself by killing itself with
    SIGINT at exit (exit status -2 instead of 130, seen 1 run in 8 of `run --report` interrupted
    at its first line), which tells a calling script the wrong story."""
    import os
    code = main()
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)
    raise SystemExit(code)

