"""Our FMI-LS-BUS CAN codec (src/fmi/lsbus_can.c) and FMUs against the standard's own C
headers: fmi3LsBusCan.h / fmi3LsBusUtilCan.h of the Modelica Association (FMI-LS-BUS 1.0,
BSD-2-Clause), which the crate fmi-sys 0.6.0 on crates.io carries
(scripts/fetch_lsbus_headers.sh fetches them with cargo into .tools/fmi-ls-bus/).

tests/c/lsbus_official_test.c is built here with them (under ASan/UBSan when the compiler
has them) and
- builds every CAN operation with the standard's FMI3_LS_BUS_CAN_CREATE_OP_* macros and
  reads it with ours, builds it with ours and reads it with the standard's
  FMI3_LS_BUS_READ_NEXT_OPERATION into its packed structs: fields equal, bytes equal;
- reads Tx_Data buffers from a run (SteeringSensors_LSBUS's, then CanBus's answer to
  them) with FMI3_LS_BUS_READ_NEXT_OPERATION_DIRECT and prints each operation from the
  standard's structs; what they must hold comes from the DBC (cantools, with the E2E CRC
  and the alive counter: the Python encoder of test_lsbus_node) and from 4_4_1_can.adoc
  (a Configuration baud rate 500 kbit/s before the first Transmit; the bus confirms each
  frame to its sender and hands it to every other node).
Without the headers (no cargo) the tests are skipped, saying so."""
import random
import shutil
import subprocess

import pytest

from artibus import ROOT
from test_canbus import Importer, unzipped  # noqa: F401  (the CanBus importer and its fixture)
from test_lsbus_node import RAD_DEG, Node, python_frame

HEADERS = ROOT / ".tools" / "fmi-ls-bus"
SOURCE = ROOT / "tests" / "c" / "lsbus_official_test.c"
CODEC = ROOT / "src" / "fmi" / "lsbus_can.c"
SANITIZERS = ["-fsanitize=address,undefined", "-fno-sanitize-recover=undefined"]

pytestmark = pytest.mark.skipif(
    not (HEADERS / "fmi3LsBusUtilCan.h").is_file(),
    reason=f"the FMI-LS-BUS headers are not in {HEADERS}: scripts/fetch_lsbus_headers.sh "
           "(run by scripts/setup_test.sh) fetches them from the crate fmi-sys with cargo")


@pytest.fixture(scope="module")
def official(tmp_path_factory):
    """the test program, built: with the sanitizers if this compiler has them"""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler (cc) to build tests/c/lsbus_official_test.c")
    exe = tmp_path_factory.mktemp("lsbus_official") / "lsbus_official_test"
    base = [cc, "-std=c11", "-Wall", "-Wextra", "-Werror", "-Wno-unused-parameter", "-pedantic", "-g",
            f"-I{HEADERS}", f"-I{CODEC.parent}", str(SOURCE), str(CODEC), "-o", str(exe)]
    for flags in (SANITIZERS, []):
        r = subprocess.run(base[:1] + flags + base[1:], capture_output=True, text=True)
        if r.returncode == 0:
            return exe
        if not flags:
            pytest.fail(f"{SOURCE} does not build against {HEADERS}:\n{r.stderr}")
    raise AssertionError("unreachable")


