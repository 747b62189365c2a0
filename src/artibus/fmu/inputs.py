"""An input file for one FMU (``read_input_file``): FMPy's and the FMI cross-check's CSV, a
``time`` column first, then one column per input by name (quoted headers allowed; an array
input as its elements ``u[1]``, ``u[2]``, ... in row-major order, FMI 3.0 2.4.7.6), turned into
the input functions of time ``artibus.fmu.simulate`` sets at each communication point.

The values at a time t, as FMPy's ``simulate_fmu`` applies an input table in Co-Simulation
(fmpy.simulation.Input, ``apply(time)`` before each step):
- a continuous input (a Real, Float64 or Float32 of variability continuous) interpolated
  linearly between the rows around t; at a time written twice (an event in the table) the
  second of the two rows (the value after the jump); before the first row and after the
  last, held;
- any other input (discrete: an Integer, a Boolean, an Enumeration, a discrete Real) the
  value of the last row at or before t (within 1e-9 relative), held.
The communication steps are cut at the events (``InputTable.events``: a time written twice,
a discrete input's change), where the FMU can take such a step, as FMPy cuts them.

Every error names the file, the line and the column: a column that is no input of the FMU,
a cell that is no number, time that goes backwards. An input no column gives is named in
``missing`` (the command line warns)."""
import csv
import math
import re

import numpy as np

from artibus.base import ArtibusError


class InputTable:
    """The rows of an input file: ``time`` (n), ``columns`` {Variable: (n, size) values: floats
    for a continuous input, else the cells' own numbers, an integer exact (an Int64 or UInt64
    beyond 2**53 is no float)}."""

    def __init__(self, time, columns, missing):
        self.time, self.columns, self.missing = time, columns, missing

    def events(self):
        """The times the inputs jump: a time written twice, a discrete input's change (its new
        value's row), as FMPy's Input.findEvents finds them"""
        out = set(self.time[1:][np.diff(self.time) == 0])
        for v, table in self.columns.items():
            if not _continuous(v):
                out.update(self.time[k] for k in range(1, len(table)) if list(table[k]) != list(table[k - 1]))
        return sorted(float(t) for t in out)

    def functions(self):
        """{name: f(t)} of each input (an array's f gives its list of values)"""
        return {v.name: _function(self.time, table, _continuous(v), bool(v.shape))
                for v, table in self.columns.items()}


def _continuous(v):
    return v.kind == "Real" and v.variability not in ("discrete", "tunable", "fixed", "constant")


def _function(time, table, continuous, array):
    def f(t):
        if continuous:
            row = [float(x) for x in _continuous_at(time, table, t)]
        else:
            row = list(_discrete_at(time, table, t))
        return row if array else row[0]
    return f


def _continuous_at(time, table, t):
    n = len(time)
    if n == 1:
        return table[0]
    i = int(np.searchsorted(time, t))             # the first row at or after t
    if i == 0:
        return table[0]
    if i == n:
        return table[-1]
    if math.isclose(t, time[i]):
        while i + 1 < n and math.isclose(time[i], time[i + 1]):
            i += 1                                # (of two rows at t: the one after the jump)
        return table[i]
    w = (time[i] - t) / (time[i] - time[i - 1])
    return w * table[i - 1] + (1.0 - w) * table[i]


def _discrete_at(time, table, t):
    n = len(time)
    if n == 1:
        return table[0]
    i = int(np.searchsorted(time, t))
    if i == 0:
        return table[0]
    if i == n:
        return table[-1]
    j = i - 1                                     # the last row at (within 1e-9) or before t
    while j + 1 < n and (time[j + 1] < t or math.isclose(t, time[j + 1])):
        j += 1
    return table[j]


_ELEMENT = re.compile(r"(.+)\[(\d+(?:,\d+)*)\]")


def read_input_file(path, model):
    """The InputTable of the CSV file ``path`` for the FMU ``model`` (artibus.fmu.model)."""
    return read_inputs(path, [v for v in model.modelVariables if v.causality == "input"], model.modelName)


class Named:
    """A Variable under the name a bench gives it ("COMPONENT.VARIABLE"): two components of
    one FMU share its Variables, a bench's input file tells them apart by this name."""

    def __init__(self, name, variable):
        self.name, self.variable = name, variable

    def __getattr__(self, attribute):      # kind, type, shape, size, variability, ...
        if attribute == "variable":
            raise AttributeError(attribute)
        return getattr(self.variable, attribute)


