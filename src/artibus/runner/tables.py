"""The memory of the result tables (issue 13).

A run's table (a row per base step, a column per recorded signal) is written
once by the stepping core. Fresh memory costs a page fault on the first write
of every 4 KiB page: about 3 us a page on a virtual machine (Firecracker),
3 ms for the 7001 x 65 table of a 7 s Bus36m_Circle run, against 0.2 ms when
the pages are in use already. Two things make it cheaper, with the same
contents (an empty table is written whole before anything reads it):

- recycling: a table's memory goes back into use for a later run once nothing
  refers to it any more (no Result, no array viewing it: numpy views keep
  their owner alive, so a buffer is free when the pool alone holds it). A
  table the user keeps is never handed out again. A sweep's worker doing
  thousands of runs gets its tables without page faults after the first few;
- huge pages: a table of HUGE bytes or more gets a mapping of its own,
  advised for transparent huge pages (MADV_HUGEPAGE; the kernel's "madvise"
  mode), 2 MiB aligned: a page fault per 2 MiB instead of per 4 KiB.

Bounded: the pool holds at most POOL_BYTES of tables in at most POOL_COUNT
buffers, in use or not (a table beyond that is not pooled and freed as usual),
and drops the least recently used free ones to make room. Thread-safe: one lock around taking a buffer (a
free buffer has no other reference, so none can appear while the lock is
held; a forked child gets a new lock). POOL_BYTES = 0 switches recycling off."""
import mmap
import os
import sys
import threading

import numpy as np

POOL_BYTES = 64 << 20        # the pool's tables together, in use or free
POOL_COUNT = 32              # and at most this many (take looks at each)
HUGE = 2 << 20               # from this size on: a mapping of its own, huge pages advised
_PAGE = 4096
_lock = threading.Lock()
_buffers = []                # [buffer, its size, its address, a view of it as the last table]: the
                             # buffers 1-D float64 arrays, each its memory's owner; the view the
                             # pool's own (a table is a new view of it); the least recently used first


def _calibrate():
    """The count sys.getrefcount gives a buffer only the pool refers to, as take() asks."""
    buf = np.empty(1)
    _buffers.append([buf, 1, 0, buf.reshape(1, 1)])
    del buf
    try:
        e = _buffers[-1]
        return sys.getrefcount(e[0])
    finally:
        _buffers.pop()


_FREE = _calibrate()


def _after_fork():
    """A child process (a sweep's worker) starts with the lock free: another thread
    of the parent may have held it at the fork."""
    global _lock
    _lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork)


def _huge(count):
    """A float64 array of ``count`` in a private anonymous mapping, its 2 MiB-aligned
    whole huge pages advised for THP (the tail too when rounding it up wastes at most
    a quarter: 3.64 MB -> 4 MB); None where the platform has no such advice."""
    advice = getattr(mmap, "MADV_HUGEPAGE", None)
    if advice is None or not hasattr(mmap, "MAP_ANONYMOUS"):
        return None
    need = count * 8
    try:
        mm = mmap.mmap(-1, need + 2 * HUGE, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    except (OSError, ValueError):
        return None
    whole = need + (-need) % HUGE
    length = whole if whole - need <= need // 4 else need - need % HUGE
    start = np.frombuffer(mm, dtype=np.uint8, count=1).ctypes.data
    offset = (-start) % HUGE
    if length:
        try:
            mm.madvise(advice, offset, length)
        except (OSError, ValueError):
            pass
    return np.frombuffer(mm, dtype=np.float64, count=count, offset=offset)


def _allocate(count):
    if count * 8 >= HUGE:
        a = _huge(count)
        if a is not None:
            return a
    return np.empty(count)


def _free(e):
    return sys.getrefcount(e[0]) <= _FREE


def take(rows, cols):
    """(table, the address of its first element): np.empty((rows, cols)) of float64,
    C order, its memory recycled (see above); its contents are undefined, as np.empty's.
    A buffer fits a table of ``count`` doubles when it is large enough and not so much
    larger that a small table the user keeps would hold a big buffer."""
    count = rows * cols
    top = count + count // 4 + _PAGE // 8
    with _lock:
        for i in range(len(_buffers) - 1, -1, -1):      # the most recently used first
            e = _buffers[i]
            if count <= e[1] <= top and sys.getrefcount(e[0]) <= _FREE:
                if i != len(_buffers) - 1:
                    _buffers.append(_buffers.pop(i))
                shaped = e[3]
                if shaped.shape != (rows, cols):
                    shaped = e[3] = e[0][:count].reshape(rows, cols)
                return shaped.view(), e[2]
    buf = _allocate(max(count, 1))
    e = [buf, buf.size, buf.ctypes.data, buf[:count].reshape(rows, cols)]
    if buf.nbytes <= POOL_BYTES and POOL_COUNT > 0:
        with _lock:
            held = sum(f[0].nbytes for f in _buffers) + buf.nbytes
            i = 0
            while (held > POOL_BYTES or len(_buffers) >= POOL_COUNT) and i < len(_buffers):
                if _free(_buffers[i]):                  # the least recently used free one goes
                    held -= _buffers.pop(i)[0].nbytes
                else:
                    i += 1
            if held <= POOL_BYTES and len(_buffers) < POOL_COUNT:
                _buffers.append(e)
    return e[3].view(), e[2]


def held():
    """(bytes the pool holds, of them free): for tests and benchmarks."""
    with _lock:
        return (sum(e[0].nbytes for e in _buffers),
                sum(e[0].nbytes for e in _buffers if _free(e)))


def clear():
    """Forget every buffer (those in use live on with their tables)."""
    with _lock:
        _buffers.clear()
