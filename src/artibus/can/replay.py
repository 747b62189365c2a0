"""Log replay (issue 12): a recorded log drives a bench in place of its driver,
and the responses the log also carries are compared with the model's, as
seed 003, section V does (Figs. 9-11).

- A log is a CSV (comment lines ``#``, a header row with ``time_s`` and one
  column per signal, empty cells where a signal has no sample) or a CAN log
  (.blf, .asc) decoded through a DBC: its signals are ``Signal`` or
  ``Message.Signal``; only frames that pass the receivers' E2E check
  (``artibus.can.decode_log``: CRC, counter) are used, each from the start of
  the cycle it was sent in (the frame's time rounded down to its message's
  cycle time: frames are sent within their cycle).
- Each driving signal feeds a component input (``--map SIGNAL=COMP.INPUT``,
  or the bench's replay profile below), held from one sample to the next
  (zero-order hold) and sampled at the start of the component's step; an input
  the bench connects is cut from its source (its connection, or its route over
  CAN) for the replay (``runner.Simulation(cut=...)``).
- A CAN log replayed into a bench that routes connections over CAN replaces
  the network: every routed input (data signals and the alive counters the
  receivers check) is fed from the log's frames of its route's message and
  signal, the frame of cycle k from the start of cycle k on, as the network
  delivers it; with every route cut the run has no network. What else the
  bench connects stays in the loop (a driver, the mechanics), unless ``--map``
  feeds it too (e.g. ``SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1]``: the
  front wheels at the sensor's recorded angle). The log's signals that were
  sent from a plant output are compared with that output. Units: a CSV column's unit is given in the map
  (``alpha[deg]=Bus.gammaF``) or the profile, a CAN signal's is the DBC's;
  both are converted to the input's unit.
- A replay profile (PROFILES, by bench) names the driving signals, a static map
  of a sensor to the input (seed 003 Appendix A: the steering sensor's angle
  to the effective steering angle, a polynomial per bus as a parameter set),
  the start state taken from the log's first samples (seed 003: "the model
  outputs were initialized with the first measurement data points"), and the
  measured responses compared with the model's.
"""
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from artibus.base import ROOT, ArtibusError, parse_real
from artibus.bench.units import declared_unit
from artibus.can.dbc import COUNTER_SIGNAL, CRC_SIGNAL, UNITS, _conversion, load_dbc
from artibus.can.logs import decode_log

DEG = math.pi / 180


@dataclass
class Series:
    """One signal of a log: sample times (s), values (in `unit`); period: how
    long the last sample holds (a CAN message's cycle; 0 for a CSV column)."""
    name: str
    time: np.ndarray
    value: np.ndarray
    unit: str = ""
    period: float = 0.0

    def hold(self):
        """f(t): the last sample at or before t (the first before it)."""
        t, v = self.time, self.value

        def f(x):
            i = int(np.searchsorted(t, x + 1e-9, side="right")) - 1
            return float(v[max(i, 0)])
        return f


