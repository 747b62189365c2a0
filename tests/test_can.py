"""CAN in the loop (artibus.can, issue 12): Bus36m_Circle_CAN (the paper's
topology: a SteeringECU per module, the tractor ECU sending the driving
direction, a SteeringActuator per module's axles) against the direct bench Bus36m_Circle (its variant guidedForceMin), logs read back
with python-can and decoded with cantools against what the receivers used,
bus load and response times, determinism, a corrupted frame never used, a
silent module ECU ending in its actuators' fallback, errors naming file,
message, signal."""
import math
import zipfile

import can as pycan
import cantools
import numpy as np
import pytest
from cantools.autosar.end_to_end import compute_profile2_crc

from artibus import ArtibusError, can as artcan
from artibus.bench import ssp
from artibus.runner import Simulation, run
from artibus.study import kpi
from can_bound import DBC, T, TO_SI, assert_within_bound, kpi_bound

DIRECT, CAN_BENCH = "Bus36m_Circle", "Bus36m_Circle_CAN"
DIRECT_VARIANT = "guidedForceMin"          # the direct bench's variant with the CAN bench's controllers
COUNTER = "AliveCounter"
#: what stands for each routed output and input in the direct bench (one instance of
#: TrainGuidance and of ForceMinimization for both modules, set-points straight into the plant)
DIRECT_OF = {
    "ECU2.gammaFront": ["ForceMin.gamma3"], "ECU2.gammaRear": ["Guidance.gamma4"],
    "ECU3.gammaFront": ["ForceMin.gamma5"], "ECU3.gammaRear": ["Guidance.gamma6"],
    "ECU2.gamma1": ["Guidance.gamma1", "ForceMin.gamma1"], "ECU3.gamma1": [],
    "ECU2.v": ["Guidance.v"], "ECU3.v": [],
    "ECU2.dPsi[1]": ["ForceMin.dPsi[1]"], "ECU3.dPsi[1]": [],
    "ECU3.dPsi[2]": ["ForceMin.dPsi[2]"],
    "Act2.cmd[1]": ["Bus.delta[3]"], "Act2.cmd[2]": ["Bus.delta[4]"],
    "Act3.cmd[1]": ["Bus.delta[5]"], "Act3.cmd[2]": ["Bus.delta[6]"],
    # the tractor ECU has no counterpart there: forwards it steers nothing (set-points 0 to Act1,
    # whose A2 stays straight as in the direct bench) and sends forwards (0), both exact on the bus
    "ECU1.gamma1": [], "Act1.cmd[1]": [], "Act1.cmd[2]": [], "ECU2.direction": [], "ECU3.direction": [],
    "ECU1.gammaFront": [], "ECU1.gammaRear": [], "ECU1.drivingDirection": [],
}


def direct_names(names):
    return [d for n in names for d in DIRECT_OF.get(n, [n])]


def routes():
    """{(message, signal): (source "C.v", [receiver "C.v", ...])} as the bench declares them."""
    bench = ssp.read(ssp.ssp_path(CAN_BENCH))
    out = {}
    for c in bench.connections:
        if c.can:
            src, ends = out.setdefault((c.can["message"], c.can["signal"]), (".".join(c.start), []))
            assert src == ".".join(c.start)
            ends.append(".".join(c.end))
    return out


ROUTES = routes()
DATA_ROUTES = {k: v for k, v in ROUTES.items() if k[1] != COUNTER}
RECEIVERS = sorted({e for _, ends in ROUTES.values() for e in ends})
SOURCES = sorted({s for s, _ in ROUTES.values()})
KPI_RECORD = [f"Bus.{n}[{a}]" for n in ("xAxle", "yAxle") for a in range(1, 7)] + ["Bus.FjointY[1]", "Driver.s"]
FALLBACK = ["ECU2.fallback", "ECU3.fallback", "Act2.fallback", "Act3.fallback", "ECU1.fallback", "Act1.fallback"]


