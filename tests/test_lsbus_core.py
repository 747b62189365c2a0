"""The FMI-LS-BUS network in C (issue 24: src/runner_core/lsbus.c, through
artibus.runner.lsbus_core): it must make the same calls in the same order as the network in
Python (artibus.runner.lsbus.Network, its reference implementation, which the one stepping
loop, the C core, calls back for with run(core=False)), so the results must be the same bit
for bit.

What is expected comes from elsewhere:
- the run of the same bench with the network in Python (the reference; tests/test_lsbus_bench.py
  checks it against Bus36m_Circle_CAN's Real-wired network): every recorded column byte for
  byte, the frames on the wire (times, identifiers, payloads), each FMU's Event Mode entries;
- the Real-wired bench Bus36m_Circle_CAN's KPIs (within 1e-9, wire time off);
- the Event Mode entries' closed form, from the Tx clock's period in the node FMUs'
  modelDescription.xml and the order within an instant (lsbus.py's docstring): per tick each
  node has the Event Mode of its Tx tick and, with the bus's wire time off, a further one in
  the same instant for the frames the bus delivers (4.); the bus one (all the instant's
  Tx_Data in one Event Mode, 3.). The first Event Mode of each FMU is not entered with
  fmi3EnterEventMode: fmi3ExitInitializationMode leads into it (FMI 3.0.2, 4.2.1, eventModeUsed).
"""
import math
import xml.etree.ElementTree as ET
import zipfile
from ctypes import CFUNCTYPE, POINTER, addressof, c_double, c_int, c_size_t, c_uint, c_void_p, cast

import numpy as np
import pytest

from artibus import fmu_dir
from artibus.bench import script, ssp
from artibus.runner import lsbus_core
from artibus.runner.lsbus import LsBusError
from artibus.runner.simulation import Simulation, run as run_bench

pytestmark = pytest.mark.slow
BENCH = "Bus36m_Circle_LSBUS"
NODES = ("Sensors", "ECU1", "ECU2", "ECU3", "Act1", "Act2", "Act3")
#: the network in Python: its outputs onto the plant's inputs too, as stimuli (LsBusSteering.stimuli)
IN_PYTHON = "C core; in Python: the network, switched off (core=False); stimuli (Python functions of time)"


def needs(*names):
    for n in names:
        if not (fmu_dir() / "fmi3" / f"{n}.fmu").is_file():
            pytest.skip(f"{fmu_dir() / 'fmi3' / n}.fmu not built")


@pytest.fixture(autouse=True)
def fmus():
    needs("CanBus", "SteeringECU_LSBUS", "SteeringActuator_LSBUS", "SteeringSensors_LSBUS")


def run(core, wire_time=False, variant=None, stop_time=None, bench=BENCH):
    """(Result, {FMU: Event Mode entries}, frames on the wire, the bus's log); core: the
    network in C (True) or in Python (False)"""
    overrides = ssp.variant_overrides(bench, [variant]) if variant else {}
    stop = stop_time or (ssp.variant_stop_time(bench, [variant]) if variant else None)
    with Simulation(bench, lsbus_wire_time=wire_time, overrides=overrides) as sim:
        result = sim.run(stop_time=stop, core=core)
        assert sim.stepping == ("C core" if core else IN_PYTHON)
        net = sim.lsbus.net
        return (result, {f.name: f.n_events for f in net.nodes + [net.bus]}, net.wire_frames(), list(net.bus.log))


@pytest.mark.parametrize("bench, wire_time, variant", [(BENCH, False, None), (BENCH, False, "laneChange"),
                                                       (BENCH, True, None), (f"{BENCH}_Backwards", False, None)])
def test_the_network_in_c_runs_the_bench_bit_for_bit_as_the_network_in_python(bench, wire_time, variant):
    ref, ref_events, ref_frames, _ = run(False, wire_time, variant, bench=bench)
    got, events, frames, _ = run(True, wire_time, variant, bench=bench)
    # the comparison means something: the bus moves, frames flow
    assert np.ptp(ref["Bus.yAxle[6]"]) > 1.0 and len(ref_frames) > 1000
    assert got.names == ref.names
    a, b = ref.array(), got.array()
    assert a.shape == b.shape
    for j, name in enumerate(ref.names):          # every column, byte for byte
        assert a[:, j].tobytes() == b[:, j].tobytes(), name
    assert frames == ref_frames                   # times, identifiers, IDE, payloads
    assert events == ref_events


@pytest.fixture(scope="module")
def core_off():
    return run(True, False)


