"""Packs written (``write_pack``: an .ssd and its files zipped into an .ssp, whole or not at all)
and an unpacked SSP run as it is (``pack_unpacked``: a folder holding SystemStructure.ssd, or an
.ssd file, packed into a temporary .ssp of this process; issue 40)."""
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError
from artibus.bench.ssd import NS, _UNPACKED


def write_pack(out, ssd_file, files):
    """The pack ``out``: the .ssd ``ssd_file`` as SystemStructure.ssd and ``files`` {name in the
    archive: path}, written whole or not at all."""
    from artibus.files import atomic_path
    out.parent.mkdir(parents=True, exist_ok=True)
    # packed under a name of this process's own, then renamed: a run that reads it never
    # sees half a file, and runs packing the same stale bench at once do not collide
    with atomic_path(out, fsync=False) as tmp:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            z.write(ssd_file, "SystemStructure.ssd")
            for ref, path in sorted(files.items()):
                z.write(path, ref)
    return out


def pack_unpacked(p):
    """An unpacked SSP (a folder holding SystemStructure.ssd, or an .ssd file: its folder the SSP's
    root, as libcosim and ecos ship their examples; SSP 1.0 3 "Packaging": the .ssp is that
    folder zipped) packed into an .ssp of this process's temporary folder, again when a file
    changed: that .ssd as SystemStructure.ssd and every file below the folder (dot-files and
    other .ssd files left out). A component whose FMU is not there is an error naming the
    .ssd, the line and the Component."""
    ssd = p / "SystemStructure.ssd" if p.is_dir() else p
    if not ssd.is_file():
        raise ArtibusError(f"{p}: no such file" if not p.is_dir() else
                           f"{p}: no SystemStructure.ssd in it (an unpacked SSP holds one at its root)")
    root = ssd.resolve().parent
    files = {f.relative_to(root).as_posix(): f for f in sorted(root.rglob("*"))
             if f.is_file() and not any(part.startswith(".") for part in f.relative_to(root).parts)
             and not (f.suffix.lower() == ".ssd" and f.parent == root)}
    _components_present(ssd, files)
    import hashlib
    key = hashlib.sha256(str(ssd.resolve()).encode())
    for name, f in files.items():
        key.update(f"{name}\0{f.stat().st_mtime_ns}\0{f.stat().st_size}\0".encode())
    key.update(f"{ssd.stat().st_mtime_ns}".encode())
    out = _unpacked_dir() / key.hexdigest()[:16] / f"{root.name or 'ssp'}.ssp"
    if not out.is_file():
        write_pack(out, ssd, files)
    _UNPACKED[str(out)] = str(ssd)
    return out


def _components_present(ssd, files):
    """An error naming the .ssd, the line and the Component whose source is not among ``files``
    (names relative to the SSP's root)."""
    try:
        tree = etree.parse(str(ssd))
    except etree.XMLSyntaxError as e:
        raise ArtibusError(f"{ssd}: not a readable SSP system structure: {e}") from None
    for c in tree.iter(f"{{{NS['ssd']}}}Component"):
        ref = c.get("source", "")
        if ref and "://" not in ref and ref not in files:
            raise ArtibusError(f"{ssd}:{c.sourceline}: <Component name=\"{c.get('name')}\" source=\"{ref}\">: "
                               f"no such file {ssd.resolve().parent / ref}")


_TEMP = []


def _unpacked_dir():
    """This process's folder of the packs of unpacked SSPs (removed when it exits)."""
    if not _TEMP:
        import atexit
        import shutil
        _TEMP.append(Path(tempfile.mkdtemp(prefix="artibus-ssd-")))
        atexit.register(shutil.rmtree, _TEMP[0], True)
    return _TEMP[0]
