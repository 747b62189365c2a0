"""Our FMI-LS-BUS CAN bus and two nodes in another tool's importer: the container FMU of
fmu-manipulation-toolbox (PyPI, 2.0: `fmucontainer`, "support of LS-BUS", its
docs/user-guide/fmucontainer/ls-bus.md), run by FMPy.

CanBus + SteeringSensors_LSBUS (node 1, the sender) + SteeringECU_LSBUS (node 2, the
tractor ECU, module 1: it takes the speed from its own input, so the sensors' frames are all
it needs) in one FMI 3.0 container, the nodes' terminals linked to the bus's Node1/Node2
(matching rule org.fmi-ls-bus.transceiver), run with fmpy.simulate_fmu.

What works: the toolbox reads our terminals and manifests (the four members of each
terminal linked crosswise, CanBus's countdown Tx_Clocks scheduled by the container) and
the container runs without an error. The container schedules only countdown input clocks
(the bus's Tx_Clock, by fmi3GetIntervalDecimal) and triggered output clocks (fmi3GetClock,
as the fmi-ls-bus-examples node has): our nodes' default, periodic input Tx_Clock
(intervalVariability="constant", 10 ms, which FMI-LS-BUS 1.0 allows) it never activates
(fmu_manipulation_toolbox 2.0 container/builder.py: only `interval_variability ==
"countdown"` enters its ClockList). So the container runs the nodes in the Tx clock's
triggered form (fmus/fmi3/lsbus-triggered/, issue 39), whose frames reach the bus every
cycle. The container steps 0 s to serve a countdown clock due now (FMI 3.0.2, 4.2 wants a
step > 0): our nodes take it as no step, with a warning.
The bus's frames reach the nodes with CanBus in its triggered form too (CanBus_Triggered:
the container passes on no countdown-clocked variable, see below): the acceptance test of
issue 39 runs the sensors and two ECUs there and compares module 2's set-points with the
FMI 2.0 SteeringECU's. Without the package the tests are skipped."""
import shutil
import zipfile

import pytest

from conftest import fmu3
from artibus import fmu_dir
from test_lsbus_node import DEG_RAD, KMH_MS, MS_KMH, RAD_DEG, python_frame

toolbox = pytest.importorskip("fmu_manipulation_toolbox", reason="fmu-manipulation-toolbox (PyPI) not installed")
from fmu_manipulation_toolbox.assembly import AssemblyNode  # noqa: E402

NODES = {"SteeringSensors_LSBUS.fmu": "Node1", "SteeringECU_LSBUS.fmu": "Node2"}
STEP = 1e-4          # the container's internal step: the wire time of a frame is ~0.23 ms
INPUTS = {"gamma1": 0.12, "dPsi[1]": 0.21, "dPsi[2]": -0.13, "gammaA6": 0.05, "vVehicle": 3.0}


def triggered(name):
    """the node in the Tx clock's triggered form (fmus/fmi3/lsbus-triggered/, issue 39)"""
    from pathlib import Path
    path = Path(fmu3("CanBus")).parent / "lsbus-triggered" / f"{name}_Triggered.fmu"
    if not path.is_file():
        pytest.fail(f"{path} not built")
    return path


@pytest.fixture(scope="module")
def container(tmp_path_factory):
    d = tmp_path_factory.mktemp("lsbus_container")
    shutil.copy(fmu3("CanBus"), d / "CanBus.fmu")
    for name in ("SteeringSensors_LSBUS", "SteeringECU_LSBUS"):      # the container's file names, our nodes'
        shutil.copy(triggered(name), d / f"{name}.fmu")
    node = AssemblyNode("LsBusContainer.fmu", step_size=STEP, auto_local=True)
    node.add_fmu("CanBus.fmu")
    for fmu, terminal in NODES.items():
        node.add_fmu(fmu)
        node.add_link(fmu, "SteeringCAN", "CanBus.fmu", terminal)
    node.add_start_value("SteeringECU_LSBUS.fmu", "module", "1")
    node.make_fmu(d, fmi_version=3)
    path = d / "LsBusContainer.fmu"
    assert path.is_file()
    return path


def simulate(path, stop):
    from fmpy import simulate_fmu
    log = []
    # the container has no Event Mode of its own (hasEventMode="false"): its runtime is the
    # clock-scheduling importer of the FMUs inside, FMPy only steps it
    result = simulate_fmu(str(path), stop_time=stop, step_size=0.001, output_interval=0.001,
                          start_values=INPUTS, logger=lambda *a: log.append(a[-1].decode(errors="replace")),
                          output=["nFrames", "steeringecu_lsbus.gamma1", "steeringecu_lsbus.aliveA1",
                                  "fallback", "stale"])
    return result, log


