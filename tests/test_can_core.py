"""The CAN network's tick in the runner's stepping core (src/runner_core/core.c,
issue 13) against artibus.can's Python path: the C codec against cantools
(the reference) on every signal of ssp/can/Bus36m.dbc and on big-endian,
signed and integer-scaled signals of a DBC written here, random values and the
range edges; frame bits and the E2E CRC against artibus.can's; the CAN benches
and their variants with the network in C and with the network in Python
(``core=False``: artibus.can.Network, the reference implementation, ticked by
the same C loop through its callback) bit for bit: every recorded column, the
sinceGood series, the network's report and summary; the same error for a value
outside its signal's range or its raw bits; the log (--can-log) written from the
frames the core recorded; the network in Python where C does not tick it
(faults, a tamper function), Simulation.stepping saying why."""
import math
import zipfile
from ctypes import CDLL, POINTER, byref, c_double, c_int, c_ubyte, c_uint, c_void_p

import cantools
import numpy as np
import pytest

from artibus import ArtibusError, ROOT
from artibus.bench import ssp
from artibus.can import e2e_crc, frame_bits
from artibus.runner import Simulation, can_signal, core_library_path

pytestmark = pytest.mark.skipif(not core_library_path().is_file(),
                                reason=f"{core_library_path()} not built (cmake target artibus_core)")

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
# signals the bench's DBC does not have: big-endian (Motorola), signed, integer scale/offset, a 1-bit flag
OTHER_DBC = """VERSION ""
BU_: A B
BO_ 100 Mixed: 8 A
 SG_ Motor12 : 7|12@0+ (0.5,-10) [-10|2037.5] "" B
 SG_ MotorS : 11|10@0- (1,0) [-512|511] "" B
 SG_ IntScaled : 33|9@1+ (2,-3) [-3|1019] "" B
 SG_ Flag : 42|1@1+ (1,0) [0|1] "" B
 SG_ SignedLE : 43|21@1- (0.001,0.5) [-1047|1048] "" B
"""


@pytest.fixture(scope="module")
def lib():
    lib = CDLL(str(core_library_path()))
    lib.artibus_can_encode.argtypes = [c_void_p, c_double, POINTER(c_ubyte), c_int]
    lib.artibus_can_encode.restype = c_int
    lib.artibus_can_decode.argtypes = [c_void_p, POINTER(c_ubyte)]
    lib.artibus_can_decode.restype = c_double
    lib.artibus_can_frame_bits.argtypes = [c_uint, POINTER(c_ubyte), c_int]
    lib.artibus_can_frame_bits.restype = c_int
    lib.artibus_can_e2e_crc.argtypes = [POINTER(c_ubyte), c_int, c_uint]
    lib.artibus_can_e2e_crc.restype = c_uint
    return lib


def signals():
    dbs = [cantools.database.load_file(str(DBC)), cantools.database.load_string(OTHER_DBC, database_format="dbc")]
    return [(m, s) for db in dbs for m in db.messages for s in m.signals]


def values(s, rng):
    """The range's edges, just inside and outside them, raw steps and their halves, random values."""
    lo, hi, q = s.minimum, s.maximum, s.conversion.scale
    edges = [lo, hi, np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf), lo - q, hi + q, lo + q / 2, hi - q / 2,
             0.0, -0.0, s.conversion.offset, s.conversion.offset + q / 2, s.conversion.offset - q / 2]
    steps = s.conversion.offset + q * (rng.integers(-2 ** s.length, 2 ** s.length, 300) + 0.5)
    return [float(v) for v in edges + list(rng.uniform(lo - 2 * q, hi + 2 * q, 2000)) + list(steps)]


