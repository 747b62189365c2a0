"""Model Exchange in the runner (issue 38): an ME FMU integrated with CVODE by the stepping
core's ME facade (src/runner_core/me.c, artibus.fmu.me) and stepped as a Co-Simulation unit,
alone (`artibus simulate --fmi-type me`) and in a bench (`Simulation(fmi_type="me")`).

Held against
- FMPy's `simulate_fmu(..., fmi_type="ModelExchange", relative_tolerance=1e-8)` (another
  importer, its own CVODE loop) on the Reference-FMUs, FMI 2.0 and 3.0: equal within 1e-6 of
  each signal's largest magnitude;
- closed forms written here: Dahlquist's x = exp(-k t); BouncingBall's free fall to its first
  bounce (a state event) and its flight after it (v = -e v at the bounce); Stair's counter,
  one more at each whole second (time events), its end at t = 9 s (terminateSimulation);
- the Co-Simulation builds of our plants in Bus36m_Circle and Urbino18_Circle: their KPIs
  within 0.5 %.
A Model Exchange FMU whose derivatives stop being numbers stops with the time and why, its
partial result kept (the CLI: one line, no traceback)."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / ".tools" / "reference-fmus"
MODELS = ["BouncingBall", "Dahlquist", "VanDerPol", "Stair"]
RTOL = 1e-8


def fmu_of(model, version):
    path = REFERENCE / ("fmi3" if version == 3 else "") / f"{model}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built (scripts/build_reference_fmus.sh; needs cargo)")
    return path


def cases():
    return [pytest.param(m, version, id=f"fmi{version}-{m}") for version in (2, 3) for m in MODELS]


def me_run(path, **kw):
    from artibus.fmu import simulate
    return simulate(str(path), interface="me", tolerance=RTOL, **kw)


def columns(result):
    a = np.array(result.rows, dtype=float)
    return {n: a[:, j] for j, n in enumerate(result.names)}


@pytest.mark.parametrize("model,version", cases())
def test_simulate_me_equals_fmpys_model_exchange(model, version):
    """At every communication point, each output within 1e-6 of its largest magnitude of FMPy's
    value there (where FMPy records an event's instant twice, before and after the event
    iteration, its last row: the values after the event, as a Co-Simulation step ends)."""
    from fmpy import simulate_fmu
    path = fmu_of(model, version)
    r = me_run(path)
    got = columns(r)
    t = got["time"]
    step = t[1] - t[0]
    ref = simulate_fmu(str(path), fmi_type="ModelExchange", relative_tolerance=RTOL, output_interval=step)
    if model == "Stair":
        # both end at the time event of t = 9 s that asks to terminate; FMPy records that instant
        # before the event iteration only, artibus (as a Co-Simulation step, and as the CS build
        # does) after it: the rows before it are compared
        assert r.terminated is not None and r.terminated.time == pytest.approx(9.0)
        assert ref["time"][-1] == pytest.approx(9.0)
        keep = t < 9.0 - 1e-9
        t, got = t[keep], {n: x[keep] for n, x in got.items()}
    names = [n for n in r.names if n != "time"]
    assert names and all(n in ref.dtype.names for n in names)
    for n in names:
        scale = np.max(np.abs(ref[n]))
        for ti, x in zip(t, got[n]):
            rows = np.nonzero(np.isclose(ref["time"], ti, rtol=1e-9, atol=1e-12))[0]
            assert len(rows), (n, ti)
            y = ref[n][rows[-1]]
            assert abs(x - y) <= 1e-6 * scale, (model, n, ti, x, y)


@pytest.mark.parametrize("method", ["bdf", "adams"])
@pytest.mark.parametrize("version", [2, 3])
def test_dahlquist_is_the_exponential(version, method):
    """der(x) = -k x, x(0) = 1, k = 1 (the model's start values): x = exp(-t), within what
    rtol 1e-8 and the absolute tolerance it implies (rtol x nominal 1 = 1e-8) allow over 10 s:
    1e-6 relative, 1e-7 absolute; with CVODE's BDF and with its Adams method."""
    r = me_run(fmu_of("Dahlquist", version), me_method=method)
    c = columns(r)
    assert c["time"][-1] == pytest.approx(10.0)
    assert np.allclose(c["x"], np.exp(-c["time"]), rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("method", ["bdf", "adams"])
@pytest.mark.parametrize("version", [2, 3])
def test_bouncing_ball_bounces_where_the_closed_form_says(version, method):
    """h(0) = 1 m, v(0) = 0, g = -9.81 m/s2, e = 0.7 (the model's start values): the ball falls
    until h = 0 at t1 = sqrt(2 h0 / |g|) (a state event: the event indicator h changes sign),
    leaves with v = e |g| t1 and flies until t2 = t1 + 2 e t1. Before t1: h = h0 - |g| t^2 / 2,
    v = -|g| t; between t1 and t2: h = e |g| t1 s - |g| s^2 / 2, v = e |g| t1 - |g| s, s = t - t1."""
    r = me_run(fmu_of("BouncingBall", version), me_method=method)
    c = columns(r)
    t, h, v = c["time"], c["h"], c["v"]
    g, e, h0 = 9.81, 0.7, 1.0
    t1 = math.sqrt(2 * h0 / g)
    t2 = t1 + 2 * e * t1
    before, after = t < t1, (t > t1) & (t < t2)
    assert before.sum() > 10 and after.sum() > 10
    assert np.allclose(h[before], h0 - g * t[before] ** 2 / 2, atol=1e-6)
    assert np.allclose(v[before], -g * t[before], atol=1e-6)
    s = t[after] - t1
    assert np.allclose(h[after], e * g * t1 * s - g * s ** 2 / 2, atol=1e-6)
    assert np.allclose(v[after], e * g * t1 - g * s, atol=1e-6)


@pytest.mark.parametrize("version", [2, 3])
def test_stair_counts_its_time_events_and_ends_at_nine_seconds(version):
    """Stair's counter starts at 1 and goes one up at each whole second (time events,
    nextEventTime); at t = 9 s it asks to terminate: the run ends there, a normal end."""
    from artibus.fmu.instance import Fmu
    r = me_run(fmu_of("Stair", version))
    c = columns(r)
    t, counter = c["time"], c["counter"]
    inside = np.abs(t - np.round(t)) > 1e-6          # the points between two events
    assert np.array_equal(counter[inside], np.floor(t[inside]) + 1)
    assert r.terminated is not None and r.terminated.time == pytest.approx(9.0) and t[-1] == pytest.approx(9.0)
    with Fmu(str(fmu_of("Stair", version)), interface="me") as fmu:    # the facade counts them
        fmu.calls.enter_initialization(0.0, tolerance=RTOL)
        fmu.calls.exit_initialization()
        assert fmu.do_step(0.0, 10.0) == pytest.approx(9.0)
        counts = fmu.calls.facade.counts()
        assert counts["time_events"] == 8 + 1 and counts["state_events"] == 0


def test_cli_simulate_fmi_type_me(tmp_path):
    """`artibus simulate FMU --fmi-type me` (FMPy's ModelExchange and fmusim's me alike) runs the
    FMU as Model Exchange: VanDerPol's x0 at t = 20 s equals FMPy's ME run's."""
    from fmpy import simulate_fmu
    path = fmu_of("VanDerPol", 2)
    out = tmp_path / "vdp.csv"
    for word in ("me", "ModelExchange"):
        p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "--fmi-type", word,
                            "--relative-tolerance", "1e-8", "-o", str(out)], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        a = np.genfromtxt(out, delimiter=",", names=True)
        ref = simulate_fmu(str(path), fmi_type="ModelExchange", relative_tolerance=1e-8)
        assert a["time"][-1] == pytest.approx(ref["time"][-1])
        x0 = np.asarray(ref["x0"], dtype=float)
        assert a["x0"][-1] == pytest.approx(x0[-1], abs=1e-6 * float(np.max(np.abs(x0))))


def test_cli_fmi_type_me_of_an_fmu_without_model_exchange_is_refused_by_name(tmp_path):
    """SteeringECU has Co-Simulation only: --fmi-type me says so in one line, no traceback."""
    path = ROOT / "fmus" / "SteeringECU.fmu"
    if not path.is_file():
        pytest.skip("fmus/ not built")
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "--fmi-type", "me",
                        "-o", str(tmp_path / "x.csv")], capture_output=True, text=True)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert "SteeringECU has no Model Exchange interface" in p.stderr, p.stderr


