"""Issue 30: benches and FMUs unpacked once, by content (artibus.cache).

What it must be: a run from the cache is the run without it, bit for bit; an
entry is named by the archive's content (a changed pack is a new entry, never
a stale one); runs at once and an interrupted unpacking leave only complete
entries; the size is bounded; ARTIBUS_CACHE_MB=0 switches it off (a temporary
copy per run, removed after it)."""
import os
import time
import zipfile
from pathlib import Path

import pytest

from artibus import cache, fmu_dir
from artibus.bench import ssp
from artibus.fmu import Fmu, instance
from artibus.runner import Simulation

BENCH = "Scania18m_Damping"


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("ARTIBUS_CACHE", str(d))
    monkeypatch.delenv("ARTIBUS_CACHE_MB", raising=False)
    monkeypatch.setattr(instance, "_MDS", {})        # (this process's descriptions read before)
    return d / "unpacked"


def _zip(path, files):
    with zipfile.ZipFile(path, "w") as z:
        for name, text in files.items():
            z.writestr(name, text)
    return path


def _leftovers(base):
    return [p.name for p in base.iterdir() if p.name.startswith(".")] if base.is_dir() else []


def test_a_run_from_the_cache_is_the_run_without_it(cache_dir, monkeypatch):
    def run():
        with Simulation(BENCH) as sim:
            return sim.run().array().copy(), Path(sim._tmp), sim._tmp_owned
    cold, where, owned = run()
    assert not owned and where.parent == cache_dir              # unpacked into the cache
    warm, again, _ = run()
    assert again == where
    monkeypatch.setenv("ARTIBUS_CACHE_MB", "0")
    off, tmp, owned = run()
    assert owned and tmp.parent != cache_dir and not tmp.exists()   # the temporary copy, removed
    assert cold.tobytes() == warm.tobytes() == off.tobytes()
    # the bench and each distinct FMU unpacked once, the FMU's model description kept beside it
    fmus = {c.source for c in ssp.read(ssp.ssp_path(BENCH)).components.values()}
    entries = [e for e in cache_dir.iterdir() if not e.name.startswith(".")]
    described = [e for e in entries if list(e.glob(".artibus-modelDescription-*.pickle"))]
    assert len(entries) == 1 + len(fmus) and len(described) == len(fmus)


def test_an_entry_is_named_by_the_content(cache_dir, tmp_path):
    a = _zip(tmp_path / "a.zip", {"x.txt": "one"})
    first, temporary = cache.unpacked(a)
    assert not temporary and (first / "x.txt").read_text() == "one"
    assert first.name == cache.content_key(a)
    _zip(a, {"x.txt": "two"})                    # the same name and size, another content
    second, _ = cache.unpacked(a)
    assert second != first and (second / "x.txt").read_text() == "two"
    assert (first / "x.txt").read_text() == "one"    # (the other entry as it was)


def test_a_run_at_the_same_time_wins_the_rename(cache_dir, tmp_path, monkeypatch):
    """Two runs unpacking one archive at once: the one renaming second finds the
    first's entry, uses it and removes its own copy."""
    a = _zip(tmp_path / "a.zip", {"x.txt": "one", "d/y.txt": "two"})
    extract = cache.extract

    def racing(archive, dest):
        monkeypatch.setattr(cache, "extract", extract)
        other, _ = cache.unpacked(archive)          # the other run, done while this one extracts
        assert other.is_dir()
        extract(archive, dest)
    monkeypatch.setattr(cache, "extract", racing)
    entry, temporary = cache.unpacked(a)
    assert not temporary and (entry / "d" / "y.txt").read_text() == "two"
    assert [p.name for p in cache_dir.iterdir()] == [entry.name]     # one entry, no copy left


def test_an_interrupted_unpacking_leaves_no_entry(cache_dir, tmp_path, monkeypatch):
    a = _zip(tmp_path / "a.zip", {"x.txt": "one"})

    def interrupted(archive, dest):
        (Path(dest) / "half.txt").write_text("half")
        raise KeyboardInterrupt
    monkeypatch.setattr(cache, "extract", interrupted)
    with pytest.raises(KeyboardInterrupt):
        cache.unpacked(a)
    assert list(cache_dir.iterdir()) == []
    monkeypatch.undo()
    monkeypatch.setenv("ARTIBUS_CACHE", str(cache_dir.parent))
    entry, _ = cache.unpacked(a)
    assert sorted(p.name for p in entry.iterdir()) == ["x.txt"]


def test_the_size_is_bounded(cache_dir, tmp_path, monkeypatch):
    """Above ARTIBUS_CACHE_MB the entries used longest ago go, never one used in
    the last hour (another run may be loading it)."""
    monkeypatch.setenv("ARTIBUS_CACHE_MB", "0.001")          # 1 kB
    old = [cache.unpacked(_zip(tmp_path / f"old{i}.zip", {"x": "x" * 800 + str(i)}))[0] for i in range(3)]
    hours_ago = time.time() - 3 * 3600
    for i, e in enumerate(old):
        os.utime(e, (hours_ago + i, hours_ago + i))          # old0 the one used longest ago
    recent, _ = cache.unpacked(_zip(tmp_path / "recent.zip", {"x": "y" * 800}))
    new, _ = cache.unpacked(_zip(tmp_path / "new.zip", {"x": "z" * 800}))
    left = {p.name for p in cache_dir.iterdir()}
    assert {e.name for e in old} & left == set()              # the old ones removed, oldest first
    assert {recent.name, new.name} <= left                    # used within the hour: kept
    assert _leftovers(cache_dir) == []
    assert cache.clean() == len(left) and list(cache_dir.iterdir()) == []


def test_cache_off(tmp_path, monkeypatch):
    monkeypatch.setenv("ARTIBUS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("ARTIBUS_CACHE_MB", "0")
    f = Fmu(fmu_dir() / "BusKinematics.fmu")
    d = Path(f._dir)
    assert d.is_dir() and f._own_dir
    f.close()
    assert not d.exists() and not (tmp_path / "cache").exists()


def test_a_closed_instance_leaves_the_entry(cache_dir):
    f = Fmu(fmu_dir() / "BusKinematics.fmu")
    g = Fmu(fmu_dir() / "BusKinematics.fmu")               # a second instance: the same entry
    assert f._dir == g._dir and Path(f._dir).parent == cache_dir
    f.close()
    g.close()
    assert (Path(f._dir) / "modelDescription.xml").is_file()
    md = list(Path(f._dir).glob(".artibus-modelDescription-*.pickle"))
    assert len(md) == 1