#: the tractor ECU's outputs, the direction each ECU steers for, the speed it decides from
TRACTOR = ["ECU1.gammaFront", "ECU1.gammaRear", "Act1.delta[1]", "Act1.delta[2]", "Bus.vx[1]"] + \
    [f"ECU{m}.drivingDirection" for m in (1, 2, 3)]


def kpis(r):
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in (2, 4, 6)}
    return np.array([kpi.trace_deviation(*ax[2], *ax[4]), kpi.trace_deviation(*ax[2], *ax[6]),
                     kpi.peak(r["Bus.FjointY[1]"])])


def run_direct(**kw):
    return run(DIRECT, overrides=ssp.variant_overrides(DIRECT, [DIRECT_VARIANT]), **kw)


@pytest.fixture(scope="module")
def direct():
    return run_direct(record=list(dict.fromkeys(KPI_RECORD + direct_names(
        [s for s, _ in DATA_ROUTES.values()] + [e for _, ends in DATA_ROUTES.values() for e in ends]))))


@pytest.fixture(scope="module")
def can_runs(tmp_path_factory):
    """Two runs of the CAN bench, one logged as .blf, one as .asc."""
    d = tmp_path_factory.mktemp("can")
    out = {}
    for suffix in ("blf", "asc"):
        log = d / f"run.{suffix}"
        with Simulation(CAN_BENCH, record=list(dict.fromkeys(KPI_RECORD + RECEIVERS + FALLBACK + TRACTOR)),
                        can_log=log) as sim:
            r = sim.run()
            out[suffix] = (r, log, sim.can.report(r.time[-1] - r.time[0]))
    return out


def test_dbc_frames_carry_counter_crc_at_10_ms():
    db = cantools.database.load_file(str(DBC))
    assert len(db.messages) == 8 and {n.name for n in db.nodes} >= {"TractorECU", "Module2ECU", "Module3ECU"}
    for m in db.messages:
        assert m.cycle_time == 10 and not m.is_extended_frame
        names = {s.name: s for s in m.signals}
        assert (names["CRC"].start, names["CRC"].length) == (0, 8)
        assert (names["AliveCounter"].start, names["AliveCounter"].length) == (8, 4)
        assert all(s.unit for s in m.signals if s.name not in ("CRC", "AliveCounter", "DrivingDirection"))


def test_e2e_crc_is_cantools_profile2_and_frame_bits_within_the_stuffing_bounds():
    rng = np.random.default_rng(3)
    for _ in range(2000):
        n = int(rng.integers(2, 9))
        data = bytes(int(b) for b in rng.integers(0, 256, n))
        data_id = int(rng.integers(0, 256))
        assert artcan.e2e_crc(data, data_id) == compute_profile2_crc(data, data_id)
        bits = artcan.frame_bits(int(rng.integers(0, 2048)), data)
        # 47 + 8 s bits without stuff bits; at most one per 4 bits after the first of the 34 + 8 s stuffed ones
        assert 47 + 8 * n <= bits <= 47 + 8 * n + (34 + 8 * n - 1) // 4
    # identifier 0, no data: 34 zero bits from SOF to the CRC (the CRC of zeros is 0), a stuff
    # bit after every fifth (00000 1 00000 1 ...): 6, then 10 bits of delimiters, ACK, EOF, 3 of IFS
    assert artcan.frame_bits(0, b"") == 34 + 6 + 10 + 3


def test_response_times_by_hand():
    """Two 8-byte messages at 500 kbit/s, 10 ms: C = 135 bit times (Davis et
    al. 2007, eq. 1); the higher one waits for the lower one already on the bus
    (B = C), the lower one for one instance of the higher one."""
    C = 135 * 2e-6
    R = artcan.response_times([(0x100, 8, 0.01), (0x200, 8, 0.01)], 500_000)
    assert R[0x100] == pytest.approx(2 * C) and R[0x200] == pytest.approx(2 * C)
    # a bus loaded beyond 100 % never ends its busy period
    assert math.isinf(artcan.response_times([(i, 8, 0.001) for i in range(5)], 500_000)[4])


