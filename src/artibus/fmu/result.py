"""Recorded trajectories (``Result``) and the error that carries the results
up to a failure (``SimulationError``)."""
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
        result.__dict__.update(names=list(names), rows=_ArrayRows(table), strings={}, units={}, _array=table)
        return result

    #: String columns: {name: [text per row]} (their column in the array is NaN)
    strings: dict = field(default_factory=dict)
    #: {name: unit} of the columns, from the FMUs' model descriptions (the variable's
    #: unit, else its declaredType's; "" for none; "s" for time)
    units: dict = field(default_factory=dict)

    def __getitem__(self, name):
        if name in self.strings:
            return np.array(self.strings[name], dtype=object)
        return self.array()[:, self.names.index(name)]

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
        if not self.strings:
            np.savetxt(path, self.array(), delimiter=",", header=header, comments="", fmt="%.12g")
            return
        # a String column as quoted text (CSV's quoting: "" for a quote)
        cols = [self.strings.get(n) for n in self.names]
        with open(path, "w") as f:
            f.write(header + "\n")
            for i, row in enumerate(self.array()):
                f.write(",".join('"' + c[i].replace('"', '""') + '"' if c is not None else f"{x:.12g}"
                                 for x, c in zip(row, cols)) + "\n")


class _ArrayRows(Sequence):
    """Result.rows of a result made from a table: its rows without copying them."""

    def __init__(self, table):
        self._table = table

    def __len__(self):
        return len(self._table)

    def __getitem__(self, i):
        return self._table[i]
