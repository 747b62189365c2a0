"""FMU state (issue 14): a state restores into a fresh instance, and a state is
validated as a whole before any of it is used (checksum of the serialized
body, instance state, time, every variable, the model's own ModelState).

Every FMU: run its default experiment for a while, take and serialize the
state, go on (the uninterrupted run); then free, instantiate anew (no
initialisation), deserialize, restore, go on, and compare. The integrator
restarts from scratch both where a state is taken and where it is restored
(README, "The FMI layer's rules"), so the two runs are the same computation:
bit for bit, for the one-step controllers and for the plants' CVODE/ARKODE
alike.

The state-corruption fuzzer: per FMU, 200 corrupted states (bit flips and
planted out-of-range counts anywhere in the state's body, in memory where no
checksum guards it, and bit flips in the serialized bytes, which the checksum
must catch); each is restored and stepped: fmi2Error or a good run, never a
crash, a hang or a non-finite output (also run in the sanitizer pytest pass).
"""
import ctypes
import random
import struct
import zlib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import FMU_NAMES
from artibus.fmu import Fmu
from conftest import fmu_file

HEADER = 80            # magic, size, guid[64], checksum: then the body (src/fmi/fmu_core.c)


def outputs(f):
    return [v for v in f.md.modelVariables if v.causality == "output" and v.type == "Real"]


def read_outputs(f):
    vrs = [v.valueReference for v in outputs(f)]
    return np.array(f.slave.getReal(vrs))


def started(name):
    f = Fmu(fmu_file(name))
    f.initialize({})
    return f


def experiment(f):
    de = f.md.defaultExperiment
    h = float(de.stepSize) if de and de.stepSize else 0.01
    return h


def steps(f, t, h, n):
    """n steps of h from t: the outputs after each"""
    out = []
    for _ in range(n):
        f.slave.doStep(t, h)
        t += h
        out.append(read_outputs(f))
    return out


def serialized(f):
    st = f.slave.getFMUstate()
    data = f.slave.serializeFMUstate(st)
    f.slave.freeFMUstate(st)
    return bytes(data)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_restore_into_fresh_instance_continues_the_run(name):
    a = started(name)
    try:
        h = experiment(a)
        t, n1, n2 = 0.0, 60, 60
        for _ in range(n1):
            a.slave.doStep(t, h)
            t += h
        data = serialized(a)
        t_saved = t
        ref = steps(a, t_saved, h, n2)
    finally:
        a.close()
    b = Fmu(fmu_file(name))           # fresh: instantiated, never initialised
    try:
        st = b.slave.deSerializeFMUstate(data)
        b.slave.setFMUstate(st)
        b.slave.freeFMUstate(st)
        got = steps(b, t_saved, h, n2)
    finally:
        b.close()
    ref, got = np.array(ref), np.array(got)
    assert np.all(np.isfinite(got))
    assert np.array_equal(ref, got), f"{name}: largest difference {np.max(np.abs(ref - got))}"


def body_offsets(name):
    """(offset, value) of every Integer parameter inside the serialized body:
    found by setting it to two values and comparing the bytes"""
    f = Fmu(fmu_file(name))           # instantiated: a state is taken without initialising
    try:
        base = serialized(f)
        found = {}
        for v in f.md.modelVariables:
            if v.type != "Integer" or v.causality != "parameter" or v.variability != "fixed":
                continue
            start = int(v.start)
            for trial in (start + 1, start - 1):
                if v.min is not None and trial < int(v.min) or v.max is not None and trial > int(v.max):
                    continue
                f.slave.setInteger([v.valueReference], [trial])
                other = serialized(f)
                f.slave.setInteger([v.valueReference], [start])
                diff = [i for i in range(HEADER, len(base)) if base[i] != other[i]]
                if diff:
                    found[v.name] = (diff[0] & ~3, v)
                break
        return found
    finally:
        f.close()


# the issue's planted counts: out of the declared range of a sizing parameter
PLANTED = {"BusDynamics": {"nModules": 5, "nAxles": 100000},
           "BusKinematics": {"N": -1},
           "MultiAxle3DOF": {"n": 100000},
           "RoadFollowDriver": {"nSpeed": 100000}}


def fnv1a(body):
    h = 1469598103934665603
    for b in body:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def with_checksum(data):
    return data[:72] + struct.pack("<Q", fnv1a(data[8:72] + data[HEADER:])) + data[HEADER:]


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_planted_out_of_range_count_is_refused(name):
    offsets = body_offsets(name)
    f = started(name)
    try:
        h = experiment(f)
        for k in range(10):
            f.slave.doStep(k * h, h)
        good = serialized(f)
        assert with_checksum(good) == good          # the checksum is FNV-1a of the GUID field and the body
        before = read_outputs(f)
        for var, value in PLANTED[name].items():
            off, v = offsets[var]
            bad = bytearray(good)
            bad[off:off + 4] = struct.pack("<i", value)
            bad = with_checksum(bytes(bad))
            f.log.clear()
            with pytest.raises(FMICallException):
                f.slave.deSerializeFMUstate(bad)
            assert any(var in m and "range" in m for m in f.log), f.log
        # the instance's values are unchanged (error state: the getters still work)
        assert np.array_equal(read_outputs(f), before)
    finally:
        f.close()


