"""Archives unpacked once and kept between runs: a bench's ``.ssp`` and its
FMUs, by the SHA-256 of their bytes (``unpacked``), and what is read from
them once (``stored``: a model description parsed and validated).

Where: ``$ARTIBUS_CACHE/unpacked``, default ``~/.cache/artibus/unpacked``
(``${XDG_CACHE_HOME:-~/.cache}/artibus``, the cache scripts/build_common.sh
keeps the third-party builds in). An entry is the directory
``<sha256>/``: written under a name of this process's own and renamed, so a
directory under its final name is always complete, runs at once that unpack
the same archive do not collide (the first rename wins, the other's copy is
removed), and an interrupted unpacking leaves nothing under a final name. The
key is the content: a rebuilt FMU or a repacked bench is a new entry, never a
stale one. A run only reads an entry (the FMUs' binaries are loaded from it).

The size is bounded: when an entry is added and the entries take more than
$ARTIBUS_CACHE_MB megabytes (default 500), the ones used longest ago are
removed, but none used in the last hour (another run may be loading it).
``clean()`` removes every entry not in use; ``ARTIBUS_CACHE_MB=0`` unpacks
into a temporary directory per run instead, removed after it (the behaviour
before the cache).

The cache reads nothing an archive can supply: what ``stored`` keeps is
named ``.artibus-<name>.pickle`` in the entry, and an archive with a member of
that prefix is refused before it is unpacked (``extract``); a kept object is
loaded only when its bytes carry the HMAC-SHA256 this cache's writer made of
them with the cache's own secret key (``$ARTIBUS_CACHE/unpacked/.hmac-key``,
made once, mode 0600), so a file changed on disk or put there by anything
else is never unpickled: it is made again."""
import hashlib
import hmac
import os
import pickle
import shutil
import tempfile
import time
from pathlib import Path

DEFAULT_MB = 500
KEEP_RECENT_S = 3600.0        # an entry used in the last hour is never pruned
_PREFIX_TMP = ".tmp-"
_PREFIX_TRASH = ".trash-"
OWN_PREFIX = ".artibus-"      # the cache's own files in an entry (``stored``): no archive member may start so
_KEY_FILE = ".hmac-key"        # in the root: the secret the kept objects are signed with
_MAGIC = b"artibus-stored-1\n"  # a kept object: _MAGIC, HMAC-SHA256(key, payload), the pickle payload


def root():
    """The cache's directory of unpacked archives, or None when switched off
    (ARTIBUS_CACHE_MB=0)."""
    env = (os.environ.get("ARTIBUS_CACHE_MB"), os.environ.get("ARTIBUS_CACHE"), os.environ.get("XDG_CACHE_HOME"))
    if _ROOT and _ROOT[0] == env:
        return _ROOT[1]
    if _limit() <= 0:
        base = None
    else:
        base = env[1] or Path(env[2] or Path.home() / ".cache") / "artibus"
        base = Path(base) / "unpacked"
    _ROOT[:] = [env, base]
    return base


_ROOT = []          # [the environment it was found from, the root]


def _limit():
    """The bound in bytes ($ARTIBUS_CACHE_MB megabytes)."""
    try:
        return float(os.environ.get("ARTIBUS_CACHE_MB", DEFAULT_MB)) * 1e6
    except ValueError:
        return DEFAULT_MB * 1e6


