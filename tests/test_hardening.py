"""Hardening (issue 14): no hidden stimulus, and the crashes of the issue's
adversarial probe, each now an fmi2Error with a message."""
import numpy as np
import pytest
from fmpy import simulate_fmu, read_model_description
from fmpy.fmi1 import FMICallException

from conftest import FMU_NAMES, fmu_file, init
from artibus.fmu import Fmu

STIMULI = {"testSteerAmp": 0.0, "testSpeedRate": 0.0, "testVehicle": False}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_default_experiment_alone_is_finite_and_not_trivial(name):
    """fmpy simulate with no start values: every stimulus is off by default,
    and the start values still make the model do something"""
    path = str(fmu_file(name))
    md = read_model_description(path)
    for v in md.modelVariables:
        if v.name in STIMULI:
            start = v.start in ("true", "1") if v.type == "Boolean" else float(v.start)
            assert start == STIMULI[v.name], f"{name}.{v.name} is on by default ({v.start})"
    outs = [v.name for v in md.modelVariables if v.causality == "output" and v.type != "String"]
    r = simulate_fmu(path, output=outs)
    table = np.array([r[o] for o in outs], dtype=float)
    assert np.all(np.isfinite(table))
    # something happens: an output other than 0, or one that changes
    assert np.any(table != 0.0) or np.any(table != table[:, :1]), f"{name}: every output stays 0"


def test_bad_resource_location_is_refused():
    """'%4' at the end of the location once decoded past the end of the buffer"""
    from ctypes import byref
    from artibus.fmu.fmi2 import _callbacks
    f = Fmu(fmu_file("RoadFollowDriver"))
    try:
        log = []
        cb = _callbacks(log)
        c = f.slave.fmi2Instantiate(b"x", 1, f.md.guid.encode(), b"file:///x/a%4", byref(cb), 0, 0)
        assert not c
        assert any("fmuResourceLocation" in m and "malformed" in m for m in log), log
    finally:
        f.close()


def test_huge_look_ahead_is_refused():
    f = Fmu(fmu_file("RoadFollowDriver"))
    try:
        f.slave.setupExperiment(startTime=0.0)
        f.slave.enterInitializationMode()
        with pytest.raises(Exception):
            f.set_values({"lookFar0": 3e8})
        assert any("lookFar0" in m for m in f.log), f.log
    finally:
        f.close()


def test_csv_road_point_far_away_is_refused(tmp_path):
    csv = tmp_path / "far.csv"
    csv.write_text("x,y\n0,0\n1e9,0\n")
    f = Fmu(fmu_file("RoadFollowDriver"))
    try:
        f.slave.setupExperiment(startTime=0.0)
        f.slave.enterInitializationMode()
        f.set_values({"road": 0, "roadFile": str(csv)})
        with pytest.raises(FMICallException):
            f.slave.exitInitializationMode()
        assert any("points" in m for m in f.log), f.log
    finally:
        f.close()


def test_non_finite_output_is_an_error():
    """m[1] = 1e308 once gave fmi2OK with Fz = inf/NaN"""
    f = Fmu(fmu_file("BusDynamics"))
    try:
        f.slave.setupExperiment(startTime=0.0)
        f.slave.enterInitializationMode()
        f.set_values({"m[1]": 1e308})
        with pytest.raises(FMICallException):
            f.slave.exitInitializationMode()
            for k in range(10):
                f.slave.doStep(0.01 * k, 0.01)
        assert any("not finite" in m or "m[1]" in m for m in f.log), f.log
    finally:
        f.close()


def test_fmus_allocate_through_a_preloaded_sanitizer():
    """FMPy's default calloc is libc's own (looked up in libc.so.6), which a
    preloaded ASan never sees; artibus's callbacks use the process's calloc.
    Meaningful in the sanitizer pass (LD_PRELOAD=libasan.so); elsewhere both
    must at least be libc's."""
    import ctypes
    import os
    import fmpy
    from artibus.fmu import memory
    addr = lambda f: ctypes.cast(f, ctypes.c_void_p).value   # noqa: E731
    preload = [p for p in os.environ.get("LD_PRELOAD", "").split() if "libasan" in p]
    if preload:
        assert addr(memory.calloc) == addr(ctypes.CDLL(preload[0]).calloc)
        assert addr(memory.calloc) != addr(fmpy.calloc)      # the blind spot this closes
    else:
        assert addr(memory.calloc) == addr(fmpy.calloc)


def test_non_finite_output_in_a_step_is_an_error_naming_it():
    """The shared layer's check after fmi2DoStep (REAL_OUTPUTS): TypesTest's
    real_out = factor real_in; a finite input 1e308 times factor 10 overflows
    to inf in the step, which must be fmi2Error naming real_out, not fmi2OK."""
    f = Fmu(fmu_file("TypesTest"))
    try:
        f.slave.setupExperiment(startTime=0.0)
        f.slave.enterInitializationMode()
        f.set_values({"factor": 10.0})
        f.slave.exitInitializationMode()
        f.slave.doStep(0.0, 0.01)                     # finite: fine
        f.set_values({"real_in": 1e308})
        with pytest.raises(FMICallException):
            f.slave.doStep(0.01, 0.01)
        assert any("real_out" in m and "inf" in m for m in f.log), f.log
    finally:
        f.close()
