"""The driver's test roads in Python, from the same C code as the FMU.

``src/models/RoadFollowDriver/roads.c`` is the one implementation of the
built-in roads, the CSV reader and the resampling by arc length. The build
also compiles it into ``build/lib/libartibus_roads.so`` (or
``$ARTIBUS_ROADS_LIB``), which this module calls with ctypes, so a plot draws
exactly the road the FMU follows::

    from artibus import roads
    x, y = roads.generate(roads.CIRCLE, R=17.5)           # the polyline
    r = roads.resample(x, y, ds=0.1)                        # r.s, r.x, r.y, r.psi
    roads.write_csv("circle.csv", x, y)                     # roadFile for road = 0

Parameters and defaults are those of RoadFollowDriver (modelDescription/
RoadFollowDriver.xml): before/after = roadBefore/roadAfter, step = roadStep.
"""
import ctypes
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from artibus.base import ROOT, ArtibusError

CSV, LANE_CHANGE, CIRCLE, ISO3888 = 0, 1, 2, 3
SOURCE = ROOT / "src" / "models" / "RoadFollowDriver" / "roads.c"
MAX_POINTS = 20000          # ROAD_MAX_POINTS in roads.h
RAW_MAX = 200000            # ROAD_RAW_MAX in roads.h
ERRLEN = 512
LINE_MAX = 4096             # ROAD_LINE_MAX in roads.h: a longer CSV line is refused

DEFAULTS = dict(before=25.0, after=50.0, laneLength=25.0, laneOffset=3.25, R=17.5,
                isoWidth=2.55, step=0.02)


class _Params(ctypes.Structure):
    _fields_ = [(n, ctypes.c_double) for n in
                ("before", "after", "laneLength", "laneOffset", "R", "isoWidth", "step")]


class _Road(ctypes.Structure):
    _fields_ = [("n", ctypes.c_int), ("ds", ctypes.c_double), ("length", ctypes.c_double)] + \
               [(n, ctypes.c_double * MAX_POINTS) for n in ("s", "x", "y", "psi")]


@dataclass
class Road:
    """A road resampled by arc length: ``s``, ``x``, ``y``, ``psi`` (tangent, rad)."""
    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    length: float
    ds: float


_lib = None


def _library():
    global _lib
    if _lib is not None:
        return _lib
    path = Path(os.environ.get("ARTIBUS_ROADS_LIB", ROOT / "build" / "lib" / "libartibus_roads.so"))
    if not path.is_file():
        raise ArtibusError(f"{path}: the road library is not built (run the set-up command of the README)")
    lib = ctypes.CDLL(str(path))
    dp = ctypes.POINTER(ctypes.c_double)
    lib.road_generate.argtypes = [ctypes.c_int, ctypes.POINTER(_Params), dp, dp, ctypes.c_int,
                                  ctypes.c_char_p, ctypes.c_size_t]
    lib.road_read_csv.argtypes = [ctypes.c_char_p, dp, dp, ctypes.c_int, ctypes.c_char_p, ctypes.c_size_t]
    lib.road_resample.argtypes = [dp, dp, ctypes.c_int, ctypes.c_double, ctypes.POINTER(_Road),
                                  ctypes.c_char_p, ctypes.c_size_t]
    for f in (lib.road_generate, lib.road_read_csv, lib.road_resample):
        f.restype = ctypes.c_int
    _lib = lib
    return lib


def _ptr(a):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def generate(kind, **params):
    """The polyline (x, y) of a built-in road, as roads.c builds it for the FMU."""
    unknown = set(params) - set(DEFAULTS)
    if unknown:
        raise ArtibusError(f"unknown road parameter(s) {sorted(unknown)}; known: {sorted(DEFAULTS)}")
    p = _Params(**{**DEFAULTS, **params})
    x, y = np.zeros(RAW_MAX), np.zeros(RAW_MAX)
    err = ctypes.create_string_buffer(ERRLEN)
    n = _library().road_generate(int(kind), ctypes.byref(p), _ptr(x), _ptr(y), RAW_MAX, err, ERRLEN)
    if n < 0:
        raise ArtibusError(err.value.decode(errors="replace"))
    return x[:n].copy(), y[:n].copy()


def read_csv(path):
    """A CSV road read by the FMU's reader: (x, y), or ArtibusError with file, line and value
    (a line longer than LINE_MAX characters is refused, never split)."""
    x, y = np.zeros(RAW_MAX), np.zeros(RAW_MAX)
    err = ctypes.create_string_buffer(ERRLEN)
    n = _library().road_read_csv(os.fsencode(path), _ptr(x), _ptr(y), RAW_MAX, err, ERRLEN)
    if n < 0:
        raise ArtibusError(err.value.decode(errors="replace"))
    return x[:n].copy(), y[:n].copy()


def resample(x, y, ds=0.1):
    """The table the FMU follows: the polyline resampled by arc length at ds."""
    x = np.ascontiguousarray(x, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    r = _Road()
    err = ctypes.create_string_buffer(ERRLEN)
    if _library().road_resample(_ptr(x), _ptr(y), len(x), float(ds), ctypes.byref(r), err, ERRLEN):
        raise ArtibusError(err.value.decode(errors="replace"))
    n = r.n
    return Road(*(np.array(getattr(r, k)[:n]) for k in ("s", "x", "y", "psi")), r.length, r.ds)


def write_csv(path, x, y):
    """Write a road as the FMU reads it (``x,y`` per line, exact doubles)."""
    with open(path, "w") as f:
        f.write("x,y\n")
        for a, b in zip(x, y):
            f.write(f"{float(a)!r},{float(b)!r}\n")