def read_csv_log(path):
    """{column: Series} of a CSV log; empty cells are missing samples."""
    path = Path(path)
    if not path.is_file():
        raise ArtibusError(f"{path}: no such file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise ArtibusError(f"{path}: not a text file (UTF-8): byte {e.start}: {e.reason}") from None
    lines = [l for l in text.splitlines() if l.strip() and not l.lstrip().startswith("#")]
    if not lines:
        raise ArtibusError(f"{path}: no header row")
    header = [h.strip() for h in lines[0].split(",")]
    if header[0] not in ("time_s", "time"):
        raise ArtibusError(f"{path}: the first column must be time_s (the time in s), not '{header[0]}'")
    cols = [[] for _ in header]
    for n, line in enumerate(lines[1:], start=2):
        cells = line.split(",")
        if len(cells) != len(header):
            raise ArtibusError(f"{path}: data row {n - 1}: {len(cells)} cells, the header has {len(header)}")
        for i, c in enumerate(cells):
            c = c.strip()
            try:
                cols[i].append(parse_real(c) if c else math.nan)
            except ValueError:
                raise ArtibusError(f"{path}: data row {n - 1}, column {header[i]}: '{c}' is not a number") from None
    t = np.array(cols[0])
    if len(t) == 0 or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise ArtibusError(f"{path}: column time_s must be finite and non-decreasing")
    out = {}
    for name, c in zip(header[1:], cols[1:]):
        v = np.array(c)
        ok = np.isfinite(v)
        out[name] = Series(name, t[ok], v[ok])
    return out


def read_can_log(path, dbc, warnings=None):
    """{Signal and Message.Signal: Series} of the frames of a .blf/.asc log that
    pass the E2E check, each valid from the start of its cycle; a message's
    alive counter only as Message.AliveCounter (the counter of each accepted
    frame, what a route of it delivers)."""
    db = load_dbc(dbc) if not hasattr(dbc, "messages") else dbc
    unknown = {}
    rows = decode_log(path, db, unknown)
    if unknown and warnings is not None:
        ids = ", ".join(f"0x{i:03X} ({n})" for i, n in sorted(unknown.items())[:8])
        warnings.append(f"{path}: {sum(unknown.values())} frame(s) with an identifier the DBC does not "
                        f"know, skipped: {ids}{', ...' if len(unknown) > 8 else ''}")
    data = {}
    for t, msg, sig, v, unit, e2e in rows:
        if e2e != "ok" or sig == CRC_SIGNAL:
            continue
        cycle = db.get_message_by_name(msg).cycle_time / 1000.0
        data.setdefault((msg, sig, unit, cycle), []).append((math.floor(t / cycle + 1e-6) * cycle, v))
    out = {}
    for (msg, sig, unit, cycle), samples in data.items():
        a = np.array(samples, dtype=float)
        s = Series(f"{msg}.{sig}", a[:, 0], a[:, 1], unit, cycle)
        out[f"{msg}.{sig}"] = s
        if sig != COUNTER_SIGNAL:
            out.setdefault(sig, s)
    return out


def read_log(path, dbc=None, warnings=None):
    """{signal: Series} of a CSV, .blf or .asc log; warnings: a list that
    receives what was skipped (frames of identifiers the DBC does not know)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return read_csv_log(path)
    if suffix in (".blf", ".asc"):
        return read_can_log(path, dbc or ROOT / "ssp" / "can" / "Bus36m.dbc", warnings)
    raise ArtibusError(f"{path}: a log is .csv, .blf or .asc")


# --- replay profiles ----------------------------------------------------------------

def steering_map(name_or_path):
    """The coefficients c[0..3] (deg) of a seed 003 Appendix A steering map."""
    from artibus.bench.parameters import find_ssv, read_parameters
    f = find_ssv(name_or_path)
    p = read_parameters(f)
    try:
        return [float(p[f"c[{i}]"]) for i in range(4)]
    except KeyError as e:
        raise ArtibusError(f"{f}: a steering map needs c[0] .. c[3] (missing {e})") from None


def map_steering(alpha_deg, c):
    """seed 003, Appendix A: gammaF [deg] = c3 a^3 + c2 a^2 + c1 a + c0."""
    a = np.asarray(alpha_deg, dtype=float)
    return ((c[3] * a + c[2]) * a + c[1]) * a + c[0]


def _kinematic_start(log, params):
    """seed 003, section V: start state from the first samples: the joint angle
    beta1, the wagon's heading theta1 and its axle P1 (DGPS); the tractor's
    heading theta0 = theta1 + beta1 (eq. 3) and its rear axle
    P0 = P1 + L1 u(theta1) + Lh1 u(theta0) (joint Lh1 behind P0, P1 L1 behind the joint)."""
    L1, Lh1 = float(params["L[1]"]), float(params["Lh[1]"])
    b1 = log["beta1_sensor_deg"].value[0] * DEG
    th1 = log["theta1_dgps_deg"].value[0] * DEG
    x1, y1 = log["x1_dgps_m"].value[0], log["y1_dgps_m"].value[0]
    th0 = th1 + b1
    return {"Bus.beta_start[1]": b1, "Bus.theta_start": th0,
            "Bus.x_start": x1 + L1 * math.cos(th1) + Lh1 * math.cos(th0),
            "Bus.y_start": y1 + L1 * math.sin(th1) + Lh1 * math.sin(th0)}


def _omega1_tacho(log, params, cmap):
    """seed 003, eq. 51: the wagon's angular velocity from the on-board signals,
    omega_1tacho. Eq. 51 couples the tractor's omega_0tacho = v0 tan(gammaF) / L0
    to the wagon by J_1(beta_1sensor, 0, 0); the log records the wagon axle's
    speed v1, so the same coupling solved for it: omega_1tacho = kappa_1 v1
    with kappa_1 = sin(delta_1) / (L1 cos(delta_1)) (eq. 20, gamma_1 = 0) and
    delta_1 = beta_1sensor - atan(Lh1 tan(gammaF) / L0) (eq. 17). gammaF from
    the steering sensor through the Appendix A map. At the steering samples,
    the other signals held. Returns a Series in rad/s."""
    L0, L1, Lh1 = (float(params[n]) for n in ("L0", "L[1]", "Lh[1]"))
    a = log["alpha_sensor_deg"]
    t = a.time
    gF = np.radians(map_steering(a.value, cmap))
    b1 = np.radians([log["beta1_sensor_deg"].hold()(x) for x in t])
    v1 = np.array([log["v1_tacho_mps"].hold()(x) for x in t])
    d1 = b1 - np.arctan(Lh1 * np.tan(gF) / L0)                        # eq. 17
    return Series("omega1_tacho (eq. 51)", t, np.sin(d1) / (L1 * np.cos(d1)) * v1, "rad/s")


@dataclass
class Profile:
    drive: dict                     # input -> (log signal, its unit)
    steering: tuple = None          # (input, steering-map parameter set): the signal is alpha_sensor in deg
    compare: list = field(default_factory=list)   # (label, log signal, unit, model output)
    path: tuple = None              # (log x, log y, model x, model y)
    start: object = None            # f(log, bench parameters of the plant) -> overrides
    # input -> (f(log, plant parameters, steering map) -> Series in the input's unit, the Boolean
    # parameter that switches it on, what the run is then called): computed from the log, fed only
    # when a variant or --set switches it on; the bench as it stands is then run too, for the report
    derived: dict = field(default_factory=dict)


PROFILES = {
    # seed 003, section V: inputs gammaF (from the steering sensor, App. A) and v1 (tachometer);
    # compared: beta1 (sensor), theta1 and the path of P1 (DGPS)
    "Urbino18_Replay": Profile(
        drive={"Bus.gammaF": ("alpha_sensor_deg", "deg"), "Bus.v": ("v1_tacho_mps", "m/s")},
        steering=("Bus.gammaF", "Urbino18SteeringMap"),
        compare=[("joint angle beta1", "beta1_sensor_deg", "deg", "Bus.beta[1]"),
                 ("wagon heading theta1", "theta1_dgps_deg", "deg", "Bus.theta[1]")],
        path=("x1_dgps_m", "y1_dgps_m", "Bus.x[1]", "Bus.y[1]"),
        start=_kinematic_start,
        # seed 003, sec. V, Fig. 11: the prediction model (variant prediction: j = 1, predictionModel)
        derived={"Bus.omegaMeas": (_omega1_tacho, "Bus.predictionModel", "prediction model")}),
}


def _parse_map(items):
    """--map SIGNAL[unit]=COMP.INPUT -> {input: (signal, unit or None)}."""
    out = {}
    for item in items or []:
        sig, eq, inp = item.partition("=")
        sig, inp = sig.strip(), inp.strip()
        if not eq or not sig or "." not in inp:
            raise ArtibusError(f"--map {item}: expected SIGNAL=COMP.INPUT or SIGNAL[unit]=COMP.INPUT")
        unit = None
        if sig.endswith("]") and "[" in sig:
            sig, _, unit = sig[:-1].partition("[")
        out[inp] = (sig, unit)
    return out


@dataclass
class Replay:
    result: object
    errors: list          # (label, rms, max, unit)
    log: dict
    profile: Profile
    drive: dict
    label: str = "model"  # what the run is (e.g. "prediction model")
    base: object = None   # (label, result, errors) of the bench as it stands, when a derived input ran
    warnings: list = field(default_factory=list)   # what the reader skipped, a log shorter than the run


def _route_profile(b):
    """A CAN log into a bench that routes connections over CAN: every routed
    input from its route's Message.Signal (unit: the DBC's); every routed data
    signal compared with the output that sent it."""
    drive, compare, seen = {}, [], set()
    for c in b.connections:
        if c.can is None:
            continue
        sig = f"{c.can['message']}.{c.can['signal']}"
        drive[f"{c.end[0]}.{c.end[1]}"] = (sig, None)
        if c.can["signal"] != COUNTER_SIGNAL and sig not in seen:
            seen.add(sig)
            compare.append((f"{sig} ({c.start[0]}.{c.start[1]})", sig, None, f"{c.start[0]}.{c.start[1]}"))
    return drive, compare


def replay(log_path, bench, maps=None, dbc=None, stop_time=None, overrides=None, steering_map_name=None,
           variants=None, record=None, offsets=None, fmi=None):
    """Run `bench` driven by the log. Returns a Replay (result, errors).
    fmi: the build of the bench's FMUs (--fmi, artibus.bench.fmi.fmi_choice).
    variants: the bench's variants (as ``artibus run --variant``); record:
    more outputs to record; offsets: {input: constant} added to a driven
    input, in the input's unit (sensitivity to a sensor offset)."""
    from artibus.bench import ssp
    from artibus.runner import Simulation
    log_path = Path(log_path)
    bench_ssp = ssp.ssp_path(bench, fmi)      # (fmi "3": the pack of its FMI 3.0 builds)
    b = ssp.read(bench_ssp)
    name = b.name
    profile = PROFILES.get(name, Profile(drive={}))
    drive = dict(profile.drive)
    can_log = log_path.suffix.lower() in (".blf", ".asc")
    if b.can is not None and can_log and any(c.can is not None for c in b.connections):
        routed, compared = _route_profile(b)
        drive.update(routed)
        profile = Profile(drive=dict(profile.drive), steering=profile.steering,
                          compare=list(profile.compare) + compared, path=profile.path, start=profile.start)
    drive.update(_parse_map(maps))
    if not drive:
        raise ArtibusError(f"replay into {name}: no driving signal: give --map SIGNAL=COMP.INPUT "
                           f"(benches with a replay profile: {', '.join(PROFILES)}, or a CAN log into a "
                           f"bench that routes connections over CAN)")
    warnings = []
    if dbc is None and b.can is not None and can_log:
        log = read_log(log_path, _bench_dbc(bench_ssp, b), warnings)
    else:
        log = read_log(log_path, dbc, warnings)
    # every driving signal must be in the log, every input a Real input of the bench
    for inp, (sig, unit) in drive.items():
        if sig not in log or len(log[sig].time) == 0:
            raise ArtibusError(f"{log_path}: no signal '{sig}' (needed for {inp} of {name}); the log has: "
                               f"{', '.join(sorted(log)) or 'nothing'}")
        comp, _, var = inp.rpartition(".")
        if comp not in b.components:
            raise ArtibusError(f"--map {sig}={inp}: no component '{comp}' in {b.file} "
                               f"(components: {', '.join(b.components)})")
    for inp in offsets or {}:
        if inp not in drive:
            raise ArtibusError(f"offset on {inp}: not an input the log drives in {name}")
    params = b.components[next(iter(b.components))].parameters
    plant = drive and b.components[next(iter(drive)).rpartition(".")[0]].parameters
    over = dict(ssp.variant_overrides(bench_ssp, variants)) if variants else {}
    over.update(overrides or {})
    if profile.start is not None:
        missing = [s for s in ("beta1_sensor_deg", "theta1_dgps_deg", "x1_dgps_m", "y1_dgps_m")
                   if s not in log or len(log[s].value) == 0]
        if missing:
            raise ArtibusError(f"{log_path}: no signal {', '.join(repr(m) for m in missing)} for the start "
                               f"state of {name} (seed 003: initialised from the first measured samples)")
        over.update({k: v for k, v in profile.start(log, plant or params).items() if k not in over})
    for inp in drive:                 # the runner adds a stimulus to the input's value: start it at 0
        over[inp] = 0.0
    # the last sample holds for its period (a CAN message's cycle)
    t_end = min(log[s].time[-1] + log[s].period for s, _ in drive.values())
    stop = stop_time if stop_time is not None else t_end
    if stop > t_end + 1e-9:
        short = min(drive.values(), key=lambda d: log[d[0]].time[-1] + log[d[0]].period)[0]
        warnings.append(f"{log_path}: the log ends at t = {t_end:g} s (signal {short}), before the stop "
                        f"time {stop:g} s: its last samples are held from there on")
    cmap = None
    if profile.steering is not None:
        cmap = steering_map(steering_map_name or profile.steering[1])
    stimuli, cut = {}, []
    with Simulation(bench_ssp, overrides=over, record=None, stimuli=None) as probe:
        units = {u.path: u for u in probe.units}
        for inp, (sig, unit) in drive.items():
            comp, _, var = inp.rpartition(".")
            v = units[comp].fmu.vars.get(var)
            if v is None or v.causality != "input" or v.kind != "Real":
                raise ArtibusError(f"--map {sig}={inp}: not a Real input of {comp} in {b.file}")
            s = log[sig]
            su = unit if unit is not None else s.unit
            values = s.value
            if cmap is not None and inp == profile.steering[0]:
                values, su = map_steering(values, cmap), "deg"       # seed 003, App. A
            k = _conversion(su, declared_unit(v) or "", f"{log_path}: signal {sig} -> {inp}")
            stimuli[inp] = Series(sig, s.time, k * values + float((offsets or {}).get(inp, 0.0))).hold()
            if any(c.end == (comp, var) for c in b.connections):
                cut.append(inp)
        label, derived = "model", []
        for inp, (fn, switch, what) in profile.derived.items():
            if over.get(switch) in (True, 1, "true"):
                comp, _, var = inp.rpartition(".")
                try:
                    s = fn(log, plant or params, cmap)
                except KeyError as e:
                    raise ArtibusError(f"{log_path}: no signal {e} for {inp} of the {what} ({switch})") from None
                stimuli[inp] = s.hold()
                over[inp] = 0.0
                label = what
                derived.append((inp, switch))
        record = list(dict.fromkeys([o for *_, o in profile.compare]
                                    + (list(profile.path[2:]) if profile.path else []) + list(drive)
                                    + list(record or [])))
    with Simulation(bench_ssp, overrides=over, record=record or None, stimuli=stimuli, cut=cut) as sim:
        result = sim.run(stop_time=stop)
    errors = compare(result, log, profile)
    base = None
    if derived:       # the bench as it stands (e.g. the integrating model), for the report
        plain = {k: v for k, v in over.items() if k not in dict(derived) and k not in {s for _, s in derived}}
        for k in ssp.variant_overrides(bench_ssp, variants) if variants else {}:
            if k not in (overrides or {}) and k in plain:
                del plain[k]
        with Simulation(bench_ssp, overrides=plain, record=record or None,
                        stimuli={k: f for k, f in stimuli.items() if k not in dict(derived)}, cut=cut) as sim:
            r0 = sim.run(stop_time=stop)
        base = ("model", r0, compare(r0, log, profile))
    return Replay(result, errors, log, profile, drive, label, base, warnings)