def test_encode_is_cantools_on_every_signal(lib):
    """C encode == cantools encode (strict=False: the range is the runner's own
    check, below); where cantools refuses the raw value (its bits cannot hold
    it) the C encoder refuses too."""
    rng = np.random.default_rng(13)
    checked = refused = 0
    for m, s in signals():
        q = can_signal(s)
        others = {o.name: o.conversion.raw_to_scaled(0, decode_choices=False) for o in m.signals if o is not s}
        for v in values(s, rng):
            buf = (c_ubyte * 8)()
            bad = lib.artibus_can_encode(byref(q), v, buf, m.length)
            try:
                ref = m.encode({**others, s.name: v}, scaling=True, strict=False)
            except Exception:        # cantools/bitstruct: the raw value does not fit
                ref = None
            if ref is None:
                assert bad == 1, (m.name, s.name, v)
                refused += 1
            else:
                assert bad == 0 and bytes(buf)[:m.length] == ref, (m.name, s.name, v, bytes(buf).hex(), ref.hex())
                checked += 1
    assert checked > 20000 and refused > 100


def test_decode_is_cantools_on_every_signal(lib):
    """C decode == cantools decode (raw * scale + offset) bit for bit, on random frames."""
    rng = np.random.default_rng(14)
    for m, s in signals():
        q = can_signal(s)
        for data in [bytes(m.length), b"\xff" * m.length] + [rng.bytes(m.length) for _ in range(500)]:
            ref = m.decode(data, scaling=True, decode_choices=False)[s.name]
            got = lib.artibus_can_decode(byref(q), (c_ubyte * 8)(*data))
            assert np.float64(got).tobytes() == np.float64(ref).tobytes(), (m.name, s.name, data.hex(), got, ref)


def test_frame_bits_and_crc_are_artibus_cans(lib):
    rng = np.random.default_rng(15)
    for _ in range(3000):
        dlc = int(rng.integers(0, 9))
        fid = int(rng.integers(0, 2048))
        data = rng.bytes(dlc) if rng.random() < 0.8 else bytes([0xFF if rng.random() < 0.5 else 0] * dlc)
        buf = (c_ubyte * 8)(*data)
        assert lib.artibus_can_frame_bits(fid, buf, dlc) == frame_bits(fid, data)
        if dlc >= 2:
            did = int(rng.integers(0, 256))
            assert lib.artibus_can_e2e_crc(buf, dlc, did) == e2e_crc(data, did)


# --- the benches: the network in C against the network in Python -------------------------

IN_PYTHON = "C core; in Python: the network, switched off (core=False)"


def both(bench, stop, overrides=None, **kw):
    """(Result, report, summary, sinceGood series, ticks) with the network in C, then in Python."""
    out = []
    for core in (True, False):
        with Simulation(bench, overrides=overrides, **kw) as sim:
            r = sim.run(stop_time=stop, core=core)
            assert sim.stepping == ("C core" if core else IN_PYTHON)
            span = r.time[-1] - r.time[0]
            out.append((r, sim.can.report(span), sim.can.summary(span), sim.can.since_series(), sim.can.ticks))
    return out


@pytest.mark.parametrize("bench, variant", [("Bus36m_Circle_CAN", None), ("Bus36m_Circle_CAN", "laneChange"),
                                            ("Bus36m_Circle_CAN", "slalom"), ("Bus36m_Circle_CAN_Backwards", None)])
def test_can_bench_network_in_c_is_the_network_in_python_bit_for_bit(bench, variant):
    overrides = ssp.variant_overrides(bench, [variant]) if variant else None
    (a, ra, sa, na, ta), (b, rb, sb, nb, tb) = both(bench, 6.0, overrides)
    assert a.names == b.names and any(n.endswith(".sinceGood") for n in a.names)
    x, y = a.array(), b.array()
    assert x.shape == y.shape == (601, len(a.names)) and np.all(np.isfinite(x))
    assert x.tobytes() == y.tobytes()
    assert ra == rb and sa == sb and ta == tb == 600
    assert na.keys() == nb.keys() and all(na[k].tobytes() == nb[k].tobytes() for k in na)
    # the traffic is real: every message on the wire, none rejected, the receivers' inputs move
    assert ra["frames"] > 8 * 60 and all(m["sent"] > 0 and m["rejected"] == 0 for m in ra["messages"])
    assert 0.05 < ra["load"] < 0.5


def _packed(tmp_path, dbc):
    """The CAN bench with its DBC changed."""
    out = tmp_path / "Bus36m_Circle_CAN.ssp"
    with zipfile.ZipFile(ssp.ssp_path("Bus36m_Circle_CAN")) as zi, zipfile.ZipFile(out, "w") as zo:
        for item in zi.infolist():
            data = zi.read(item.filename)
            if item.filename == "resources/Bus36m.dbc":
                data = dbc(data.decode()).encode()
            zo.writestr(item, data)
    return out


