"""Issue 41 (reliability, round 4), classes 6, 7, 8 and the CAN-log item of 10:
each test is the hostile use that gave a traceback, a lost result or code run
from an archive, and what must happen instead.

6. --can-log on a full disk (a real one: a tiny tmpfs): one line naming the log
   and the cause, the run's results in -o all the same, nothing of the log left.
7. The cache reads nothing an archive supplies: a member named like the
   cache's own files is refused, never unpickled; a cache file changed on
   disk is made again, never loaded.
8. Messages, not tracebacks: the Dask scheduler killed mid-sweep (the cases
   done kept, the same command resumes), an -o name longer than the file
   system allows, a reader that goes away (`artibus list | head -1`).
10. A CAN log whose time goes back says so: the file, the frame, both times."""
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import fmpy
import pytest

from artibus import cache, fmu_dir
from artibus.base import ArtibusError
from artibus.can import logs

ROOT = Path(__file__).resolve().parents[1]
ENOSPC_TEXT = os.strerror(28)          # "No space left on device"


def cli(*args, cwd, env=None, timeout=300):
    return subprocess.run([sys.executable, "-m", "artibus", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, env={**os.environ, **(env or {})})


def one_line_error(r):
    """The last line of a failed command's stderr, after checking it failed without a traceback."""
    assert r.returncode != 0, r.stdout
    assert "Traceback" not in r.stderr, r.stderr
    return r.stderr.strip().splitlines()[-1]


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory):
    """One cache for this file's runs (the benches unpacked once), not the user's."""
    return {"ARTIBUS_CACHE": str(tmp_path_factory.mktemp("cache")), "ARTIBUS_CACHE_MB": "500"}


def _times(csv):
    """The time column of a results CSV (the first column), as floats."""
    rows = [line.split(",", 1)[0] for line in Path(csv).read_text().splitlines() if line and line[0] != "#"]
    return [float(t) for t in rows[1:]]


# --- 6: --can-log on a full disk -------------------------------------------------------------

@pytest.fixture
def full_disk(tmp_path):
    """A file system of 64 KiB (tmpfs) with one 4 KiB page left: a log's first
    block fits, the rest finds the disk full (ENOSPC). Skipped where mounting
    is not permitted (not root, a container without CAP_SYS_ADMIN)."""
    d = tmp_path / "full"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(d)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
    try:
        (d / "filler").write_bytes(b"\0" * 15 * 4096)         # 15 of its 16 pages
        yield d
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


@pytest.mark.parametrize("bench,suffix", [("Bus36m_Circle_CAN", ".blf"), ("Bus36m_Circle_CAN", ".asc"),
                                          ("Bus36m_Circle_LSBUS", ".blf")])
def test_can_log_on_a_full_disk_is_one_line_and_the_results_are_kept(tmp_path, full_disk, shared_cache,
                                                                      bench, suffix):
    """The probe: two tracebacks, a .part of the log left on the full disk and
    no results file, although -o was on a disk with room."""
    log = full_disk / f"run{suffix}"
    r = cli("run", bench, "-o", tmp_path / "r.csv", "--can-log", log, "--stop-time", 20, cwd=tmp_path,
            env=shared_cache)
    line = one_line_error(r)
    assert str(log) in line and ENOSPC_TEXT in line, line
    assert sum("error" in x for x in r.stderr.splitlines()) == 1, r.stderr
    t = _times(tmp_path / "r.csv")                             # the run's results, whole
    assert t[0] == 0.0 and t[-1] == pytest.approx(20.0, abs=1e-9)
    assert all(b > a for a, b in zip(t, t[1:]))
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]     # no log, no .part


# --- 7: the cache trusts nothing from an archive -------------------------------------------------

