"""Fault injection on the CAN path (artibus.can, issue 12): frame loss,
latency and jitter, corrupted frames, a silent node, bus-off. Expected
patterns are computed here from the faults' definitions (the same seed drawn
with numpy, the window's ticks, the E2E rules) and checked against the
receivers' inputs, the runner's stale record and the log read back with
python-can and cantools."""
import csv
import math
import subprocess
import sys

import can as pycan
import cantools
import numpy as np
import pytest
from cantools.autosar.end_to_end import compute_profile2_crc

from artibus import ArtibusError, ROOT, can as artcan
from artibus.runner import Simulation

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
BENCH = "Bus36m_Circle_CAN"
T = 0.01                 # the network's tick = every message's cycle
N_STALE = 3              # SteeringECU.nStale (its start value, the bench keeps it): stale in the 3rd cycle in a row
DB = cantools.database.load_file(str(DBC))
DEG = math.pi / 180


def frames_of(log, name):
    """(timestamp, data) of every frame of message `name` in a .blf/.asc log, and the error frames."""
    fid = DB.get_message_by_name(name).frame_id
    reader = pycan.BLFReader(str(log)) if str(log).endswith(".blf") else pycan.ASCReader(str(log))
    frames, errors = [], []
    for f in reader:
        if f.is_error_frame:
            errors.append(f)
        elif f.arbitration_id == fid:
            frames.append((f.timestamp, bytes(f.data)))
    return frames, errors


def tick_of(t):
    return int(math.floor(t / T + 1e-6))


def quantised(name, signal, value_si, unit_factor):
    """The value a receiver gets: encoded and decoded by cantools (scale of the DBC)."""
    m = DB.get_message_by_name(name)
    values = {s.name: 0 for s in m.signals}
    values[signal] = value_si / unit_factor
    return m.decode(m.encode(values, scaling=True))[signal] * unit_factor


def run(faults, stop, record, log=None):
    with Simulation(BENCH, record=record, can_log=log, can_faults=faults) as sim:
        r = sim.run(stop_time=stop)
        return r, sim.can.report(stop), sim.can.summary(stop)


# --- loss -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def lossy(tmp_path_factory):
    log = tmp_path_factory.mktemp("loss") / "loss.blf"
    rec = ["ECU3.dPsi[2]", "ECU3.stale", "Bus.artAngle[2]", "Driver.s"]
    return run(["loss:SensorG2_Angle:0.1:seed=7"], 70.0, rec, log) + (log,)


def test_loss_10_percent_run_completes_and_stale_record_starts_where_the_seed_drops(lossy):
    """One uniform number per frame of the message (numpy default_rng(seed)),
    the frame lost below the rate: the run covers its 70 s, the lost frames
    are missing from the log, the receivers hold the last good value over
    them, and the runner's sinceGood record equals the run lengths of the
    drop pattern: it first reaches N_STALE exactly at the N_STALE-th
    consecutive drop."""
    r, rep, summary, log = lossy
    n = 7000
    assert r.time[-1] == pytest.approx(70.0)
    dropped = np.random.default_rng(7).random(n) < 0.1
    assert 0.08 < dropped.mean() < 0.12
    since = np.zeros(n, dtype=int)
    run_len = 0
    for k in range(n):
        run_len = run_len + 1 if dropped[k] else 0
        since[k] = run_len
    first = int(np.argmax(since >= N_STALE))
    assert since[first] == N_STALE and dropped[first - N_STALE + 1:first + 1].all()
    col = r["can.SensorG2_Angle.sinceGood"]
    np.testing.assert_array_equal(col[1:], since)                   # row k + 1: after tick k
    assert int(np.argmax(col >= N_STALE)) - 1 == first
    # module 3's ECU flags SensorG2_Angle (bit 4) stale exactly in those cycles: its own check on the counters
    flagged = (r["ECU3.stale"][1:].astype(int) & 4) != 0
    assert int(np.argmax(flagged)) == first
    np.testing.assert_array_equal(flagged, since >= N_STALE)
    m = next(x for x in rep["messages"] if x["name"] == "SensorG2_Angle")
    assert m["lost"] == dropped.sum() and m["sent"] == n - dropped.sum() and m["rejected"] == 0
    assert m["longest"] == since.max()
    # the log: what was on the wire, counters of the frames made (lost ones included)
    frames, _ = frames_of(log, "SensorG2_Angle")
    kept = np.flatnonzero(~dropped)
    assert [tick_of(t) for t, _ in frames] == list(kept)
    assert [d[1] & 0xF for _, d in frames] == list(kept % 16)
    # the receivers: the quantised angle of the tick where a frame came, held where none did
    for x in ("ECU3.dPsi[2]",):
        got = r[x][1:]
        for k in range(1, n):
            if dropped[k]:
                assert got[k] == got[k - 1], (x, k)
        for k in kept[:400]:
            assert got[k] == pytest.approx(quantised("SensorG2_Angle", "ArtAngleG2", r["Bus.artAngle[2]"][k], DEG),
                                           abs=1e-12), (x, k)
    assert "SensorG2_Angle" in summary and f"{since.max()}, reached at" in summary