def test_can_bench_reproduces_the_direct_kpis_within_a_derived_bound(direct, can_runs):
    """The bound derived from the DBC (tests/can_bound.py): each routed
    signal's error as a constant bias on its receivers' counterparts in the
    direct bench (DIRECT_OF: one controller instance for both module ECUs, the
    set-points straight into the plant). The alive counters carry no data.
    No receiver leaves normal operation (fallback 0); the paths of A4 and A6
    (the deviation KPIs' axles) within the bound, the paper's figures hold."""
    # the tractor ECU's signals have no counterpart: 0 and forwards, exact (test_tractor_ecu_...)
    signals = [(msg, sig, direct_names([src])[0], direct_names(ends))
               for (msg, sig), (src, ends) in DATA_ROUTES.items() if direct_names(ends)]
    bound = kpi_bound(direct, kpis, run_direct, signals, KPI_RECORD)
    assert_within_bound(can_runs["blf"][0], direct, kpis, bound, (4, 6), FALLBACK)


@pytest.mark.parametrize("suffix", ["blf", "asc"])
def test_log_decodes_to_the_values_the_receivers_used(can_runs, suffix):
    """The log read back with python-can, decoded with cantools (independently
    of artibus.can), gives each receiver's input bit for bit: the k-th frame
    of a message feeds the receivers' step from tick k on (recorded after it,
    row k + 1), converted deg -> rad, km/h -> m/s. Every frame passes
    cantools' profile-2 CRC check with its data ID, counters count up."""
    r, log, _ = can_runs[suffix]
    db = cantools.database.load_file(str(DBC))
    reader = pycan.BLFReader(str(log)) if suffix == "blf" else pycan.ASCReader(str(log))
    frames = {}
    for f in reader:
        frames.setdefault(f.arbitration_id, []).append(f)
    n = len(r.time) - 1
    for (msg, sig), (src, ends) in ROUTES.items():
        m = db.get_message_by_name(msg)
        fs = frames[m.frame_id]
        assert len(fs) == n
        data_id = int(m.dbc.attributes["E2EDataID"].value)
        assert all(compute_profile2_crc(bytes(f.data), data_id) == f.data[0] for f in fs)
        assert [f.data[1] & 0xF for f in fs] == [k % 16 for k in range(n)]
        # simulated time: frame k queued at tick k, on the wire for less than a cycle
        times = np.array([f.timestamp for f in fs])
        assert np.all((times > np.arange(n) * T) & (times < np.arange(n) * T + T))
        values = np.array([m.decode(bytes(f.data), decode_choices=False)[sig] for f in fs])
        factor = TO_SI[m.get_signal_by_name(sig).unit or ""]
        for x in ends:
            np.testing.assert_array_equal(r[x][1:], values * factor, err_msg=f"{msg}.{sig} -> {x}")
    # the tool prints the same values
    rows = artcan.decode_log(log, DBC)
    assert all(e == "ok" for *_, e in rows)
    assert len(rows) == sum(len(db.get_message_by_frame_id(i).signals) * len(fs) for i, fs in frames.items())


