"""A sweep's results in its output folder: one Parquet file a case
(``cases/<key>.parquet``, and its time series), written atomically as its task
comes back; the manifest; the table of every case of the sweep in case order,
assembled at the end and on resume (``assemble``)."""
import contextlib
import errno
import json
import os
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError

CASES_DIR, SERIES_DIR = "cases", "series"
TABLE, MANIFEST, WORST, PLOT = "results.parquet", "sweep.json", "worst.txt", "study.png"
STATUS_OK, STATUS_FAILED = "ok", "failed"
#: a case an FMU ended before the stop time (fmi2Terminated): its KPIs over what ran, not a failure
STATUS_TERMINATED = "terminated"


@contextlib.contextmanager
def _written(path, tmp):
    """A write of ``tmp`` then renamed onto ``path``: on any failure the
    temporary file is removed (nothing half-written is left) and a full disk
    (ENOSPC, EDQUOT) or another OS error is one ArtibusError naming the file."""
    try:
        yield
        os.replace(tmp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(e, OSError):
            if e.errno in (errno.ENOSPC, errno.EDQUOT):
                raise ArtibusError(f"{path}: no space left on device while writing it; the sweep "
                                   f"stopped there (nothing half-written is left: free space and run "
                                   f"the same command again to resume)") from None
            raise ArtibusError(f"{path}: cannot write it: {e.strerror or e}") from None
        raise


def _write_parquet(table, path):
    import pyarrow.parquet as pq
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    with _written(path, tmp):
        pq.write_table(table, tmp)


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
    with _written(path, tmp):
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
        finally:
            os.close(fd)


def _write_text(path, text):
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    with _written(path, tmp):
        tmp.write_text(text)


def read_case(path):
    """The row of a case file, or None if it cannot be read (a torn or
    corrupt file, one of another format): that case is run again."""
    import pyarrow.parquet as pq
    try:
        rows = pq.read_table(path).to_pylist()
    except Exception:          # pyarrow's ArrowInvalid, OSError, ...
        return None
    if len(rows) != 1 or not isinstance(rows[0].get("status"), str):
        return None
    return rows[0]


LOCK = ".sweep.lock"


class FolderLock:
    """One sweep at a time in an output folder: an exclusive lock (flock) on
    ``OUT/.sweep.lock``, which holds the PID of the sweep holding it. The
    lock goes with the process (also when it is killed); a second sweep
    into the folder is refused naming the first's PID."""

    def __init__(self, out):
        self.path = Path(out) / LOCK
        self.fd = None

    def __enter__(self):
        import fcntl
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as e:
            raise ArtibusError(f"{self.path}: cannot make the sweep's lock: {e.strerror or e}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            try:
                pid = os.read(fd, 32).decode(errors="replace").strip() or "?"
            finally:
                os.close(fd)
            raise ArtibusError(f"{self.path.parent}: another sweep (PID {pid}) is writing into this folder; "
                               f"wait for it to end, or give another -o") from None
        try:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
        except OSError as e:
            os.close(fd)
            raise ArtibusError(f"{self.path}: cannot write the sweep's lock: {e.strerror or e}") from None
        self.fd = fd
        return self

    def __exit__(self, *exc):
        os.close(self.fd)          # the lock goes with the descriptor
        self.fd = None


def assemble(out, keys=None, rows=None):
    """results.parquet from the cases of this sweep (its manifest's keys), in case
    order: each case's row from rows (key -> row, the cases just run) or else read
    from its case file; the table made once, at the end."""
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
            row = read_case(f)
            if row is None:
                continue
        done.add(k)
        table.append({**row, "case": i})
    table = _table(table)
    _write_parquet(table, out / TABLE)
    return table