def test_same_seed_same_run_other_seed_other_run(tmp_path):
    spec = ["loss:SensorG2_Angle:0.2:seed=11", "latency:Module2ECU_Cmd:0.02:jitter=0.005:seed=3@2-4"]
    rec = ["Act2.cmd[2]", "ECU3.dPsi[2]"]
    a = run(spec, 5.0, rec, tmp_path / "a.blf")
    b = run(spec, 5.0, rec, tmp_path / "b.blf")
    c = run(["loss:SensorG2_Angle:0.2:seed=12", "latency:Module2ECU_Cmd:0.02:jitter=0.005:seed=4@2-4"],
            5.0, rec, tmp_path / "c.blf")
    np.testing.assert_array_equal(a[0].array(), b[0].array())
    fa, fb, fc = (list(pycan.BLFReader(str(tmp_path / f"{x}.blf"))) for x in "abc")
    assert [(f.timestamp, bytes(f.data)) for f in fa] == [(f.timestamp, bytes(f.data)) for f in fb]
    assert [(f.timestamp, bytes(f.data)) for f in fa] != [(f.timestamp, bytes(f.data)) for f in fc]


def test_kpis_with_faults_next_to_fault_free(tmp_path):
    """artibus run --can-fault ... --report: the fault-free run's KPIs are
    printed and written beside the faulty run's; with 10 % loss on one hinge
    angle the steered trailers still keep seed 000's < 1.0 m deviation."""
    out = tmp_path / "rep"
    p = subprocess.run([sys.executable, "-m", "artibus", "run", BENCH, "--can-fault", "loss:SensorG2_Angle:0.1:seed=7",
                        "--report", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "KPIs with faults (loss:SensorG2_Angle:0.1:seed=7) against the fault-free run" in p.stdout
    assert "longest run of cycles without a good frame" in p.stdout
    lines = (out / "kpi_faults.csv").read_text().splitlines()
    assert lines[0] == "kpi,unit,fault_free,with_faults,difference" and len(lines) > 3
    rows = [l.rsplit(",", 3) for l in lines[1:]]
    dev = [(float(a), float(b)) for name, a, b, _ in rows if "deviation" in name.lower()][:2]
    assert len(dev) == 2 and all(b < 1.0 for _, b in dev)
    assert any(float(a) != float(b) for _, a, b, _ in rows if a != "nan")
    assert (out / "fault-free" / "index.html").is_file() and (out / "index.html").is_file()
    # the receivers' fallback in the report and its KPIs: module 3's ECU, which uses G2, falls
    # back where 3 frames in a row were lost; no receiver does without the faults
    with open(out / "kpi_faults.csv", newline="") as f:
        table = list(csv.DictReader(f))
    worst = {row["kpi"].split(":")[0]: (float(row["fault_free"]), float(row["with_faults"]))
             for row in table if "worst fallback state" in row["kpi"]}
    assert set(worst) == {"ECU1", "ECU2", "ECU3", "Act1", "Act2", "Act3"}
    assert all(a == 0.0 for a, _ in worst.values())
    assert worst["ECU3"][1] >= 1.0 and worst["ECU2"][1] == 0.0
    assert (out / "fallback.png").is_file() and "fallback.png" in (out / "index.html").read_text()
    assert "bus load" in (out / "can_bus.txt").read_text()


# --- corrupted frames: never used -----------------------------------------------------

@pytest.mark.parametrize("mode, window, rejected", [
    ("crc", (20.0, 20.5), range(2000, 2050)),        # every frame in the window: payload bit flipped after the CRC
    ("repeat", (20.0, 20.03), range(2000, 2003)),    # the last good counter again, three times
    ("skip", (20.0, 20.01), range(2000, 2001)),      # the counter jumps over a value: a wrong sequence
])
def test_corrupted_frame_is_never_used(tmp_path, mode, window, rejected):
    """The receivers keep the last good value over every rejected frame; the
    log holds the frames as sent: the rejected ones fail the profile-2 CRC
    (crc) or carry a counter that is not the last good one + 1 (repeat,
    skip); the next frame is used again."""
    log = tmp_path / "c.asc"
    rec = ["ECU2.dPsi[1]", "ECU3.dPsi[1]", "Bus.artAngle[1]"]
    r, rep, _ = run([f"corrupt:SensorG1_Angle:{mode}@{window[0]}-{window[1]}"], 21.0, rec, log)
    m = next(x for x in rep["messages"] if x["name"] == "SensorG1_Angle")
    assert m["rejected"] == len(rejected) and m["corrupted"] == len(rejected) and m["sent"] == 2100
    frames, _ = frames_of(log, "SensorG1_Angle")
    data_id = int(DB.get_message_by_name("SensorG1_Angle").dbc.attributes["E2EDataID"].value)
    k0, k1 = rejected[0], rejected[-1]
    good_counter = frames[k0 - 1][1][1] & 0xF
    for k in rejected:
        d = frames[k][1]
        if mode == "crc":
            assert compute_profile2_crc(d, data_id) != d[0]
        else:
            assert compute_profile2_crc(d, data_id) == d[0]
            assert (d[1] & 0xF) != (good_counter + 1) % 16
    nxt = frames[k1 + 1][1]
    assert compute_profile2_crc(nxt, data_id) == nxt[0]
    for x in ("ECU2.dPsi[1]", "ECU3.dPsi[1]"):
        got = r[x]
        held = got[k0]                                   # row k0: after tick k0 - 1, the last good frame
        assert np.all(got[k0 + 1:k1 + 2] == held), x     # rows after the rejected ticks
        assert got[k1 + 2] == DB.get_message_by_name("SensorG1_Angle").decode(nxt)["ArtAngleG1"] * DEG
    if mode == "crc":   # the plant's angle moved meanwhile: holding is visible
        assert abs(r["Bus.artAngle[1]"][k1] - r["Bus.artAngle[1]"][k0]) > 0.05 * DEG
    # the tool's view of the log agrees: exactly these frames are not ok
    bad = sorted({tick_of(t) for t, msg, s, v, u, e in artcan.decode_log(log, DBC)
                  if msg == "SensorG1_Angle" and e != "ok"})
    assert bad == list(rejected)


# --- latency --------------------------------------------------------------------------

def test_latency_shifts_the_receivers_input_by_its_ticks(tmp_path):
    """latency 0.02 s on Module2ECU_Cmd in 10..20 s: frame k is on the wire in
    tick k + 2 and the plant's A3/A4 set-points after tick k + 2 are the
    controllers' outputs of tick k, quantised."""
    log = tmp_path / "l.blf"
    rec = ["Act2.cmd[1]", "Act2.cmd[2]", "ECU2.gammaFront", "ECU2.gammaRear"]
    r, rep, _ = run(["latency:Module2ECU_Cmd:0.02@10-20"], 21.0, rec, log)
    frames, _ = frames_of(log, "Module2ECU_Cmd")
    ticks = [tick_of(t) for t, _ in frames]
    counters = [d[1] & 0xF for _, d in frames]
    assert ticks[:1000] == list(range(1000))
    k = ticks.index(1002)
    assert ticks[k:k + 998] == list(range(1002, 2000)) and counters[k:k + 998] == [c % 16 for c in range(1000, 1998)]
    m = next(x for x in rep["messages"] if x["name"] == "Module2ECU_Cmd")
    assert m["delayed"] == 1000
    for src, dst, sig in (("ECU2.gammaFront", "Act2.cmd[1]", "SteerCmdA3"), ("ECU2.gammaRear", "Act2.cmd[2]", "SteerCmdA4")):
        for tk in range(1002, 2000, 7):
            want = quantised("Module2ECU_Cmd", sig, r[src][tk - 2], DEG)
            assert r[dst][tk + 1] == pytest.approx(want, abs=1e-12), (dst, tk)
    assert r["can.Module2ECU_Cmd.sinceGood"][1001:1004].tolist() == [1, 2, 0]


# --- silent node, bus-off -----------------------------------------------------------

def test_silent_node_sends_nothing_in_its_window(tmp_path):
    log = tmp_path / "s.blf"
    r, rep, _ = run(["silent:Module3ECU@20-21"], 22.0, ["Act3.cmd[1]", "Act3.cmd[2]", "ECU3.gammaRear"], log)
    frames, _ = frames_of(log, "Module3ECU_Cmd")
    ticks = [tick_of(t) for t, _ in frames]
    assert ticks == [k for k in range(2200) if not 2000 <= k < 2100]
    for x in ("Act3.cmd[1]", "Act3.cmd[2]"):
        assert np.all(r[x][2001:2101] == r[x][2000])
    assert r["can.Module3ECU_Cmd.sinceGood"][2100] == 100 and r["can.Module3ECU_Cmd.sinceGood"][2101] == 0
    # its first frame after the window (counter 101 ahead: within the 15 an E2E receiver allows) is used
    assert r["Act3.cmd[2]"][2101] == pytest.approx(quantised("Module3ECU_Cmd", "SteerCmdA6", r["ECU3.gammaRear"][2100], DEG),
                                                    abs=1e-12)
    assert rep["messages"][-1]["suppressed"] == 100


@pytest.mark.parametrize("recover, resume", [(None, None), ("recover=0.1", 3011)])
def test_busoff_stops_the_node_and_recovers_after_128x11_bits(tmp_path, recover, resume):
    """busoff at 30 s: one burst of 32 failed attempts (error frames in the
    log), then nothing from the node; with recovery, frames again from the
    first tick after burst + 128 x 11 bit times (2.8 ms at 500 kbit/s) +
    the stated delay: 30.0 + (< 9.3 ms) + 0.1 s -> the tick at 30.11 s."""
    log = tmp_path / "b.blf"
    spec = "busoff:HingeSensorG1@30" + (f":{recover}" if recover else "")
    r, rep, _ = run([spec], 30.5, ["ECU2.dPsi[1]"], log)
    frames, errors = frames_of(log, "SensorG1_Angle")
    ticks = [tick_of(t) for t, _ in frames]
    assert ticks[:3000] == list(range(3000))
    assert len(errors) >= 1 and all(abs(e.timestamp - 30.0) < T for e in errors)
    if resume is None:
        assert ticks[3000:] == []
        assert np.all(r["ECU2.dPsi[1]"][3001:] == r["ECU2.dPsi[1]"][3000])
    else:
        assert ticks[3000:] == list(range(resume, 3050))
    assert rep["error_frames"] == 32


# --- bad specifications -----------------------------------------------------------------

@pytest.mark.parametrize("spec, words", [
    ("loss:NoSuchMsg:0.1", ["--can-fault loss:NoSuchMsg:0.1", "no message or sending node 'NoSuchMsg'", "SensorG1_Angle"]),
    ("silent:SensorG1_Angle", ["no node 'SensorG1_Angle'", "its sender is HingeSensorG1"]),
    ("busoff:SteerActuatorM2@3", ["node SteerActuatorM2 sends no message"]),
    ("loss:SensorG1_Angle:1.5", ["--can-fault loss:SensorG1_Angle:1.5", "rate = '1.5'"]),
    ("jam:SensorG1_Angle", ["unknown fault 'jam'"]),
    ("corrupt:SensorG1_Angle:flip", ["corrupt mode 'flip'", "crc, repeat, skip"]),
    ("loss:SensorG1_Angle:0.1@5-2", ["window '@5-2'"]),
    ("latency:Module2ECU_Cmd", ["latency needs its delay"]),
    ("loss:SensorG1_Angle:0.1:jitter=1", ["loss takes no option 'jitter'"]),
    ("loss:SensorG1_Angle:0.1:seed=x", ["seed = 'x'"]),
])
def test_bad_fault_specs_are_errors_naming_them_and_leave_no_log(tmp_path, spec, words):
    log = tmp_path / "x.blf"
    with pytest.raises(ArtibusError) as e:
        with Simulation(BENCH, can_log=log, can_faults=[spec]) as sim:
            sim.run(stop_time=0.1)
    assert all(w in str(e.value) for w in words), str(e.value)
    assert list(tmp_path.iterdir()) == []


def test_cli_fault_errors_and_benches_without_can(tmp_path):
    p = subprocess.run([sys.executable, "-m", "artibus", "run", BENCH, "--can-fault", "loss:Nope:0.1",
                        "--stop-time", "0.1", "-o", str(tmp_path / "r.csv")], capture_output=True, text=True)
    assert p.returncode == 1 and "Traceback" not in p.stderr and "'Nope'" in p.stderr
    assert not (tmp_path / "r.csv").exists()
    with pytest.raises(ArtibusError, match="routes no connection over CAN"):
        Simulation("Urbino18_Circle", can_faults=["loss:SensorG1_Angle:0.1"])


def test_parse_fault_reads_as_written():
    f = artcan.parse_fault("latency:Module2ECU_Cmd:0.02:jitter=0.005:seed=3")
    assert (f.kind, f.target, f.delay, f.jitter, f.seed, f.start, f.end) == \
        ("latency", "Module2ECU_Cmd", 0.02, 0.005, 3, -math.inf, math.inf)
    f = artcan.parse_fault("corrupt:TractorECU_State:crc@20.0-20.5")
    assert (f.mode, f.start, f.end, f.rate) == ("crc", 20.0, 20.5, 1.0)
    f = artcan.parse_fault("busoff:Module2ECU@30:recover")
    assert (f.kind, f.start, f.recover) == ("busoff", 30.0, 0.0)
    assert artcan.parse_fault("silent:Module3ECU@20").start == 20.0