def test_tractor_ecu_sends_the_driving_direction_and_all_see_forwards_throughout(can_runs):
    """The paper's topology forwards too: the tractor ECU is a SteeringECU
    instance with module = 1, the sender of both of TractorECU's messages
    (the DBC's node TractorECU sends TractorECU_State and TractorECU_Cmd):
    DrivingDirection from its output drivingDirection to module 2's and 3's
    ECUs, its set-points to module 1's actuators. It decides the direction
    from the speed it reads (hysteresis vDir): the circle is driven at 3 m/s
    and the bus never rolls back by vDir, so the three ECUs steer forwards (0)
    throughout, and module 1, steering nothing forwards, commands exactly 0."""
    db = cantools.database.load_file(str(DBC))
    bench = ssp.read(ssp.ssp_path(CAN_BENCH))
    ecu1 = bench.components["ECU1"]
    assert ecu1.source.endswith("SteeringECU.fmu") and ecu1.parameters["module"] == 1
    tractor = {m.name for m in db.messages if m.senders == ["TractorECU"]}
    assert tractor == {"TractorECU_State", "TractorECU_Cmd"}
    src, ends = ROUTES[("TractorECU_State", "DrivingDirection")]
    assert src == "ECU1.drivingDirection" and sorted(ends) == ["ECU2.direction", "ECU3.direction"]
    assert {ROUTES[("TractorECU_Cmd", s)][0] for s in ("SteerCmdA1", "SteerCmdA2")} == {"ECU1.gammaFront", "ECU1.gammaRear"}
    # what the tractor ECU receives: the speed (vehicle network, no route) and its own axle's angle
    assert sorted(e for _, es in ROUTES.values() for e in es if e.startswith("ECU1.")) == ["ECU1.aliveA1", "ECU1.gamma1"]
    assert any(c.start == ("Bus", "vx[1]") and c.end == ("ECU1", "v") and not c.can for c in bench.connections)
    r = can_runs["blf"][0]
    v_dir = ecu1.parameters["vDir"]
    assert r["Bus.vx[1]"][0] > v_dir and np.all(r["Bus.vx[1]"] > -v_dir)
    for x in ["ECU1.drivingDirection", "ECU2.drivingDirection", "ECU3.drivingDirection",
              "ECU2.direction", "ECU3.direction"]:
        assert np.all(r[x] == 0), x
    for x in ("ECU1.gammaFront", "ECU1.gammaRear", "Act1.delta[1]", "Act1.delta[2]", "Act1.cmd[1]", "Act1.cmd[2]"):
        assert np.all(r[x] == 0), x


def test_two_runs_give_identical_traffic(can_runs):
    """The .blf of one run and the .asc of another: the same frames, bytes and
    simulated times (to the .asc's microsecond)."""
    a = list(pycan.BLFReader(str(can_runs["blf"][1])))
    b = list(pycan.ASCReader(str(can_runs["asc"][1])))
    assert len(a) == len(b) > 0
    assert all(x.arbitration_id == y.arbitration_id and bytes(x.data) == bytes(y.data) for x, y in zip(a, b))
    assert max(abs(x.timestamp - y.timestamp) for x, y in zip(a, b)) < 1e-6
    n = len(cantools.database.load_file(str(DBC)).messages)     # every message once per 10 ms tick
    ids = [x.arbitration_id for x in a[:2 * n]]
    assert ids[:n] == sorted(ids[:n]) and ids[n:] == ids[:n]      # ordered by identifier in each tick


def test_bus_load_and_response_times(can_runs):
    rep = can_runs["blf"][2]
    assert rep["bitrate"] == 500_000
    # bits of the frames actually sent, from the log, with this module's stuffing count
    frames = list(pycan.BLFReader(str(can_runs["blf"][1])))
    bits = sum(artcan.frame_bits(f.arbitration_id, bytes(f.data)) for f in frames)
    assert rep["bits"] == bits and rep["frames"] == len(frames)
    assert rep["load"] == pytest.approx(bits / (500_000 * 70.0)) and rep["load"] < 0.30
    for m in rep["messages"]:
        assert m["observed"] <= m["wcrt"] < m["period"] == pytest.approx(T), m


