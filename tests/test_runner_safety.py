"""Nothing lost (issue 15): atomic writes, a full disk, SIGINT/SIGTERM while
simulating and while writing, concurrent runs of a stale bench, a bounded
step plan, output paths checked before the run."""
import errno
import os

import pytest

from artibus import ArtibusError
from artibus.files import atomic_path, atomic_write, check_output


def test_atomic_write_keeps_old_file_on_interrupt(tmp_path):
    """An interrupted write leaves the previous file, whole, and no temporary file."""
    out = tmp_path / "r.csv"
    with atomic_write(out) as f:
        f.write("old\n")
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(out) as f:
            f.write("half of the new")
            raise KeyboardInterrupt
    assert out.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_atomic_path_keeps_suffix_and_renames(tmp_path):
    out = tmp_path / "plot.png"
    with atomic_path(out) as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path and not out.exists()
        tmp.write_bytes(b"png")
    assert out.read_bytes() == b"png" and len(list(tmp_path.iterdir())) == 1


def test_full_disk_is_one_error_and_no_torn_file(tmp_path, monkeypatch):
    """ENOSPC midway through a write: no file under the final name, an ArtibusError naming it."""
    out = tmp_path / "r.csv"

    class Full:
        def __init__(self, f):
            self.f, self.n = f, 0

        def write(self, s):
            self.n += len(s)
            if self.n > 10:
                raise OSError(errno.ENOSPC, "No space left on device")
            return self.f.write(s)

    with pytest.raises(ArtibusError, match="no space left on device"):
        with atomic_write(out) as f:
            full = Full(f)
            for _ in range(10):
                full.write("0123456789\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where", ["dir", "missing", "readonly"])
def test_check_output_refuses_bad_places(tmp_path, where):
    path = {"dir": tmp_path, "missing": tmp_path / "no" / "r.csv", "readonly": "/proc/r.csv"}[where]
    with pytest.raises(ArtibusError, match="-o"):
        check_output(path)
    check_output(tmp_path / "r.csv")
    assert list(tmp_path.iterdir()) == []