def test_the_core_s_kpis_equal_bus36m_circle_can_s(core_off):
    ref = run_bench("Bus36m_Circle_CAN")
    got = core_off[0]
    k_ref = {k.name: k.value for k in script.load(BENCH).kpis(ref)}
    k_got = {k.name: k.value for k in script.load(BENCH).kpis(got)}
    assert set(k_ref) == set(k_got)
    assert "max deviation of A4 from the A2 trace" in k_ref and "max deviation of A6 from the A2 trace" in k_ref
    n = 0
    for name, v in k_ref.items():
        if isinstance(v, float) and math.isfinite(v):
            assert k_got[name] == pytest.approx(v, rel=1e-9, abs=1e-300), name
            n += 1
    assert n >= 4


def tx_period(fmu):
    """the Tx_Clock's intervalDecimal in the FMU's modelDescription.xml (s)"""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    (period,) = {float(c.get("intervalDecimal")) for c in root.iter("Clock") if c.get("name").endswith("Tx_Clock")}
    return period


def test_event_mode_entries_per_simulated_second_are_the_closed_form(core_off):
    result, events, frames, _ = core_off
    duration = result.time[-1] - result.time[0]
    for name in ("SteeringSensors_LSBUS", "SteeringECU_LSBUS", "SteeringActuator_LSBUS"):
        assert tx_period(fmu_dir() / "fmi3" / f"{name}.fmu") == 0.01
    ticks = round(duration / 0.01)
    assert ticks == 7000
    for node in NODES:                            # 2 per tick: 200 per simulated second
        assert events[node] == 2 * ticks - 1, node
        assert (events[node] + 1) / duration == pytest.approx(2 / 0.01)
    assert events["bus"] == ticks - 1
    print(f"\nEvent Mode entries per simulated second: {(events['ECU1'] + 1) / duration:g} per node, "
          f"{(events['bus'] + 1) / duration:g} for the bus; {len(frames)} frames")


@pytest.fixture
def lsbus_cores(monkeypatch):
    """the _LsBusCore of each run in the test (the network in C), as its run begins"""
    cores, begin = [], lsbus_core._LsBusCore.begin

    def kept(self, n):
        cores.append(self)
        return begin(self, n)
    monkeypatch.setattr(lsbus_core._LsBusCore, "begin", kept)
    return cores


def test_a_clock_after_the_discrete_states_is_refused_by_the_core(lsbus_cores):
    with Simulation(BENCH) as sim:
        sim.run(stop_time=0.05, core=True)
        (net,) = lsbus_cores
        lib, c = net.lib, net.c
        vr = sim.lsbus.net.nodes[1].terminals[next(iter(sim.lsbus.net.nodes[1].terminals))].tx_clock
        vrs = (c_uint * 1)(vr)
        lib.artibus_lsbus_set_clocks.argtypes = [c_void_p, c_int, c_void_p, c_size_t]
        node = net.fmus[1]
        node.mode, node.need = 1, 0              # after fmi3UpdateDiscreteStates, no further iteration asked
        assert lib.artibus_lsbus_set_clocks(addressof(c), 1, vrs, 1) == 1
        text = c.message.decode()
        assert "fmi3SetClock" in text and "refused" in text and "5.2.2" in text and str(vr) in text
        node.mode = 2                             # Step Mode
        assert lib.artibus_lsbus_set_clocks(addressof(c), 1, vrs, 1) == 1
        assert "Step Mode" in c.message.decode()
        sim.lsbus.net.nodes[1].fmu.enterEventMode()
        node.mode = 0                             # in Event Mode: the clock goes to the FMU, which takes it
        assert lib.artibus_lsbus_set_clocks(addressof(c), 1, vrs, 1) == 0


def test_more_data_than_a_terminal_holds_is_an_error_naming_it(monkeypatch):
    monkeypatch.setattr(lsbus_core, "BUFFER", 8)    # less than one CAN Transmit operation (16 + DL bytes)
    with Simulation(BENCH) as sim:
        with pytest.raises(LsBusError, match="FMU bus: more data routed to one terminal"):
            sim.run(stop_time=0.05, core=True)


_GET_BINARY = CFUNCTYPE(c_int, c_void_p, POINTER(c_uint), c_size_t, POINTER(c_size_t), POINTER(c_void_p), c_size_t)


