"""artibus.runner.markers, the hook the tests that interrupt a run wait on (issue 41):
a line per event on the descriptor given, a byte awaited after it when asked, and
nothing from a process that has another file under that descriptor's number."""
import os

import pytest

from artibus import ArtibusError
from artibus.runner import markers


@pytest.fixture
def pipes(monkeypatch):
    """(marks read end, go write end, go read end) with ARTIBUS_PROGRESS_FD and
    ARTIBUS_PROGRESS_WAIT_FD naming the marks' write end and the go read end."""
    marks, mark_w = os.pipe()
    go_r, go_w = os.pipe()
    monkeypatch.setenv("ARTIBUS_PROGRESS_FD", f"{mark_w}:{os.fstat(mark_w).st_ino}")
    monkeypatch.setenv("ARTIBUS_PROGRESS_WAIT_FD", f"{go_r}:{os.fstat(go_r).st_ino}")
    monkeypatch.setattr(markers, "_broken", set())
    monkeypatch.setattr(markers, "_checked", {})
    yield marks, go_w, go_r
    for fd in (marks, mark_w, go_r, go_w):
        try:
            os.close(fd)
        except OSError:
            pass


def test_a_line_per_event_then_the_byte_awaited(pipes):
    marks, go, go_r = pipes
    os.write(go, b"ggg")                             # three bytes, two events
    markers.mark("t=250.0")
    markers.mark("saving /x/r.csv")
    assert os.read(marks, 100) == b"t=250.0\nsaving /x/r.csv\n"
    assert os.read(go_r, 100) == b"g"                # a byte taken per event
    os.close(go)                                     # the test gone: end of file, no more waiting
    markers.mark("case k")
    assert os.read(marks, 100) == b"case k\n"


def test_another_file_under_the_number_gets_nothing(pipes, monkeypatch, tmp_path):
    """A worker the run starts inherits the environment, not the descriptor: what
    it has under that number (here a file) is not written to, and it does not wait."""
    marks, _, _ = pipes
    fd = os.open(tmp_path / "other", os.O_WRONLY | os.O_CREAT)
    try:
        monkeypatch.setenv("ARTIBUS_PROGRESS_FD", f"{fd}:{os.fstat(marks).st_ino}")   # the pipe's inode
        markers.mark("t=1.0")
    finally:
        os.close(fd)
    assert (tmp_path / "other").read_bytes() == b""


def test_off_without_the_variable(monkeypatch):
    monkeypatch.delenv("ARTIBUS_PROGRESS_FD", raising=False)
    markers.mark("t=1.0")                            # nothing to write to: nothing happens


def test_a_bad_value_names_the_variable(monkeypatch):
    monkeypatch.setattr(markers, "_checked", {})
    monkeypatch.setenv("ARTIBUS_PROGRESS_FD", "5")
    with pytest.raises(ArtibusError, match=r"ARTIBUS_PROGRESS_FD='5': expected FD:INODE"):
        markers.mark("t=1.0")
