"""The command line's standard output and the file system's limits: what
``artibus.cli.main`` says (or does not) when its reader has gone or a name is
too long, instead of a traceback."""
import errno
import os
import signal
import sys


def stdout_gone():
    """True when standard output is a pipe or socket whose reader has gone
    (POLLERR on its write end), so that a BrokenPipeError of another pipe
    (a worker's, a subprocess's) is not taken for it."""
    import select
    try:
        poll = select.poll()
        poll.register(sys.stdout.fileno(), select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poll.poll(0))
    except (AttributeError, OSError, ValueError):
        return False


def quiet_exit():
    """The reader of standard output has gone (`artibus list | head -1`): no
    traceback, no "Exception ignored" at the exit's flush: standard output is
    pointed at /dev/null and the exit code is a shell's for SIGPIPE, 141 (the
    Python documentation's "Note on SIGPIPE", library/signal)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return 128 + signal.SIGPIPE


def path_error(e):
    """The one line for an OSError that is the user's path, not a fault of
    ours (a name longer than the file system allows: ENAMETOOLONG), or None."""
    if e.errno == errno.ENAMETOOLONG:
        return f"{e.filename}: {e.strerror} (a name longer than the file system allows)"
    return None
