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

A report folder is written the same way, whole (atomic_dir: a new folder beside
it, swapped in at the end), and no output may replace an input of its run
(check_not_input: the same file by identity, so a hard or symbolic link too).
"""
import contextlib
import errno
import os
import secrets
import signal
import stat
import threading
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


def _kind(mode):
    """what a file that is not a regular one is, in words"""
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def not_regular(path):
    """None if ``path`` is a new name or a regular file (through a symbolic
    link too), else what it is ("a character device", "a FIFO", ...)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    except OSError:
        return None          # e.g. a dangling link: the rename replaces the link
    return None if stat.S_ISREG(st.st_mode) else _kind(st.st_mode)


class KeptTemporary(ArtibusError):
    """The complete file could not take its final name; it is kept under ``self.kept``."""


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
        what = not_regular(path)
        if what is not None:       # a device, a FIFO, a directory: never replaced by the rename
            raise KeptTemporary(f"{path}: is {what}, not replaced; the complete file is kept as {tmp}")
        os.replace(tmp, path)
    except KeptTemporary as e:
        e.kept = tmp
        raise
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


@contextlib.contextmanager
def signals_held(written=None):
    """SIGINT and SIGTERM held while the block runs, so that a final write
    finishes, then delivered: the interrupt (KeyboardInterrupt, or the
    command line's SIGTERM one) is raised after the block, with
    ``e.written = written`` (what is complete on disk, for the message).
    Outside the main thread (no handlers there) the block just runs."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got, old = [], {}

    def hold(signum, frame):
        got.append(signum)
    for s in (signal.SIGINT, signal.SIGTERM):
        old[s] = signal.signal(s, hold)
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
    if got:
        try:
            signal.raise_signal(got[0])
        except KeyboardInterrupt as e:
            e.written = written
            raise


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
    results are not lost at the end: ``path`` must be a new name or a regular
    file (not a directory, a device, a FIFO or a socket), its directory must
    exist and take a new file. ArtibusError otherwise."""
    path = Path(path)
    if path.is_dir():
        raise ArtibusError(f"{what} {path}: is a directory (give a file name, e.g. {path / 'results.csv'})")
    kind = not_regular(path)
    if kind is not None:
        raise ArtibusError(f"{what} {path}: is {kind}: the output is a regular file or a new name")
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


# --- an output never replaces an input (issue 41) --------------------------------

