"""The steering CAN's frame codec in C (src/models/common/bus36m_can.c, generated from
ssp/can/Bus36m.dbc by artibus.can.gen_c; issue 24) against the Python side the runner's
network uses: cantools' encode (scaling, strict) with artibus.can's E2E CRC and the alive
counter, byte for byte, on random values within each signal's DBC range, the range edges
and the rounding ties; decode back equal to cantools' decode; values outside the range
refused as cantools refuses them; the committed files equal a fresh generation."""
import math
import random
from ctypes import CDLL, POINTER, c_double, c_int, c_ubyte, c_uint, c_uint8, c_uint32

import pytest

from artibus import ROOT
from artibus.can import e2e_crc
from artibus.can.gen_c import generate

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
STEM = ROOT / "src" / "models" / "common" / "bus36m_can"


def _lib_path():
    import os
    fmus = os.environ.get("ARTIBUS_FMU_DIR")
    if fmus and (ROOT / fmus).parent.joinpath("lib", "libartibus_can_codec.so").is_file():
        return (ROOT / fmus).parent / "lib" / "libartibus_can_codec.so"
    return ROOT / "build" / "lib" / "libartibus_can_codec.so"


pytestmark = pytest.mark.skipif(not _lib_path().is_file(),
                                reason=f"{_lib_path()} not built (cmake target artibus_can_codec)")


@pytest.fixture(scope="module")
def lib():
    lib = CDLL(str(_lib_path()))
    lib.bus36m_encode.argtypes = [c_int, POINTER(c_double), c_uint, POINTER(c_ubyte)]
    lib.bus36m_encode.restype = c_int
    lib.bus36m_decode.argtypes = [c_int, POINTER(c_ubyte), POINTER(c_double)]
    lib.bus36m_decode.restype = None
    lib.bus36m_index.argtypes = [c_uint32]
    lib.bus36m_index.restype = c_int
    lib.bus36m_e2e_crc.argtypes = [POINTER(c_ubyte), c_int, c_uint8]
    lib.bus36m_e2e_crc.restype = c_uint8
    return lib


def data_signals(m):
    return [s for s in m.signals if s.name not in ("CRC", "AliveCounter")]


def python_frame(m, values, counter):
    """the runner's Network._encode: cantools (strict) with counter and CRC 0, then the CRC"""
    v = dict(zip([s.name for s in data_signals(m)], values), AliveCounter=counter, CRC=0)
    data = bytearray(m.encode(v, scaling=True, strict=True))
    data[0] = e2e_crc(data, int(m.dbc.attributes["E2EDataID"].value))
    return bytes(data)


def c_frame(lib, index, values, counter):
    buf = (c_ubyte * 8)()
    rc = lib.bus36m_encode(index, (c_double * 2)(*values), counter, buf)
    return rc, bytes(buf)


def sample(s, rng):
    """a value within the signal's range: uniform, an edge, or a rounding tie (k + 1/2) * scale + offset"""
    r = rng.random()
    if r < 0.1:
        return float(s.minimum)
    if r < 0.2:
        return float(s.maximum)
    if r < 0.4:
        k = rng.randint(0, 2 ** s.length - 2) - (2 ** (s.length - 1) if s.is_signed else 0)
        v = (k + 0.5) * s.scale + s.offset
        if s.minimum <= v <= s.maximum:
            return v
    return rng.uniform(s.minimum, s.maximum)


def test_the_committed_codec_is_what_the_dbc_generates():
    header, source = generate(DBC, STEM, label="ssp/can/Bus36m.dbc")
    assert STEM.with_suffix(".h").read_text(encoding="utf-8") == header
    assert STEM.with_suffix(".c").read_text(encoding="utf-8") == source


def test_every_message_is_in_the_table(lib, db):
    for m in db.messages:
        assert lib.bus36m_index(m.frame_id) >= 0, m.name
    assert lib.bus36m_index(0x7FF) == -1


def test_random_values_encode_to_the_python_bytes_and_decode_back(lib, db):
    rng = random.Random(24)
    n = 0
    for m in db.messages:
        idx = lib.bus36m_index(m.frame_id)
        sigs = data_signals(m)
        for _ in range(3000):
            values = [sample(s, rng) for s in sigs]
            counter = rng.randint(0, 15)
            rc, data = c_frame(lib, idx, values, counter)
            assert rc == 0, (m.name, values)
            want = python_frame(m, values, counter)
            assert data[:m.length] == want, (m.name, values, counter, data.hex(), want.hex())
            assert data[m.length:] == bytes(8 - m.length)
            # the CRC the receivers check, and the counter's bits (E2E profile 2)
            assert data[0] == e2e_crc(want, int(m.dbc.attributes["E2EDataID"].value))
            assert data[1] & 0x0F == counter
            out = (c_double * 2)()
            lib.bus36m_decode(idx, (c_ubyte * 8)(*data), out)
            dec = m.decode(want, scaling=True, decode_choices=False)
            for j, s in enumerate(sigs):
                assert out[j] == dec[s.name], (m.name, s.name)
                assert abs(out[j] - values[j]) <= s.scale / 2 * (1 + 1e-9), (m.name, s.name, values[j])
            n += 1
    assert n == 3000 * len(db.messages)


def test_a_value_outside_its_range_is_refused_as_cantools_refuses_it(lib, db):
    for m in db.messages:
        idx = lib.bus36m_index(m.frame_id)
        sigs = data_signals(m)
        for j, s in enumerate(sigs):
            ok = [float(x.minimum) for x in sigs]
            for bad in (s.maximum + s.scale, s.minimum - s.scale, math.nan, math.inf):
                values = list(ok)
                values[j] = bad
                rc, _ = c_frame(lib, idx, values, 0)
                assert rc == j + 1, (m.name, s.name, bad)
                if math.isfinite(bad):
                    with pytest.raises(Exception):
                        python_frame(m, values, 0)


def test_the_crc_is_autosar_profile_2(lib):
    # AUTOSAR E2E profile 2's CRC-8H2F check value (AUTOSAR_SWS_CRCLibrary, 7.2.1.2):
    # bytes 31 32 33 34 35 36 37 38 39 ("123456789") give 0xDF; here bytes 1.. and a data ID
    # go through it, so "12345678" with data ID 0x39 ('9') must give the same
    data = (c_ubyte * 9)(0, *b"12345678")
    assert lib.bus36m_e2e_crc(data, 9, 0x39) == 0xDF
