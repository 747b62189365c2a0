"""Issue 41, classes 1 and 2: an output never replaces an input, and a report
folder is written whole or not at all.

1. Every output a command writes (-o, --report, pack --portable -o, a sweep's
   folder, --csv) is checked against the run's inputs by identity before
   anything runs: the same file under its own name, another spelling, a
   symbolic link, a hard link, a folder link, or (for a report, which replaces
   its folder whole) a folder holding an input is refused with one line naming
   the input; the input's bytes are unchanged.
2. `artibus run BENCH --report DIR` over an earlier report, interrupted by
   SIGINT or SIGTERM at 20 moments the run reports (its lines on stdout, each
   file appearing in the report's new folder): DIR holds exactly the earlier
   report or a complete new one, never a mix, and the message says which.
"""
import contextlib
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from artibus import fmu_dir
from artibus.base import ROOT
from artibus.cli import main

BENCH = "Urbino18_Circle"              # BusKinematics + RoadFollowDriver
SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="p">
  <ssv:Parameters>
    <ssv:Parameter name="Driver.vSet"><ssv:Real value="3.0"/></ssv:Parameter>
  </ssv:Parameters>
</ssv:ParameterSet>
"""


@pytest.fixture
def world(tmp_path, monkeypatch):
    """A private FMU folder (the bench's two FMUs, another bench's pack) as
    $ARTIBUS_FMU_DIR, so that a check that fails replaces copies, never the
    repository's files; work/: the bench's pack as X.ssp, a parameter file,
    the replay log; the working directory."""
    fmus, work = tmp_path / "fmus", tmp_path / "work"
    fmus.mkdir()
    work.mkdir()
    for f in ("BusKinematics.fmu", "RoadFollowDriver.fmu", "Scania18m_OpenLoop.ssp", f"{BENCH}.ssp"):
        shutil.copy(fmu_dir() / f, fmus / f)          # (the pack newer than its sources: not packed again)
    shutil.copy(fmu_dir() / f"{BENCH}.ssp", work / "X.ssp")
    (work / "p.ssv").write_text(SSV)
    for f in ("log.csv", "drive.units.csv"):
        shutil.copy(ROOT / "ssp" / "logs" / "Urbino18_test.csv", work / f)
    monkeypatch.setenv("ARTIBUS_FMU_DIR", str(fmus))
    monkeypatch.chdir(work)
    return tmp_path


def _link(world, kind):
    """work/link.csv: a symbolic or hard link to X.ssp; work/res.units.csv: a hard
    link to X.ssp; dirlink: a link to work/; work/index.html: an earlier report's page."""
    w = world / "work"
    if kind == "symlink":
        (w / "link.csv").symlink_to(w / "X.ssp")
    elif kind == "hardlink":
        os.link(w / "X.ssp", w / "link.csv")
    elif kind == "dirlink":
        (world / "dirlink").symlink_to(w)
    elif kind == "sidecar":           # where -o work/res.csv puts its units
        os.link(w / "X.ssp", w / "res.units.csv")
    elif kind == "report":            # an earlier report's folder that holds the bench
        (w / "index.html").write_text("<html></html>")


