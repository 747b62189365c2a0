"""SwayBaseline (an ACS5-like condition-based damping modelled from seed 001's
description, 1.4.1, 5.2.5, 6.1.4): the ground level against the thesis's
13.5 % at 100 km/h and the line through it, the sway control's switching and
hold time counted here, the end-protection ramp, the cap, bad input."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import init

TS = 0.01
KMH = 1 / 3.6
OUTS = ["pct", "pctGround", "sscActive", "epActive", "tSinceSSC"]


def run(fmu, n, t0=0.0, **signals):
    rows = []
    for i in range(n):
        t = t0 + i * TS
        fmu.set_values({k: f(t) for k, f in signals.items()})
        fmu.slave.doStep(t, TS)
        rows.append(fmu.get(*OUTS))
    return {k: np.array(c) for k, c in zip(OUTS, zip(*rows))}


@pytest.mark.parametrize("kmh", [0, 30, 50, 80, 100, 120, 130, 150])
def test_ground_level_rises_with_speed(open_fmu, kmh):
    """13.5 % at 100 km/h (seed 001, 5.2.2, the ACS5's ground level there),
    3.5 % standing (the floor, 5.1.1), linear in between and on to 130 km/h,
    held beyond."""
    fmu = open_fmu("SwayBaseline")
    init(fmu, v=kmh * KMH)
    out = run(fmu, 3, v=lambda t: kmh * KMH)
    expect = 3.5 + 10.0 * min(kmh, 130) / 100
    assert out["pctGround"][-1] == pytest.approx(expect, rel=1e-12)
    assert out["pct"][-1] == pytest.approx(expect, rel=1e-12)
    assert out["sscActive"][-1] == 0


def test_sway_control_switching_and_hold(open_fmu):
    """At 100 km/h |LambdaDot| crosses 0.37 rad/s between t = 1.00 s and
    1.50 s (an oscillation): SSC on at the first sample above it, 34 %, and
    off tHold = 1.5 s after the last sample above it; below 60 km/h never."""
    rate = lambda t: 0.5 * math.sin(2 * math.pi * 4 * t) if 1.0 - 1e-9 <= t < 1.5 - 1e-9 else 0.01
    fmu = open_fmu("SwayBaseline")
    init(fmu, v=100 * KMH)
    out = run(fmu, 400, v=lambda t: 100 * KMH, LambdaDot=rate)
    t = np.arange(400) * TS
    above = np.array([abs(rate(x)) >= 0.37 for x in t])
    first, last = t[above][0], t[above][-1]
    on = out["sscActive"] == 1
    assert t[on][0] == pytest.approx(first)
    assert t[on][-1] == pytest.approx(last + 1.5 - TS)           # on for [last, last + tHold)
    assert np.all(on[(t >= first - 1e-9) & (t < last + 1.5 - 1e-9)])
    assert np.all(out["pct"][on] == 34.0)
    assert np.all(out["pct"][~on] == pytest.approx(13.5))
    assert out["tSinceSSC"][-1] == pytest.approx(t[-1] - last)
    fmu.slave.reset()
    init(fmu, v=59 * KMH)
    out = run(fmu, 200, v=lambda t: 59 * KMH, LambdaDot=lambda t: 1.0)
    assert np.all(out["sscActive"] == 0)


def test_end_protection_ramp_and_cap(open_fmu):
    """0 at 44 deg, linear to 34 % at 50 deg, whichever side; pct the largest
    request, at most pctMax."""
    fmu = open_fmu("SwayBaseline")
    init(fmu)
    cases = [(40, 3.5), (44, 3.5), (46, 34 / 3), (47, 17.0), (-48.5, 34 * 0.75), (50, 34.0), (53, 34.0)]
    out = run(fmu, len(cases), Lambda=lambda t: math.radians(cases[int(round(t / TS))][0]))
    for (deg, expect), pct, ep in zip(cases, out["pct"], out["epActive"]):
        assert pct == pytest.approx(max(expect, 3.5), rel=1e-9), deg
        assert ep == (1.0 if abs(deg) > 44 else 0.0), deg
    fmu.slave.reset()
    init(fmu, pctMax=20.0)
    out = run(fmu, 2, Lambda=lambda t: math.radians(52), v=lambda t: 100 * KMH, LambdaDot=lambda t: 1.0)
    assert np.all(out["pct"] == 20.0) and np.all(out["sscActive"] == 1)


def test_outputs_change_only_at_sample_instants(open_fmu):
    fmu = open_fmu("SwayBaseline")
    init(fmu, Ts=0.02)
    vals = []
    for i in range(10):
        fmu.set_values({"v": i * 3.0})
        fmu.slave.doStep(i * TS, TS)
        vals.append(fmu.get("pctGround")[0])
    assert list(np.diff([3.5] + vals) != 0) == [False, False] + [True, False] * 4   # samples at 0, 20, 40 ms ...


def test_reversing_warns_once_and_stays_finite(open_fmu):
    fmu = open_fmu("SwayBaseline")
    init(fmu)
    out = run(fmu, 20, v=lambda t: -5.0, LambdaDot=lambda t: 1.0)
    assert np.all(out["pct"] == 3.5) and np.all(out["sscActive"] == 0)
    assert len([m for m in fmu.log if "[Warning]" in m and "v = -5" in m]) == 1


@pytest.mark.parametrize("values,word", [({"LambdaEP1": 0.7}, "LambdaEP1"),
                                         ({"nGround": 2, "groundSpeed[2]": 0.0}, "groundSpeed")])
def test_bad_parameters_are_refused(open_fmu, values, word):
    fmu = open_fmu("SwayBaseline")
    with pytest.raises(FMICallException):
        init(fmu, **values)
    assert any(word in m for m in fmu.log)


@pytest.mark.parametrize("name,value", [("pctMax", 51.0), ("pctSSC", -1.0), ("groundPct[2]", 60.0)])
def test_percentages_out_of_range_are_refused(open_fmu, name, value):
    fmu = open_fmu("SwayBaseline")
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        fmu.set_values({name: value})
    assert any(name in m for m in fmu.log)