@pytest.mark.parametrize("name", ["ForceMinimization", "ZeroSideslipSteering", "TrainGuidance"])
def test_corrupted_sample_counter_is_refused_not_a_hang(name):
    """a sample counter of -2^40 once looped for 2^40 samples in one 10 ms step"""
    f = started(name)
    try:
        h = experiment(f)
        for k in range(5):
            f.slave.doStep(k * h, h)
        size = len(serialized(f))
        st = f.slave.getFMUstate()
        raw = (ctypes.c_char * size).from_address(st.value if hasattr(st, "value") else st)
        body = bytes(raw[HEADER:size])
        # the counter: the 8-byte integer whose value is the samples taken so far (5 or 6)
        hits = [i for i in range(0, len(body) - 7, 8) if struct.unpack_from("<q", body, i)[0] in (5, 6)]
        assert hits
        for i in hits:
            struct.pack_into("<q", raw, HEADER + i, -(1 << 40))
        f.log.clear()
        with pytest.raises(FMICallException):
            f.slave.setFMUstate(st)
        assert any("sample" in m for m in f.log), f.log
    finally:
        f.close()


def test_checksum_catches_a_flipped_bit():
    f = started("BusDynamics")
    try:
        data = bytearray(serialized(f))
        data[HEADER + 200] ^= 0x10
        f.log.clear()
        with pytest.raises(FMICallException):
            f.slave.deSerializeFMUstate(bytes(data))
        assert any("checksum" in m for m in f.log), f.log
    finally:
        f.close()


N_FUZZ = 200


@pytest.mark.parametrize("name", FMU_NAMES)
def test_state_corruption_fuzzer(name):
    rng = random.Random(zlib.crc32(name.encode()))      # the same corruptions every run
    f = started(name)
    try:
        h = experiment(f)
        t = 0.0
        for _ in range(20):
            f.slave.doStep(t, h)
            t += h
        good = serialized(f)
        st0 = f.slave.deSerializeFMUstate(good)
        size = len(good)
        counts = {"refused": 0, "ran": 0, "serialized refused": 0}
        PLANT = [5, -1, 100000, 2 ** 31 - 1, -2 ** 31]
        # where the counts, indices, modes and flags are: 4-byte words holding
        # a small nonzero integer (and others that look like one)
        small = [i for i in range(HEADER, size - 3, 4) if 0 < struct.unpack_from("<i", good, i)[0] <= 1000]
        for trial in range(N_FUZZ):
            if trial % 4 == 3:                       # serialized bytes: the checksum must catch it
                bad = bytearray(good)
                for _ in range(rng.randint(1, 4)):
                    i = rng.randrange(size)
                    bad[i] ^= 1 << rng.randrange(8)
                if bytes(bad) == good:
                    continue
                with pytest.raises(FMICallException):
                    f.slave.deSerializeFMUstate(bytes(bad))
                counts["serialized refused"] += 1
                continue
            st = f.slave.deSerializeFMUstate(good)
            addr = st.value if hasattr(st, "value") else st
            raw = (ctypes.c_char * size).from_address(addr)
            if trial % 2:                            # planted count: on a count-like word, or anywhere aligned
                if small and rng.random() < 0.7:
                    i = rng.choice(small)
                else:
                    i = HEADER + 4 * rng.randrange((size - HEADER) // 4)
                struct.pack_into("<i", raw, i, rng.choice(PLANT))
            else:                                    # bit flips anywhere in the body
                for _ in range(rng.randint(1, 8)):
                    i = HEADER + rng.randrange(size - HEADER)
                    raw[i] = bytes([raw[i][0] ^ (1 << rng.randrange(8))])
            try:
                f.slave.setFMUstate(st)
                counts["ran"] += 1
                try:
                    ts = struct.unpack_from("<d", bytes(raw[HEADER + 8:HEADER + 16]))[0]
                    for _ in range(3):
                        f.slave.doStep(ts, h)
                        ts += h
                        assert np.all(np.isfinite(read_outputs(f)))
                except FMICallException:
                    pass
            except FMICallException:
                counts["refused"] += 1
            f.slave.freeFMUstate(st)
            f.slave.setFMUstate(st0)                 # a good state brings the instance back
        f.slave.freeFMUstate(st0)
        print(name, counts)                          # pytest -s: the figures
        assert sum(counts.values()) >= N_FUZZ - 5, counts
        assert counts["serialized refused"] >= N_FUZZ // 4 - 5
    finally:
        f.close()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_state_from_before_initialisation_restores_and_initialises_again(name):
    """a state taken right after instantiation, restored into a running
    instance: it is instantiated again, and initialises and steps as new"""
    f = Fmu(fmu_file(name))
    try:
        st = f.slave.getFMUstate()
        f.initialize({})
        h = experiment(f)
        for k in range(5):
            f.slave.doStep(k * h, h)
        f.slave.setFMUstate(st)
        f.slave.freeFMUstate(st)
        with pytest.raises(FMICallException):       # instantiated again: no step before initialising
            f.slave.doStep(5 * h, h)
        f.slave.setFMUstate(f.slave.deSerializeFMUstate(serialized_fresh(name)))
        f.initialize({})
        f.slave.doStep(0.0, h)
        assert np.all(np.isfinite(read_outputs(f)))
    finally:
        f.close()


def serialized_fresh(name):
    g = Fmu(fmu_file(name))
    try:
        return serialized(g)
    finally:
        g.close()
