"""RoadFollowDriver's roads: CSV against built-in, bad road files and
parameters (fmi2Error naming file, line and value), the mirror property, and
the Python side of the road generator (artibus.roads)."""
import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from artibus import ArtibusError, fmu_path
from artibus.bench import roads
from artibus.fmu import Fmu
from test_driver import CAR, drive_car

BEFORE, AFTER = 25.0, 50.0


def run_alone(values, stop=6.0, h=0.02):
    """the driver with its built-in test vehicle: delta over time"""
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values({"testVehicle": True, **values})   # the stimulus is off by default
        d.slave.exitInitializationMode()
        out, t = [], 0.0
        while t < stop - 1e-9:
            d.slave.doStep(t, h)
            t += h
            out.append(d.get("delta", "eLat", "s"))
    return np.array(out)


@pytest.mark.parametrize("kind", [roads.LANE_CHANGE, roads.CIRCLE, roads.ISO3888])
def test_csv_road_steers_as_the_built_in_road(kind, tmp_path):
    x, y = roads.generate(kind)
    path = tmp_path / "road.csv"
    roads.write_csv(path, x, y)
    built_in = run_alone({"road": kind})
    from_csv = run_alone({"road": 0, "roadFile": str(path)})
    assert np.max(np.abs(built_in[:, 0])) > 0.01, "the road does not steer: the test cannot fail"
    assert np.max(np.abs(from_csv - built_in)) <= 1e-9


def expect_init_error(values, *words):
    with Fmu(fmu_path("RoadFollowDriver")) as d:
        d.slave.setupExperiment(startTime=0.0)
        d.slave.enterInitializationMode()
        d.set_values(values)
        with pytest.raises(FMICallException):
            d.slave.exitInitializationMode()
        text = " ".join(d.log)
    for w in words:
        assert w in text, f"{w!r} not in log: {text}"
    return text


