"""`--can-fault` on the FMI-LS-BUS bench (artibus.runner.lsbus_faults): the faults injected by the
bus simulation FMU CanBus (its faultSilentNode, faultBusOffNode, faultCorruptId, faultStart).

The reference is the Real-wired bench Bus36m_Circle_CAN with the same fault, injected there by
the runner's own CAN model (artibus.can.faults): a silent ECU, an ECU bus-off for good, every
frame of a message corrupted (CRC). The receivers see the same frames missing from the same tick
on, so the plant follows the same trajectory, bit for bit, and it differs from the fault-free
run (the actuators' stale fallback, seed 000's degraded mode). The frames on the wire are
counted against the closed form (100 per second per message, none of the silent node's from
T0). A fault CanBus cannot inject is refused, naming what it does instead.
"""
import numpy as np
import pytest

from artibus import cli, fmu_dir
from artibus.base import ArtibusError
from artibus.runner.simulation import Simulation, run as run_bench

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module", autouse=True)
def built():
    for n in ("CanBus", "SteeringECU_LSBUS", "SteeringActuator_LSBUS", "SteeringSensors_LSBUS"):
        if not (fmu_dir() / "fmi3" / f"{n}.fmu").is_file():
            pytest.skip(f"{n}.fmu (FMI 3.0) not built")


@pytest.fixture(scope="module")
def fault_free():
    return run_bench("Bus36m_Circle_LSBUS")


def lsbus(fault):
    with Simulation("Bus36m_Circle_LSBUS", can_faults=[fault]) as sim:
        r = sim.run()
        frames = sim.lsbus.net.wire_frames()
        return r, frames, sim.stepping


@pytest.mark.parametrize("fault,can_fault,message,t0", [
    ("silent:Module2ECU@20", "silent:Module2ECU@20", 0x120, 20.0),   # Module2ECU_Cmd: its only message
    ("silent:ECU3@25", "silent:Module3ECU@25", 0x130, 25.0),         # the node by its component name
    ("busoff:Module3ECU@15", "busoff:Module3ECU@15", 0x130, 15.0),
    ("corrupt:Module2ECU_Cmd@30", "corrupt:Module2ECU_Cmd@30", 0x120, 30.0),   # a CRC Bus Error each
])
def test_a_fault_on_the_lsbus_bench_is_the_can_benchs(fault, can_fault, message, t0, fault_free):
    ours, frames, stepping = lsbus(fault)
    assert stepping.startswith("C core")               # CanBus injects it: the core runs it
    theirs = run_bench_with_fault(can_fault)
    common = [n for n in ours.names[1:] if n in theirs.names]
    assert len(common) == len(ours.names) - 1
    for n in common:
        np.testing.assert_array_equal(ours[n], theirs[n], err_msg=f"{fault}: {n}")
    # it did something: the actuators fell back, the trajectory left the fault-free one
    moved = max(float(np.max(np.abs(ours[n] - fault_free[n]))) for n in common)
    assert moved > 1e-3, fault
    early = ours.time <= t0
    for n in common:                                   # before T0, nothing changed
        np.testing.assert_array_equal(ours[n][early], fault_free[n][early])
    # the frames on the wire: 100 per second per message, the faulted one's only before T0
    sent = [t for t, can_id, *_ in frames if can_id == message]
    others = [t for t, can_id, *_ in frames if can_id == 0x101]
    assert len(others) == 7000                         # 70 s at 10 ms
    assert len(sent) == round(t0 / 0.01) and max(sent) < t0


def run_bench_with_fault(fault):
    with Simulation("Bus36m_Circle_CAN", can_faults=[fault]) as sim:
        return sim.run()


@pytest.mark.parametrize("fault,words", [
    ("loss:ECU2:0.1", "not loss"),
    ("latency:Module2ECU_Cmd:0.02", "not latency"),
    ("corrupt:TractorECU_Cmd:repeat@3", "CRC error"),
    ("corrupt:TractorECU_Cmd:crc:rate=0.5@3", "CRC error"),
    ("busoff:Module2ECU@3:recover", "stays off"),
    ("silent:ECU2@3-5", "to the end of the run"),
    ("silent:HingeSensorG1@3", "the one node Sensors"),
    ("silent:Nobody@3", "not a node of the FMI-LS-BUS network"),
    ("corrupt:NoSuchMessage@3", "not a message of Bus36m.dbc"),
])
def test_a_fault_canbus_cannot_inject_is_refused(fault, words):
    with pytest.raises(ArtibusError) as e:
        Simulation("Bus36m_Circle_LSBUS", can_faults=[fault]).close()
    assert words in str(e.value) and fault.split("@")[0].split(":")[1] in str(e.value)


def test_two_faults_need_one_start_time(capsys, tmp_path):
    with pytest.raises(ArtibusError, match="one start time"):
        Simulation("Bus36m_Circle_LSBUS", can_faults=["silent:ECU2@3", "busoff:ECU3@4"]).close()
    assert cli.main(["run", "Bus36m_Circle_LSBUS", "--can-fault", "silent:ECU2@3", "--can-fault",
                     "silent:ECU3@3", "-o", str(tmp_path / "r.csv")]) != 0
    assert "one silent fault" in capsys.readouterr().err
