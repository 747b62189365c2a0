"""Recorded trajectories (``Result``), the error that carries the results
up to a failure (``SimulationError``), and an FMU's own end of a run
(``Termination``, ``terminated``)."""
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from artibus.base import ArtibusError


class SimulationError(ArtibusError):
    """The FMU returned an error; ``result`` holds what was computed before."""

    def __init__(self, message, result, log):
        super().__init__(message)
        self.result = result
        self.log = log


@dataclass(frozen=True)
class Termination:
    """An FMU ended the run, as FMI 2.0 lets it (fmi2DoStep returned fmi2Discard
    and fmi2GetBooleanStatus(fmi2Terminated) says true, FMI 2.0.4 section 4.2.3)
    or FMI 3.0 (fmi3DoStep's terminateSimulation): a normal end at ``time`` (its
    fmi2LastSuccessfulTime, FMI 3.0's lastSuccessfulTime), not a failure."""
    component: str      # the component (a bench) or the model (an FMU alone) that ended it
    time: float         # s
    how: str = "fmi2Terminated"   # FMI 3.0: fmi3DoStep's "terminateSimulation" (FMI 3.0 4.2.1)

    def __str__(self):
        return f"{self.component} ended the simulation at t = {self.time:g} s ({self.how})"


#: FMI 2.0's fmi2Discard and the status kinds asked after it (fmi2Functions.h)
FMI2_DISCARD, FMI2_LAST_SUCCESSFUL_TIME, FMI2_TERMINATED = 2, 2, 3


def terminated(slave, status):
    """After fmi2DoStep returned ``status``: the FMU's fmi2LastSuccessfulTime if it
    ended the simulation (fmi2Discard with fmi2Terminated true), else None (then a
    failure). An FMU that cannot say (its status functions fail) has not ended it.
    NaN where it ended it but gives no fmi2LastSuccessfulTime (the caller takes
    the end of the step then)."""
    if status != FMI2_DISCARD:
        return None
    try:
        if not slave.getBooleanStatus(FMI2_TERMINATED):
            return None
    except Exception:
        return None
    try:
        return float(slave.getRealStatus(FMI2_LAST_SUCCESSFUL_TIME))
    except Exception:
        return float("nan")


@dataclass
class Result:
    """Recorded trajectories: ``result['x[1]']`` is an array over ``result.time``."""
    names: list
    rows: list = field(default_factory=list)

    @classmethod
    def from_array(cls, names, table):
        """A result from a filled table (a row per time), kept as its array;
        its rows a view of the table's (no list of a row object per time)."""
        result = cls.__new__(cls)           # (the fields' defaults without __init__'s calls)
        result.__dict__.update(names=list(names), rows=_ArrayRows(table), strings={}, integers={}, units={},
                               descriptions={}, terminated=None, _array=table)
        return result

    #: String columns: {name: [text per row]} (their column in the array is NaN)
    strings: dict = field(default_factory=dict)
    #: 64-bit integer columns (FMI 3.0 Int64, UInt64): {name: [int per row, None where not
    #: read]}, exact; their column in the array holds the nearest float64 (exact up to 2**53)
    integers: dict = field(default_factory=dict)
    #: {name: unit} of the columns, from the FMUs' model descriptions (the variable's
    #: unit, else its declaredType's; "" for none; "s" for time)
    units: dict = field(default_factory=dict)
    #: {name: description} of the columns, from the model descriptions ("" for none),
    #: for the writers that keep one per channel (an MDF 4 file: artibus.runner.formats)
    descriptions: dict = field(default_factory=dict)
    #: a Termination where an FMU ended the run before the stop time, else None
    terminated: Termination | None = None

    def __getitem__(self, name):
        if name in self.strings:
            return np.array(self.strings[name], dtype=object)
        exact = self.exact_integers(name)
        if exact is not None:
            return exact
        return self.array()[:, self.names.index(name)]

    def exact_integers(self, name):
        """A 64-bit integer column as exact integers (numpy int64, or uint64 where a value is
        above 2**63 - 1), or None: not such a column, or a row without its value (then the
        float column, NaN there)."""
        values = self.integers.get(name)
        if values is None or any(x is None for x in values):
            return None
        return np.array(values, dtype=integer_type(values))

    @property
    def time(self):
        return self["time"]

    def array(self):
        cached = getattr(self, "_array", None)
        if cached is None or len(cached) != len(self.rows):
            cached = self._array = np.array(self.rows, dtype=float).reshape(-1, len(self.names))
        return cached

    def to_csv(self, path):
        header = ",".join(f'"{n}"' for n in self.names)
        if not self.strings and not self.integers:
            np.savetxt(path, self.array(), delimiter=",", header=header, comments="", fmt="%.12g")
            return
        # a String column as quoted text (CSV's quoting: "" for a quote), a 64-bit integer
        # column's cells with all their digits
        cells = [_quoted if n in self.strings else _integer if n in self.integers else _number
                 for n in self.names]
        cols = [self.strings.get(n, self.integers.get(n)) for n in self.names]
        with open(path, "w") as f:
            f.write(header + "\n")
            for i, row in enumerate(self.array()):
                f.write(",".join(cell(x, c[i] if c is not None else None)
                                 for x, c, cell in zip(row, cols, cells)) + "\n")


#: the largest FMI 3.0 Int64 (a larger integer column is a UInt64's)
INT64_MAX = 2**63 - 1


def integer_type(values):
    """numpy's type of a 64-bit integer column (ints, None where not read): uint64 where a
    value is above 2**63 - 1 (only a UInt64 has one), else int64."""
    return np.uint64 if any(x is not None and x > INT64_MAX for x in values) else np.int64


def _number(x, _):
    return f"{x:.12g}"


def _quoted(_, text):
    return '"' + text.replace('"', '""') + '"'


def _integer(x, exact):
    return f"{x:.12g}" if exact is None else str(exact)


class _ArrayRows(Sequence):
    """Result.rows of a result made from a table: its rows without copying them."""

    def __init__(self, table):
        self._table = table

    def __len__(self):
        return len(self._table)

    def __getitem__(self, i):
        return self._table[i]
