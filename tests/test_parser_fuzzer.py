"""The parser fuzzer (issue 28): every reader of a file a user hands us takes
N_INPUTS inputs made by Hypothesis (a real file of its kind with bytes
inserted, deleted and replaced, numbers in other syntaxes, markup, NULs,
invalid UTF-8; and plain random bytes) and either reads it or raises the
project's own error (ArtibusError, naming the file), never another exception.

Readers: .ssd (artibus.bench.ssp.read of an .ssp), .ssv (read_parameters),
.ssm (a parameter mapping in an .ssp), road CSV (artibus.bench.roads.read_csv,
the FMU's C reader), replay CSV (read_csv_log), ASC and BLF CAN logs
(artibus.can.decode_log), designs (.csv and .yaml: read_design, then the
cases typed against a bench's variables). Derandomized (the same inputs every
run), no deadline; about 65 s of CPU for all of them (18000 inputs).
ARTIBUS_FUZZ_INPUTS=200 for a quick look."""
import io
import os
import types
import zipfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from artibus import ArtibusError, ROOT
from artibus.base import fmu_path

N_INPUTS = int(os.environ.get("ARTIBUS_FUZZ_INPUTS", "2000"))     # fewer for a quick look
FUZZ = settings(max_examples=N_INPUTS, deadline=None, derandomize=True, database=None, print_blob=True,
                suppress_health_check=list(HealthCheck))

TOKENS = [b"<", b">", b"/>", b'"', b"'", b"&amp;", b"&#0;", b"]]>", b"<!--", b"<!DOCTYPE a [<!ENTITY e 'x'>]>",
          b"1_5", b"0x1A", b"0x1p3", b"nan", b"NaN", b"inf", b"-INF", b"-1e308", b"1e309", b"4.9e-324",
          "\u0661\u0662".encode(), b"\x00", b"\xff\xfe", b"\xc3\x28", b"\r\n", b"\n" * 3, b",", b";", b"\t", b"#",
          b"=", b":", b"[", b"]", b"{", b"}", b"- ", b"!!python/object:os.system", b"*a", b"&a",
          b"resources/", b"../", b"x" * 300, b"9" * 40, b"-", b"."]


def _edited(seed, script):
    """``seed`` edited by ``script``, read 4 bytes an edit: where (2 bytes, scaled
    to the length), how many bytes go (0..24), what comes in (one of TOKENS, or
    the byte itself); a script starting with 0 is the input itself, raw bytes.
    One flat byte string: cheap to make and to shrink."""
    if script[:1] == b"\0":
        return script[1:]
    data = bytearray(seed)
    for i in range(0, len(script) - 3, 4):
        where, cut, what = int.from_bytes(script[i:i + 2], "little"), script[i + 2] % 25, script[i + 3]
        p = where * (len(data) + 1) // 65536
        data[p:p + cut] = TOKENS[what] if what < len(TOKENS) else bytes([what])
    return bytes(data)


def mutated(seed):
    return st.binary(min_size=4, max_size=48).map(lambda script: _edited(seed, script))


def only_our_errors(fn, *args):
    try:
        fn(*args)
    except ArtibusError:
        pass


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@pytest.fixture(scope="module", autouse=True)
def schemas_loaded_once():
    """FMPy's SSP readers load their XSD afresh for every file (most of a
    read's time); here once: the same schema, the same validation."""
    import fmpy.ssp.ssd as ssd
    from lxml import etree
    cache = {}

    class Etree:
        def __getattr__(self, name):
            return getattr(etree, name)

        @staticmethod
        def XMLSchema(file):
            if file not in cache:
                cache[file] = etree.XMLSchema(file=file)
            return cache[file]
    old = ssd.etree
    ssd.etree = Etree()
    yield
    ssd.etree = old


# --- SSP files ------------------------------------------------------------------------------