class _Payload:
    """Unpickled, it makes the directory ``marker`` (pickle calls os.mkdir): the
    proof that the cache ran code an archive supplied."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return os.mkdir, (self.marker,)


def _with_members(src, dest, members):
    """A copy of the zip ``src`` with ``members`` {name: bytes} added (or replacing theirs)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dest, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            if info.filename not in members:
                zout.writestr(info, zin.read(info.filename))
        for name, data in members.items():
            zout.writestr(name, data)
    return dest


def _poisoned_names():
    """The names the cache keeps its own files under (``.artibus-<name>.pickle``
    beside the unpacked members: the model description FMPy read), and others
    of its prefix."""
    return [f".artibus-modelDescription-fmpy-{fmpy.__version__}.pickle", ".artibus-bench-0.pickle",
            "documentation/.artibus-x.pickle"]


@pytest.mark.parametrize("how", ["simulate", "bench"])
def test_an_archive_member_named_like_the_cache_files_is_never_loaded(tmp_path, how):
    """The probe: TrainGuidance.fmu with a member .artibus-modelDescription-
    fmpy-<version>.pickle: `simulate` unpickled it from the cache entry (its
    code ran) before any check. The marker must never appear; the archive is
    refused by name (or the run is correct)."""
    marker = tmp_path / "pwned"
    payload = pickle.dumps(_Payload(marker))
    fmu = _with_members(fmu_dir() / "TrainGuidance.fmu", tmp_path / "TrainGuidance.fmu",
                        {n: payload for n in _poisoned_names()})
    env = {"ARTIBUS_CACHE": str(tmp_path / "cache"), "ARTIBUS_CACHE_MB": "500"}
    if how == "simulate":
        r = cli("simulate", fmu, "-o", tmp_path / "out.csv", "--stop-time", 0.1, cwd=tmp_path, env=env)
    else:                                   # inside a bench: the .ssp's FMU and a member of the .ssp itself
        ssp = _with_members(fmu_dir() / "Bus36m_Circle.ssp", tmp_path / "Poisoned.ssp",
                            {"resources/TrainGuidance.fmu": fmu.read_bytes(), _poisoned_names()[1]: payload})
        r = cli("run", ssp, "--variant", "guided", "-o", tmp_path / "out.csv", "--stop-time", 0.1, cwd=tmp_path,
                env=env)
    assert not marker.exists(), "the cache unpickled a file from the archive"
    if r.returncode == 0:
        assert _times(tmp_path / "out.csv")[-1] == pytest.approx(0.1)
    else:
        line = one_line_error(r)
        assert ".artibus-" in line and (fmu.name in line or "Poisoned.ssp" in line), line