def read_inputs(path, inputs, owner):
    """The InputTable of the CSV file ``path`` for the input Variables ``inputs`` (each by its
    ``name``: a bench's as Named) of ``owner`` (the FMU's or the bench's name, for the errors)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = [(k + 1, r) for k, r in enumerate(csv.reader(f)) if r and any(c.strip() for c in r)]
    except OSError as e:
        raise ArtibusError(f"--input-file {path}: cannot be read ({e.strerror or e})") from None
    except (UnicodeDecodeError, csv.Error) as e:
        raise ArtibusError(f"--input-file {path}: not a CSV text file ({e})") from None
    if not rows:
        raise ArtibusError(f"--input-file {path}: empty (expected a header: time, then one column per input)")
    (_, header), body = rows[0], rows[1:]
    header = [h.strip() for h in header]
    if header[0].lower() != "time":
        raise ArtibusError(f"{path}:1: the first column is {header[0]!r}, expected 'time'")
    places = _columns(path, header, {v.name: v for v in inputs}, owner)
    values = _numbers(path, header, body)
    time = np.array([float(r[0]) for r in values])
    back = np.flatnonzero(np.diff(time) < 0)
    if back.size:
        k = int(back[0]) + 1
        raise ArtibusError(f"{path}:{body[k][0]}: time {time[k]:g} s goes back from {time[k - 1]:g} s "
                           "(the rows must be in time order)")
    columns = {}
    for v, idx in places.items():
        if any(i is None for i in idx):
            absent = [f"{v.name}[{k + 1}]" for k, i in enumerate(idx) if i is None]
            raise ArtibusError(f"{path}:1: the array input {v.name} has {v.size} elements; no column for "
                               f"{', '.join(absent)}")
        rows = [[r[i] for i in idx] for r in values]
        columns[v] = np.array(rows, dtype=float) if _continuous(v) else rows
    missing = [v.name for v in inputs if v not in columns]
    return InputTable(time, columns, missing)


def _columns(path, header, inputs, owner):
    """{Variable: [column index per element]} of the header's input columns (``inputs``: {name:
    Variable})"""
    places = {}
    for j, name in enumerate(header[1:], start=1):
        v, k = inputs.get(name), 0
        m = _ELEMENT.fullmatch(name)
        if v is None and m and m.group(1) in inputs and inputs[m.group(1)].shape:
            v = inputs[m.group(1)]
            k = _flat_index(path, name, [int(x) for x in m.group(2).split(",")], v.shape)
        if v is None:
            known = ", ".join(inputs) or "none"
            raise ArtibusError(f"{path}:1: column {j + 1} {name!r} is no input of {owner} "
                               f"(its inputs: {known})")
        if v.kind in ("String", "Binary", "Clock"):
            raise ArtibusError(f"{path}:1: column {name!r}: {v.name} is a {v.type}; an input file gives numbers")
        idx = places.setdefault(v, [None] * v.size)
        if idx[k] is not None:
            raise ArtibusError(f"{path}:1: column {name!r} is given twice")
        idx[k] = j
    return places


def _flat_index(path, name, index, shape):
    if len(index) != len(shape) or any(not 1 <= i <= n for i, n in zip(index, shape)):
        raise ArtibusError(f"{path}:1: column {name!r}: no such element of an array of shape "
                           f"{'x'.join(map(str, shape))} (FMI 3.0 indices start at 1)")
    k = 0
    for i, n in zip(index, shape):               # row-major, as FMI 3.0 orders an array
        k = k * n + (i - 1)
    return k


def _numbers(path, header, body):
    """The rows' cells as numbers: an integer as an int (exact), else a float; true/false as 1/0"""
    if not body:
        raise ArtibusError(f"{path}: a header and no rows")
    out = []
    for line, row in body:
        if len(row) != len(header):
            raise ArtibusError(f"{path}:{line}: {len(row)} cells, the header has {len(header)} columns")
        out.append([_number(path, line, header[j], cell) for j, cell in enumerate(row)])
    return out


def _number(path, line, column, cell):
    text = cell.strip()
    if text.lower() in ("true", "false"):
        return int(text.lower() == "true")
    try:
        return int(text)
    except ValueError:
        pass
    try:
        x = float(text)
    except ValueError:
        raise ArtibusError(f"{path}:{line}: column {column!r}: {cell!r} is not a number") from None
    if not math.isfinite(x):
        raise ArtibusError(f"{path}:{line}: column {column!r}: {cell!r} is not a finite number")
    return x
