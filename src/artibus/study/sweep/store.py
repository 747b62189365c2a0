"""A sweep's results in its output folder: one Parquet file a case
(``cases/<key>.parquet``, and its time series), written atomically as its task
comes back; the manifest; the table of every case of the sweep in case order,
assembled at the end and on resume (``assemble``)."""
import json
import os
from pathlib import Path

import numpy as np

CASES_DIR, SERIES_DIR = "cases", "series"
TABLE, MANIFEST, WORST, PLOT = "results.parquet", "sweep.json", "worst.txt", "study.png"
STATUS_OK, STATUS_FAILED = "ok", "failed"
#: a case an FMU ended before the stop time (fmi2Terminated): its KPIs over what ran, not a failure
STATUS_TERMINATED = "terminated"


def _write_parquet(table, path):
    import pyarrow.parquet as pq
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    pq.write_table(table, tmp)
    os.replace(tmp, path)


def _parquet_bytes(table):
    import pyarrow as pa
    import pyarrow.parquet as pq
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


def _case_row(key, index, case, row):
    """A case's row of the table: key, case (its index), its values, status, error, wall_s, the KPIs."""
    cols = {"key": key, "case": index}
    cols.update(case)
    for k in ("status", "error", "wall_s"):
        cols[k] = row[k]
    for k, v in row.items():
        if k not in cols:
            cols[k] = v
    return cols


def _table(rows):
    """The rows as one table: the columns in the order they first appear (a
    failed case has no KPIs: null there), each column's type from its values."""
    import pyarrow as pa
    names = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    return pa.table({n: [r.get(n) for r in rows] for n in names}) if rows else pa.table({})


def _series_table(series):
    import pyarrow as pa
    return pa.table({k: np.asarray(v) for k, v in series.items()})


def _write_bytes(data, path):
    """data into the file path, atomically (a hidden .part file renamed); plain os
    calls: pathlib's open costs more system calls, paid a case in the client."""
    path = os.fspath(path)
    head, name = os.path.split(path)
    tmp = os.path.join(head, f".{name}.{os.getpid()}.part")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)
    os.replace(tmp, path)


def _write_text(path, text):
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    tmp.write_text(text)
    os.replace(tmp, path)


def assemble(out, keys=None, rows=None):
    """results.parquet from the cases of this sweep (its manifest's keys), in case
    order: each case's row from rows (key -> row, the cases just run) or else read
    from its case file; the table made once, at the end."""
    import pyarrow.parquet as pq
    out = Path(out)
    if keys is None:
        keys = json.loads((out / MANIFEST).read_text())["keys"]
    rows = rows or {}
    table, done = [], set()
    for i, k in enumerate(keys):
        if k in done:
            continue
        row = rows.get(k)
        if row is None:
            f = out / CASES_DIR / f"{k}.parquet"
            if not f.is_file():
                continue
            row = pq.read_table(f).to_pylist()[0]
        done.add(k)
        table.append({**row, "case": i})
    table = _table(table)
    _write_parquet(table, out / TABLE)
    return table