def test_a_truncated_binary_from_a_node_is_answered_with_a_format_error_not_a_crash(monkeypatch):
    """the Sensors node's Tx_Data one byte short (its last Transmit's Length beyond the
    binary): CanBus answers with a Format Error and a warning (4____network_abstraction.adoc),
    the frames of the other nodes go on, the run ends"""
    begin = lsbus_core._LsBusCore.begin

    def truncating(self, n):
        address = begin(self, n)
        f = self.fmus[0]                          # Sensors, the first node
        real = _GET_BINARY(f.getBinary)

        def short(instance, vrs, nvr, sizes, values, nvalues):
            status = real(instance, vrs, nvr, sizes, values, nvalues)
            for i in range(nvr):
                if sizes[i] > 0:
                    sizes[i] -= 1
            return status

        hook = _GET_BINARY(short)
        self._keep.append(hook)
        f.getBinary = cast(hook, c_void_p).value
        return address

    _, _, ref_frames, _ = run(True, stop_time=0.2)
    monkeypatch.setattr(lsbus_core._LsBusCore, "begin", truncating)
    result, _, frames, log = run(True, stop_time=0.2)
    assert result.time[-1] == pytest.approx(0.2)
    ref_ids, ids = {f[1] for f in ref_frames}, {f[1] for f in frames}
    assert ids < ref_ids and ids                  # the sensors' frames missing, the others on the wire
    warnings = [m for status, m in log if status == 1]
    assert warnings and any("malformed" in m for m in warnings), log[:3]


def test_a_stimulus_of_the_user_s_own_is_called_back_for_with_the_network():
    """the core propagates the network's outputs onto the plant in C (core.h's ac_stimulus), no
    other Python function of time: with a user's own stimulus the stimuli are called back for
    in Python, the network's outputs with them, and stepping says so. Its stimulus adds 0 to
    the plant's Fx[2] (the driver's force, not the network's): the run is the bench's plain
    one, the network in C, bit for bit."""
    with Simulation(BENCH) as sim:
        plain = sim.run(stop_time=1.0)
        assert sim.stepping == "C core"
    with Simulation(BENCH, stimuli={"Bus.Fx[2]": lambda t: 0.0}) as sim:
        got = sim.run(stop_time=1.0)
        assert sim.stepping.startswith("C core; in Python: ")
        assert sim.stepping.endswith("stimuli (Python functions of time)")
    assert np.ptp(plain["Bus.yAxle[6]"]) > 0 and got.array().tobytes() == plain.array().tobytes()


_DO_STEP = CFUNCTYPE(c_int, c_void_p, c_double, c_double, c_int, c_void_p, c_void_p, c_void_p, c_void_p)


def test_an_fmu_s_failed_call_is_an_error_naming_the_function_and_the_time(monkeypatch):
    """ECU2's fmi3DoStep failing from t = 0.1 s (returning fmi3Error, FMI 3.0.2 2.2.3): the run
    stops there with the error the network in Python gives (the time, the function, the status)"""
    begin = lsbus_core._LsBusCore.begin

    def failing(self, n):
        address = begin(self, n)
        f = self.fmus[2]                          # ECU2
        real = _DO_STEP(f.doStep)

        def step(instance, t, h, no_set, *out):
            return 3 if t >= 0.1 - 1e-9 else real(instance, t, h, no_set, *out)

        hook = _DO_STEP(step)
        self._keep.append(hook)
        f.doStep = cast(hook, c_void_p).value
        return address

    monkeypatch.setattr(lsbus_core._LsBusCore, "begin", failing)
    with Simulation(BENCH) as sim:
        with pytest.raises(LsBusError, match=r"^t = 0\.100000 s: FMU ECU2: fmi3DoStep failed with status 3 \(error\)\.$"):
            sim.run(stop_time=0.5, core=True)


def test_the_networks_fmu_calls_are_timed_only_when_asked(monkeypatch):
    """benchmarks/suite.py's split of the network's time: inside its FMUs' calls (timed in C
    around each call when lsbus_core.TIME_FMU_CALLS) and the master's own; off by default
    (two time stamps a call), then nothing is counted"""
    from artibus.runner import lsbus_core
    walls = {}
    for timed in (False, True):
        monkeypatch.setattr(lsbus_core, "TIME_FMU_CALLS", timed)
        with Simulation("Bus36m_Circle_LSBUS") as sim:
            sim.run(stop_time=2.0)
            assert sim.stepping == "C core"
            walls[timed] = (sim.lsbus.wall, sim.lsbus.fmu_wall)
    assert walls[False][1] == 0.0 and walls[False][0] > 0
    wall, fmu = walls[True]
    assert 0 < fmu < wall