def test_a_corrupted_frame_is_not_used(tmp_path):
    """Entering the circle (t = 9 .. 12 s), every SensorG1_Angle frame has a
    wrong CRC; from t = 10.5 s right CRCs but a frozen counter: the receivers
    keep the last good articulation angle throughout while the plant's keeps
    changing. Both module ECUs see its alive counter stop and enter their
    fallback in the 3rd cycle without a new frame (nStale = 3): holding, then
    ramping; their actuators, whose commands keep coming, do not."""
    from artibus import can as can_mod

    def tamper(msg):
        if msg.arbitration_id == 0x102 and msg.timestamp > 9.0:
            data = bytearray(msg.data)
            if msg.timestamp < 10.5:
                data[2] ^= 0x01
            else:
                data[1] = (data[1] & 0xF0) | (899 % 16)      # the counter of the last good frame (tick 899)
                data[0] = can_mod.e2e_crc(data, 18)
            msg = pycan.Message(timestamp=msg.timestamp, arbitration_id=msg.arbitration_id,
                                is_extended_id=False, data=data)
        return msg

    with Simulation(CAN_BENCH, record=["ECU2.dPsi[1]", "ECU3.dPsi[1]", "Bus.artAngle[1]", "ECU2.aliveG1",
                                       "ECU2.stale", "Act2.fallback"] + FALLBACK[:2]) as sim:
        sim.can.tamper = tamper
        r = sim.run(stop_time=12.0)
        rejected = {m["name"]: m["rejected"] for m in sim.can.report(12.0)["messages"]}
    after = r.time > 9.0 + 2 * T
    for x in ("ECU2.dPsi[1]", "ECU3.dPsi[1]", "ECU2.aliveG1"):
        held = r[x][after]
        assert np.all(held == held[0])
    # the last good frame is tick 899 (t = 8.99 s); ticks 900, 901, 902 bring none: stale in the
    # ECUs' sample at 9.02 s, recorded at the end of that step (row of t = 9.03 s)
    for x in FALLBACK[:2]:
        first = r.time[np.argmax(r[x] > 0)]
        assert first == pytest.approx(9.03), (x, first)
        v = r[x][r.time >= 9.03 - 1e-9]
        assert v[0] == 1 and 2 in v and np.all(np.diff(v) >= 0)       # holding, then ramping (to straight)
    assert np.all(r["ECU2.stale"][r.time > 9.03] == 2)                 # bit 2: SensorG1_Angle
    assert np.all(r["Act2.fallback"] == 0)
    assert np.ptp(r["Bus.artAngle[1]"][after]) > math.radians(0.5)
    assert rejected["SensorG1_Angle"] == 300 and rejected["SensorG2_Angle"] == 0   # ticks 900..1199


def test_silent_module_ecu_ends_in_the_actuators_fallback_not_in_a_jack_knife():
    """Module 3's ECU falls silent at t = 20 s on the circle (every frame it
    sends from then on is unusable: a wrong CRC, the tamper hook; to the
    receivers the same as no frame). Its actuators detect it in the 3rd cycle
    without a new counter (nStale = 3), hold A5 and A6 for tHold = 0.2 s, ramp
    them to straight at 0.1 rad/s and stay there (fallback 1, 2, 3); module
    2's ECU does not depend on module 3's and goes on. The bus completes the
    circle, its articulation bounded well below 90 deg, and straight again at
    the end (a jack-knifed bus does not straighten)."""
    t_off = 20.0

    def silence(msg):
        if msg.arbitration_id == 0x130 and msg.timestamp > t_off:
            data = bytearray(msg.data)
            data[2] ^= 0x01
            msg = pycan.Message(timestamp=msg.timestamp, arbitration_id=msg.arbitration_id,
                                is_extended_id=False, data=data)
        return msg

    art = ["Bus.artAngle[1]", "Bus.artAngle[2]"]
    rec = ["Act3.fallback", "Act3.delta[1]", "Act3.delta[2]", "Act2.fallback", "ECU2.fallback", "ECU3.fallback",
           "Act2.delta[2]", "Driver.s"] + art
    with Simulation(CAN_BENCH, record=rec) as sim:
        sim.can.tamper = silence
        r = sim.run()
    t, fb = r.time, r["Act3.fallback"]
    # the frame of tick 2000 ends on the wire after 20 s: the last good one is tick 1999; ticks
    # 2000..2002 bring none, stale in the actuators' sample at 20.02 s, recorded at 20.03 s
    t1 = t[np.argmax(fb > 0)]
    assert t1 == pytest.approx(20.03)
    hold = (t >= t1) & (t < t1 + 0.2 - 1e-9)
    assert np.all(fb[hold] == 1)
    held = r["Act3.delta[2]"][hold]
    assert np.all(held == held[0]) and abs(held[0]) > 0.05          # A6 held, steering into the circle
    t2 = t[np.argmax(fb == 2)]
    assert t2 == pytest.approx(t1 + 0.2)
    # ramp at 0.1 rad/s: the larger held angle takes |angle| / 0.1 s to reach 0
    t3 = t[np.argmax(fb == 3)]
    big = max(abs(r["Act3.delta[1]"][hold][0]), abs(held[0]))
    assert t3 - t2 == pytest.approx(big / 0.1, abs=0.011)
    after = t >= t3
    assert np.all(fb[after] == 3) and np.all(r["Act3.delta[1]"][after] == 0) and np.all(r["Act3.delta[2]"][after] == 0)
    assert np.all(r["Act2.fallback"] == 0) and np.all(r["ECU2.fallback"] == 0) and np.all(r["ECU3.fallback"] == 0)
    assert np.ptp(r["Act2.delta[2]"][t > t3]) > 0.1                   # module 2 still steers
    # no jack-knife: the circle completed; the articulation stays well below 90 deg (a jack-knife
    # runs on beyond it) while module 3 runs straight on the circle (G2 about 65 deg, where the
    # unsteered bus, Bus36m_Circle, has 61 deg and the steered one 56 deg), and comes back on the
    # straight after it (below 10 deg from t = 60 s; the unsteered bus: G1 4.3, G2 1.7 deg), not
    # stuck at its circle value
    assert r["Driver.s"][-1] > 25 + 2 * math.pi * 17.5
    for a in art:
        circle = np.max(np.abs(r[a]))
        assert circle < math.radians(75.0), a
        end = np.max(np.abs(r[a][t > 60.0]))
        assert end < math.radians(10.0) and end < 0.2 * circle, a