def _bench_dbc(bench_ssp, b):
    """The bench's DBC, loaded from the .ssp (no file left behind)."""
    import tempfile
    import zipfile
    source = b.can["source"]
    with zipfile.ZipFile(bench_ssp) as z, tempfile.TemporaryDirectory(prefix="artibus-replay-") as tmp:
        if source not in z.namelist():
            raise ArtibusError(f"{bench_ssp}: <Can source=\"{source}\">: no such member")
        f = Path(tmp) / Path(source).name
        f.write_bytes(z.read(source))
        return load_dbc(f, f"{bench_ssp}/{source}")


def _to_si(unit):
    """factor from a log's unit to the FMUs' SI unit (rad, m/s, ...)."""
    return UNITS.get(unit or "", ("", 1.0))[1]


def compare(result, log, profile):
    """Model against measured at the measured samples (within the run): RMS and
    largest error of each compared signal, and of the path (distance of the
    model's point from the measured one at each fix)."""
    out = []
    t = result.time
    for label, sig, unit, output in profile.compare:
        if sig not in log:
            continue
        s = log[sig]
        keep = s.time <= t[-1] + 1e-9
        model = np.interp(s.time[keep], t, result[output])
        unit = s.unit if unit is None else unit
        k = _to_si(unit)
        e = (model - s.value[keep] * k) / k
        if unit == "deg" and "heading" in label:
            e = (e + 180.0) % 360.0 - 180.0
        out.append((label, float(np.sqrt(np.mean(e ** 2))), float(np.max(np.abs(e))), unit))
    if profile.path is not None and profile.path[0] in log:
        sx, sy = log[profile.path[0]], log[profile.path[1]]
        keep = sx.time <= t[-1] + 1e-9
        mx = np.interp(sx.time[keep], t, result[profile.path[2]])
        my = np.interp(sx.time[keep], t, result[profile.path[3]])
        d = np.hypot(mx - sx.value[keep], my - sy.value[keep])
        out.append(("path of P1 (distance at the fixes)", float(np.sqrt(np.mean(d ** 2))), float(np.max(d)), "m"))
    return out