SSD = (ROOT / "ssp" / "benches" / "Urbino18_Replay" / "SystemStructure.ssd").read_bytes()
SSV = (ROOT / "ssp" / "parameters" / "Urbino18.ssv").read_bytes()
SSM = (ROOT / "ssp" / "parameters" / "Scania18mDampingController.ssm").read_bytes()
SSD_MAPPED = SSD.replace(b'<ssd:ParameterBinding source="resources/Urbino18.ssv"/>',
                         b'<ssd:ParameterBinding source="resources/Urbino18.ssv">'
                         b'<ssd:ParameterMapping source="resources/map.ssm"/></ssd:ParameterBinding>')
SSM_SEED = (b'<?xml version="1.0" encoding="UTF-8"?>\n<ssm:ParameterMapping '
            b'xmlns:ssm="http://ssp-standard.org/SSP1/SystemStructureParameterMapping" '
            b'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0">\n'
            b'  <ssm:MappingEntry source="L0" target="L0"><ssc:LinearTransformation factor="1.5" offset="0"/>'
            b'</ssm:MappingEntry>\n  <ssm:MappingEntry source="N" target="N"/>\n</ssm:ParameterMapping>\n')


def _ssp(path, ssd, ssv=SSV, ssm=None):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.writestr("resources/Urbino18.ssv", ssv)
        z.write(fmu_path("BusKinematics"), "resources/BusKinematics.fmu")   # its units are read
        if ssm is not None:
            z.writestr("resources/map.ssm", ssm)
    return path


def test_seeds_are_read(work):
    """the unmutated seeds are good files (so the mutations start from a file that reads)"""
    from artibus.bench import ssp
    b = ssp.read(_ssp(work / "seed.ssp", SSD))
    assert "Bus" in b.components and b.components["Bus"].parameters["L0"] == 5.9
    m = ssp.read(_ssp(work / "seed_m.ssp", SSD_MAPPED, ssm=SSM_SEED))
    assert m.components["Bus"].parameters == {"L0": 5.9 * 1.5, "N": 1}
    assert SSM.startswith(b"<?xml")


@FUZZ
@given(data=mutated(SSD))
def test_ssd(work, data):
    from artibus.bench import ssp
    only_our_errors(ssp.read, _ssp(work / "ssd.ssp", data))


@FUZZ
@given(data=mutated(SSV))
def test_ssv(work, data):
    from artibus.bench.parameters import read_parameters
    f = work / "p.ssv"
    f.write_bytes(data)
    only_our_errors(read_parameters, f)


@FUZZ
@given(data=mutated(SSM_SEED))
def test_ssm(work, data):
    from artibus.bench import ssp
    only_our_errors(ssp.read, _ssp(work / "ssm.ssp", SSD_MAPPED, ssm=data))


# --- CSV: roads, replay logs ----------------------------------------------------------------

ROAD = b"".join((ROOT / "ssp" / "roads" / "Bus36m_Slalom.csv").read_bytes().splitlines(True)[:40])
REPLAY = b"".join((ROOT / "ssp" / "logs" / "Urbino18_test.csv").read_bytes().splitlines(True)[:40])


@FUZZ
@given(data=mutated(ROAD))
def test_road_csv(work, data):
    from artibus.bench import roads
    f = work / "road.csv"
    f.write_bytes(data)
    only_our_errors(roads.read_csv, f)


@FUZZ
@given(data=mutated(REPLAY))
def test_replay_csv(work, data):
    from artibus.can import replay
    f = work / "log.csv"
    f.write_bytes(data)
    only_our_errors(replay.read_csv_log, f)


# --- CAN logs ----------------------------------------------------------------------------------

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"


def _frames():
    """a few good frames of the bench's DBC (CRC and counter right), as python-can Messages"""
    import can
    from cantools.autosar.end_to_end import compute_profile2_crc
    from artibus.can.dbc import load_dbc
    db = load_dbc(DBC)
    out = []
    for k in range(6):
        for m in db.messages[:3]:
            data = bytearray(m.length)
            data[1] = k & 0x0F
            data[0] = compute_profile2_crc(bytes(data), int(m.dbc.attributes["E2EDataID"].value))
            out.append(can.Message(timestamp=1.0 + 0.01 * k, arbitration_id=m.frame_id, data=bytes(data),
                                   is_extended_id=False))
    return db, out