@pytest.mark.parametrize("version", [2, 3])
def test_derivatives_no_longer_numbers_stop_with_the_time_and_why(tmp_path, version):
    """Dahlquist with k = -1000: x = exp(1000 t) overflows near t = ln(DBL_MAX) / 1000 = 0.7098 s,
    its derivative becomes inf. The run stops there: one line naming the FMU, the time and the
    derivative; the rows before it kept (OUT.partial.csv), x = exp(1000 t) on them (to 1e-4: the
    relative error of rtol 1e-8 grows with the 700 e-foldings of x)."""
    path = fmu_of("Dahlquist", version)
    out = tmp_path / "d.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "--fmi-type", "me",
                        "--set", "k=-1000", "--relative-tolerance", "1e-8", "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    first = p.stderr.splitlines()[0]
    assert first.startswith("artibus: error: ") and "Dahlquist failed at t = 0.7 s" in first, first
    assert "derivative of continuous state 1 is inf" in first and "CVODE failed" in first, first
    partial = tmp_path / "d.partial.csv"
    a = np.genfromtxt(partial, delimiter=",", names=True)
    assert a["time"][-1] == pytest.approx(0.7) and len(a) == 8
    assert np.allclose(a["x"], np.exp(1000 * a["time"]), rtol=1e-4)