def _errors_core_and_python(path, stop_time):
    """The error text of a run that must fail, with the network in C and with the
    network in Python (each checked to have run where it should)."""
    errors = []
    for core in (True, False):
        with Simulation(path) as sim:
            with pytest.raises(ArtibusError) as e:
                sim.run(stop_time=stop_time, core=core)
            assert sim.stepping == ("C core" if core else IN_PYTHON)
        errors.append(str(e.value))
    return errors


@pytest.mark.parametrize("change, words", [
    # the hinge G1 swings beyond 2 deg on the circle: the runner's range check
    (("ArtAngleG1 : 16|16@1- (0.1,0) [-90|90]", "ArtAngleG1 : 16|16@1- (0.1,0) [-2|2]"),
     ["message SensorG1_Angle, signal ArtAngleG1", "Bus.artAngle[1]", "outside the signal's range [-2, 2]"]),
    # within the range but beyond 8 signed bits (12.7 deg): cantools' (bitstruct's) refusal
    (("ArtAngleG1 : 16|16@1- (0.1,0) [-90|90]", "ArtAngleG1 : 16|8@1- (0.1,0) [-90|90]"),
     ["message SensorG1_Angle:", "out of range"]),
])
def test_a_value_the_frame_cannot_carry_is_the_same_error(tmp_path, change, words):
    errors = _errors_core_and_python(_packed(tmp_path, lambda t: t.replace(*change)), 60.0)
    assert errors[0] == errors[1] and all(w in errors[0] for w in words), errors
    t = float(errors[0].rpartition("t = ")[2].split(" ")[0].rstrip(")"))
    assert 0.0 < t < 60.0


def _network_state(net, sim):
    return ([bytes(u.raw.inp) for u in sim.units],
            [(m.counter, m.last_counter, m.good_tick, m.produced, m.sent, m.rejected, dict(m.why), m.bits,
              list(m.since)) for m in net.messages], (net.frames, net.ticks, dict(net.observed)))


def test_settle_through_the_core_is_network_settle():
    """The initialisation's settle through the core's codec (_CanCore.settle,
    artibus_core_can_settle) against artibus.can's Network.settle (cantools):
    from the same senders' outputs (random values in their signals' ranges,
    the range edges, now and then one outside), counters, E2E states and
    receivers' inputs, the same receivers' inputs bit for bit and the same
    network state (last_counter None, good_tick -ratio, nothing sent or
    counted), or the same error."""
    from artibus.can import COUNTER_SIGNAL
    from artibus.runner.core import _core_stepper
    from artibus.runner.plan import _Plan
    rng = np.random.default_rng(16)
    with Simulation("Bus36m_Circle_CAN") as sim:
        net, core = sim.can, _core_stepper(sim, _Plan(sim.order, 10), True).can
        routes = [r for m in net.messages for r in m.routes if r.signal.name != COUNTER_SIGNAL]
        assert len(routes) >= 8
        moved = errors = 0
        for trial in range(300):
            outs = {}
            for r in routes:
                s = r.signal
                pick = rng.random()
                v = (s.minimum if pick < 0.1 else s.maximum if pick < 0.2 else
                     s.maximum + (s.maximum - s.minimum) if pick < 0.21 else
                     s.conversion.offset + s.conversion.scale * (int(rng.integers(-100, 100)) + 0.5) if pick < 0.4
                     else rng.uniform(s.minimum, s.maximum))
                outs[id(r)] = v / r.factor
            garbage = [rng.uniform(-1e3, 1e3, u.raw.n_in) for u in sim.units]
            state = [(int(rng.integers(16)), None if rng.random() < 0.3 else int(rng.integers(16)),
                      int(rng.integers(-5, 100))) for _ in net.messages]
            got = []
            for settle in (net.settle, core.settle):
                for r in routes:
                    r.unit.raw.out[r.index] = outs[id(r)]
                for u, g in zip(sim.units, garbage):
                    u.raw.inp[:u.raw.n_in] = g
                for m, (c, last, good) in zip(net.messages, state):
                    m.counter, m.last_counter, m.good_tick = c, last, good
                try:
                    settle()
                    error = None
                except ArtibusError as e:
                    error = str(e)
                got.append((error, _network_state(net, sim)))
            assert got[0] == got[1], trial
            if got[0][0] is None:
                assert all(m.last_counter is None and m.good_tick == -m.ratio for m in net.messages)
                moved += got[0][1][0] != [bytes(np.asarray(g).tobytes()) for g in garbage]
            else:
                assert "outside the signal's range" in got[0][0] and "t = nan s" in got[0][0]
                errors += 1
        assert moved > 100 and errors > 10


