"""The FMU state fuzzer with recomputed checksums (issue 28).

tests/test_fmu_state.py corrupts states in memory, where no checksum guards
them; a serialized state with a flipped bit is refused by its checksum before
any model code sees it. An attacker (or a bug in an importer) can recompute
the checksum (FNV-1a over the GUID field and the body, src/fmi/fmi2Functions.c),
so here every corrupted state carries a valid one, and what is tested is the
FMU's own validation: the layer's (instance state, time, every variable finite
and in its declared range) and the model's (model_check_parameters, the same
function model_init runs, then model_state_valid).

Per FMU, N_STATES corrupted states, most of them parameters and inputs planted
with values inside their declared ranges that the model itself must refuse
(the probe's RoadFollowDriver lookFar0 = -1e308: [-inf, 1000] allows it, the
far look-ahead point behind the near one made a later step read its road
table at index -999999941), the others bit flips and planted counts in the
model's own states and the time. Each is deserialized, restored and stepped:
fmi2Error with a message, or steps with finite outputs; never a crash or a
sanitizer finding (this file runs in the sanitizer pass, tests/conftest.py)."""
import random
import struct
import zlib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from artibus.fmu import Fmu
from conftest import FMU_NAMES, fmu_file

HEADER = 80            # magic, size, guid[64], checksum: then the body
N_STATES = 400


def fnv1a(data):
    h = 1469598103934665603
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def fnv1a_np(data):
    """FNV-1a, the loop in Python over bytes (a state is a few kB: fast enough)"""
    return fnv1a(data)


def with_checksum(data):
    data = bytes(data)
    return data[:72] + struct.pack("<Q", fnv1a_np(data[8:72] + data[HEADER:])) + data[HEADER:]


def serialized(f):
    st = f.slave.getFMUstate()
    data = bytes(f.slave.serializeFMUstate(st))
    f.slave.freeFMUstate(st)
    return data


def outputs(f):
    return [v.valueReference for v in f.md.modelVariables if v.causality == "output" and v.type == "Real"]


def _trial_value(v, rng):
    """A value of variable v inside its declared range: the extremes, zero,
    tiny and huge numbers, the negated start, a random one"""
    if v.type == "Boolean":
        return rng.choice([0, 1])
    lo = float(v.min) if v.min is not None else (-2 ** 31 if v.type == "Integer" else -np.inf)
    hi = float(v.max) if v.max is not None else (2 ** 31 - 1 if v.type == "Integer" else np.inf)
    start = float(v.start) if v.start is not None else 0.0
    if v.type in ("Integer", "Enumeration"):
        cands = [lo, hi, 0, -1, 1, 2, start + 1, start - 1, rng.randint(int(max(lo, -1e6)), int(min(hi, 1e6)))]
        cands = [int(c) for c in cands if lo <= c <= hi and abs(c) < 2 ** 31]
        return rng.choice(cands) if cands else int(start)
    big = 1e308
    cands = [max(lo, -big), min(hi, big), 0.0, -0.0, 5e-324, -5e-324, -1.0, 1.0, 1e-300, -start,
             start * 1e6, start * 1e-6, start + 1e-9, rng.uniform(max(lo, -1e3), min(hi, 1e3))]
    cands = [c for c in cands if np.isfinite(c) and lo <= c <= hi]
    return rng.choice(cands) if cands else start


