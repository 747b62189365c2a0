"""Bus36m_Circle, unsteered: the simulated steady state on the circle against an
independent computation for the same data (issue 5).

The independent computation is the steady circular equilibrium solved directly
as an algebraic problem in tests/circle_equilibrium.py, written from first
principles and sharing no code with the plant (dynamics.cpp): all three
modules turn at one constant yaw rate Omega about one fixed centre O, so in
module 1's frame (which rotates with Omega) the configuration is stationary.
For each module, Newton-Euler with the centripetal acceleration of its CG,
-Omega^2 (CG - O), and no angular acceleration:

    sum of tyre forces + hinge forces      = m_m * (-Omega^2 (CG_m - O))
    sum of their moments about CG_m        = 0

the tyre forces from the slip angles of each axle in the rigid rotation about O
(velocity Omega e_z x (A - O), alpha = atan2(-w, sqrt(u^2 + vSlip^2)) from its
components along and across the wheel), tyreModel 1: Fy = mu C alpha saturated
at mu Fz, with the bench's C, mu and the plant's static loads Fz; the drive
force on A2 along its wheel. Unknowns: O (2), the yaw angles of modules 2 and 3
relative to module 1, the two hinge forces (force of the front module on the
rear one, equal and opposite on the front module) and the drive force: 9
unknowns, 9 equations. The operating point is only the front steering angle
delta[1] (Driver.delta) and the speed of module 1's CG (Bus.v) on the window.

Compared: the radius of every axle's path about O against circles fitted to
the simulated axle traces (1 cm), the hinge forces FjointX/Y (1 %), and, as a
by-product, the drive force and the yaw rate.

The window. The bench drives one 360 deg circle, and that is not long enough
for this train to settle: with A3 and A5 sliding (saturated at mu Fz) the
trailers turn in slowly (articulation 2 still grows by ~0.007 rad/s at the
exit; on the last third of the circle delta[1] spreads by 0.011 rad and
artAngle[2] by 0.09 rad, and the equilibrium for that window's mean delta[1]
and speed misses the fitted A6 radius by 1.5 m and FjointY[1] by 185 %). The
trailers settle with a time constant of about 7 s (20 m); the PI speed
control also needs ~20 s to build up the 70 kN drive force. So the test runs
the same bench with the driver's road replaced, through a parameter override
(Driver.road = 0, Driver.roadFile), by the same road with the circle driven
LAPS times (same points, a longer straight after it; the first lap is checked
to be identical to the bench's), and takes the last lap before the exit as
the window, checking that steering, speed, articulation angles and yaw rates
have settled there.
"""
import math

import numpy as np
import pytest

from artibus import runner
from circle_equilibrium import fit_circle, solve_equilibrium

BENCH = "Bus36m_Circle"
LAPS = 4              # circles driven; the window is the last one
EXIT_MARGIN = 10.0    # m of the last lap left out before the exit (driver look-ahead)
TOL_RADIUS = 0.01     # m
TOL_FORCE = 0.01      # relative
# the plant's tolerance, tighter than its default (1e-6): at 1e-6 the
# articulation angles still drift by 3e-4 rad over the window (the steadiness
# check allows 2e-4), at 1e-8 by 1e-5
SOLVER = {"Bus.rtol": 1e-8, "Bus.atol": 1e-8}


# ---------------------------------------------------------------- the bench --

def _value(sim, comp, name):
    """a parameter as the run uses it: bound in the bench, else the FMU's start."""
    params = sim.parameters[comp]
    if name in params:
        return params[name]
    unit = next(u for u in sim.units if u.path == comp)
    return unit.fmu.vars[name].start


def circle_road(path, R, before, after, laps, h):
    """The built-in road 2 (a straight along +x, a circle of radius R entered
    tangentially, the straight again), with the circle driven `laps` times:
    the same polyline points for the first lap."""
    nb = math.ceil(before / h - 1e-9)
    nc = math.ceil(2 * math.pi * abs(R) / h - 1e-9)
    na = math.ceil(after / h - 1e-9)
    x = [before * i / nb for i in range(nb)]
    y = [0.0] * nb
    phi = math.copysign(2 * math.pi, R) * np.arange(laps * nc) / nc
    x += list(before + R * np.sin(phi))
    y += list(R * (1 - np.cos(phi)))
    x += [before + (after * i / na if na else 0.0) for i in range(na + 1)]
    y += [0.0] * (na + 1)
    np.savetxt(path, np.column_stack([x, y]), delimiter=",", fmt="%.17g")