def test_the_toolbox_links_our_terminals_and_schedules_the_bus_clocks(container):
    with zipfile.ZipFile(container) as z:
        txt = z.read("resources/container.txt").decode()
        md = z.read("modelDescription.xml").decode()
    # each node's Tx_Data -> the bus's NodeK.Rx_Data and the bus's NodeK.Tx_Data -> its Rx_Data
    # travel through the container's local binaries (4_4_1_can.adoc's terminal, crosswise)
    for local in ("steeringsensors_lsbus.SteeringCAN.Tx_Data", "canbus.Node1.Tx_Data",
                  "steeringecu_lsbus.SteeringCAN.Tx_Data", "canbus.Node2.Tx_Data"):
        assert f'name="{local}"' in md
    # CanBus (the container's FMU 0) NodeK.Tx_Clock (countdown, vr 100 k + 4) for k = 1, 2 in
    # the clocks the container schedules: "<FMU_INDEX> <NB> <FMU_VR> <VR> [<FMU_VR> <VR>]"
    head, rows = txt.split("# importer CLOCKS:")[1].split("\n", 1)
    lines = rows.split("\n")
    n_fmus = int(lines[0].split()[0])
    scheduled = set()
    for line in lines[1:1 + n_fmus]:
        fmu, nb, *pairs = (int(x) for x in line.split())
        scheduled |= {(fmu, pairs[2 * i]) for i in range(nb)}
    assert {(0, 104), (0, 204)} <= scheduled, scheduled
    assert 'isBusSimulationFMU' not in md          # the container itself is no bus simulation