# (id, links to make, the command, the input it names (relative to the test's folder))
CASES = [
    ("bench-by-path", None, ["run", "work/X.ssp", "-o", "work/X.ssp"], "work/X.ssp"),
    ("bench-other-spelling", None, ["run", "work/X.ssp", "-o", "work/../work/./X.ssp"], "work/X.ssp"),
    ("bench-symlink", "symlink", ["run", "work/X.ssp", "-o", "work/link.csv"], "work/X.ssp"),
    ("bench-hardlink", "hardlink", ["run", "work/X.ssp", "-o", "work/link.csv"], "work/X.ssp"),
    ("bench-through-folder-link", "dirlink", ["run", "work/X.ssp", "-o", "dirlink/X.ssp"], "work/X.ssp"),
    ("its-fmu", None, ["run", BENCH, "-o", "fmus/BusKinematics.fmu"], "fmus/BusKinematics.fmu"),
    ("runner-pack-of-bench", None, ["run", BENCH, "--stop-time", "1", "-o", f"fmus/{BENCH}.ssp"], f"fmus/{BENCH}.ssp"),
    ("runner-pack-other", None, ["run", BENCH, "-o", "fmus/Scania18m_OpenLoop.ssp"], "fmus/Scania18m_OpenLoop.ssp"),
    ("ssv", None, ["run", "work/X.ssp", "--ssv", "work/p.ssv", "-o", "work/p.ssv"], "work/p.ssv"),
    ("report-holds-bench", "report", ["run", "work/X.ssp", "--stop-time", "1", "--report", "work"], "work/X.ssp"),
    ("report-link-holds-bench", ("report", "dirlink"),
     ["run", "work/X.ssp", "--stop-time", "1", "--report", "dirlink"], "work/X.ssp"),
    ("units-sidecar", "sidecar", ["run", "work/X.ssp", "-o", "work/res.csv"], "work/X.ssp"),
    ("replay-sidecar-onto-log", None, ["replay", "work/drive.units.csv", "--bench", "Urbino18_Replay",
                                       "--stop-time", "2", "-o", "work/drive.csv"], "work/drive.units.csv"),
    ("pack-portable-onto-runner-pack", None, ["pack", "--portable", BENCH, "-o", f"fmus/{BENCH}.ssp"],
     f"fmus/{BENCH}.ssp"),
    ("pack-portable-onto-itself", None, ["pack", "--portable", "work/X.ssp", "-o", "work/X.ssp"], "work/X.ssp"),
    ("simulate-onto-fmu", None, ["simulate", "fmus/BusKinematics.fmu", "--stop-time", "1", "-o",
                                 "fmus/BusKinematics.fmu"], "fmus/BusKinematics.fmu"),
    ("replay-onto-log", None, ["replay", "work/log.csv", "--bench", "Urbino18_Replay", "--stop-time", "2",
                               "-o", "work/log.csv"], "work/log.csv"),
    ("sweep-folder-is-bench", None, ["sweep", "work/X.ssp", "--grid", "Driver.vSet=2,3", "--workers", "1",
                                     "-o", "work/X.ssp"], "work/X.ssp"),
]


@pytest.mark.parametrize("links,argv,victim", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_output_onto_an_input_is_refused(world, capsys, links, argv, victim):
    """Each output onto an input of the run: exit 1 before anything runs, one
    line naming the input file, and the input byte for byte as it was."""
    for kind in (links if isinstance(links, tuple) else (links,)):
        _link(world, kind)
    victim = world / victim
    before = victim.read_bytes()
    argv = [a if not a.startswith(("work", "fmus", "dirlink")) else str(world / a) for a in argv]
    rc = main(argv)
    err = capsys.readouterr().err
    assert victim.read_bytes() == before, f"{victim} was replaced"
    assert rc == 1 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("artibus: error: ") and victim.name in err and "choose another" in err, err
    assert not [p for p in victim.parent.iterdir() if ".tmp-" in p.name or p.name.endswith(".partial.csv")]


def test_outputs_that_are_not_inputs_are_written(world, capsys):
    """The check refuses inputs only: a new name beside the bench, an earlier
    report's folder (index.html) without inputs, and -o inside the report."""
    w = world / "work"
    assert main(["run", str(w / "X.ssp"), "--stop-time", "0.5", "-o", str(w / "new.csv")]) == 0
    assert (w / "new.csv").read_text().startswith('"time",')
    rep = world / "rep"
    rep.mkdir()
    (rep / "index.html").write_text("an earlier report")
    assert main(["run", str(w / "X.ssp"), "--stop-time", "0.5", "--report", str(rep),
                 "-o", str(rep / "mine.csv")]) == 0, capsys.readouterr().err
    assert (rep / "mine.csv").read_text().startswith('"time",') and "an earlier report" not in (rep / "index.html").read_text()
    assert not (rep / "results.csv").exists()


def test_report_folder_with_other_files_is_refused(world, capsys):
    """A report replaces its folder whole: a folder with files and no index.html
    (not an earlier report) is refused, its files left."""
    d = world / "mine"
    d.mkdir()
    (d / "notes.txt").write_text("mine")
    assert main(["run", str(world / "work" / "X.ssp"), "--stop-time", "0.5", "--report", str(d)]) == 1
    err = capsys.readouterr().err
    assert "notes.txt" in err and "not a report" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in d.iterdir()) == ["notes.txt"]


