"""The stepping core's library (src/runner_core/, <build>/lib/libartibus_core.so)
and its structs: ``core_library_path``, ``load`` (the library and its functions'
signatures), ``struct`` (a struct of core.h/lsbus.h as the ctypes class the
library's own layout table gives, artibus.runner.layout)."""
import os
from ctypes import CDLL, c_int, c_long, c_void_p
from pathlib import Path

from artibus.base import ROOT, ArtibusError
from artibus.runner import layout

_loaded = {}                    # path -> (library, structs) or (None, why not)


def core_library_path():
    """$ARTIBUS_CORE_LIB, else the build next to the FMUs in use: with
    $ARTIBUS_FMU_DIR = <build>/fmus (the sanitizer build's FMUs) its
    <build>/lib/libartibus_core.so when built, else build/lib's."""
    if os.environ.get("ARTIBUS_CORE_LIB"):
        return Path(os.environ["ARTIBUS_CORE_LIB"])
    name = "libartibus_core.so"
    fmus = os.environ.get("ARTIBUS_FMU_DIR")
    if fmus and (Path(fmus).parent / "lib" / name).is_file():
        return Path(fmus).parent / "lib" / name
    return ROOT / "build" / "lib" / name


def load():
    """(the loaded core library, None) or (None, why not): not built, not loadable,
    or a layout table ctypes cannot reproduce (artibus.runner.layout)."""
    got = _entry()
    return (got[0], None) if got[0] is not None else got


_current = [None, None]         # (the environment it was for, _loaded's entry of its library)


def _entry():
    """_loaded's entry of the library in use, looked up again only when the environment that
    chooses it ($ARTIBUS_CORE_LIB, $ARTIBUS_FMU_DIR) changed: no path built or stat made per call."""
    key = (os.environ.get("ARTIBUS_CORE_LIB"), os.environ.get("ARTIBUS_FMU_DIR"))
    if _current[0] != key:
        path = core_library_path()
        if path not in _loaded:
            _loaded[path] = _load(path)
        _current[:] = [key, _loaded[path]]
    return _current[1]


def _load(path):
    if not path.is_file():
        return None, f"{path} is not built"
    try:
        lib = CDLL(str(path))
    except OSError as e:
        return None, f"{path}: {e}"
    if not hasattr(lib, "artibus_core_layout"):
        return None, f"{path} is of an older build (no artibus_core_layout): build it again"
    try:
        structs = layout.structs(lib)
    except layout.LayoutError as e:
        return None, f"{path}: {e}"
    for name, args, res in (("artibus_core_record_start", [c_void_p], None),
                            ("artibus_core_run", [c_void_p, c_long, c_long], c_int),
                            ("artibus_core_can_settle", [c_void_p], c_int),
                            ("artibus_core_settle", [c_void_p, c_void_p], c_int)):
        f = getattr(lib, name)
        f.argtypes, f.restype = args, res
    return lib, structs


def struct(name):
    """The ctypes class of core.h's or lsbus.h's struct ``name`` (e.g. "ac_unit"), as
    the library in use lays it out; ArtibusError when the library is not there."""
    lib, structs = _entry()
    if lib is None:
        raise ArtibusError(f"the C stepping core: {structs}")
    return structs[name]