def _identity(path):
    """(st_dev, st_ino) of the file ``path`` names, through symbolic links: two
    names of one file (a hard link, a symbolic link) have the same; None where
    there is no such file."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino


def _holders(path):
    """The identities of every folder that holds ``path``: its parents as written
    (made absolute) and as resolved (its symbolic links followed)."""
    p = Path(os.path.abspath(path))
    found = set()
    for q in (*p.parents, *Path(os.path.realpath(p)).parents):
        ident = _identity(q)
        if ident is not None:
            found.add(ident)
    return found


def check_not_input(path, what, inputs, folder=False, beside=None):
    """The output ``path`` (``what``: its option, "-o", "--report", ...) checked
    before anything runs against the run's ``inputs`` [(path, what it is)] by
    identity, so a hard link or a symbolic link to an input counts: an output
    that is an input would replace the bench, an FMU or a parameter file with
    results. ``folder``: ``path`` is a folder the output replaces whole (a
    report, atomic_dir), refused also when it holds an input. ``beside``: the
    output the user named, when ``path`` is a file written beside it (its
    units). ArtibusError naming the input otherwise; returns ``path``."""
    me = _identity(path)
    kind = "folder" if folder else "file"
    named = f"{what} {beside}: {path}, written beside it," if beside is not None else f"{what} {path}"
    for inp, label in inputs:
        ident = _identity(inp)
        if ident is None:
            continue
        if ident == me:
            link = "" if os.path.abspath(path) == os.path.abspath(inp) else ", the same file by another name"
            raise ArtibusError(f"{named} is {label} ({inp}{link}); choose another {kind}")
        if folder and me is not None and me in _holders(inp):
            raise ArtibusError(f"{named} holds {label} ({inp}), which writing the report there would "
                               f"remove; choose another folder")
    return Path(path)


def given(paths, what):
    """[(path, what it is)] of the files the user gave as inputs (--ssv FILE, a log, ...)."""
    return [(Path(p), what) for p in paths or () if p is not None]


def _fmus_of(pack):
    """The names of the FMUs in the .ssp ``pack`` (resources/NAME.fmu), none where it is unreadable."""
    import zipfile
    try:
        with zipfile.ZipFile(pack) as z:
            return {Path(n).name for n in z.namelist() if n.endswith(".fmu")}
    except (OSError, zipfile.BadZipFile):
        return set()


def bench_inputs(bench):
    """[(path, what it is)]: the files a run of ``bench`` (a name of ssp/benches
    or the path of an .ssp) reads, and the runner's own files every bench is
    packed from, which no output may replace (check_not_input): the .ssp given,
    the runner's packs and FMUs in the FMU folder (fmus/*.ssp, *.fmu, fmus/fmi3/),
    and every file under ssp/ (the benches' folders with their variants,
    parameter sets, roads, CAN databases, logs)."""
    from artibus.base import ROOT, fmu_dir
    found = []
    p, own = Path(str(bench)), fmu_dir()
    if p.suffix == ".ssp":
        found.append((p, "the bench being run"))
    used = _fmus_of(p if p.suffix == ".ssp" else own / f"{p.name}.ssp")
    for d in (own, own / "fmi3"):
        for f in sorted(d.glob("*.ssp")):
            found.append((f, "the runner's pack of the bench being run" if f.stem == p.stem
                          else "one of the runner's packs in the FMU folder"))
        found += [(f, "an FMU of the bench being run" if f.name in used else "one of the runner's FMUs")
                  for f in sorted(d.glob("*.fmu"))]
    for f in sorted((ROOT / "ssp").rglob("*")):
        if f.is_file():
            found.append((f, f"one of the benches' source files ({f.parent.relative_to(ROOT)}/)"))
    return found


def swap_dir(tmp, path):
    """The complete folder ``tmp`` takes the name ``path``; the folder that had
    it (an earlier report) is removed once the new one is in place, and left
    in place if the new one cannot take its name. renameat2(RENAME_EXCHANGE)
    swaps the two at once (Linux, glibc >= 2.28); elsewhere two renames, with
    the old folder renamed back if the second one fails."""
    import shutil
    tmp, path = Path(tmp), Path(path)
    if not path.exists():
        os.rename(tmp, path)
        return path
    if _exchange(tmp, path):
        shutil.rmtree(tmp, ignore_errors=True)          # (the earlier folder, now under tmp's name)
        return path
    old = path.with_name(f"{path.name}.old{TMP_MARK}{os.getpid()}-{os.urandom(3).hex()}")
    os.rename(path, old)
    try:
        os.rename(tmp, path)
    except BaseException:
        os.rename(old, path)
        raise
    shutil.rmtree(old, ignore_errors=True)
    return path


def _exchange(a, b):
    """Swap the names of ``a`` and ``b`` in one step (renameat2 with
    RENAME_EXCHANGE); False where the system or file system cannot."""
    import ctypes
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0


#: the report folders this process has put in place, complete (atomic_dir),
#: for the message of a signal that comes after one; the command line empties it
REPORTS_DONE = []


def report_said(e, what):
    """The command line's message after an interrupt (``what``: what it says of
    the results) with what became of the report folder (``e.report``, set by
    atomic_dir): the earlier one kept, none written, or the new one complete."""
    report = getattr(e, "report", None)
    if report is None and REPORTS_DONE:             # the signal came after the report was in place
        report = (REPORTS_DONE[-1], "complete")
    if report is None:
        return what
    said = {"kept": f"the earlier report in {report[0]} is kept as it was",
            "none": f"no report written to {report[0]}",
            "complete": f"the report in {report[0]} is complete"}[report[1]]
    return said if what == "nothing written" and report[1] == "complete" else f"{what}; {said}"


def _not_a_report(path):
    """What of the folder ``path`` shows it is not a report (its first few
    entries) when it has entries and no index.html, else None."""
    try:
        names = sorted(os.listdir(path))
    except OSError:
        return None
    if not names or "index.html" in names:
        return None
    return ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")


@contextlib.contextmanager
def atomic_dir(path, what="--report"):
    """A folder written whole or not at all (a report): yields a new temporary
    folder beside ``path`` (``NAME.tmp-PID-XXXX``); when the block ends without
    an exception it is swapped in (swap_dir, SIGINT and SIGTERM held until the
    swap is done), otherwise removed, ``path`` left as it was. A folder that has
    files but no index.html is not an earlier report: refused, not replaced."""
    import shutil
    path = Path(path)
    final = Path(os.path.realpath(path)) if path.is_symlink() else Path(os.path.abspath(path))
    if final.exists() and not final.is_dir():
        raise ArtibusError(f"{what} {path}: not a directory")
    if final in (Path.cwd(), *Path.cwd().parents):
        raise ArtibusError(f"{what} {path}: is the working directory or holds it; "
                           f"the report replaces its folder whole: give another one")
    foreign = _not_a_report(final)
    if foreign:
        raise ArtibusError(f"{what} {path}: holds files that are not a report ({foreign}); the report "
                           f"replaces its folder whole: give a new or empty folder, or an earlier report's")
    make_dir(final.parent, what)
    tmp = final.with_name(f"{final.name}{TMP_MARK}{os.getpid()}-{os.urandom(3).hex()}")
    state, made, swapping = ("kept" if final.is_dir() else "none"), False, False
    try:
        tmp.mkdir()
        made = True
        yield tmp
        with signals_held():
            swapping = True
            swap_dir(tmp, final)
            state = "complete"
            REPORTS_DONE.append(path)
    except BaseException as e:
        if state != "complete":
            shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(e, KeyboardInterrupt):        # for the command line's message (report_said)
            e.report = (path, state)
            raise
        if swapping and isinstance(e, OSError):
            raise ArtibusError(f"{what} {path}: the new report could not take its name ({e.strerror or e}); "
                               + ("the earlier one is kept" if state == "kept" else "nothing written")) from None
        err = _disk_error(path, e)
        if err is not None:
            raise err from None
        if isinstance(e, OSError) and not made:
            raise ArtibusError(f"{what} {path}: cannot make a folder beside it ({e.strerror})") from None
        raise


# --- archives (.ssp, .fmu): checked as a whole before anything is unpacked ----------

#: limits of what an archive may unpack to, checked before extraction; the
#: environment variables override them (docs/guide: "Limits")
MAX_UNPACKED_MB = 2048          # $ARTIBUS_MAX_UNPACKED_MB: total size of the members, MiB
MAX_MEMBERS = 20000             # $ARTIBUS_MAX_MEMBERS: number of members


def _limit(env, default):
    text = os.environ.get(env)
    if text is None or not text.strip():
        return default
    from artibus.base import parse_integer
    try:
        value = parse_integer(text)
    except ValueError:
        raise ArtibusError(f"${env} = {text!r}: expected a whole number") from None
    if value <= 0:
        raise ArtibusError(f"${env} = {text!r}: expected a number > 0")
    return value


def check_archive(z, label):
    """The members of the open ZipFile ``z`` checked before anything is read
    from it: none a symbolic link, an absolute path, a path with a drive or a
    backslash or one that leaves the folder (``..``), none given twice (also
    as a file and a folder of the same name); their count and total
    unpacked size within MAX_MEMBERS and MAX_UNPACKED_MB. ArtibusError naming
    ``label`` and the member otherwise."""
    members = z.infolist()
    max_members = _limit("ARTIBUS_MAX_MEMBERS", MAX_MEMBERS)
    max_bytes = _limit("ARTIBUS_MAX_UNPACKED_MB", MAX_UNPACKED_MB) * 2 ** 20
    if len(members) > max_members:
        raise ArtibusError(f"{label}: {len(members)} members, more than the limit of {max_members} "
                           f"($ARTIBUS_MAX_MEMBERS)")
    seen, dirs, total = {}, set(), 0
    for m in members:
        name = m.filename
        mode = m.external_attr >> 16
        if stat.S_ISLNK(mode):
            raise ArtibusError(f"{label}: member '{name}' is a symbolic link (not allowed in an archive here)")
        parts = name.rstrip("/").split("/")
        if (not name or name.startswith("/") or "\\" in name or ":" in parts[0] or "\0" in name
                or any(p in ("..",) for p in parts)):
            raise ArtibusError(f"{label}: member '{name}' is not a relative path inside the archive")
        key = "/".join(p for p in parts if p not in ("", "."))
        if key in seen:
            raise ArtibusError(f"{label}: member '{name}' is given twice (also as '{seen[key]}')")
        seen[key] = name
        for i in range(1, len(parts)):
            dirs.add("/".join(p for p in parts[:i] if p not in ("", ".")))
        total += m.file_size
        if total > max_bytes:
            raise ArtibusError(f"{label}: its members unpack to more than the limit of "
                               f"{max_bytes // 2 ** 20} MiB ($ARTIBUS_MAX_UNPACKED_MB), at member '{name}'")
    for key, name in seen.items():
        if key in dirs and not name.endswith("/"):
            raise ArtibusError(f"{label}: member '{name}' is a file and also a folder of other members")
    return members


def extract_archive(path, dest=None, prefix="artibus-", members=None):
    """The archive ``path`` (a zip: .ssp, .fmu) checked (check_archive), then
    unpacked into ``dest`` or a new temporary folder, whose path is returned;
    ``members``: only these names. On any failure (a bad member, a full disk)
    the temporary folder is removed and the error names the archive."""
    import shutil
    import tempfile
    import zipfile
    path = Path(path)
    made = dest is None
    try:
        z = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as e:
        raise ArtibusError(f"{path}: not a readable zip archive: {e}") from None
    target = None
    try:
        with z:
            check_archive(z, str(path))
            target = Path(tempfile.mkdtemp(prefix=prefix)) if made else Path(dest)
            z.extractall(target, members=members)
        return target
    except BaseException as e:
        if made and target is not None:
            shutil.rmtree(target, ignore_errors=True)
        if isinstance(e, OSError) and e.errno in (errno.ENOSPC, errno.EDQUOT):
            raise ArtibusError(f"{path}: no space left on device while unpacking it into "
                               f"{target.parent if made and target else target} (a larger TMPDIR?); "
                               f"nothing of it is left there") from None
        if isinstance(e, OSError):
            raise ArtibusError(f"{path}: cannot unpack it into {target}: {e}") from None
        if isinstance(e, (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, NotImplementedError)):
            raise ArtibusError(f"{path}: a member cannot be unpacked: {e}") from None
        raise