def _records(n_mod, n_axle):
    rec = ["Driver.delta", "Driver.Fx", "Driver.s", "Bus.v"]
    rec += [f"Bus.{v}[{a}]" for v in ("xAxle", "yAxle", "Fz") for a in range(1, n_axle + 1)]
    rec += [f"Bus.r[{m}]" for m in range(1, n_mod + 1)]
    rec += [f"Bus.{v}[{k}]" for v in ("FjointX", "FjointY", "artAngle") for k in range(1, n_mod)]
    return rec


def plant_parameters(sim):
    """The plant's data for the equilibrium, as this run binds it (1-based lists)."""
    v = lambda n: _value(sim, "Bus", n)
    n, na = int(v("nModules")), int(v("nAxles"))
    P = dict(nMod=n, nAxles=na, tyreModel=int(v("tyreModel")), vSlip=float(v("vSlip")))
    P["m"] = [None] + [float(v(f"m[{m}]")) for m in range(1, n + 1)]
    P["lHf"] = [None] + [float(v(f"lHf[{k}]")) for k in range(1, n)]
    P["lHr"] = [None] + [float(v(f"lHr[{k}]")) for k in range(1, n)]
    P["axleModule"] = [None] + [int(v(f"axleModule[{a}]")) for a in range(1, na + 1)]
    for name in ("xA", "C", "mu"):
        P[name] = [None] + [float(v(f"{name}[{a}]")) for a in range(1, na + 1)]
    return P


@pytest.fixture(scope="module")
def circle(tmp_path_factory):
    """The bench with its circle driven LAPS times: results, data, window."""
    road = tmp_path_factory.mktemp("road") / "circle_laps.csv"
    with runner.Simulation(BENCH) as sim:          # the bench as it is bound
        P = plant_parameters(sim)
        drv = {n: float(_value(sim, "Driver", n)) for n in ("R", "roadBefore", "roadAfter", "roadStep", "vSet")}
        assert int(_value(sim, "Driver", "road")) == 2       # the built-in circle
        assert float(_value(sim, "Bus", "testSteerAmp")) == 0.0
        connected = {l.name for l in sim.links if l.dst.path == "Bus"}
        # the default (unsteered): the controllers built in hold A3..A6 at exactly 0
        # (tests/test_circle_variants.py)
        assert _value(sim, "Guidance", "guided") is False and int(_value(sim, "ForceMin", "law")) == 0
    # the equilibrium drives A2 only, steers A1 only, has no hinge torques
    assert connected - {f"Bus.delta[{a}]" for a in (3, 4, 5, 6)} == {"Bus.delta[1]", "Bus.Fx[2]"}
    assert P["tyreModel"] == 1
    # a longer straight after the laps: the run ends on it, before the road's
    # end (where the driver brakes to a stop)
    circle_road(road, drv["R"], drv["roadBefore"], drv["roadAfter"] + 300.0, LAPS, drv["roadStep"])
    lap = 2 * math.pi * abs(drv["R"])
    s_exit = drv["roadBefore"] + LAPS * lap
    stop = s_exit / drv["vSet"] + 10.0    # the guided corner runs faster than vSet on the circle
    record = _records(P["nMod"], P["nAxles"])
    r = runner.run(BENCH, stop_time=stop, record=record,
                   overrides={"Driver.road": 0, "Driver.roadFile": str(road), **SOLVER})
    res = {n: np.asarray(r[n]) for n in record}
    res["time"] = np.asarray(r.time)
    s = res["Driver.s"]
    assert s.max() > s_exit, "the run ended before the exit of the last lap"
    window = (s > s_exit - lap) & (s < s_exit - EXIT_MARGIN)
    return dict(res=res, P=P, drv=drv, lap=lap, window=window, record=record)


# --------------------------------------------------------- the comparison --

def operating_point(circle):
    w, res = circle["window"], circle["res"]
    P = dict(circle["P"])
    P["Fz"] = [None] + [float(res[f"Bus.Fz[{a}]"][w].mean()) for a in range(1, P["nAxles"] + 1)]
    return P, float(res["Driver.delta"][w].mean()), float(res["Bus.v"][w].mean())


def compare(circle, P=None):
    """Equilibrium against simulation on the window: errors by name."""
    P0, delta1, V = operating_point(circle)
    eq = solve_equilibrium(P if P is not None else P0, delta1, V)
    w, res = circle["window"], circle["res"]
    err = {}
    for a in range(1, P0["nAxles"] + 1):
        _, R, _ = fit_circle(res[f"Bus.xAxle[{a}]"][w], res[f"Bus.yAxle[{a}]"][w])
        err[f"radius A{a} [m]"] = (eq["radius"][a], R)
    for k in range(1, P0["nMod"]):
        for c in ("FjointX", "FjointY"):
            err[f"{c}[{k}] [N]"] = (eq[c][k], float(res[f"Bus.{c}[{k}]"][w].mean()))
    err["drive force [N]"] = (eq["Fdrive"], float(res["Driver.Fx"][w].mean()))
    err["yaw rate [rad/s]"] = (eq["Omega"], float(res["Bus.r[1]"][w].mean()))
    return err, eq