@pytest.fixture(scope="module")
def can_seeds(work):
    import can
    db, frames = _frames()
    asc, blf = work / "seed.asc", work / "seed.blf"
    for path in (asc, blf):
        with can.Logger(str(path)) as w:
            for m in frames:
                w.on_message_received(m)
    return db, asc.read_bytes(), blf.read_bytes()


def test_can_seeds_are_read(can_seeds, work):
    from artibus.can import decode_log
    db, asc, blf = can_seeds
    for name, data in (("s.asc", asc), ("s.blf", blf)):
        f = work / name
        f.write_bytes(data)
        rows = decode_log(f, db)
        assert len({r[0] for r in rows}) == 6 and all(r[5] == "ok" for r in rows), name


def _can_fuzz(work, can_seeds, name, pick):
    from artibus.can import decode_log
    db, asc, blf = can_seeds
    seed = asc if name.endswith(".asc") else blf

    @FUZZ
    @given(data=mutated(seed))
    def run(data):
        f = work / name
        f.write_bytes(data)
        only_our_errors(decode_log, f, db)
    run()


def test_asc(work, can_seeds):
    _can_fuzz(work, can_seeds, "f.asc", None)


def test_blf(work, can_seeds):
    _can_fuzz(work, can_seeds, "f.blf", None)


# --- designs ----------------------------------------------------------------------------------

DESIGN_YAML = b"""method: lhs
seed: 3
n: 8
parameters:
  Bus.L0: {distribution: uniform, low: 4.0, high: 7.0}
  Bus.N: {distribution: normal, mean: 1, std: 0.1}
"""
DESIGN_GRID = b"""method: grid
parameters:
  Bus.L0: [5.0, 5.5, "6.0"]
  Bus.k: "0:1:1"
  Bus.steerable[1]: [true, false]
variants: [a]
"""
DESIGN_CSV = b"Bus.L0,Bus.k,variant\n5.9,1,a\n6.1,0,\n"


def _info():
    """a bench's variables as bench_info gives them (without packing one)"""
    def var(t):
        return types.SimpleNamespace(type=t, kind=t, declaredType=None, min=None, max=None)   # (FMI 2.0 types: kind = type)
    return types.SimpleNamespace(name="Fuzz", components=["Bus"], variants={"a": "h"},
                                 variables={"Bus.L0": var("Real"), "Bus.N": var("Real"), "Bus.k": var("Integer"),
                                            "Bus.steerable[1]": var("Boolean")})


def _design(path):
    from artibus.study.sweep.designs import build_cases, read_design
    build_cases(_info(), read_design(path), str(path))


def test_design_seeds_are_read(work):
    for name, data, n in (("d.yaml", DESIGN_YAML, 8), ("g.yaml", DESIGN_GRID, 12), ("d.csv", DESIGN_CSV, 2)):
        from artibus.study.sweep.designs import build_cases, read_design
        f = work / name
        f.write_bytes(data)
        assert len(build_cases(_info(), read_design(f), name)) == n, name


@pytest.mark.parametrize("suffix, seed", [(".yaml", DESIGN_YAML), (".yml", DESIGN_GRID), (".csv", DESIGN_CSV)])
def test_design(work, suffix, seed):
    """YAML designs: N_INPUTS between lhs (.yaml) and grid (.yml); CSV designs: N_INPUTS"""
    @settings(FUZZ, max_examples=N_INPUTS if suffix == ".csv" else N_INPUTS // 2)
    @given(data=mutated(seed))
    def run(data):
        f = work / f"design{suffix}"
        f.write_bytes(data)
        only_our_errors(_design, f)
    run()