def content_key(path):
    """The SHA-256 of the file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


_KEYS = {}          # (path, size, mtime_ns, ctime_ns, inode) -> content key, for this process


def _key(path):
    """content_key(path), hashed once per file in this process: again only when
    its size, times or inode changed. A file changed in the last 2 s is hashed
    each time (its times may not have moved yet: the clock of file times is
    coarse)."""
    st = os.stat(path)
    stamp = (str(path), st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
    key = _KEYS.get(stamp)
    if key is None:
        key = content_key(path)
        if time.time_ns() - max(st.st_mtime_ns, st.st_ctime_ns) > 2_000_000_000:
            _KEYS[stamp] = key
    return key


def extract(archive, dest):
    """Every member of the zip ``archive`` into the directory ``dest``, the
    archive checked first (artibus.files.extract_archive: member count and
    unpacked size, links, duplicates, paths that leave the folder; here: no
    member named like the cache's own files, ``_refuse_own_names``): ArtibusError
    naming the archive and the member otherwise."""
    from artibus.files import extract_archive
    _refuse_own_names(archive)
    extract_archive(archive, dest)


def _refuse_own_names(archive):
    """ArtibusError naming ``archive`` and the member when a member's name, or
    a folder on its path, starts with OWN_PREFIX: such a file would sit where
    the cache keeps what it read (``stored``), so the archive could supply it.
    An archive that is not a readable zip is left to extract_archive to name."""
    import zipfile
    try:
        with zipfile.ZipFile(archive) as z:
            names = z.namelist()
    except (zipfile.BadZipFile, OSError):
        return
    from artibus.base import ArtibusError
    for name in names:
        if any(p.startswith(OWN_PREFIX) for p in name.replace("\\", "/").split("/")):
            raise ArtibusError(f"{archive}: member '{name}' has a name reserved for artibus's cache "
                               f"(starting with '{OWN_PREFIX}'); refused")


def unpacked(archive):
    """(directory, temporary): the zip ``archive`` unpacked. From the cache
    (temporary False: the caller leaves it as it is) or, with the cache off
    or not writable, into a new temporary directory (temporary True: the
    caller removes it). The archive is checked before it is unpacked
    (``extract``): an archive refused, not a zip, with a broken member or
    that does not fit on the disk is an ArtibusError naming it, and nothing
    of it is left in the cache. An entry is only ever made by ``extract``, so
    an archive found in the cache was checked when it was added."""
    base = root()
    if base is not None:
        try:
            key = _key(archive)
            entry = base / key
            if entry.is_dir():
                _touch(entry)
                return entry, False
            base.mkdir(parents=True, exist_ok=True)
        except OSError:
            base = None                 # (an unwritable cache: as with the cache off)
    if base is None:
        tmp = tempfile.mkdtemp(prefix="artibus-")
        try:
            extract(archive, tmp)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return Path(tmp), True
    tmp = base / f"{_PREFIX_TMP}{key}-{os.getpid()}-{os.urandom(4).hex()}"
    try:
        tmp.mkdir()
        extract(archive, tmp)
        try:
            os.rename(tmp, entry)
        except OSError:                 # another run renamed its copy first: that one it is
            if not entry.is_dir():
                raise
            shutil.rmtree(tmp, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    _prune(base, keep=entry)
    return entry, False


def stored(entry, name, make):
    """What ``make()`` returns, kept in the cache entry ``entry`` (a directory
    ``unpacked`` returned) as ``.artibus-<name>.pickle``: made once per content,
    read back after, but only when its signature is the cache's own
    (``_load``): a file not from this cache's writer is made again and
    replaced. A temporary directory (the cache off) keeps nothing."""
    entry = Path(entry)
    base = root()
    if base is None or entry.parent != base:
        return make()
    f = entry / f"{OWN_PREFIX}{name}.pickle"
    key = _secret(base)
    if key is None:                     # (no key can be kept: nothing is read or kept)
        return make()
    found, value = _load(f, key)
    if found:
        return value
    value = make()
    _save(f, key, value)
    return value


def _load(f, key):
    """(True, the object) kept in ``f`` when its HMAC is this cache's, checked
    before a byte of it is unpickled; (False, None) otherwise (none yet, a
    file changed or not ours, from another version)."""
    try:
        with open(f, "rb") as fh:
            data = fh.read()
    except OSError:
        return False, None
    n = len(_MAGIC)
    head, mac, payload = data[:n], data[n:n + 32], data[n + 32:]
    if head != _MAGIC or not hmac.compare_digest(mac, hmac.new(key, payload, "sha256").digest()):
        return False, None
    try:
        return True, pickle.loads(payload)
    except Exception:                   # (ours, but of another version of a class)
        return False, None


def _save(f, key, value):
    """``value`` pickled and signed into ``f`` (a temporary name, renamed)."""
    tmp = f.with_name(f"{f.name}.{os.getpid()}-{os.urandom(4).hex()}")
    try:
        payload = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
        with open(tmp, "wb") as fh:
            fh.write(_MAGIC + hmac.new(key, payload, "sha256").digest() + payload)
        os.replace(tmp, f)
    except Exception:                   # (not picklable, not writable: made each time)
        try:
            os.unlink(tmp)
        except OSError:
            pass


def _secret(base):
    """The cache's secret key (32 random bytes in base/.hmac-key, readable by
    its owner only), made once: written under a temporary name and linked to
    its final one, so runs at once all read the first one made and none reads
    half of it. None when it can be neither read nor made."""
    f = Path(base) / _KEY_FILE
    for _ in range(2):
        try:
            key = f.read_bytes()
            if len(key) == 32:
                return key
            return None                 # (not ours: nothing is trusted, nothing is replaced)
        except FileNotFoundError:
            pass
        except OSError:
            return None
        tmp = f.with_name(f"{_PREFIX_TMP}key-{os.getpid()}-{os.urandom(4).hex()}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(fd, "wb") as fh:
                fh.write(os.urandom(32))
            try:
                os.link(tmp, f)
            except FileExistsError:     # another run made it first: that one it is
                pass
        except OSError:
            return None
        finally:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    return None


def _touch(entry):
    """An entry's mtime is when it was last used (the pruning's order); at
    most once a minute, to spare the disk."""
    try:
        if time.time() - entry.stat().st_mtime > 60:
            os.utime(entry)
    except OSError:
        pass


def _size(d):
    total = 0
    for dirpath, _, files in os.walk(d):
        for f in files:
            try:
                total += os.lstat(os.path.join(dirpath, f)).st_size
            except OSError:
                pass
    return total


def _entries(base):
    out = []
    for e in base.iterdir():
        if e.name.startswith(".") or not e.is_dir():
            continue
        try:
            out.append((e.stat().st_mtime, e))
        except OSError:
            pass
    return sorted(out)


def _remove(entry):
    """An entry renamed away first (so no run finds half of it), then removed."""
    trash = entry.with_name(f"{_PREFIX_TRASH}{entry.name}-{os.urandom(4).hex()}")
    try:
        os.rename(entry, trash)
    except OSError:
        return
    shutil.rmtree(trash, ignore_errors=True)


def _prune(base, keep=None):
    """The entries used longest ago removed while the cache is above its bound."""
    limit = _limit()
    try:
        entries = [(m, e, _size(e)) for m, e in _entries(base)]
    except OSError:
        return
    total = sum(s for _, _, s in entries)
    now = time.time()
    for mtime, e, size in entries:
        if total <= limit:
            break
        if e == keep or now - mtime < KEEP_RECENT_S:
            continue
        _remove(e)
        total -= size


def clean(older_than=0.0):
    """Every entry not used in the last ``older_than`` seconds removed, and
    whatever an interrupted run left (temporary copies older than an hour).
    Returns the number of entries removed."""
    base = root()
    if base is None or not base.is_dir():
        return 0
    now = time.time()
    n = 0
    for mtime, e in _entries(base):
        if now - mtime >= older_than:
            _remove(e)
            n += 1
    for e in base.iterdir():
        if e.name.startswith((_PREFIX_TMP, _PREFIX_TRASH)):
            try:
                if now - e.stat().st_mtime > KEEP_RECENT_S:
                    shutil.rmtree(e, ignore_errors=True)
            except OSError:
                pass
    return n