def write(tmp_path, text, name="road.csv"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_missing_road_file(tmp_path):
    p = str(tmp_path / "nowhere.csv")
    expect_init_error({"road": 0, "roadFile": p}, p, "cannot open", "No such file")


def test_unreadable_road_file(tmp_path):
    """a directory opens but cannot be read"""
    expect_init_error({"road": 0, "roadFile": str(tmp_path)}, str(tmp_path), "read error")


def test_road_file_name_without_file():
    expect_init_error({"road": 0, "roadFile": ""}, "roadFile", "names no file")


def test_road_file_with_one_point(tmp_path):
    p = write(tmp_path, "x,y\n0,0\n")
    expect_init_error({"road": 0, "roadFile": p}, p, "1 point(s)", "at least 2")


def test_road_file_with_nan(tmp_path):
    p = write(tmp_path, "x,y\n0,0\n1,0\n2,nan\n3,0\n")
    expect_init_error({"road": 0, "roadFile": p}, p, "line 4", "y = nan")


def test_road_file_with_repeated_point(tmp_path):
    p = write(tmp_path, "x,y\n0,0\n1,0.5\n1,0.5\n3,0\n")
    expect_init_error({"road": 0, "roadFile": p}, p, "line 4", "(1, 0.5)", "line 3")


def test_road_file_with_text(tmp_path):
    p = write(tmp_path, "x,y\n0,0\n1,zero\n")
    expect_init_error({"road": 0, "roadFile": p}, p, "line 3", "1,zero")


@pytest.mark.parametrize("name,value", [("lookNear0", 0.0), ("lookNear0", -1.0)])
def test_non_positive_look_ahead(name, value):
    expect_init_error({name: value}, name, f"{value:g}", "> 0")


def test_far_look_ahead_before_the_near_one():
    expect_init_error({"lookNear0": 5.0, "lookFar0": 4.0}, "lookFar0 = 4", "lookNear0 = 5")


def test_road_file_in_resources_is_looked_up(tmp_path):
    """a bare file name is looked up in the FMU's resources/ (none shipped: the
    message shows where it looked)"""
    text = expect_init_error({"road": 0, "roadFile": "my_road.csv"}, "my_road.csv", "resources/my_road.csv")
    assert "cannot open" in text


# ---- mirror property ----------------------------------------------------------

@pytest.mark.parametrize("kind", [roads.LANE_CHANGE, roads.CIRCLE, roads.ISO3888])
def test_mirrored_road_mirrors_the_steering(kind, tmp_path):
    """y -> -y: the road, the car's pose and the steering angle change sign"""
    x, y = roads.generate(kind)
    roads.write_csv(tmp_path / "a.csv", x, y)
    roads.write_csv(tmp_path / "b.csv", x, -y)
    a = drive_car(0, {**CAR, "roadFile": str(tmp_path / "a.csv")}, stop=8.0)
    b = drive_car(0, {**CAR, "roadFile": str(tmp_path / "b.csv")}, stop=8.0)
    assert np.max(np.abs(a["delta"])) > 0.05
    assert np.max(np.abs(a["delta"] + b["delta"])) <= 1e-12
    assert np.max(np.abs(a["eLat"] + b["eLat"])) <= 1e-9
    assert np.max(np.abs(a["y"] + b["y"])) <= 1e-9


def test_circle_with_negative_radius_is_the_mirror_image():
    a = run_alone({"road": 2, "R": 17.5}, stop=8.0)
    b = run_alone({"road": 2, "R": -17.5}, stop=8.0)
    assert np.max(np.abs(a[:, 0])) > 0.1
    assert np.max(np.abs(a[:, 0] + b[:, 0])) <= 1e-12


# ---- the Python side ----------------------------------------------------------

def test_python_roads_circle_geometry():
    """resampled circle road: every point on the circle's arc at distance R from
    the centre (25, 17.5), length 25 + 2 pi 17.5 + 50, spacing 0.1 m"""
    x, y = roads.generate(roads.CIRCLE, R=17.5)
    r = roads.resample(x, y, ds=0.1)
    assert r.length == pytest.approx(BEFORE + 2 * math.pi * 17.5 + AFTER, rel=1e-6)
    arc = (r.s > BEFORE + 0.05) & (r.s < BEFORE + 2 * math.pi * 17.5 - 0.05)
    assert np.max(np.abs(np.hypot(r.x[arc] - BEFORE, r.y[arc] - 17.5) - 17.5)) < 1e-4
    assert np.allclose(np.hypot(np.diff(r.x), np.diff(r.y))[:-1], 0.1, rtol=1e-4)
    # the tangent turns by 2 pi along the road
    assert np.unwrap(r.psi)[-1] == pytest.approx(2 * math.pi, abs=1e-6)


def test_python_roads_lane_change_shape():
    x, y = roads.generate(roads.LANE_CHANGE, laneLength=60.0, laneOffset=3.25)
    xi = np.array([0.0, 25.0, 55.0, 85.0, 135.0])
    assert np.interp(xi, x, y) == pytest.approx([0, 0, 3.25 / 2, 3.25, 3.25], abs=1e-12)


def test_python_roads_read_csv_errors(tmp_path):
    p = write(tmp_path, "0,0\n1,inf\n")
    with pytest.raises(ArtibusError, match="line 2"):
        roads.read_csv(p)
    with pytest.raises(ArtibusError, match="radius"):
        roads.generate(roads.CIRCLE, R=0.5)


def test_road_built_again_when_its_parameters_change_in_initialisation(tmp_path):
    """The road is kept between reads in initialisation mode while what it is
    made from is unchanged, and built again when that changes: a driver whose
    outputs were read with a 60 m lane change, then set to 25 m, drives the
    25 m lane change exactly as one set to 25 m from the start; a CSV road is
    read again (its file may have changed)."""
    def drive(first, then, road_file=None):
        with Fmu(fmu_path("RoadFollowDriver")) as d:
            d.slave.setupExperiment(startTime=0.0)
            d.slave.enterInitializationMode()
            d.set_values({"testVehicle": True, **first})   # the stimulus is off by default
            d.get("delta")                          # the model is initialised with `first`
            if road_file is not None:
                roads.write_csv(road_file, *roads.generate(roads.LANE_CHANGE, laneLength=25.0))
            d.set_values(then)
            d.slave.exitInitializationMode()
            out, t = [], 0.0
            while t < 5.0 - 1e-9:
                d.slave.doStep(t, 0.02)
                t += 0.02
                out.append(d.get("delta", "eLat", "s"))
        return np.array(out)
    fresh = drive({"road": 1, "laneLength": 25.0}, {})
    changed = drive({"road": 1, "laneLength": 60.0}, {"laneLength": 25.0})
    other = drive({"road": 1, "laneLength": 60.0}, {})
    assert np.max(np.abs(fresh[:, 0] - other[:, 0])) > 0.01, "60 m and 25 m steer alike: the test cannot fail"
    assert np.array_equal(changed, fresh)
    path = tmp_path / "road.csv"
    roads.write_csv(path, *roads.generate(roads.LANE_CHANGE, laneLength=60.0))
    from_file = drive({"road": 0, "roadFile": str(path)}, {}, road_file=path)
    assert np.max(np.abs(from_file - fresh)) <= 1e-9