BENCHES = {"Bus36m_Circle": "BusDynamics", "Urbino18_Circle": "BusKinematics"}


@pytest.mark.slow
@pytest.mark.parametrize("bench,fmi,method", [("Bus36m_Circle", None, "bdf"), ("Urbino18_Circle", None, "bdf"),
                                              ("Bus36m_Circle", "3", "bdf"), ("Bus36m_Circle", None, "adams")])
def test_a_plant_as_model_exchange_gives_the_co_simulation_builds_kpis(bench, fmi, method):
    """The plant's ME build in the bench (fmi_type "me": every FMU that has ME; here the plant
    alone), integrated by the facade at its default 1e-6: every KPI within 0.5 % of the run
    with its CS build (which integrates with its own CVODE at 1e-6); FMI 2.0, and the FMI 3.0
    builds (fmi "3"); CVODE's BDF and its Adams method."""
    from artibus.bench import script
    from artibus.runner import Simulation
    if not (ROOT / "fmus" / ("fmi3" if fmi else "") / f"{BENCHES[bench]}.fmu").is_file():
        pytest.skip("fmus/ not built")
    with Simulation(bench, fmi=fmi) as sim:
        cs = {k.name: k.value for k in script.load(bench).kpis(sim.run())}
    with Simulation(bench, fmi=fmi, fmi_type="me", me_method=method) as sim:
        assert all(u.fmu.fmi == (3 if fmi else 2) for u in sim.units)
        assert [u.fmu.md.modelName for u in sim.units if u.fmu.interface == "me"] == [BENCHES[bench]]
        me = {k.name: k.value for k in script.load(bench).kpis(sim.run())}
        counts = next(u.fmu.calls.facade.counts() for u in sim.units if u.fmu.interface == "me")
    assert counts["steps"] > 0 and counts["rhs"] >= counts["steps"]
    assert cs.keys() == me.keys() and cs
    for n in cs:
        assert me[n] == pytest.approx(cs[n], rel=5e-3), n


@pytest.mark.slow
def test_cli_run_fmi_type_me_runs_the_plant_as_model_exchange(tmp_path):
    """`artibus run BENCH --fmi-type me`: the run Simulation(fmi_type="me") makes, column for
    column (the same calls: deterministic), and not the Co-Simulation run."""
    from artibus.runner import Simulation
    if not (ROOT / "fmus" / "BusKinematics.fmu").is_file():
        pytest.skip("fmus/ not built")
    out = tmp_path / "u.csv"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", "Urbino18_Circle", "--fmi-type", "me",
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    import csv
    with open(out) as f:
        rows = list(csv.reader(f))
    head, table = rows[0], np.array(rows[1:], dtype=float)
    with Simulation("Urbino18_Circle", fmi_type="me") as sim:
        me = sim.run()
    with Simulation("Urbino18_Circle") as sim:
        cs = sim.run()
    name = "Bus.y[0]"                      # the front axle's lateral position
    got = table[:, head.index(name)]
    assert len(got) == len(me[name]) and np.ptp(got) > 1.0
    assert np.allclose(got, me[name], rtol=1e-10, atol=1e-10)       # (the CSV's 12 digits)
    assert not np.allclose(got, cs[name], rtol=1e-8, atol=1e-8)