def variable_offsets(name):
    """{variable: byte offset in the serialized state} of every Real, Integer
    and Boolean parameter and input: found by setting it (instantiated, before
    initialisation) and seeing which bytes change"""
    f = Fmu(fmu_file(name))
    try:
        base = np.frombuffer(serialized(f), dtype=np.uint8)
        found = {}
        for v in f.md.modelVariables:
            if v.causality not in ("parameter", "input") or v.type not in ("Real", "Integer", "Boolean"):
                continue
            if v.type == "Real":
                start = float(v.start) if v.start is not None else 0.0
                lo = float(v.min) if v.min is not None else -np.inf
                hi = float(v.max) if v.max is not None else np.inf
                trial = next((x for x in (start + 0.4375, start - 0.4375, (lo + hi) / 2 if np.isfinite(lo + hi) else start)
                              if lo <= x <= hi and x != start), None)
                if trial is None:
                    continue
                f.slave.setReal([v.valueReference], [trial])
                other = np.frombuffer(serialized(f), dtype=np.uint8)
                f.slave.setReal([v.valueReference], [start])
                align = 8
            elif v.type == "Integer":
                start = int(v.start) if v.start is not None else 0
                lo = int(v.min) if v.min is not None else -2 ** 31
                hi = int(v.max) if v.max is not None else 2 ** 31 - 1
                trial = next((x for x in (start + 1, start - 1) if lo <= x <= hi), None)
                if trial is None:
                    continue
                f.slave.setInteger([v.valueReference], [trial])
                other = np.frombuffer(serialized(f), dtype=np.uint8)
                f.slave.setInteger([v.valueReference], [start])
                align = 4
            else:
                start = v.start in ("true", "1", True)
                f.slave.setBoolean([v.valueReference], [not start])
                other = np.frombuffer(serialized(f), dtype=np.uint8)
                f.slave.setBoolean([v.valueReference], [start])
                align = 4
            diff = np.flatnonzero(base[HEADER:] != other[HEADER:])
            if len(diff):
                found[v.name] = (HEADER + (int(diff[0]) // align) * align, v)
        return found
    finally:
        f.close()


def _plant(raw, off, v, value):
    if v.type == "Real":
        struct.pack_into("<d", raw, off, value)
    else:
        struct.pack_into("<i", raw, off, int(value))


def started(name):
    f = Fmu(fmu_file(name))
    f.initialize({})
    return f


def step_size(f):
    de = f.md.defaultExperiment
    return float(de.stepSize) if de and de.stepSize else 0.01


def test_road_follow_driver_far_point_behind_the_near_one_is_refused_on_restore():
    """The probe: lookFar0 = -1e308 in a state with a valid checksum was
    accepted; the next fmi2DoStep read the road table out of bounds."""
    offsets = variable_offsets("RoadFollowDriver")
    f = started("RoadFollowDriver")
    try:
        h = step_size(f)
        for k in range(10):
            f.slave.doStep(k * h, h)
        good = serialized(f)
        off, v = offsets["lookFar0"]
        bad = bytearray(good)
        _plant(bad, off, v, -1e308)
        f.log.clear()
        with pytest.raises(FMICallException):
            st = f.slave.deSerializeFMUstate(with_checksum(bad))
            f.slave.setFMUstate(st)
        assert any("lookFar0" in m and "parameters are not valid" in m for m in f.log), f.log
    finally:
        f.close()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_corrupted_states_with_valid_checksums(name):
    rng = random.Random(zlib.crc32(b"checksummed " + name.encode()))
    offsets = list(variable_offsets(name).values())
    f = started(name)
    try:
        h = step_size(f)
        t = 0.0
        for _ in range(20):
            f.slave.doStep(t, h)
            t += h
        good = serialized(f)
        st0 = f.slave.deSerializeFMUstate(good)
        size = len(good)
        body_vars = min(o for o, _ in offsets) if offsets else HEADER + 16
        outs = outputs(f)
        counts = {"deserialize refused": 0, "restore refused": 0, "step refused": 0, "ran": 0}
        for trial in range(N_STATES):
            bad = bytearray(good)
            kind = trial % 8
            if kind < 6 and offsets:                 # parameters and inputs in their declared ranges
                for _ in range(1 if kind < 4 else rng.randint(2, 4)):
                    off, v = rng.choice(offsets)
                    _plant(bad, off, v, _trial_value(v, rng))
            elif kind == 6:                          # the model's own states (after the variables)
                end = max(o for o, _ in offsets) + 8 if offsets else body_vars
                lo = end if end < size - 8 else HEADER + 16
                for _ in range(rng.randint(1, 4)):
                    i = rng.randrange(lo, size)
                    if rng.random() < 0.5:
                        bad[i] ^= 1 << rng.randrange(8)
                    else:
                        i = lo + 4 * ((i - lo) // 4)
                        if i + 4 <= size:
                            struct.pack_into("<i", bad, i, rng.choice([-1, 0, 5, 100000, 2 ** 31 - 1, -2 ** 31]))
            else:                                    # the time
                struct.pack_into("<d", bad, HEADER + 8, rng.choice([-1e308, 1e308, -1.0, 1e15, 5e-324, t + 1e6]))
            data = with_checksum(bad)
            f.log.clear()
            try:
                st = f.slave.deSerializeFMUstate(data)
            except FMICallException:
                counts["deserialize refused"] += 1
                assert f.log, "refused without a message"
                f.slave.setFMUstate(st0)
                continue
            try:
                f.slave.setFMUstate(st)
            except FMICallException:
                counts["restore refused"] += 1
                assert f.log, "refused without a message"
                f.slave.freeFMUstate(st)
                f.slave.setFMUstate(st0)
                continue
            ts = struct.unpack_from("<d", data, HEADER + 8)[0]
            try:
                for _ in range(3):
                    f.slave.doStep(ts, h)
                    ts += h
                    y = np.array(f.slave.getReal(outs)) if outs else np.zeros(0)
                    assert np.all(np.isfinite(y)), (name, trial, y)
                counts["ran"] += 1
            except FMICallException:
                counts["step refused"] += 1
                assert f.log, "a step refused without a message"
            f.slave.freeFMUstate(st)
            f.slave.setFMUstate(st0)
        f.slave.freeFMUstate(st0)
        print(name, counts)                          # pytest -s: the figures
        assert sum(counts.values()) == N_STATES
        assert counts["ran"] > 0                     # not everything refused: the good values do run
    finally:
        f.close()