def test_the_nodes_frames_reach_the_bus_every_cycle(container):
    """the nodes in the triggered form (their Tx_Clock an output triggered clock, which the
    container reads with fmi3GetClock after an eventHandlingNeeded): every 10 ms from t = 0 the
    sensors' four frames and the tractor ECU's two (TractorECU_State, ECU1_SteerCmd: ssp/can/
    Bus36m.dbc's senders) are put on CanBus's wire: 6 (k + 1) frames after tick k, closed form"""
    r, log = simulate(container, 0.05)
    assert not [m for m in log if "rror" in m and "stale" not in m and "no previous interval" not in m], log
    assert r["time"][-1] == pytest.approx(0.05)
    for t, n in zip(r["time"], r["nFrames"]):
        k = int((t + 1e-9) // 0.01)          # the last tick at or before t
        assert n <= 6 * (k + 1) and (t < k * 0.01 + 0.002 or n == 6 * (k + 1)), (t, n)


def test_the_container_schedules_the_bus_countdown_clocks_without_an_error(container):
    """CanBus answers fmi3GetIntervalDecimal as FMI 3.0.2, 2.2.9 says (fmi3IntervalUnchanged: the
    interval given before; a frame's end announced by the Tx clocks, not again as nextEventTime):
    the container's scheduler no longer stops with "no previous interval" (it did when CanBus
    also gave the frame's end as nextEventTime: the container cut its step there and counted the
    unchanged interval down by that cut step, container.c container_set_next_event_time)"""
    r, log = simulate(container, 0.05)
    assert not [m for m in log if "previous interval" in m or "rror" in m and "stale" not in m], log
    assert r["time"][-1] == pytest.approx(0.05)


# ---- the bus in its triggered Tx form: frames reach the ECUs ---------------------------------
# fmu-manipulation-toolbox 2.0 passes no countdown-clocked variable on: container.c
# container_proceed_event activates the scheduled clocks, sets the receivers' clocks
# (fmu_set_clocks) and deactivates them again (container_clocks_deactivate) before
# container_update_discrete_state sets the clocked inputs (fmu_set_clocked_inputs sets a
# variable only while its clock is active): the node's Rx_Clock ticks, its Rx_Data is never set
# (the toolbox's own tests/ls-bus/REF-log-bus+nodes.txt shows "Set RX clock to 1" and no "Set RX
# buffer" for the nodes). Triggered output clocks it passes on (the nodes' Tx clocks above), so
# CanBus has a triggered form (fmus/fmi3/lsbus-triggered/CanBus_Triggered.fmu): NodeK.Tx_Clock
# an output clock, activated by fmi3UpdateDiscreteStates for the next super-dense instant.

ECUS = {"ECU1.fmu": 1, "ECU2.fmu": 2}     # the tractor ECU (its speed its own input) and module 2's


@pytest.fixture(scope="module")
def container_triggered(tmp_path_factory):
    """CanBus_Triggered with the sensors (Node1), the tractor ECU (Node2: it sends TractorECU_State,
    module 2's speed and direction) and module 2's ECU (Node3, S4 = 0: no arc lag of A4, so its
    set-points are a function of the frames' values alone), each in its Tx clock's triggered form"""
    from pathlib import Path
    d = tmp_path_factory.mktemp("lsbus_container_triggered")
    shutil.copy(Path(fmu3("CanBus")).parent / "lsbus-triggered" / "CanBus_Triggered.fmu", d / "CanBus.fmu")
    shutil.copy(triggered("SteeringSensors_LSBUS"), d / "Sensors.fmu")
    for name in ECUS:
        shutil.copy(triggered("SteeringECU_LSBUS"), d / name)
    node = AssemblyNode("LsBusTriggered.fmu", step_size=STEP, auto_local=True)
    node.add_fmu("CanBus.fmu")
    for k, fmu in enumerate(["Sensors.fmu", *ECUS], 1):
        node.add_fmu(fmu)
        node.add_link(fmu, "SteeringCAN", "CanBus.fmu", f"Node{k}")
    for fmu, module in ECUS.items():
        node.add_start_value(fmu, "module", str(module))
    node.add_start_value("ECU2.fmu", "S4", "0")
    node.add_start_value("CanBus.fmu", "nNodes", "3")
    node.make_fmu(d, fmi_version=3)
    return d / "LsBusTriggered.fmu"


def received(db):
    """what module 2's ECU must receive: each input through the DBC's scaling (cantools), in SI"""
    def through(msg, signal, value, to_dbc, from_dbc):
        _, data = python_frame(db, msg, {**{s.name: 0 for s in db.get_message_by_name(msg).signals
                                            if s.name not in ("CRC", "AliveCounter")}, signal: to_dbc * value}, 0)
        return from_dbc * db.get_message_by_name(msg).decode(data, scaling=True)[signal]
    return {"gamma1": through("SensorA1_Angle", "RoadWheelAngleA1", INPUTS["gamma1"], RAD_DEG, DEG_RAD),
            "dPsi[1]": through("SensorG1_Angle", "ArtAngleG1", INPUTS["dPsi[1]"], RAD_DEG, DEG_RAD),
            "dPsi[2]": through("SensorG2_Angle", "ArtAngleG2", INPUTS["dPsi[2]"], RAD_DEG, DEG_RAD),
            "gammaA6": through("SensorA6_Angle", "RoadWheelAngleA6", INPUTS["gammaA6"], RAD_DEG, DEG_RAD),
            "v": through("TractorECU_State", "VehicleSpeed", INPUTS["vVehicle"], MS_KMH, KMH_MS),
            "direction": 0.0}       # forwards (SAE J1939's two-bit state 0)


def test_frames_reach_the_ecus_and_the_commands_equal_the_benchs(container_triggered, db):
    """Acceptance (issue 39): in the container, every 10 ms from t = 0 the sensors' and the tractor
    ECU's frames reach module 2's ECU within the cycle; it receives the DBC's values of the inputs
    (cantools), and its set-points of A3 and A4 equal those of the FMI 2.0 SteeringECU (the CAN
    bench's ECU, fmus/SteeringECU.fmu, module 2, S4 = 0) fed those values, within the resolution
    of Module2ECU_Cmd's SteerCmdA3/A4 (0.01 deg); alive counters advance, nothing stale, no fallback"""
    from fmpy import simulate_fmu
    outs = ["nFrames"] + [f"ecu2.{n}" for n in ("gamma1", "v", "dPsi[1]", "dPsi[2]", "gammaA6", "direction",
                                                 "aliveA1", "aliveState", "gammaFront", "gammaRear",
                                                 "fallback", "stale", "fault")]
    log = []
    r = simulate_fmu(str(container_triggered), stop_time=0.05, step_size=0.001, output_interval=0.001,
                     start_values=INPUTS, output=outs, logger=lambda *a: log.append(a[-1].decode(errors="replace")))
    assert not [m for m in log if "rror" in m or "stale" in m], log
    t = r["time"]
    after = t >= 0.0105            # the frames of the tick at 0 on the wire (~1.2 ms), then the ECU's cycle at 0.01
    # 4 sensor frames, 2 of the tractor ECU, 1 of module 2's ECU each 10 ms from t = 0 (ssp/can/Bus36m.dbc's
    # senders), all on the wire within 2 ms of their tick (7 frames of at most 0.27 ms at 500 kbit/s)
    for x, n in zip(t, r["nFrames"]):
        assert x < 0.002 or n >= 7 * (int((x - 0.002) // 0.01) + 1), (x, n)
    want = received(db)
    for name, value in want.items():
        assert r[f"ecu2.{name}"][after] == pytest.approx(value, abs=1e-12), name
    assert r["ecu2.aliveState"][-1] == 4.0 and r["ecu2.aliveA1"][-1] == 4.0     # ticks 0..0.04 s: counters 0..4
    assert not r["ecu2.stale"].any() and not r["ecu2.fallback"].any() and not r["ecu2.fault"].any()
    bench = simulate_fmu(str(fmu_dir() / "SteeringECU.fmu"), stop_time=0.01, step_size=0.01, output_interval=0.01,
                         start_values={"module": 2, "S4": 0.0, **want}, output=["gammaFront", "gammaRear"])
    res = DEG_RAD * db.get_message_by_name("Module2ECU_Cmd").get_signal_by_name("SteerCmdA3").scale
    for name in ("gammaFront", "gammaRear"):
        assert abs(bench[name][-1]) > 10 * res, name          # a set-point, not a trivial 0
        assert r[f"ecu2.{name}"][after] == pytest.approx(bench[name][-1], abs=res), name