@pytest.mark.parametrize("variant, direct_bench, stop", [("laneChange", "Bus36m_LaneChange", 22.0),
                                                         ("slalom", "Bus36m_Slalom", 42.0)])
def test_lane_change_and_slalom_run_on_can_as_variants(variant, direct_bench, stop):
    """The bench's variants put the road tests on the CAN topology: the same
    road, speed and start as the direct benches (A2 within 5 cm of its path
    there, 1.4 % of the 3.5 m lane offset), A4 and A6 as close to A2's trace
    as there (within 5 cm), the hinge force below the paper's 4 kN, no
    receiver in fallback, every ECU steering forwards."""
    rec = [f"Bus.{n}[{a}]" for n in ("xAxle", "yAxle") for a in (2, 4, 6)] + ["Bus.FjointY[1]"]
    dirs = [f"ECU{m}.drivingDirection" for m in (1, 2, 3)]
    c = run(CAN_BENCH, overrides=ssp.variant_overrides(CAN_BENCH, [variant]), record=rec + FALLBACK + dirs,
            stop_time=stop)
    d = run(direct_bench, record=rec)
    assert c.time[-1] == d.time[-1] == stop
    assert np.max(np.hypot(c["Bus.xAxle[2]"] - d["Bus.xAxle[2]"], c["Bus.yAxle[2]"] - d["Bus.yAxle[2]"])) < 0.05
    for a in (4, 6):
        dev = [kpi.trace_deviation(r["Bus.xAxle[2]"], r["Bus.yAxle[2]"], r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"])
               for r in (c, d)]
        assert abs(dev[0] - dev[1]) < 0.05, (a, dev)
    assert kpi.peak(c["Bus.FjointY[1]"]) < 4e3
    for x in FALLBACK + dirs:       # and forwards throughout, as the tractor ECU decided
        assert np.all(c[x] == 0), x


# --- errors: file, message, signal named; nothing half-written ---------------------------

def _variant(tmp_path, dbc=None, ssd=None):
    """The packed CAN bench with its DBC and/or its .ssd text changed."""
    src = ssp.ssp_path(CAN_BENCH)
    out = tmp_path / "Bus36m_Circle_CAN.ssp"
    with zipfile.ZipFile(src) as zi, zipfile.ZipFile(out, "w") as zo:
        for item in zi.infolist():
            data = zi.read(item.filename)
            if item.filename == "resources/Bus36m.dbc" and dbc is not None:
                data = dbc(data.decode()).encode()
            if item.filename == "SystemStructure.ssd" and ssd is not None:
                data = ssd(data.decode()).encode()
            zo.writestr(item, data)
    return out


@pytest.mark.parametrize("case, words", [
    ("malformed", ["resources/Bus36m.dbc", "not a valid DBC"]),
    ("no_crc", ["resources/Bus36m.dbc", "message SensorG2_Angle", "signal CRC"]),
    ("signal", ["SystemStructure.ssd:", "Connection Bus.artAngle[1] -> ECU2.dPsi[1]",
                "SensorG1_Angle", "no data signal 'ArtAngleG9'"]),
    ("message", ["SystemStructure.ssd:", "no message 'SensorG9_Angle'"]),
    ("range", ["resources/Bus36m.dbc", "message SensorG1_Angle", "signal ArtAngleG1",
               "Bus.artAngle[1]", "outside the signal's range [-2, 2]"]),
    ("interface", ["--can nosuch:can0", "no interface 'nosuch'"]),
])
def test_errors_name_file_message_signal_and_leave_no_log(tmp_path, case, words):
    dbc = ssd = None
    kw = {}
    if case == "malformed":
        dbc = lambda t: t.replace("BO_ 258 SensorG1_Angle: 4 HingeSensorG1", "BO_ 258 SensorG1_Angle 4 HingeSensorG1")
    elif case == "no_crc":
        rx = "TractorECU,Module2ECU,Module3ECU"
        dbc = lambda t: t.replace(f' SG_ CRC : 0|8@1+ (1,0) [0|255] "" {rx}\n SG_ AliveCounter : 8|4@1+ (1,0) [0|15] "" {rx}\n SG_ ArtAngleG2',
                                  f' SG_ AliveCounter : 8|4@1+ (1,0) [0|15] "" {rx}\n SG_ ArtAngleG2')
    elif case == "signal":
        ssd = lambda t: t.replace('message="SensorG1_Angle" signal="ArtAngleG1"', 'message="SensorG1_Angle" signal="ArtAngleG9"', 1)
    elif case == "message":
        ssd = lambda t: t.replace('message="SensorG1_Angle"', 'message="SensorG9_Angle"', 1)
    elif case == "range":    # hinge G1 swings beyond 2 deg on the circle
        dbc = lambda t: t.replace('ArtAngleG1 : 16|16@1- (0.1,0) [-90|90]', 'ArtAngleG1 : 16|16@1- (0.1,0) [-2|2]')
    elif case == "interface":
        kw["can"] = "nosuch:can0"
    path = _variant(tmp_path, dbc, ssd)
    log = tmp_path / "traffic.blf"
    with pytest.raises(ArtibusError) as e:
        with Simulation(path, can_log=log, **kw) as sim:
            sim.run(stop_time=20.0)
    msg = str(e.value)
    assert all(w in msg for w in words), msg
    assert list(tmp_path.glob("traffic*")) == []


def test_cli_run_and_decode(tmp_path):
    import subprocess
    import sys
    log, out = tmp_path / "t.asc", tmp_path / "d.csv"
    r = subprocess.run([sys.executable, "-m", "artibus", "run", CAN_BENCH, "--stop-time", "0.5",
                        "--can", "virtual", "--can-log", str(log), "-o", str(tmp_path / "r.csv")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "bus load" in r.stdout and "worst-case response" in r.stdout
    r = subprocess.run([sys.executable, "-m", "artibus", "can", "decode", str(log), "--csv", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = out.read_text().splitlines()
    assert lines[0] == "time_s,message,signal,value,unit,e2e" and len(lines) == 1 + 50 * (4 * 3 + 4 + 3 * 4)   # 4 sensor frames of 3 signals, the tractor state, 3 command frames
    r = subprocess.run([sys.executable, "-m", "artibus", "run", CAN_BENCH, "--can", "nosuch"],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "Traceback" not in r.stderr and "--can nosuch" in r.stderr