# ---- 2: a report is written whole or not at all --------------------------------------

def _report(argv, cwd):
    r = subprocess.run([sys.executable, "-m", "artibus", *argv], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, r.stderr
    return r


def _files(d):
    return {p.relative_to(d).as_posix(): p.read_bytes() for p in sorted(Path(d).rglob("*")) if p.is_file()}


def _state(d, old, new):
    """"old" when ``d`` holds exactly the earlier report's files (bytes), "new" when
    it holds every file of a complete new report with none of the earlier one's
    (each file differs from the earlier report's where the two reports differ,
    results.csv and kpis.csv are the new run's); else a description of the mix."""
    got = _files(d)
    if got == old:
        return "old"
    if set(got) != set(new):
        return f"mixed: files {sorted(set(got) ^ set(new))} differ from a new report's"
    stale = [f for f in got if got[f] == old.get(f) and new[f] != old.get(f)]
    wrong = [f for f in ("results.csv", "results.units.csv", "kpis.csv") if got[f] != new[f]]
    return "new" if not stale and not wrong else f"mixed: earlier {stale}, not the new run's {wrong}"


class _Lines:
    """A process's stdout lines, read as they come (a thread), for events."""

    def __init__(self, stream):
        self.lines = []
        self.thread = threading.Thread(target=lambda: self.lines.extend(iter(stream.readline, "")), daemon=True)
        self.thread.start()


def _wait_event(proc, lines, report, moment):
    """Poll until ``moment`` happened: ("line", k) k lines printed on stdout,
    ("text", s) a line with s printed, ("file", k) k + 1 names seen: the
    report's new folder (REPORT.tmp-*) and the files appearing in it, and the
    temporary files appearing in REPORT itself. False if the process ended first."""
    kind, k = moment
    seen = set()
    while proc.poll() is None:
        if kind == "line" and len(lines.lines) >= k or kind == "text" and any(k in ln for ln in lines.lines):
            return True
        if kind == "file":
            for t in report.parent.glob(f"{report.name}.tmp-*"):
                seen.add(t.name)
                with contextlib.suppress(OSError):
                    seen.update(f"{t.name}/{n}" for n in os.listdir(t))
            with contextlib.suppress(OSError):
                seen.update(n for n in os.listdir(report) if ".tmp-" in n)
            if len(seen) >= k + 1:
                return True
        time.sleep(0.0005)         # a poll of the event, not a wait for a state
    return False


@pytest.mark.slow
def test_interrupted_report_is_the_old_one_or_the_new_one(tmp_path):
    """SIGINT/SIGTERM at 20 moments of `run --report DIR` over an earlier report
    (stop time 1 s; the new run 2 s): DIR is exactly the earlier report or a
    complete new one; the message says which; a finished run's results are
    kept beside DIR (DIR.csv); no temporary folder is left."""
    ref, d, kept = tmp_path / "ref", tmp_path / "rep", tmp_path / "earlier"
    _report(["run", BENCH, "--stop-time", "1", "--report", str(kept)], tmp_path)
    old = _files(kept)
    _report(["run", BENCH, "--stop-time", "2", "--report", str(ref)], tmp_path)
    new = _files(ref)
    assert set(old) == set(new) and old["results.csv"] != new["results.csv"]
    moments = ([("line", 1), ("line", 2)] + [("file", k) for k in range(0, 17)] + [("text", ": report ")])
    outcomes = []
    for i, moment in enumerate(moments):
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(kept, d)                       # the earlier report, byte for byte
        sig = (signal.SIGINT, signal.SIGTERM)[i % 2]
        proc = subprocess.Popen([sys.executable, "-m", "artibus", "run", BENCH, "--stop-time", "2", "--report", str(d)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                                env={**os.environ, "PYTHONUNBUFFERED": "1"})
        lines = _Lines(proc.stdout)
        if _wait_event(proc, lines, d, moment):
            proc.send_signal(sig)
        err = proc.stderr.read()
        proc.wait(timeout=120)
        lines.thread.join(timeout=10)
        state = _state(d, old, new)
        outcomes.append((moment, proc.returncode, state))
        assert state in ("old", "new"), (moment, state, err)
        assert "Traceback" not in err, err
        if proc.returncode in (0, -sig):        # done; or the signal came after the command line's handlers
            assert state == "new" and (proc.returncode == 0 or not err), (moment, err)
        else:
            assert proc.returncode == 128 + sig and len(err.strip().splitlines()) == 1, (moment, err)
            assert err.startswith(f"artibus: stopped by {sig.name}; "), err
            said = "old" if f"the earlier report in {d} is kept as it was" in err else \
                "new" if f"the report in {d} is complete" in err else None
            assert said == state, (moment, err, state)
            if said == "old" and "results are complete in" in err:     # the finished run's, kept beside DIR
                assert (tmp_path / "rep.csv").read_bytes() == new["results.csv"], err
        assert not list(tmp_path.glob("rep.tmp-*")) and not list(tmp_path.glob("rep.old*")), moment
        for f in ("rep.csv", "rep.units.csv", "rep.partial.csv", "rep.partial.units.csv"):
            (tmp_path / f).unlink(missing_ok=True)
    print("outcomes:", outcomes)
    assert sum(1 for _, rc, _ in outcomes if rc != 0) >= 10, outcomes   # most trials were interrupted


def test_a_swap_that_fails_restores_the_earlier_report(tmp_path, monkeypatch):
    """Where the folders cannot be exchanged in one step and the new folder
    cannot take the name, the earlier report is renamed back: one error, the
    earlier files as they were, no temporary folder left."""
    from artibus import files
    from artibus.base import ArtibusError
    d = tmp_path / "rep"
    d.mkdir()
    (d / "index.html").write_text("earlier")
    rename = os.rename

    def failing(a, b):
        if ".tmp-" in Path(a).name and not Path(a).name.startswith("rep.old"):
            raise OSError(28, "No space left on device")
        rename(a, b)
    monkeypatch.setattr(files, "_exchange", lambda a, b: False)
    monkeypatch.setattr(os, "rename", failing)
    with pytest.raises(ArtibusError, match="the earlier one is kept"):
        with files.atomic_dir(d) as tmp:
            (tmp / "index.html").write_text("new")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"] and (d / "index.html").read_text() == "earlier"


def test_an_interrupt_in_the_block_keeps_the_earlier_report(tmp_path):
    """KeyboardInterrupt while the new report is written: the earlier report as
    it was, e.report says so (the command line's message), no temporary folder."""
    from artibus import files
    d = tmp_path / "rep"
    d.mkdir()
    (d / "index.html").write_text("earlier")
    with pytest.raises(KeyboardInterrupt) as e:
        with files.atomic_dir(d) as tmp:
            (tmp / "index.html").write_text("new")
            raise KeyboardInterrupt
    assert e.value.report == (d, "kept")
    assert files.report_said(e.value, "nothing written") == f"nothing written; the earlier report in {d} is kept as it was"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"] and (d / "index.html").read_text() == "earlier"
