"""The FMUs' memory callbacks: the process's own calloc and free.

FMPy's defaults are libc's calloc/free looked up in libc.so.6 itself
(``CDLL(find_library("c"))``), which bypasses an interposed allocator: under a
preloaded AddressSanitizer (the sanitizer test pass) the FMUs' heap blocks then
escaped it. ``CDLL(None)`` resolves the names in the process's global scope,
where a preloaded sanitizer comes first; without one they are libc's, as before.
"""
import ctypes
import sys

if sys.platform == "win32":                    # no global scope there: FMPy's own
    from fmpy import calloc, free               # noqa: F401
else:
    _process = ctypes.CDLL(None)
    calloc = _process.calloc
    calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
    calloc.restype = ctypes.c_void_p
    free = _process.free
    free.argtypes = [ctypes.c_void_p]
    free.restype = None