def failures(err):
    bad = []
    for name, (mine, sim) in err.items():
        if name.startswith("radius"):
            ok = abs(mine - sim) <= TOL_RADIUS
        else:
            ok = abs(mine - sim) <= TOL_FORCE * abs(sim)
        if not ok:
            bad.append(f"{name}: equilibrium {mine:.6g}, simulation {sim:.6g}")
    return bad


# ------------------------------------------------------------------ tests --

def test_the_laps_continue_the_bench_circle(circle):
    """The first lap with the longer road is the bench's own run, to the
    point where the driver starts to see the bench's exit."""
    bench = runner.run(BENCH, record=circle["record"], overrides=SOLVER)
    res = circle["res"]
    n = len(bench.time)
    s_bench = np.asarray(bench["Driver.s"])
    same = s_bench < circle["drv"]["roadBefore"] + circle["lap"] - EXIT_MARGIN
    assert same.sum() > 0.5 * n
    assert np.array_equal(np.asarray(bench.time)[same], res["time"][:n][same])
    for name in circle["record"]:
        np.testing.assert_allclose(np.asarray(bench[name])[same], res[name][:n][same],
                                   rtol=1e-7, atol=1e-6, err_msg=name)


def test_window_is_steady(circle):
    """On the last lap the driver's steering, the speed, the articulation
    angles and the loads have settled, every module turns at the same yaw
    rate, and every axle runs on a circle about one common centre."""
    w, res, P = circle["window"], circle["res"], circle["P"]
    assert w.sum() > 2000                                     # >= 20 s at 10 ms
    assert np.ptp(res["Driver.delta"][w]) < 5e-4              # rad (sampling jitter ~5e-5 rad rms)
    assert np.ptp(res["Bus.v"][w]) < 1e-3                     # m/s
    assert np.ptp(res["Driver.Fx"][w]) < 1e-3 * abs(res["Driver.Fx"][w].mean())
    for k in range(1, P["nMod"]):
        assert np.ptp(res[f"Bus.artAngle[{k}]"][w]) < 2e-4      # rad
    r1 = res["Bus.r[1]"][w]
    for m in range(1, P["nMod"] + 1):
        assert np.abs(res[f"Bus.r[{m}]"][w] - r1.mean()).max() < 1e-4   # rad/s
    for a in range(1, P["nAxles"] + 1):
        assert np.ptp(res[f"Bus.Fz[{a}]"][w]) == 0.0
    centres = []
    for a in range(1, P["nAxles"] + 1):
        c, R, rms = fit_circle(res[f"Bus.xAxle[{a}]"][w], res[f"Bus.yAxle[{a}]"][w])
        assert rms < 1e-3, f"A{a}: not a circle (rms {rms:.2e} m)"
        centres.append(c)
    centres = np.array(centres)
    assert np.abs(centres - centres.mean(axis=0)).max() < TOL_RADIUS


def test_equilibrium_matches_the_steady_state(circle):
    """Radii of A1..A6 about the turn centre to 1 cm, hinge forces to 1 %
    (and the drive force and yaw rate the equilibrium implies, to 1 %)."""
    err, eq = compare(circle)
    print()
    for name, (mine, sim) in err.items():
        d = (f"{1000 * (mine - sim):+.3f} mm" if name.startswith("radius")
             else f"{100 * (mine / sim - 1):+.5f} %")
        print(f"{name:18s} equilibrium {mine:14.6f} simulation {sim:14.6f}  {d}")
    assert not failures(err), failures(err)


@pytest.mark.parametrize("what, factor", [("m", 1.02), ("C", 1.02), ("lHr", 1.002)])
def test_a_wrong_model_fails(circle, what, factor):
    """The comparison can fail: a 2 % wrong mass or cornering stiffness, or a
    hinge 1.2 cm out of place, in the equilibrium is caught. (The mass is
    caught by the small lateral force in hinge 1 only, 1.5 % off: at 0.63 m/s2
    centripetal the tyres, sliding at A3 and A5, dominate; a 1 % mass error
    would pass.)"""
    P, _, _ = operating_point(circle)
    P[what] = [None] + [factor * v for v in P[what][1:]]
    err, _ = compare(circle, P)
    assert failures(err)
