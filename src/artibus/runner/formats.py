"""A run's results as the file's extension says (``-o``): CSV, Parquet, ASAM MDF 4
or MATLAB, each holding the columns' units (a CSV in its sidecar, see
artibus.runner.results.save) and, where the format has a place for them, the
variables' descriptions. ``check_format`` refuses any other extension before a
run starts; ``write`` writes one (to the temporary path results.save renames)."""
import re
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError
from artibus.fmu.result import integer_type

#: the extensions -o accepts, what each is (for the messages and the help)
FORMATS = {
    ".csv": "CSV (units in OUT.units.csv)",
    ".parquet": "Parquet (pandas, Arrow)",
    ".mf4": "ASAM MDF 4 (asammdf, CANape, INCA)",
    ".mat": "MATLAB (scipy.io.loadmat, MATLAB's load)",
}

#: MATLAB's longest variable name (namelengthmax) and the variables a .mat holds beside the signals
_MATLAB_MAX = 63
_MATLAB_RESERVED = ("units", "names", "descriptions")


def check_format(path, what="-o"):
    """``path``'s extension one of FORMATS, else an error naming the file and listing
    them (before the run: a results file is never written in a format not asked for)."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        given = f"'{suffix}'" if suffix else "no extension"
        raise ArtibusError(f"{what} {path}: results are written by the file's extension, and {given} is none "
                           f"of them: {', '.join(f'{k} {v}' for k, v in FORMATS.items())}")
    return path


def write(result, path, tmp):
    """The results into ``tmp`` in the format of ``path``'s extension (checked: check_format)."""
    suffix = Path(check_format(path)).suffix.lower()
    {".csv": _csv, ".parquet": _parquet, ".mf4": _mf4, ".mat": _mat}[suffix](result, tmp)


def _meta(result):
    return getattr(result, "units", None) or {}, getattr(result, "descriptions", None) or {}


def _csv(result, tmp):
    result.to_csv(tmp)


def _parquet(result, tmp):
    """One column per signal (a String signal as text, a 64-bit integer one as int64 or
    uint64, null where not read); each field's metadata holds its ``unit`` and
    ``description`` (Arrow's field metadata, which pyarrow.parquet.read_schema gives
    back; pandas.read_parquet reads the table)."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    units, descriptions = _meta(result)
    columns, fields = [], []
    for n in result.names:
        if n in result.strings:
            col = pa.array(result.strings[n], pa.string())
        elif n in result.integers:
            col = pa.array(result.integers[n], pa.from_numpy_dtype(integer_type(result.integers[n])))
        else:
            col = pa.array(result[n], pa.float64())
        columns.append(col)
        fields.append(pa.field(n, col.type, metadata={"unit": units.get(n, ""),
                                                      "description": descriptions.get(n, "")}))
    pq.write_table(pa.Table.from_arrays(columns, schema=pa.schema(fields)), str(tmp))


def _mf4(result, tmp):
    """ASAM MDF 4.10 through asammdf: one channel group whose master is the
    run's time (MDF 4 5.10: the time master channel, in s), a channel per
    signal with its name, unit and description (the channel's comment); a
    String signal as bytes (UTF-8), a 64-bit integer one as int64 or uint64 where
    every row has its value (else as float64, NaN where not read)."""
    from asammdf import MDF, Signal
    units, descriptions = _meta(result)
    t = np.asarray(result.time, dtype=float)
    signals = []
    for n in result.names[1:]:
        samples = (np.array([s.encode("utf-8") for s in result.strings[n]]) if n in result.strings
                   else result[n])
        signals.append(Signal(samples=samples, timestamps=t, name=n, unit=units.get(n, ""),
                              comment=descriptions.get(n, "")))
    mdf = MDF(version="4.10")
    try:
        mdf.append(signals, comment="artibus results", common_timebase=True)
        mdf.save(str(tmp), overwrite=True)
    finally:
        mdf.close()


def matlab_names(names):
    """A MATLAB variable name for each signal name, all different: ASCII letters,
    digits and "_", a letter first, at most 63 characters (MATLAB's
    namelengthmax); none of the .mat's own variables (_MATLAB_RESERVED).
    "Bus.x[1]" -> "Bus_x_1"; a name taken already gets "_2", "_3", ..."""
    used, out = set(_MATLAB_RESERVED), []
    for n in names:
        key = re.sub(r"[^A-Za-z0-9]", "_", n).strip("_")
        if not key[:1].isalpha():
            key = "x_" + key if key else "x"
        key = key[:_MATLAB_MAX].rstrip("_")
        unique, i = key, 1
        while unique in used:
            i += 1
            unique = f"{key[:_MATLAB_MAX - len(str(i)) - 1]}_{i}"
        used.add(unique)
        out.append(unique)
    return out


def _mat(result, tmp):
    """MATLAB 5 .mat: a variable per signal (matlab_names; a String signal a
    cell array of its texts) and three structs with a field per variable: the
    signal's ``names`` (as in the CSV), ``units`` and ``descriptions``. Struct
    fields up to 63 characters (scipy's long_field_names, MATLAB 7.6 on). A 64-bit
    integer signal as int64 or uint64 where every row has its value."""
    from scipy.io import savemat
    units, descriptions = _meta(result)
    keys = matlab_names(result.names)
    out = {}
    for k, n in zip(keys, result.names):
        out[k] = np.array(result.strings[n], dtype=object) if n in result.strings else result[n]
    out["names"] = dict(zip(keys, result.names))
    out["units"] = {k: units.get(n, "") for k, n in zip(keys, result.names)}
    out["descriptions"] = {k: descriptions.get(n, "") for k, n in zip(keys, result.names)}
    savemat(str(tmp), out, long_field_names=True)