def test_a_cache_file_changed_on_disk_is_made_again_not_loaded(tmp_path, monkeypatch):
    """What the cache keeps (cache.stored) is loaded only as its writer wrote
    it: a file replaced on disk (here by a pickle that would make a marker) or
    with a byte changed is never unpickled, the value is made again."""
    monkeypatch.setenv("ARTIBUS_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("ARTIBUS_CACHE_MB", raising=False)
    archive = tmp_path / "a.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("x.txt", "one")
    entry, temporary = cache.unpacked(archive)
    assert not temporary
    made = []

    def make():
        made.append(1)
        return {"value": len(made)}

    assert cache.stored(entry, "thing", make) == {"value": 1}
    assert cache.stored(entry, "thing", make) == {"value": 1} and len(made) == 1      # kept, read back
    kept = [p for p in entry.iterdir() if p.name.startswith(".artibus-") and "thing" in p.name]
    assert len(kept) == 1
    marker = tmp_path / "pwned"
    kept[0].write_bytes(pickle.dumps(_Payload(marker)))                 # replaced on disk
    assert cache.stored(entry, "thing", make) == {"value": 2}
    assert not marker.exists()
    data = bytearray(kept[0].read_bytes())                               # one byte changed
    data[-3] ^= 0x01
    kept[0].write_bytes(bytes(data))
    assert cache.stored(entry, "thing", make) == {"value": 3}
    # and through the command line: a run whose cache entry's model description was replaced
    env = {"ARTIBUS_CACHE": str(tmp_path / "cli-cache"), "ARTIBUS_CACHE_MB": "500"}
    assert cli("simulate", "TrainGuidance", "-o", tmp_path / "a.csv", "--stop-time", 0.1, cwd=tmp_path,
               env=env).returncode == 0
    described = list((tmp_path / "cli-cache" / "unpacked").glob("*/.artibus-modelDescription-*"))
    assert described
    for f in described:
        f.write_bytes(pickle.dumps(_Payload(marker)))
    r = cli("simulate", "TrainGuidance", "-o", tmp_path / "b.csv", "--stop-time", 0.1, cwd=tmp_path, env=env)
    assert not marker.exists(), "the cache unpickled a file changed on disk"
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


# --- 8: messages, not tracebacks ---------------------------------------------------------------

def _dask(*args, cwd):
    return subprocess.Popen([str(Path(sys.executable).parent / "dask"), *map(str, args)], cwd=cwd,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _wait_for_file(path, proc, bound=120.0):
    """Until ``path`` exists with content (the event), failing if ``proc`` ends
    first; ``bound`` only bounds a failure."""
    end = time.monotonic() + bound
    while not (path.is_file() and path.stat().st_size > 0):
        assert proc.poll() is None, f"{proc.args} ended ({proc.returncode}) before writing {path}"
        assert time.monotonic() < end, f"{path} not written in {bound:g} s"
        time.sleep(0.05)


def test_the_scheduler_killed_mid_sweep_is_a_message_and_the_sweep_resumes(tmp_path, shared_cache):
    """The probe: `sweep --scheduler ADDRESS` with the scheduler killed (SIGKILL)
    after the first case: a traceback (OSError from a new scatter). Now: one
    line naming the scheduler and the folder, every finished case kept, and
    the same command without the scheduler finishes the rest."""
    from held_run import HeldRun
    sched_file = tmp_path / "scheduler.json"
    scheduler = _dask("scheduler", "--scheduler-file", sched_file, "--port", 0, "--dashboard-address", ":0",
                      cwd=tmp_path)
    worker = None
    try:
        _wait_for_file(sched_file, scheduler)
        import json
        address = json.loads(sched_file.read_text())["address"]
        worker = _dask("worker", "--scheduler-file", sched_file, "--nworkers", 1, "--nthreads", 1,
                       "--no-dashboard", cwd=tmp_path)
        grid = "Driver.vSet=1:3:0.5"                     # 5 cases
        args = ["sweep", "Urbino18_Circle", "--grid", grid, "--out", "out", "--stop-time", 100]
        with HeldRun([*args, "--scheduler", address], cwd=tmp_path, env=shared_cache) as run:
            run.wait_for(lambda line: line.startswith("case "))      # held after its first case's file
            scheduler.kill()
            scheduler.wait()
            err = run.finish()
            assert run.proc.returncode != 0 and "Traceback" not in err, err
            line = err.strip().splitlines()[-1]
            assert address in line and "out/cases" in line and "again" in line, line
    finally:
        for p in (scheduler, worker):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    kept = sorted((tmp_path / "out" / "cases").glob("*.parquet"))
    assert 1 <= len(kept) < 5
    r = cli(*args, "--workers", 1, cwd=tmp_path, env=shared_cache)
    assert r.returncode == 0, r.stderr
    assert f"5 cases, {5 - len(kept)} run now (0 failed), {len(kept)} done before" in r.stdout, r.stdout
    import pyarrow.parquet as pq
    table = pq.read_table(tmp_path / "out" / "results.parquet")
    assert table.num_rows == 5 and set(table.column("status").to_pylist()) == {"ok"}


@pytest.mark.parametrize("command", [["simulate", "TrainGuidance", "-o"], ["run", "Urbino18_Circle", "-o"],
                                     ["run", "Urbino18_Circle", "--report"], ["sweep", "Urbino18_Circle",
                                                                            "--grid", "Driver.vSet=2,3", "--out"]])
def test_an_output_name_longer_than_the_file_system_allows_is_one_line(tmp_path, shared_cache, command):
    """The probe: OSError ENAMETOOLONG as a traceback, for -o, --report and a sweep's --out."""
    name = "n" * 300                                   # NAME_MAX is 255 bytes on Linux file systems
    r = cli(*command, name + (".csv" if command[-1] == "-o" else ""), "--stop-time", 0.1, cwd=tmp_path,
            env=shared_cache)
    line = one_line_error(r)
    assert line.startswith("artibus: error: ") and name in line and os.strerror(36) in line, line
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize("command", [["list"], ["info", "BusDynamics"], ["list", "--parameters"]])
def test_a_reader_that_went_away_ends_the_command_quietly(tmp_path, command):
    """`artibus info BusDynamics | head -1`: the probe printed a BrokenPipeError
    traceback (and "Exception ignored ... BrokenPipeError" at the exit). The
    reader's end here is closed before the command writes anything (not a race
    with `head`): the command ends without a word, as a shell's pipeline
    expects (exit 141, 128 + SIGPIPE, or 0)."""
    r, w = os.pipe()
    os.close(r)                                       # the reader has gone before the first write
    try:
        p = subprocess.Popen([sys.executable, "-m", "artibus", *command], stdout=w, stderr=subprocess.PIPE,
                             text=True, cwd=tmp_path)
    finally:
        os.close(w)
    _, err = p.communicate(timeout=120)
    assert err == "", err
    assert p.returncode in (0, 128 + signal.SIGPIPE)


# --- 10 (the CAN-log item): time that goes back ---------------------------------------------

ASC_HEAD = ("date Thu Dec 3 10:00:00.000 am 2026\nbase hex  timestamps absolute\n"
            "no internal events logged\nBegin Triggerblock Thu Dec 3 10:00:00.000 am 2026\n")


def _asc(path, stamps):
    body = "".join(f"   {t} 1  101             Rx   d 4 00 00 00 00\n" for t in stamps)
    path.write_text(ASC_HEAD + body + "End TriggerBlock\n")
    return path


@pytest.mark.parametrize("stamps,frame,times", [
    (["0.010000", "0.020000", "-0.005000"], 3, ("-0.005000", "0.020000")),   # back below the start
    (["0.010000", "0.020000", "0.015000"], 3, ("0.015000", "0.020000")),     # back, still after it
    (["0.010000", "-0.5"], 2, ("-0.500000", "0.010000")),
])
def test_a_can_log_whose_time_goes_back_names_the_frame_and_both_times(tmp_path, shared_cache, stamps, frame,
                                                                       times):
    """The probe: a frame stamped before the previous one, below 0 (as written
    by a logger whose clock stepped back), was refused as "not a finite number
    of seconds". It must say the time goes back, with the file, the frame and
    both times, in `replay` too."""
    f = _asc(tmp_path / "back.asc", stamps)
    with pytest.raises(ArtibusError) as e:
        logs.read_log(f)
    msg = str(e.value)
    assert str(f) in msg and f"frame {frame}" in msg and "back" in msg and "not a finite" not in msg, msg
    assert all(t in msg for t in times), msg
    r = cli("replay", f, "--bench", "Bus36m_Circle_CAN", cwd=tmp_path, env=shared_cache)
    line = one_line_error(r)
    assert f"frame {frame}" in line and all(t in line for t in times), line


def test_a_can_log_starting_before_its_start_is_refused_by_name(tmp_path):
    """A first frame stamped below 0: python-can's reader skips such a line
    without a word; refused naming the line, the frame and its time (not as
    "not a finite number")."""
    f = _asc(tmp_path / "early.asc", ["-0.250000", "0.010000"])
    with pytest.raises(ArtibusError, match=r"early\.asc, line 5: frame 1: time -0\.250000 s is before the log's "
                                           r"start"):
        logs.read_log(f)