def test_a_value_the_frame_cannot_carry_in_the_initialisation_is_the_same_error(tmp_path):
    """The settle's error (t = nan: the initialisation) with the network in C as in Python."""
    path = _packed(tmp_path, lambda t: t.replace("ArtAngleG1 : 16|16@1- (0.1,0) [-90|90]",
                                                 "ArtAngleG1 : 16|16@1- (0.1,0) [80|90]"))
    errors = _errors_core_and_python(path, 1.0)
    assert errors[0] == errors[1] and "t = nan s" in errors[0] and "ArtAngleG1" in errors[0], errors


@pytest.mark.parametrize("suffix", [".blf", ".asc"])
def test_log_written_from_the_cores_frames_is_the_python_networks(tmp_path, suffix):
    """--can-log: the core records every frame, python-can's writer writes them
    after the run; the log reads back as the network's in Python, frame for frame
    (time stamps, identifiers, data, direction; the channel the run's virtual
    bus's, a number of its own per network in the process)."""
    import can
    from can.util import channel2int
    logs, results = [], []
    for core in (True, False):
        log = tmp_path / f"{'core' if core else 'python'}{suffix}"
        with Simulation("Bus36m_Circle_CAN", can_log=log) as sim:
            results.append(sim.run(stop_time=3.0, core=core))
            assert sim.stepping == ("C core" if core else IN_PYTHON)
            channel = channel2int(sim.can.bus.channel_id)
        reader = can.BLFReader if suffix == ".blf" else can.ASCReader
        frames = list(reader(str(log)))
        assert {m.channel for m in frames} == {channel}
        logs.append([(m.timestamp, m.arbitration_id, m.dlc, bytes(m.data), m.is_rx, m.is_error_frame,
                      m.is_extended_id) for m in frames])
    assert results[0].array().tobytes() == results[1].array().tobytes()
    assert logs[0] == logs[1] and len(logs[0]) > 8 * 150
    assert list(tmp_path.glob("*.part")) == []


@pytest.mark.parametrize("kw, why", [
    ({"can_faults": ["loss:SensorG2_Angle:0.1"]}, "faults (--can-fault)"),
    ({"tamper": lambda msg: msg}, "a tamper function"),
])
def test_faults_and_tamper_tick_in_python(kw, why):
    """C does not tick a network with faults or a tamper function: the core calls back for
    its ticks (artibus.can.Network.tick), with core None or True alike, and says why. The
    same faults give the same run (their random draws seeded); an identity tamper function
    leaves every frame as it is, so its run is the network's in C without one, bit for bit."""
    kw = dict(kw)
    tamper = kw.pop("tamper", None)
    tables = []
    for core in (None, True):
        with Simulation("Bus36m_Circle_CAN", **kw) as sim:
            sim.can.tamper = tamper
            tables.append(sim.run(stop_time=2.0, core=core).array().tobytes())
            assert sim.stepping == f"C core; in Python: the network, {why}"
            lost = sum(m["lost"] for m in sim.can.report(2.0)["messages"])
    assert tables[0] == tables[1]
    if tamper is None:
        assert lost > 5                     # the faults act: SensorG2_Angle loses about 1 frame in 10
    else:
        with Simulation("Bus36m_Circle_CAN") as sim:
            plain = sim.run(stop_time=2.0).array().tobytes()
            assert sim.stepping == "C core"
        assert tables[0] == plain and lost == 0
