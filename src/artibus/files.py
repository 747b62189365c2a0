"""Writing files so that nothing is torn: every result, report and pack is
written to a temporary name in the same directory and renamed onto the final
name (os.replace, atomic on one file system). A run stopped midway (Ctrl-C,
SIGTERM, a full disk, a crash) leaves either the old file or the complete new
one under the final name, never half a file; the temporary one is removed
(unless the process is killed with SIGKILL: then a ``NAME.tmp-PID-XXXX`` file
is left beside it, never under the final name).

    with atomic_write("out.csv") as f:          # a text (or binary: mode="wb") file object
        f.write(...)
    with atomic_path("plot.png") as tmp:        # a path, for writers that take one
        fig.savefig(tmp)                        # (tmp keeps the suffix: format by extension)

A full disk (ENOSPC, EDQUOT) becomes an ArtibusError naming the file.
"""
import contextlib
import errno
import os
from pathlib import Path

from artibus.base import ArtibusError

TMP_MARK = ".tmp-"          # NAME.tmp-PID-XXXX.SUFFIX


def temp_name(path):
    """A temporary name beside ``path``, unique to this process and call, that keeps its suffix."""
    path = Path(path)
    return path.with_name(f"{path.name}{TMP_MARK}{os.getpid()}-{os.urandom(3).hex()}{path.suffix}")


def _disk_error(path, e):
    if isinstance(e, OSError) and e.errno in (errno.ENOSPC, errno.EDQUOT):
        return ArtibusError(f"{path}: no space left on device while writing it; "
                            f"nothing written under that name")
    if isinstance(e, OSError) and e.errno == errno.EROFS:
        return ArtibusError(f"{path}: read-only file system; nothing written")
    return None


@contextlib.contextmanager
def atomic_path(path, fsync=True):
    """Yields a temporary path beside ``path``; when the block ends without an
    exception the file written there becomes ``path`` (flushed to disk first
    with fsync=True); otherwise it is removed and ``path`` is left as it was."""
    path = Path(path)
    tmp = temp_name(path)
    try:
        yield tmp
        if not tmp.exists():
            raise ArtibusError(f"{path}: nothing was written")
        if fsync:
            fd = os.open(tmp, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        os.replace(tmp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        err = _disk_error(path, e)
        if err is not None:
            raise err from None
        raise


@contextlib.contextmanager
def atomic_write(path, mode="w", encoding="utf-8", newline=None, fsync=True):
    """A file object on a temporary file beside ``path`` ("w" text or "wb"
    binary), renamed onto ``path`` when the block ends without an exception."""
    if mode not in ("w", "wb", "x", "xb"):
        raise ValueError(f"atomic_write: mode {mode!r} (expected w or wb)")
    kw = {} if "b" in mode else {"encoding": encoding, "newline": newline}
    with atomic_path(path, fsync=False) as tmp:
        with open(tmp, mode.replace("x", "w"), **kw) as f:
            yield f
            f.flush()
            if fsync:
                os.fsync(f.fileno())


def write_text(path, text, encoding="utf-8"):
    """Path.write_text, atomically."""
    with atomic_write(path, encoding=encoding) as f:
        f.write(text)
    return Path(path)


def write_bytes(path, data):
    """Path.write_bytes, atomically."""
    with atomic_write(path, "wb") as f:
        f.write(data)
    return Path(path)


def check_output(path, what="-o"):
    """An output file's place checked before a run, so that a long run's
    results are not lost at the end: ``path`` must not be a directory, its
    directory must exist and take a new file. ArtibusError otherwise."""
    path = Path(path)
    if path.is_dir():
        raise ArtibusError(f"{what} {path}: is a directory (give a file name, e.g. {path / 'results.csv'})")
    parent = path.parent
    if not parent.exists():
        raise ArtibusError(f"{what} {path}: directory {parent} does not exist")
    if not parent.is_dir():
        raise ArtibusError(f"{what} {path}: {parent} is not a directory")
    probe = parent / f".{path.name}.probe-{os.getpid()}-{os.urandom(3).hex()}"
    fd = None
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as e:
        raise ArtibusError(f"{what} {path}: cannot write in {parent} ({e.strerror})") from None
    finally:
        if fd is not None:
            os.close(fd)
            os.unlink(probe)
    if path.exists() and not os.access(path, os.W_OK) and os.geteuid() != 0:
        raise ArtibusError(f"{what} {path}: the file exists and is read-only")
    return path


def make_dir(path, what="--report"):
    """A directory for the output (a report's): made with its parents where
    missing; ArtibusError naming ``what`` when it cannot be made or is not one."""
    try:
        Path(path).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ArtibusError(f"{what} {path}: cannot make the directory ({e.strerror})") from None
    if not Path(path).is_dir():
        raise ArtibusError(f"{what} {path}: not a directory")
    return Path(path)