def runs(rep):
    """[(label, result, errors)] of a replay: the bench as it stands first
    (when a derived input ran too), then the replay's own run. Error labels
    of a run other than the bench as it stands carry its name in brackets."""
    out = [rep.base] if rep.base is not None else []
    own = rep.errors if rep.base is None else [(f"{l} [{rep.label}]", a, b, u) for l, a, b, u in rep.errors]
    return out + [(rep.label, rep.result, own)]


def write_report(rep, out_dir, title):
    """PNGs (model against measured: joint angle, heading, path; seed 003
    Figs. 9-11; with a prediction model, the integrating model beside it, as
    Fig. 11) and errors.csv in out_dir."""
    from artibus import report
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    log, p = rep.log, rep.profile
    every = runs(rep)
    shown = [c for c in p.compare if c[1] in log]
    images = []
    if shown:
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(len(shown), 1, figsize=(9, 3 * len(shown)), sharex=True)
        for ax, (label, sig, unit, output) in zip(np.atleast_1d(axes), shown):
            unit = log[sig].unit if unit is None else unit
            for name, r, _ in every:
                ax.plot(r.time, r[output] / _to_si(unit), "-." if name != "model" else "-",
                        label=f"{name} (replayed inputs)")
            ax.plot(log[sig].time, log[sig].value, ".", ms=2 if len(log[sig].time) > 200 else 5, label=f"measured ({sig})")
            ax.set_ylabel(f"{label} [{unit}]")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        np.atleast_1d(axes)[-1].set_xlabel("time [s]")
        fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        fig.savefig(out / "angles.png", dpi=110)
        plt.close(fig)
        images.append("angles.png")
    if p.path is not None and p.path[0] in log:
        curves = {f"{name} P1": (r[p.path[2]], r[p.path[3]]) for name, r, _ in every}
        curves["measured P1 (DGPS fixes)"] = (log[p.path[0]].value, log[p.path[1]].value)
        report.birds_eye(out / "path.png", curves, title=title)
        images.append("path.png")
    rows = ["quantity,rms,max,unit"] + [f'"{l}",{a:.6g},{b:.6g},{u}' for _, _, errs in every
                                        for l, a, b, u in errs]
    part = out / "errors.csv.part"
    part.write_text("\n".join(rows) + "\n")
    part.replace(out / "errors.csv")
    return images


