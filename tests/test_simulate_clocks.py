"""A lone clocked FMI 3.0 Co-Simulation FMU in `artibus simulate` (issue 38): Event Mode, its
periodic input Clock activated at t_start + shift + k interval (FMI 3.0 2.2, "Clocks":
"Periodic Clock"), the steps cut there, its clocked Binary output recorded as hex text while
the Clock is active (2.2, "Model Partitions and Clocked Variables").

The FMU: our FMI-LS-BUS sensor node fmus/fmi3/SteeringSensors_LSBUS.fmu, its Tx_Clock periodic
(interval read here from its modelDescription.xml). At each activation it sends one CAN Transmit
operation per sensor message of ssp/can/Bus36m.dbc, each with an alive counter incremented by one
per frame (the DBC: byte 1, bits 0-3); the first activation starts with a Configuration. The
operations are parsed here after FMI-LS-BUS 4.4.1 (CAN), "Transmit": OP Code 0x10 (4 bytes),
Length = 16 + Data Length (4), ID (4), Ide (1), Rtr (1), Data Length (2), Data; "Configuration"
OP Code 0x40; numbers little-endian (FMI-LS-BUS 4, "Network Abstraction")."""
import re
import struct
import zipfile

import numpy as np
import pytest
from lxml import etree

from artibus import fmu_dir
from artibus.base import ROOT
from artibus.fmu import simulate

NODE = "SteeringSensors_LSBUS"
TX = "SteeringCAN.Tx_Data"
#: the node's two forms (its README): Tx_Clock a periodic input clock the importer ticks, or a
#: triggered output clock the node activates in an Event Mode it asks for (fmi3DoStep's
#: eventHandlingNeeded), which the importer reads with fmi3GetClock (2.2, "Output Clock")
FORMS = {"periodic input clock": f"fmi3/{NODE}.fmu",
         "triggered output clock": f"fmi3/lsbus-triggered/{NODE}_Triggered.fmu"}


def form(name):
    path = fmu_dir() / FORMS[name]
    if not path.is_file():
        pytest.skip(f"{path} not built")
    return path


def tx_clock():
    """(intervalDecimal, shiftDecimal) of the node's Tx_Clock, from its modelDescription.xml"""
    with zipfile.ZipFile(fmu_dir() / "fmi3" / f"{NODE}.fmu") as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    el = root.find("ModelVariables/Clock[@name='SteeringCAN.Tx_Clock']")
    return float(el.get("intervalDecimal")), float(el.get("shiftDecimal", "0"))


def sensor_messages():
    """{CAN ID: DLC} of the DBC's messages a sensor node sends (BO_ ID NAME: DLC SENDER)"""
    text = (ROOT / "ssp" / "can" / "Bus36m.dbc").read_text()
    return {int(i): int(n) for i, n, s in re.findall(r"^BO_ (\d+) \w+: (\d+) (\w+)", text, re.M) if "Sensor" in s}


def operations(hex_text):
    """[(OP Code, ID or None, data bytes or None)] of one Tx_Data value"""
    data, out, k = bytes.fromhex(hex_text), [], 0
    while k < len(data):
        op, length = struct.unpack_from("<II", data, k)
        if op == 0x10:
            can_id, _ide, _rtr, n = struct.unpack_from("<IBBH", data, k + 8)
            assert length == 16 + n
            out.append((op, can_id, data[k + 16:k + 16 + n]))
        else:
            out.append((op, None, None))
        k += length
    assert k == len(data)
    return out


def transmitted(hex_text):
    """{CAN ID: alive counter} of the CAN Transmit operations of one Tx_Data value"""
    return {i: d[1] & 0x0F for op, i, d in operations(hex_text) if op == 0x10}


@pytest.mark.parametrize("name", FORMS)
def test_the_clock_ticks_at_every_interval(name):
    interval, shift = tx_clock()
    r = simulate(form(name), stop_time=0.2, step=interval, outputs=[TX])
    texts, times = r.strings[TX], np.asarray(r["time"])
    assert len(times) == 21
    messages = sensor_messages()
    assert len(messages) == 4
    for k, (t, x) in enumerate(zip(times, texts)):
        assert t == pytest.approx(shift + k * interval)
        assert transmitted(x) == {i: k % 16 for i in messages}, (t, x)
        assert all(len(d) == messages[i] for op, i, d in operations(x) if op == 0x10)
    assert operations(texts[0])[0][0] == 0x40 and all(op == 0x10 for x in texts[1:] for op, *_ in operations(x))


