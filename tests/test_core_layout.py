"""Issue 37: one declaration of the stepping core's structs.

The ctypes structures of artibus.runner are built from the library's own table
(src/runner_core/gen_layout.py reads core.h, lsbus.h and me.h). These tests hold that
table and the classes made from it to a reading that shares nothing with the
generator: the compiler's debugging information (DWARF, read with binutils'
readelf) of a translation unit that includes the headers. A field the generator
missed, misread or misplaced, or a ctypes class that lays a field elsewhere,
fails here by name.
"""
import re
import shutil
import subprocess
from ctypes import sizeof

import pytest

from artibus.runner import corelib, layout
from tests.conftest import ROOT

HEADERS = [ROOT / "src/runner_core/core.h", ROOT / "src/runner_core/lsbus.h", ROOT / "src/runner_core/me.h"]
INCLUDES = [ROOT / "src/runner_core", ROOT / "include/fmi2", ROOT / "include/fmi3"]

pytestmark = pytest.mark.skipif(not corelib.core_library_path().is_file() or shutil.which("readelf") is None,
                                reason="the C core is not built, or no readelf")


def dwarf_structs(tmp_path):
    """{typedef name: (size, [(member, offset, size)])} of every struct the headers
    typedef, from gcc -g's DWARF as readelf prints it."""
    names = sorted({m for h in HEADERS for m in re.findall(r"\}\s*(ac_\w+)\s*;", h.read_text())})
    src = tmp_path / "probe.c"
    src.write_text('#include "core.h"\n#include "me.h"\n' + "".join(f"{n} probe_{n};\n" for n in names))
    obj = tmp_path / "probe.o"
    subprocess.run(["gcc", "-std=c11", "-g", "-gdwarf-4", "-c", str(src), "-o", str(obj)]
                   + [f"-I{d}" for d in INCLUDES], check=True)
    dump = subprocess.run(["readelf", "--debug-dump=info", str(obj)], check=True,
                          capture_output=True, text=True).stdout
    dies = _dies(dump)
    out = {}
    for d in dies.values():
        if d["tag"] == "DW_TAG_typedef" and d.get("DW_AT_name") in names:
            st = dies[d["DW_AT_type"]]
            if st["tag"] != "DW_TAG_structure_type":
                continue
            members = [(m["DW_AT_name"], int(m["DW_AT_data_member_location"]), _size(dies, m["DW_AT_type"]))
                       for m in st["children"] if m["tag"] == "DW_TAG_member"]
            out[d["DW_AT_name"]] = (int(st["DW_AT_byte_size"]), members)
    return out


def _dies(dump):
    """readelf's debugging entries: {offset: {"tag", attributes, "children"}}."""
    dies, stack = {}, []
    for line in dump.splitlines():
        m = re.match(r"\s*<(\d+)><([0-9a-f]+)>: Abbrev Number: \d+ \((DW_TAG_\w+)\)", line)
        if m:
            depth, off = int(m.group(1)), f"<0x{m.group(2)}>"
            die = {"tag": m.group(3), "children": []}
            dies[off] = die
            del stack[depth:]
            if stack:
                stack[-1]["children"].append(die)
            stack.append(die)
            continue
        a = re.match(r"\s*<[0-9a-f]+>\s+(DW_AT_\w+)\s*:\s*(.*)$", line)
        if a and stack:
            value = a.group(2).strip()
            if a.group(1) == "DW_AT_name":
                value = value.split(":")[-1].strip()        # "(indirect string, offset: 0x..): name"
            stack[-1][a.group(1)] = value
    return dies


def _size(dies, ref):
    """The byte size of the type at ref (through typedefs and qualifiers; arrays by their bounds)."""
    d = dies[ref]
    if "DW_AT_byte_size" in d:
        return int(d["DW_AT_byte_size"])
    if d["tag"] == "DW_TAG_array_type":               # its subrange: DW_AT_count, or DW_AT_upper_bound + 1
        n = 1
        for sub in d["children"]:
            n *= int(sub["DW_AT_count"]) if "DW_AT_count" in sub else int(sub["DW_AT_upper_bound"]) + 1
        return _size(dies, d["DW_AT_type"]) * n
    return _size(dies, d["DW_AT_type"])


@pytest.fixture(scope="module")
def library_structs():
    lib, why = corelib.load()
    assert lib is not None, why
    return layout.structs(lib)


def test_every_struct_of_the_headers_is_in_the_library_with_the_compilers_layout(tmp_path, library_structs):
    dwarf = dwarf_structs(tmp_path)
    assert len(dwarf) >= 15, sorted(dwarf)            # ac_source .. ac_settle, ac_ls_terminal .. ac_lsbus
    assert sorted(library_structs) == sorted(dwarf)
    for name, (size, members) in dwarf.items():
        cls = library_structs[name]
        assert sizeof(cls) == size, name
        assert [f for f, _ in cls._fields_] == [m for m, _, _ in members], name
        for member, offset, msize in members:
            got = getattr(cls, member)
            assert (name, member, got.offset, got.size) == (name, member, offset, msize)


def test_a_table_ctypes_cannot_reproduce_is_refused_by_field(monkeypatch, library_structs):
    """A library whose table puts a field elsewhere than ctypes would (an older or
    foreign build, a packed struct): refused, naming the struct and field."""
    lib, _ = corelib.load()
    real = layout.rows(lib)
    moved = [(s, f, k, o + 4 if (s, f) == ("ac_unit", "step") else o, n) for s, f, k, o, n in real]
    monkeypatch.setattr(layout, "rows", lambda _: moved)
    with pytest.raises(layout.LayoutError, match=r"ac_unit\.step: the library has it at offset \d+"):
        layout.structs(lib)


def test_the_generator_names_a_type_it_does_not_know(tmp_path):
    """A field of a type gen_layout.py has no kind for stops the build with the header's line."""
    h = tmp_path / "x.h"
    h.write_text("/* a */\ntypedef struct {\n    double a;\n    float b;\n} ac_x;\n")
    r = subprocess.run(["python3", str(ROOT / "src/runner_core/gen_layout.py"), str(tmp_path / "x.c"), str(h)],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "x.h:4: the type 'float' of 'b'" in r.stderr, r.stderr
