"""The stepping core's structs as ctypes structures, built from the library's own
layout table (issue 37: one declaration of the core's structs).

src/runner_core/gen_layout.py reads core.h and lsbus.h at build time and
compiles into the library a table of each struct's fields in declaration order:
name, kind, offset and size, the offsets and sizes the compiler's
(``artibus_core_layout``). ``structs(lib)`` turns that table into ctypes
``Structure`` classes and checks that ctypes lays each field where the
compiler did; a library whose table ctypes cannot reproduce is refused with the
first field that differs. Python declares no struct of its own, so Python and C
cannot disagree, and there is no version number to keep in step by hand.
"""
from ctypes import (POINTER, Structure, c_char, c_char_p, c_double, c_int, c_long, c_longlong, c_size_t,
                    c_ubyte, c_uint, c_ulonglong, c_void_p, sizeof)

#: gen_layout.KINDS' letters -> ctypes types (every pointer is an address: c_void_p)
CTYPES = {"d": c_double, "i": c_int, "I": c_uint, "l": c_long, "q": c_longlong, "Q": c_ulonglong,
          "z": c_size_t, "B": c_ubyte, "c": c_char, "p": c_void_p}


class _Row(Structure):
    """gen_layout.py's ac_layout_row"""
    _fields_ = [("type", c_char_p), ("field", c_char_p), ("kind", c_char), ("offset", c_size_t),
                ("size", c_size_t)]


class LayoutError(Exception):
    """The library's table cannot be reproduced with ctypes (the message says where)."""


def rows(lib):
    """The library's table: [(struct, field, kind, offset, size)], a struct's own row first
    (field "", its size)."""
    f = lib.artibus_core_layout
    f.restype, f.argtypes = POINTER(_Row), []
    table, out = f(), []
    for i in range(10000):
        r = table[i]
        if r.type is None:
            return out
        out.append((r.type.decode(), r.field.decode(), r.kind.decode(), r.offset, r.size))
    raise LayoutError("artibus_core_layout: no end row")


def structs(lib):
    """{struct name: ctypes Structure class} of the library's table, each checked
    field by field (offset, size) and as a whole (size)."""
    fields, size = {}, {}
    for name, field, kind, offset, n in rows(lib):
        if field == "":
            size[name] = n
            fields[name] = []
        else:
            fields[name].append((field, kind, offset, n))
    made = {}
    for name, fs in fields.items():
        cls = type(name, (Structure,), {"_fields_": [(f, _ctype(name, f, k, n)) for f, k, _, n in fs]})
        for f, _, offset, n in fs:
            got = getattr(cls, f)
            if (got.offset, got.size) != (offset, n):
                raise LayoutError(f"{name}.{f}: the library has it at offset {offset} ({n} bytes), "
                                  f"ctypes at {got.offset} ({got.size} bytes)")
        if sizeof(cls) != size[name]:
            raise LayoutError(f"{name}: {size[name]} bytes in the library, {sizeof(cls)} in ctypes")
        made[name] = cls
    return made


def _ctype(struct, field, kind, size):
    """A field's ctypes type: its kind's, or an array of it when its size says so."""
    if kind not in CTYPES:
        raise LayoutError(f"{struct}.{field}: kind '{kind}' unknown to artibus.runner.layout")
    t = CTYPES[kind]
    if size == sizeof(t):
        return t
    if size % sizeof(t):
        raise LayoutError(f"{struct}.{field}: {size} bytes is no whole number of {t.__name__}")
    return t * (size // sizeof(t))