@pytest.mark.parametrize("name", FORMS)
def test_ticks_between_the_recorded_points_cut_the_steps(name):
    """at a step of 0.4 intervals the Clock still ticks every interval (the steps cut there, not
    recorded; the triggered form's ticks: at its nextEventTime); a row at a tick holds its
    frames, a row between ticks none (the Clock inactive: its clocked output is not read)"""
    interval, shift = tx_clock()
    step = 0.4 * interval
    r = simulate(form(name), stop_time=0.2, step=step, outputs=[TX])
    times, texts = np.asarray(r["time"]), r.strings[TX]
    np.testing.assert_allclose(times, np.arange(len(times)) * step, atol=1e-12)     # no row at a tick between
    at_tick = np.isclose((times - shift) / interval, np.round((times - shift) / interval), atol=1e-9)
    assert at_tick.sum() == 11 and (~at_tick).sum() > 20
    for t, x, tick in zip(times, texts, at_tick):
        if tick:   # the alive counter counts every activation, the unrecorded ones too
            k = int(round((t - shift) / interval))
            assert transmitted(x) == {i: k % 16 for i in sensor_messages()}, (t, x)
        else:
            assert x == "", (t, x)


class _Slave:
    """A stand-in for an FMU's fmi3GetIntervalDecimal: the next (interval, qualifier) of each call"""

    def __init__(self, answers):
        self.answers, self.asked = list(answers), 0

    def getIntervalDecimal(self, vrs, intervals, qualifiers):
        self.asked += 1
        intervals[0], qualifiers[0] = self.answers.pop(0)


def test_a_countdown_clock_is_due_at_the_event_time_plus_the_interval_the_fmu_gives():
    """FMI 3.0 2.2, "Clock Types": a countdown Clock's interval asked in Initialization Mode and in
    every Event Mode; fmi3IntervalChanged (2) "relative to the time of the current Event Mode",
    fmi3IntervalUnchanged (1) / fmi3IntervalNotYetKnown (0) leave the Clock as it was. No lone
    FMU here has a countdown input Clock (the bus FMU's are driven by the network): a stand-in."""
    from artibus.fmu.clocks import Clock, Schedule
    el = etree.fromstring('<Clock name="c" valueReference="7" causality="input" intervalVariability="countdown"/>')
    slave = _Slave([(0.0, 0), (0.25, 2), (0.0, 1), (0.5, 2)])
    calls = type("Calls", (), {"slave": slave})()
    s = Schedule(calls, [Clock(el)], "stand-in.fmu")
    s.start(1.0)                                    # not yet known: no tick
    assert s.next_time() == float("inf") and s.due(5.0) == []
    s.update(1.0)                                   # changed: 0.25 after this Event Mode at t = 1
    assert s.next_time() == pytest.approx(1.25) and s.due(1.25) == [7] and s.due(1.2) == []
    s.ticked([7])
    s.update(1.25)                                  # unchanged after its activation: none due
    assert s.next_time() == float("inf")
    s.update(2.0)                                   # a new interval in the Event Mode at t = 2
    assert s.next_time() == pytest.approx(2.5) and slave.asked == 4


def test_a_periodic_clock_counts_from_its_first_tick_without_drift():
    """t_i = t_start + shift + i interval (FMI 3.0 2.2, "Periodic Clock"), not a running sum"""
    from artibus.fmu.clocks import Clock, Schedule
    el = etree.fromstring('<Clock name="p" valueReference="3" causality="input" intervalVariability="fixed" '
                          'intervalDecimal="0.1" shiftDecimal="0.05"/>')
    s = Schedule(type("Calls", (), {"slave": _Slave([])})(), [Clock(el)], "stand-in.fmu")
    s.start(2.0)
    assert s.next_time() == 2.05
    for _ in range(1000):
        s.ticked(s.due(s.next_time()))
    assert s.next_time() == 2.05 + 1000 * 0.1


def test_the_command_line_records_the_binary_output_fmpy_s_option_names(tmp_path):
    """`--output-variables` (FMPy's name; ours `--record`): the clocked Binary as hex text, at each
    tick, empty between; a Clock asked for is refused by name"""
    import csv
    import subprocess
    import sys
    interval, shift = tx_clock()
    out = tmp_path / "node.csv"
    fmu = str(fmu_dir() / "fmi3" / f"{NODE}.fmu")
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", fmu, "--stop-time", str(4 * interval),
                        "--step", str(interval / 2), "--output-variables", TX, "-o", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 9
    for k, row in enumerate(rows):
        if k % 2:
            assert row[TX] == ""
        else:
            assert transmitted(row[TX]) == {i: (k // 2) % 16 for i in sensor_messages()}
    p = subprocess.run([sys.executable, "-m", "artibus", "simulate", fmu, "--record", "SteeringCAN.Tx_Clock",
                        "-o", str(tmp_path / "c.csv")], capture_output=True, text=True)
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "SteeringCAN.Tx_Clock is an FMI 3.0 Clock" in p.stderr
