"""Markers for the tests: a run says where it is, and may wait there.

A test that interrupts a run must signal it at a moment the run reports, not
after a sleep that assumes how fast the machine is (issue 41: on an idle fast
machine the signal came after the run had finished). Off unless the test's
environment sets these; then one dictionary look-up per marker:

``ARTIBUS_PROGRESS_FD=N:INODE``
    the run writes a line to file descriptor N (inherited, e.g. a pipe's write
    end given with ``pass_fds``; INODE its ``os.fstat(N).st_ino``, so that a
    process that has another file under that number, such as a sweep's worker
    started by the run with the same environment, writes nothing) at each of
    these events:

    - ``t=<time>``: the step loop has reached ``<time>`` s (after each piece of
      base steps the C core does, artibus.runner.core, and every ``PIECE``
      steps of ``artibus simulate``); not after the last one;
    - ``saving <path>``: the write of a results file begins (inside
      artibus.files.signals_held: a signal from now on is taken after it);
    - ``case <key>``: a sweep's case file is written.

``ARTIBUS_PROGRESS_WAIT_FD=M:INODE`` (with N)
    after each line the run reads one byte from M before it goes on: the test
    holds the run at the event it read (a signal then arrives there, and the
    run cannot have ended) and lets it go on by writing a byte. End of file on
    M (the test closed it): no more waiting.

A descriptor that fails (the test has gone) switches the markers off; the run
goes on.
"""
import os

from artibus.base import ArtibusError

#: steps between two markers of a loop in Python (artibus.fmu.simulate; the C core's: core.CORE_PIECE)
PIECE = 5000
_ENV, _WAIT_ENV = "ARTIBUS_PROGRESS_FD", "ARTIBUS_PROGRESS_WAIT_FD"
_broken = set()          # descriptors that failed: not written again in this process
#: called after each wait at a marker, where set (artibus.fmu.isolated: the run's child process
#: asks its parent, which takes the test's signal, whether one came while it waited)
after_wait = None
_checked = {}            # "N:INODE" -> N when descriptor N is that file in this process, else None


def _fd(name):
    """The descriptor $name names, if this process has that very file under it."""
    text = os.environ.get(name)
    if not text:
        return None
    if text not in _checked:
        try:
            fd, inode = (int(x) for x in text.split(":"))
        except ValueError:
            raise ArtibusError(f"{name}={text!r}: expected FD:INODE (two integers)") from None
        try:
            _checked[text] = fd if os.fstat(fd).st_ino == inode else None
        except OSError:                  # not open here
            _checked[text] = None
    return _checked[text]


def mark(line):
    """Write ``line`` and a newline to $ARTIBUS_PROGRESS_FD and, with
    $ARTIBUS_PROGRESS_WAIT_FD, wait for a byte on that one; nothing when unset.
    A signal while it waits is raised here (KeyboardInterrupt, as anywhere
    in the loop) unless it is held (signals_held): then the wait goes on."""
    out = _fd(_ENV)
    if out is None or out in _broken:
        return
    wait = _fd(_WAIT_ENV)
    try:
        os.write(out, f"{line}\n".encode())
        if wait is not None and wait not in _broken and not os.read(wait, 1):
            _broken.add(wait)                # end of file: the test lets it run
        if wait is not None and after_wait is not None:
            after_wait()
    except OSError:
        _broken.add(out)