@pytest.mark.parametrize("bench,fmi", [("MultiAxle_StepSteer", None), ("Bus36m_Circle", "3")])
def test_the_fmus_jacobian_in_cvode_gives_the_same_run(bench, fmi):
    """With CVODE's Jacobian from the plant's directional derivatives (Facade.use_jacobian; the
    plants provide them exactly) the ME run equals the one with CVODE's difference quotients
    within the integration's tolerance (the positions and headings within 1e-5 of each one's
    peak at rtol 1e-6; the bench's KPIs within 0.5 %, as the CS and ME builds: accelerations
    and tyre forces near saturation move more between two solutions both within tolerance),
    and CVODE evaluated fewer right-hand sides (no difference-quotient columns): the Jacobian
    was used."""
    from artibus.bench import script
    from artibus.runner import Simulation
    runs, counts = [], []
    for jac in (False, True):          # the Jacobian asked as `run --me-jacobian` asks it
        with Simulation(bench, fmi=fmi, fmi_type="me", me_jacobian=jac) as sim:
            facade = next(u.fmu.calls.facade for u in sim.units if u.fmu.interface == "me")
            assert facade.jacobian_available
            r = sim.run()
            runs.append(r)
            counts.append(facade.counts())
    a, b = runs[0].array(), runs[1].array()
    assert runs[0].names == runs[1].names and a.shape == b.shape
    plant = next(u.path for u in sim.units if u.fmu.interface == "me")
    keep = [i for i, n in enumerate(runs[0].names) if n.split("[")[0] in
            {f"{plant}.{v}" for v in ("x", "y", "psi", "X", "Y", "phi")}]
    assert keep, runs[0].names
    peak = np.maximum(np.nanmax(np.abs(a[:, keep]), axis=0), 1.0)
    assert np.nanmax(np.abs(a[:, keep] - b[:, keep]) / peak) < 1e-5
    k0, k1 = ({k.name: k.value for k in script.load(bench).kpis(r)} for r in runs)
    for n in k0:
        if isinstance(k0[n], float) and math.isfinite(k0[n]):
            assert k1[n] == pytest.approx(k0[n], rel=5e-3, abs=1e-9), n
    assert counts[1]["rhs"] < counts[0]["rhs"], counts


def test_use_jacobian_of_an_fmu_without_directional_derivatives_is_refused():
    """The Reference-FMUs' VanDerPol (FMI 2.0 ME) says providesDirectionalDerivative="false"
    (its model description as built): asking for its Jacobian is one clear error"""
    from artibus.base import ArtibusError
    from artibus.fmu.instance import Fmu
    path = ROOT / ".tools" / "reference-fmus" / "VanDerPol.fmu"
    if not path.is_file():
        pytest.skip("the Reference-FMUs are not built (scripts/build_reference_fmus.sh)")
    with Fmu(path, interface="me") as fmu:
        facade = fmu.calls.facade
        assert not facade.jacobian_available
        with pytest.raises(ArtibusError, match="provides no directional derivatives"):
            facade.use_jacobian(True)


def test_simulate_me_jacobian_runs_alone_and_refuses_an_fmu_without_derivatives(tmp_path):
    """`artibus simulate BusDynamics --fmi-type me --me-jacobian` (its test steering on) equals
    the run with CVODE's difference quotients within the integration's tolerance (every column
    within 1e-4 of its peak at rtol 1e-6); an FMU without directional derivatives (the
    Reference-FMUs' VanDerPol) is refused in one line naming the file, no traceback"""
    import subprocess
    import sys
    runs = []
    for flag in ([], ["--me-jacobian"]):
        out = tmp_path / f"bus{len(flag)}.csv"
        subprocess.run([sys.executable, "-m", "artibus", "simulate", "BusDynamics", "--fmi-type", "me", *flag,
                        "--set", "testSteerAmp=0.05", "--stop-time", "8", "-o", str(out)], check=True,
                       capture_output=True)
        runs.append(np.genfromtxt(out, delimiter=",", names=True))
    a, b = runs
    assert a.dtype.names == b.dtype.names and len(a) == len(b) == 801
    for n in a.dtype.names:
        assert np.abs(a[n] - b[n]).max() <= 1e-4 * max(np.abs(a[n]).max(), 1e-3), n
    assert np.abs(a["psi1"]).max() > 0.01          # psi[1], rad: the test steering turned the bus
    path = ROOT / ".tools" / "reference-fmus" / "VanDerPol.fmu"
    if not path.is_file():
        pytest.skip("the Reference-FMUs are not built (scripts/build_reference_fmus.sh)")
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", str(path), "--fmi-type", "me",
                        "--me-jacobian", "-o", str(tmp_path / "v.csv")], capture_output=True, text=True)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "VanDerPol.fmu" in lines[0] and "directional derivatives" in lines[0], p.stderr
    assert not (tmp_path / "v.csv").exists()
