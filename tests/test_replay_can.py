"""A CAN run's own log replayed into its bench (artibus replay, issue 12):
Bus36m_Circle_CAN logged as .blf and .asc, the log fed back into the
receivers of the bench's routes (and, with --map, into the front wheels),
against the run."""
import math
import subprocess
import sys

import numpy as np
import pytest

from artibus import ArtibusError, ROOT
from artibus.can import replay

CAN_BENCH = "Bus36m_Circle_CAN"
DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
TO_SI = {"deg": math.pi / 180, "km/h": 1 / 3.6, "": 1.0}      # the DBC's units to the FMUs' (rad, m/s)
FRONT = "SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1]"
PLANT = ([f"Bus.{n}[{a}]" for n in ("xAxle", "yAxle") for a in range(1, 7)]
         + ["Bus.artAngle[1]", "Bus.artAngle[2]", "Bus.vx[1]"])


def can_routes():
    """{receiver "C.v": (message, signal)} of the bench's routed connections (read from its .ssd)."""
    from artibus.bench import ssp
    b = ssp.read(ssp.ssp_path(CAN_BENCH))
    return {f"{c.end[0]}.{c.end[1]}": (c.can["message"], c.can["signal"]) for c in b.connections if c.can}


ROUTED = can_routes()


@pytest.fixture(scope="module")
def can_original(tmp_path_factory):
    """The CAN bench run once per log format, its traffic logged; the plant and
    every routed input recorded."""
    from artibus.runner import Simulation
    d = tmp_path_factory.mktemp("canlog")
    out = {}
    for suffix in ("blf", "asc"):
        log = d / f"run.{suffix}"
        with Simulation(CAN_BENCH, record=PLANT + ["Driver.delta"] + sorted(ROUTED), can_log=log) as sim:
            out[suffix] = (sim.run(), log)
    return out


def path_distance(r, ref, a):
    return np.hypot(r[f"Bus.xAxle[{a}]"] - ref[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"] - ref[f"Bus.yAxle[{a}]"])


@pytest.mark.parametrize("suffix", ["blf", "asc"])
def test_can_log_replayed_into_its_bench_reproduces_the_run_bit_for_bit(can_original, suffix):
    """The log replaces the network: every routed input (data and alive
    counters) fed from the frames of its route, the frame of cycle k from
    t = k T on, the driver and the mechanics in the loop as before. The
    receivers then get what the network gave them, so the ECUs, actuators and
    plant repeat the run bit for bit; each sender, computed again, matches
    its logged frames within half a step of its signal's resolution (the DBC's
    scale, read here with cantools)."""
    import cantools
    r0, log = can_original[suffix]
    rep = replay.replay(log, CAN_BENCH, record=PLANT + sorted(ROUTED))
    r = rep.result
    assert len(r.time) == len(r0.time) and r.time[-1] == pytest.approx(70.0)
    for x in PLANT + sorted(ROUTED):
        np.testing.assert_array_equal(r[x], r0[x], err_msg=x)
    db = cantools.database.load_file(str(DBC))
    checked = set()
    for label, rms, mx, unit in rep.errors:
        msg, _, sig = label.split(" ")[0].partition(".")
        s = db.get_message_by_name(msg).get_signal_by_name(sig)
        assert unit == (s.unit or "") and mx <= s.scale / 2 * (1 + 1e-6), (label, mx, s.scale)
        checked.add((msg, sig))
    assert checked == {v for v in ROUTED.values() if v[1] != "AliveCounter"}


def _tv(x):
    """running total variation of a series"""
    return np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])


@pytest.mark.parametrize("suffix", ["blf", "asc"])
def test_front_angle_from_the_log_keeps_the_trajectory_within_the_resolution_bound(can_original, suffix):
    """The front wheels too at the logged sensor angle (--map
    SensorA1_Angle.RoadWheelAngleA1=Bus.delta[1]; the driver stays in the
    loop for the drive force only, which is not on the steering CAN). The
    plant's front angle then differs from the run's by the frame's
    quantisation only: at most q/2, q = 0.025 deg (the DBC's scale), and the
    rest of its inputs are the run's. Bound: for a linear response y = h * e
    to an input error |e| <= q/2, |y| <= q/2 int |h|, and int |h| is the total
    variation of the step response; the step responses are replays with a
    constant offset of +q/2 and -q/2 on the front angle (their deviation from
    the replay without offset); the bound is the larger running total
    variation (per coordinate for the axle paths). Axle paths and
    articulation angles stay within it; the front steering is open loop
    now, so they do differ."""
    import cantools
    r0, log = can_original[suffix]
    s = cantools.database.load_file(str(DBC)).get_message_by_name("SensorA1_Angle").get_signal_by_name("RoadWheelAngleA1")
    q = s.scale * TO_SI[s.unit]
    rep = replay.replay(log, CAN_BENCH, maps=[FRONT], record=PLANT)
    r = rep.result
    # the front angle the plant got in the step from t_k (recorded in row k + 1, with the step's
    # inputs): the driver's output at t_k (row k) in the run, within q/2
    e = r["Bus.delta[1]"][1:] - r0["Driver.delta"][:-1]
    assert np.max(np.abs(e)) <= q / 2 * (1 + 1e-9)
    steps = [replay.replay(log, CAN_BENCH, maps=[FRONT], record=PLANT, offsets={"Bus.delta[1]": sg * q / 2}).result
             for sg in (1, -1)]
    for g in (1, 2):
        x = f"Bus.artAngle[{g}]"
        bound = max(np.max(_tv(st[x] - r[x])) for st in steps)
        dev = np.max(np.abs(r[x] - r0[x]))
        assert 0 < dev <= bound, (x, dev, bound)
    for a in range(1, 7):
        bx, by = (max(np.max(_tv(st[f"Bus.{c}Axle[{a}]"] - r[f"Bus.{c}Axle[{a}]"])) for st in steps) for c in "xy")
        dev = np.max(path_distance(r, r0, a))
        assert 0 < dev <= math.hypot(bx, by), (a, dev, bx, by)


def test_replay_cli_on_a_can_log(can_original, tmp_path):
    """artibus replay LOG --bench Bus36m_Circle_CAN --map ...: the routed inputs
    and the mapped one listed, the senders' errors printed and written."""
    _, log = can_original["asc"]
    out = tmp_path / "rep"
    p = subprocess.run([sys.executable, "-m", "artibus", "replay", str(log), "--bench", CAN_BENCH, "--map", FRONT,
                        "--stop-time", "2", "-o", str(tmp_path / "r.csv"), "--report", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "Bus.delta[1] <- SensorA1_Angle.RoadWheelAngleA1" in p.stdout
    assert "ECU3.aliveG2 <- SensorG2_Angle.AliveCounter" in p.stdout
    assert "SensorG1_Angle.ArtAngleG1 (Bus.artAngle[1])" in (out / "errors.csv").read_text()


def test_cut_errors_and_no_network_when_every_route_is_cut():
    from artibus.runner import Simulation
    with pytest.raises(ArtibusError, match="cut Bus.gammaF: the input is not connected"):
        Simulation("Urbino18_Replay", cut=["Bus.gammaF"])
    with pytest.raises(ArtibusError, match="cut Bus.x.0.: not an input"):
        Simulation("Urbino18_Replay", cut=["Bus.x[0]"])
    with Simulation(CAN_BENCH, cut=list(ROUTED)) as sim:
        assert sim.can is None and not any(l.name in ROUTED for l in sim.links)
    with pytest.raises(ArtibusError, match="every connection .* is cut"):
        Simulation(CAN_BENCH, cut=list(ROUTED), can_log="x.blf")