def page_parts(rep, out_dir, title):
    """A replay's page as every bench's: (KPIs, [(image, caption)], notes):
    the figures of write_report and errors.csv in out_dir, a KPI row per
    compared signal and run (RMS and largest error of model against
    measured). The rows are not graded: a replay has no paper bound (seed 003
    shows its errors as plots)."""
    from artibus.report import Kpi
    out = Path(out_dir)
    images = write_report(rep, out, title)
    kpis = []
    for name, _, errors in runs(rep):
        for label, rms, mx, unit in errors:
            kpis.append(Kpi(f"{name}: {label}, RMS error against measured", rms, unit, "", "seed 003, sec. V"))
            kpis.append(Kpi(f"{name}: {label}, largest error", mx, unit))
    captions = {"angles.png": "Model (driven by the log's inputs) against measured: each compared signal over "
                              "time (seed 003, Figs. 9-10).",
                "path.png": "The wagon axle P1's path: the model's against the measured DGPS fixes (Fig. 11)."}
    driven = "; ".join(f"{inp} <- {sig}" for inp, (sig, _) in rep.drive.items())
    notes = [f"Inputs driven from the log: {driven}; the start state from its first samples.",
             "Every error: errors.csv (RMS and largest, per run)."]
    return kpis, [(i, captions.get(i, i)) for i in images], notes


def report_page(rep, out_dir, title, intro="", notes=()):
    """page_parts written as a page, out_dir/index.html (artibus.report.write_html); returns the KPIs."""
    from artibus.report import write_html
    out = Path(out_dir)
    kpis, images, parts = page_parts(rep, out, title)
    write_html(out, title, intro, kpis, [(out / i, c) for i, c in images], list(notes) + parts)
    return kpis