def run(exe, *args):
    r = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True,
                       env={"ASAN_OPTIONS": "detect_leaks=1", "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0 and "FAIL" not in r.stdout and not r.stderr, r.stdout + r.stderr
    return r.stdout


def parsed(exe, tmp_path, buffers):
    """[[(op, {field: value})] per buffer] as the standard's read macros see them"""
    files = []
    for i, data in enumerate(buffers):
        f = tmp_path / f"buf{i}.bin"
        f.write_bytes(data)
        files.append(f)
    out = {str(f): [] for f in files}
    for line in run(exe, *files).splitlines():
        path, name, *fields = line.split(" ")
        out[path].append((name, dict(kv.split("=", 1) for kv in fields)))
    return [out[str(f)] for f in files]


def transmit_fields(can_id, data):
    return ("Transmit", {"id": str(can_id), "ide": "0", "rtr": "0", "dl": str(len(data)), "data": data.hex()})


def test_every_operation_the_standards_macros_build_is_ours_byte_for_byte(official):
    out = run(official)
    # "operations: N checks, 0 failed": every operation of 4_4_1_can.adoc with its
    # argument edges (DL 0-8, FD lengths to 64, XL to 2048, 11/29-bit IDs, each error code,
    # flag, status and configuration kind), both ways, and a buffer of nine
    n = int(out.split("operations: ")[1].split(" checks")[0])
    assert n >= 600 and out.strip().endswith("0 failed"), out


def sensor_inputs(rng):
    return dict(gamma1=rng.uniform(-0.8, 0.8), gammaA6=rng.uniform(-0.8, 0.8),
                **{"dPsi[1]": rng.uniform(-1.5, 1.5), "dPsi[2]": rng.uniform(-1.5, 1.5)})


def sensor_frames(db, inputs, counter):
    """{id: bytes}: the DBC's four sensor frames of these inputs (the Python encoder)"""
    return dict([
        python_frame(db, "SensorA1_Angle", {"RoadWheelAngleA1": RAD_DEG * inputs["gamma1"]}, counter),
        python_frame(db, "SensorG1_Angle", {"ArtAngleG1": RAD_DEG * inputs["dPsi[1]"]}, counter),
        python_frame(db, "SensorG2_Angle", {"ArtAngleG2": RAD_DEG * inputs["dPsi[2]"]}, counter),
        python_frame(db, "SensorA6_Angle", {"RoadWheelAngleA6": RAD_DEG * inputs["gammaA6"]}, counter)])


def sensors_run(tmp_path, ticks):
    """SteeringSensors_LSBUS's Tx_Data at `ticks` 10 ms ticks, with the inputs of each"""
    node = Node("SteeringSensors_LSBUS", tmp_path)
    rng = random.Random(7)
    out = []
    try:
        for _ in range(ticks):
            inputs = sensor_inputs(rng)
            out.append((inputs, node.event(**inputs)))
            node.step()
    finally:
        node.close()
    return out


def test_a_nodes_tx_data_read_with_the_standards_macros(official, tmp_path, db):
    run_ = sensors_run(tmp_path, 3)
    for k, ((inputs, _), ops) in enumerate(zip(run_, parsed(official, tmp_path, [tx for _, tx in run_]))):
        if k == 0:   # CAN_BAUDRATE (0x01) 500 kbit/s before the first Transmit (4_4_1_can.adoc, Configuration)
            assert ops[0] == ("Configuration", {"type": "1", "baudrate": "500000"})
            ops = ops[1:]
        want = sensor_frames(db, inputs, k % 16)
        assert sorted(ops, key=lambda o: int(o[1]["id"])) == [transmit_fields(i, want[i]) for i in sorted(want)]


def test_canbus_tx_data_read_with_the_standards_macros(official, tmp_path, db, unzipped):  # noqa: F811
    (inputs, tx), = sensors_run(tmp_path, 1)
    want = sensor_frames(db, inputs, 0)
    bus = Importer(unzipped)
    try:
        bus.send({1: tx})               # the sensors on node 1, the other seven listen
        bus.run(0.01)
    finally:
        bus.close()
    raw = bus.raw
    got = parsed(official, tmp_path, [data for _, _, data in raw])
    confirms = [f["id"] for (_, k, _), ops in zip(raw, got) if k == 1 for name, f in ops if name == "Confirm"]
    # the sender hears a Confirm of each frame in arbitration order (the lowest ID first,
    # ISO 11898-1), and none of its own frames back
    assert confirms == [str(i) for i in sorted(want)]
    assert not [o for (_, k, _), ops in zip(raw, got) if k == 1 for o in ops if o[0] != "Confirm"]
    for node in range(2, 9):
        frames = [o for (_, k, _), ops in zip(raw, got) if k == node for o in ops]
        assert frames == [transmit_fields(i, want[i]) for i in sorted(want)], node


def test_the_examples_operations_built_by_hand_are_the_standards(official, tmp_path):
    """test_lsbus_examples's hand-built operations of the fmi-ls-bus-examples node and bus,
    read with the standard's macros: each as the example's App.c builds it"""
    from test_lsbus_examples import EXAMPLE_CONFIG, EXAMPLE_FRAME, arbitration_lost, bus_error, confirm
    from test_canbus import transmit
    buf = EXAMPLE_CONFIG + transmit(*EXAMPLE_FRAME) + confirm(0x1) + arbitration_lost(0x201) + bus_error(0x1, 4, 1, 1)
    (ops,) = parsed(official, tmp_path, [buf])
    assert ops == [("Configuration", {"type": "1", "baudrate": "100000"}),
                   ("Configuration", {"type": "4", "behavior": "1"}),
                   transmit_fields(0x1, bytes([1, 2, 3, 4])),
                   ("Confirm", {"id": "1"}), ("ArbitrationLost", {"id": "513"}),
                   ("BusError", {"id": "1", "code": "4", "flag": "1", "sender": "1"})]
