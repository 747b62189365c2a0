"""Reliability, round 3 (issue 28): hostile files, signals, full disks and
concurrent sweeps. Each test reproduces one defect of the issue's probe (on
main f502f0b) and asserts the clear error, or the correct result, instead:
nothing lost, nothing written outside the output.

The FMU state fuzzer with recomputed checksums is tests/test_state_fuzzer.py,
the parser fuzzer tests/test_parser_fuzzer.py."""
import errno
import os
import signal
import stat
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from artibus import ArtibusError, ROOT, fmu_path
from artibus import files
from artibus.base import parse_integer, parse_real
from artibus.bench import roads, ssp
from artibus.bench.parameters import coerce, typed
from artibus.can import logs
from artibus.can.dbc import load_dbc
from artibus.fmu import Fmu, Result

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"


def cli(*args, cwd, env=None):
    return subprocess.run([sys.executable, "-m", "artibus", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300, env={**os.environ, **(env or {})})


def one_line_error(r):
    assert r.returncode != 0, r.stdout
    assert "Traceback" not in r.stderr, r.stderr
    return r.stderr.strip().splitlines()[-1]


# --- line readers: a line longer than the limit is refused, never split -----------------

def _road(path, comment_len, n=200):
    lines = ["x,y", "# " + "c" * comment_len] + [f"{k * 0.5},{0.01 * k}" for k in range(n)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_road_csv_line_longer_than_the_limit_is_an_error_naming_file_and_line(tmp_path):
    """The probe: a comment of more than 1023 characters was split and its tail
    ("ccc...") became a point: 201 points instead of 200."""
    f = _road(tmp_path / "long.csv", roads.LINE_MAX)          # "# " + LINE_MAX: over the limit
    with pytest.raises(ArtibusError, match=r"long\.csv', line 2: longer than 4096 characters"):
        roads.read_csv(f)
    ok = _road(tmp_path / "ok.csv", roads.LINE_MAX - 2)       # exactly LINE_MAX characters: read whole
    x, y = roads.read_csv(ok)
    assert len(x) == 200 and x[-1] == 99.5


def test_road_csv_through_the_fmu_refuses_the_long_line(tmp_path):
    f = _road(tmp_path / "long.csv", 5000)
    fmu = Fmu(fmu_path("RoadFollowDriver"))
    try:
        with pytest.raises(Exception):
            fmu.initialize({"road": 0, "roadFile": str(f)})
        assert any("line 2: longer than" in m for m in fmu.log), fmu.log
    finally:
        fmu.close()


@pytest.mark.parametrize("cell", ["0x10", "0x1p3", "inf", "1_5"])
def test_road_csv_takes_decimal_numbers_only(tmp_path, cell):
    f = tmp_path / "r.csv"
    f.write_text(f"x,y\n0,0\n{cell},1\n2,2\n")
    with pytest.raises(ArtibusError, match="line 3"):
        roads.read_csv(f)


# --- output paths -------------------------------------------------------------------------

def test_output_that_is_a_device_fifo_or_directory_is_refused_before_the_run(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for p, what in ((Path("/dev/null"), "character device"), (fifo, "FIFO"), (tmp_path, "directory")):
        with pytest.raises(ArtibusError, match=what):
            files.check_output(p)
    # the command line: refused before the run, the device untouched
    r = cli("simulate", "TypesTest", "-o", "/dev/null", cwd=tmp_path)
    assert "is a character device" in one_line_error(r)
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    r = cli("simulate", "TypesTest", "-o", str(fifo), cwd=tmp_path)
    assert "FIFO" in one_line_error(r)


def test_atomic_rename_never_replaces_a_non_regular_file(tmp_path):
    """Made a FIFO after the check (a race): the rename refuses, the complete file is kept."""
    fifo = tmp_path / "out.csv"
    os.mkfifo(fifo)
    with pytest.raises(files.KeptTemporary, match="FIFO") as e:
        with files.atomic_write(fifo) as f:
            f.write("complete\n")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert Path(e.value.kept).read_text() == "complete\n"


# --- signals during the final write --------------------------------------------------------

def _result(n=2000):
    t = np.arange(n) * 0.01
    r = Result.from_array(["time", "y"], np.column_stack([t, np.sin(t)]))
    r.units = {"time": "s", "y": "m"}
    return r


def test_sigterm_during_the_final_write_finishes_it(tmp_path, monkeypatch):
    """The probe: SIGTERM while the results were written said "nothing written"
    and the finished run was discarded."""
    from artibus import cli as cli_mod, runner
    old = signal.signal(signal.SIGTERM, cli_mod._on_sigterm)
    real = os.fsync
    sent = []

    def fsync(fd):                 # the signal arrives in the middle of the write
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGTERM)
        return real(fd)
    monkeypatch.setattr(os, "fsync", fsync)
    out = tmp_path / "out.csv"
    try:
        with pytest.raises(KeyboardInterrupt) as e:
            runner.save(_result(), out)
    finally:
        signal.signal(signal.SIGTERM, old)
    assert sent and e.value.written == out
    lines = out.read_text().splitlines()
    assert len(lines) == 2001 and (tmp_path / "out.units.csv").is_file()
    assert not list(tmp_path.glob("*.tmp-*"))


def test_the_command_line_says_the_finished_run_is_complete(tmp_path, monkeypatch, capsys):
    from artibus import cli as cli_mod
    real = os.fsync
    sent = []

    def fsync(fd):
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGTERM)
        return real(fd)
    monkeypatch.setattr(os, "fsync", fsync)
    out = tmp_path / "t.csv"
    old = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    try:
        rc = cli_mod.main(["simulate", "TypesTest", "-o", str(out), "--stop-time", "0.5"])
    finally:
        signal.signal(signal.SIGTERM, old[0])
        signal.signal(signal.SIGINT, old[1])
    err = capsys.readouterr().err
    assert rc == 143 and f"the finished run's results are complete in {out}" in err, err
    assert len(out.read_text().splitlines()) > 2


# --- one strict number syntax -------------------------------------------------------------

@pytest.mark.parametrize("text", ["1_5", "0x1A", "0x1p3", "\u0661\u0662", "1.5.2", "", "e3", "1e", "--1",
                                  "1\u00a0", "1 2"])
def test_number_syntax_is_strict(text):
    with pytest.raises(ValueError):
        parse_real(text)
    with pytest.raises(ValueError):
        typed("Real", text)


@pytest.mark.parametrize("text, value", [("1.5", 1.5), (" -2e-3 ", -2e-3), (".5", 0.5), ("+7", 7.0),
                                         ("1E3", 1000.0), ("-inf", -np.inf)])
def test_decimal_numbers_are_read(text, value):
    assert parse_real(text) == value


def test_integers_are_strict():
    assert parse_integer(" -12 ") == -12
    for text in ("1_0", "0x10", "1.0", "1e3", "\u0661"):
        with pytest.raises(ValueError):
            parse_integer(text)


def test_set_with_underscores_is_an_error_not_15(tmp_path):
    """The probe: --set Bus.L0=1_5 ran with L0 = 15."""
    r = cli("simulate", "BusKinematics", "--set", "L0=1_5", "--stop-time", "0.1", cwd=tmp_path)
    line = one_line_error(r)
    assert "L0" in line and "1_5" in line, line
    from fmpy import read_model_description
    v = next(v for v in read_model_description(str(fmu_path("BusKinematics"))).modelVariables if v.name == "L0")
    with pytest.raises(ValueError):
        coerce(v, "1_5")


def test_design_grid_and_replay_csv_use_the_same_syntax(tmp_path):
    from artibus.can import replay
    from artibus.study.sweep.designs import parse_values
    with pytest.raises(ArtibusError, match="malformed range"):
        parse_values("1_0:20:5", "--grid Driver.vSet")
    log = tmp_path / "log.csv"
    log.write_text("time_s,v\n0,1\n0.1,1_5\n")
    with pytest.raises(ArtibusError, match=r"data row 2, column v: '1_5' is not a number"):
        replay.read_csv_log(log)


# --- CAN logs -------------------------------------------------------------------------------

ASC_HEAD = ("date Thu Dec 3 10:00:00.000 am 2026\nbase hex  timestamps absolute\n"
            "no internal events logged\nBegin Triggerblock Thu Dec 3 10:00:00.000 am 2026\n")


def _asc(path, stamps, ident="101"):
    body = "".join(f"   {t} 1  {ident}             Rx   d 4 00 00 00 00\n" for t in stamps)
    path.write_text(ASC_HEAD + body + "End TriggerBlock\n")
    return path


def test_garbage_blf_is_an_error_naming_the_file(tmp_path):
    """The probe: a traceback (BLFParseError raised outside the try)."""
    f = tmp_path / "bad.blf"
    f.write_bytes(b"garbage, not a BLF file " * 20)
    with pytest.raises(ArtibusError, match=r"bad\.blf: cannot read the log at frame 1"):
        logs.read_log(f)
    r = cli("replay", str(f), "--bench", "Bus36m_Circle_CAN", cwd=tmp_path)
    assert "bad.blf" in one_line_error(r)


def test_asc_time_going_backwards_is_an_error_naming_the_frame(tmp_path):
    f = _asc(tmp_path / "back.asc", ["0.010000", "0.020000", "0.015000"])
    with pytest.raises(ArtibusError, match=r"back\.asc: frame 3 \(ID 0x101\): time 0\.015000 s is before"):
        logs.read_log(f)


@pytest.mark.parametrize("stamp", ["nan", "inf"])
def test_asc_non_finite_stamp_is_an_error(tmp_path, stamp):
    """python-can skips such a line without a word (the probe: replayed silently).
    (-0.5 after 0.01 is time going back, said as such: test_reliability_round4.py)"""
    f = _asc(tmp_path / "nan.asc", ["0.010000", stamp])
    with pytest.raises(ArtibusError, match=rf"nan\.asc, line 6: time stamp '{stamp}' is not a finite number"):
        logs.read_log(f)


def test_unknown_identifiers_are_counted(tmp_path):
    f = _asc(tmp_path / "u.asc", ["0.010000", "0.020000", "0.030000"], ident="7FF")
    unknown = {}
    assert logs.decode_log(f, DBC, unknown) == []
    assert unknown == {0x7FF: 3}


def test_a_log_ending_before_the_stop_time_is_reported(tmp_path):
    from artibus.can import replay
    log = ROOT / "ssp" / "logs" / "Urbino18_test.csv"
    t_end = replay.read_csv_log(log)["v1_tacho_mps"].time[-1]
    rep = replay.replay(log, "Urbino18_Replay", stop_time=t_end + 1.0)
    assert any("the log ends at" in w and "before the stop time" in w for w in rep.warnings), rep.warnings
    assert not replay.replay(log, "Urbino18_Replay").warnings


# --- sweeps ---------------------------------------------------------------------------------

def test_a_second_sweep_into_the_folder_is_refused_naming_the_first(tmp_path):
    """The probe: two sweeps into one folder; the second died, its table lost."""
    import artibus
    from artibus.study.sweep.store import FolderLock
    out = tmp_path / "s"
    out.mkdir()
    with FolderLock(out):
        with pytest.raises(ArtibusError, match=f"another sweep \\(PID {os.getpid()}\\)"):
            artibus.sweep("Bus36m_Circle", grid={"Driver.vSet": "3,5"}, out=out, progress=None, plot=False)
    with FolderLock(out):          # released: taken again
        pass


def test_an_unreadable_case_file_is_run_again(tmp_path):
    from artibus.study.sweep.store import assemble, read_case, _write_bytes, _parquet_bytes, _table
    f = tmp_path / "k.parquet"
    _write_bytes(_parquet_bytes(_table([{"key": "k", "case": 0, "status": "ok", "error": "", "wall_s": 1.0}])), f)
    assert read_case(f)["status"] == "ok"
    f.write_bytes(f.read_bytes()[:40])                   # torn
    assert read_case(f) is None
    f.write_bytes(b"PAR1" + b"\0" * 100 + b"PAR1")        # corrupt
    assert read_case(f) is None


class _FullDisk:
    """os, whose write fails with ENOSPC after ``after`` bytes"""

    def __init__(self, after=0):
        self.after = after

    def __getattr__(self, name):
        return getattr(os, name)

    def write(self, fd, data):
        if self.after <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        n = min(len(data), self.after)
        self.after -= n
        return os.write(fd, bytes(data[:n]))


def test_a_full_disk_is_one_error_naming_the_file_and_nothing_half_written(tmp_path, monkeypatch):
    from artibus.study.sweep import store
    monkeypatch.setattr(store, "os", _FullDisk(after=10))
    f = tmp_path / "cases" / "abc.parquet"
    f.parent.mkdir()
    with pytest.raises(ArtibusError, match=r"abc\.parquet: no space left on device"):
        store._write_bytes(b"x" * 1000, f)
    assert not list(f.parent.iterdir())                    # no .part, no torn file


@pytest.mark.slow
def test_a_sweep_onto_a_full_disk_and_a_corrupt_case_on_resume(tmp_path, monkeypatch):
    import artibus
    from artibus.study.sweep import store
    kw = dict(grid={"Driver.vSet": "3,5"}, fixed={"Driver.roadBefore": 2.0}, stop_time=1.0, progress=None,
              plot=False, workers=1)
    out = tmp_path / "s"
    monkeypatch.setattr(store, "os", _FullDisk(after=16))      # the lock's PID, then the disk is full
    with pytest.raises(ArtibusError, match=r"cases/\w+\.parquet: no space left on device"):
        artibus.sweep("Bus36m_Circle", out=out, **kw)
    monkeypatch.undo()
    assert not [p for p in out.rglob("*") if p.name.endswith(".part")]
    first = artibus.sweep("Bus36m_Circle", out=out, **kw)
    assert first.ran == 2
    case = sorted((out / "cases").iterdir())[0]
    case.write_bytes(b"garbage")
    again = artibus.sweep("Bus36m_Circle", out=out, **kw)
    assert again.ran == 1 and again.table.num_rows == 2


# --- archives -------------------------------------------------------------------------------

def _zip(path, members):
    with zipfile.ZipFile(path, "w") as z:
        for name, data, *mode in members:
            info = zipfile.ZipInfo(name)
            if mode:
                info.external_attr = mode[0] << 16
            z.writestr(info, data)
    return path


@pytest.mark.parametrize("members, words", [
    ([("SystemStructure.ssd", "<a/>"), ("resources", "target", stat.S_IFLNK | 0o777),
      ("resources/x.fmu", "x")], "member 'resources' is a symbolic link"),
    ([("SystemStructure.ssd", "<a/>"), ("SystemStructure.ssd", "<b/>")], "member 'SystemStructure.ssd' is given twice"),
    ([("SystemStructure.ssd", "<a/>"), ("../evil", "x")], "member '../evil' is not a relative path"),
    ([("SystemStructure.ssd", "<a/>"), ("/etc/evil", "x")], "member '/etc/evil' is not a relative path"),
    ([("SystemStructure.ssd", "<a/>"), ("a\\b", "x")], "is not a relative path"),
    ([("SystemStructure.ssd", "<a/>"), ("d", "x"), ("d/e", "y")], "member 'd' is a file and also a folder"),
])
def test_hostile_archive_members_are_refused_naming_them(tmp_path, members, words):
    f = _zip(tmp_path / "b.ssp", members)
    with pytest.raises(ArtibusError, match=words.replace("(", r"\(").replace(".", r"\.")):
        ssp.read(f)
    with pytest.raises(ArtibusError, match=r"b\.ssp"):
        files.extract_archive(f)


def test_an_ssp_with_two_system_structures_is_refused(tmp_path):
    """The probe: the last of two SystemStructure.ssd silently won."""
    src = ssp.ssp_path("Bus36m_Circle")
    out = tmp_path / "two.ssp"
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w") as b:
        for n in a.namelist():
            b.writestr(n, a.read(n))
        b.writestr("SystemStructure.ssd", a.read("SystemStructure.ssd").replace(b"Circle", b"Other"))
    with pytest.raises(ArtibusError, match="SystemStructure.ssd' is given twice"):
        ssp.read(out)


def test_size_and_member_count_are_limited_before_extraction(tmp_path, monkeypatch):
    bomb = tmp_path / "bomb.ssp"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", "<a/>")
        z.writestr("resources/zeros.bin", b"\0" * (3 * 2 ** 20))       # 3 MiB of zeros, a few kB packed
    monkeypatch.setenv("ARTIBUS_MAX_UNPACKED_MB", "2")
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", None)
    with pytest.raises(ArtibusError, match=r"more than the limit of 2 MiB .*resources/zeros\.bin"):
        files.extract_archive(bomb)
    assert not list((tmp_path / "tmp").iterdir())          # checked before anything was unpacked
    monkeypatch.setenv("ARTIBUS_MAX_UNPACKED_MB", "4")
    d = files.extract_archive(bomb)
    assert (d / "resources" / "zeros.bin").stat().st_size == 3 * 2 ** 20
    monkeypatch.setenv("ARTIBUS_MAX_MEMBERS", "1")
    with pytest.raises(ArtibusError, match="2 members, more than the limit of 1"):
        files.extract_archive(bomb)
    monkeypatch.setenv("ARTIBUS_MAX_MEMBERS", "x")
    with pytest.raises(ArtibusError, match="ARTIBUS_MAX_MEMBERS"):
        files.extract_archive(bomb)


@pytest.mark.parametrize("cache_mb", ["500", "0"])
def test_a_full_temporary_disk_leaves_no_folder(tmp_path, monkeypatch, cache_mb):
    """The probe: ENOSPC from extractall (a traceback) and folders of up to 61 MB left.
    Unpacked into a new cache (artibus.cache) or, with the cache off, a temporary folder."""
    import tempfile
    (tmp_path / "tmp").mkdir()
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    monkeypatch.setenv("ARTIBUS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("ARTIBUS_CACHE_MB", cache_mb)
    monkeypatch.setattr(tempfile, "tempdir", None)

    def full(self, *a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(zipfile.ZipFile, "extractall", full)
    with pytest.raises(ArtibusError, match="no space left on device while unpacking"):
        Fmu(fmu_path("TypesTest"))
    with pytest.raises(ArtibusError, match="no space left on device while unpacking"):
        from artibus.runner import Simulation
        Simulation(ssp.ssp_path("Bus36m_Circle"))
    assert not list((tmp_path / "tmp").iterdir())
    assert not [p for p in (tmp_path / "cache").rglob("*") if p.is_dir() and p.name != "unpacked"]


def test_an_fmu_with_a_symlink_member_is_refused(tmp_path):
    src = fmu_path("TypesTest")
    out = tmp_path / "TypesTest.fmu"
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w") as b:
        for n in a.namelist():
            b.writestr(n, a.read(n))
        info = zipfile.ZipInfo("resources/link")
        info.external_attr = (stat.S_IFLNK | 0o777) << 16
        b.writestr(info, "/etc/passwd")
    with pytest.raises(ArtibusError, match="member 'resources/link' is a symbolic link"):
        Fmu(out)


# --- DBC --------------------------------------------------------------------------------------

@pytest.mark.parametrize("old, new, words", [
    ("SG_ ArtAngleG1 : 16|16@1-", "SG_ ArtAngleG1 : 10|16@1-", "ArtAngleG1 and AliveCounter are overlapping"),
    ("BO_ 258 SensorG1_Angle: 4", "BO_ 258 SensorG1_Angle: 3", "ArtAngleG1 does not fit in message SensorG1_Angle"),
    ("BO_ 259 SensorG2_Angle", "BO_ 258 SensorG2_Angle", "SensorG1_Angle and SensorG2_Angle have the same identifier 0x102"),
    ("BO_ 259 SensorG2_Angle", "BO_ 259 SensorG1_Angle", "two messages are named SensorG1_Angle"),
    ('BA_ "E2EDataID" BO_ 258 18;', 'BA_ "E2EDataID" BO_ 258 300;', "E2EDataID"),
    ('BA_ "GenMsgCycleTime" BO_ 258 10;', 'BA_ "GenMsgCycleTime" BO_ 258 0;', "GenMsgCycleTime"),
])
def test_malformed_dbc_is_a_named_error(tmp_path, old, new, words):
    text = DBC.read_text()
    assert old in text
    f = tmp_path / "bad.dbc"
    f.write_text(text.replace(old, new, 1))
    with pytest.raises(ArtibusError, match=r"bad\.dbc") as e:
        load_dbc(f)
    assert words in str(e.value), str(e.value)


def test_a_routed_message_missing_from_the_dbc_is_a_named_error_at_set_up(tmp_path):
    from artibus.runner import Simulation
    src = ssp.ssp_path("Bus36m_GuidedCAN") if "Bus36m_GuidedCAN" in ssp.bench_names() else None
    if src is None:
        can_benches = [b for b in ssp.bench_names() if ssp.read(ssp.ssp_path(b)).can is not None]
        src = ssp.ssp_path(can_benches[0])
    b = ssp.read(src)
    out = tmp_path / "nomsg.ssp"
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(out, "w") as z:
        for n in a.namelist():
            data = a.read(n)
            if n == b.can["source"]:
                data = data.replace(b"BO_ 258 SensorG1_Angle", b"BO_ 258 SensorG1_Angel")
                data = data.replace(b"SG_ 258 ", b"SG_ 258 ")
            z.writestr(n, data)
    with pytest.raises(ArtibusError, match="has no message 'SensorG1_Angle'"):
        Simulation(out)


def test_simulate_refuses_results_that_cannot_fit_in_memory():
    """The probe: `simulate`, unlike `run`, started a run whose table could not fit."""
    from artibus.fmu import simulate
    with pytest.raises(ArtibusError, match="more than half the memory available"):
        simulate(fmu_path("TypesTest"), stop_time=1e13, step=1e-3)
