"""An artibus command in the background that says where it is and waits there
(artibus.runner.markers), for the tests that interrupt a run: they signal it at
an event the run reports, never after a sleep that assumes the machine's speed
(issue 41: on an idle fast machine a run signalled 2 s after its start had
finished). Timeouts here only bound a failure (a run that never reports)."""
import os
import select
import signal
import subprocess
import sys
import tempfile
import time

#: seconds a run may take to report its next marker before the test fails (a failure bound only)
BOUND = 300.0


class HeldRun:
    """``python -m artibus ARGS`` with a pipe for its marker lines and, with
    ``hold`` (the default), a pipe it waits on after each line: it stays at the
    event the test read until the test lets it go (``release``), is signalled
    there (``signal``), or ends (``finish``). Its stdout and stderr go to
    temporary files (no pipe of theirs can fill while the test reads markers)."""

    def __init__(self, args, cwd, env=None, hold=True, new_session=False):
        marks, mark_w = os.pipe()
        go_r, self._go = os.pipe()
        env = {**os.environ, **(env or {}), "ARTIBUS_PROGRESS_FD": f"{mark_w}:{os.fstat(mark_w).st_ino}"}
        if hold:
            env["ARTIBUS_PROGRESS_WAIT_FD"] = f"{go_r}:{os.fstat(go_r).st_ino}"
        self._out, self._err = tempfile.TemporaryFile("w+"), tempfile.TemporaryFile("w+")
        try:
            self.proc = subprocess.Popen([sys.executable, "-m", "artibus", *map(str, args)], cwd=cwd, env=env,
                                         stdout=self._out, stderr=self._err, pass_fds=(mark_w, go_r),
                                         start_new_session=new_session)
        finally:
            os.close(mark_w)          # the run holds the only write end: end of file when it exits
            os.close(go_r)
        self._marks, self._buf, self.seen, self._group = marks, b"", [], new_session

    def next(self):
        """The run's next marker line, or None when it has exited without one.
        Fails the test after BOUND seconds without either."""
        end = time.monotonic() + BOUND
        while b"\n" not in self._buf:
            left = end - time.monotonic()
            ready, _, _ = select.select([self._marks], [], [], max(0.0, left))
            assert ready, f"no marker from {self.proc.args} in {BOUND:g} s"
            chunk = os.read(self._marks, 4096)
            if not chunk:
                return None
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        self.seen.append(line.decode())
        return self.seen[-1]

    def wait_for(self, predicate):
        """Read markers, letting the run go on past each, until one satisfies
        ``predicate``: that line; the run is held there (it has not ended)."""
        while True:
            line = self.next()
            assert line is not None, f"the run ended without the marker awaited; markers {self.seen[-3:]}, " \
                                     f"stderr: {self.stderr()}"
            if predicate(line):
                return line
            self.release()

    def release(self):
        """Let the held run go on to its next marker."""
        os.write(self._go, b"g")

    def signal(self, sig):
        self.proc.send_signal(sig)

    def kill_group(self, sig):
        """``sig`` to the run's process group (new_session=True)."""
        os.killpg(self.proc.pid, sig)

    def finish(self):
        """Stop holding the run (it no longer waits), wait for its end: its stderr."""
        if self._go is not None:
            os.close(self._go)
            self._go = None
        self.proc.wait(timeout=BOUND)
        while self.next() is not None:       # (markers after the last one read: the pipe's end)
            pass
        return self.stderr()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        """A run the test left (it failed midway) is killed, not left waiting."""
        if self.proc.poll() is None:
            if self._group:
                os.killpg(self.proc.pid, signal.SIGKILL)
            else:
                self.proc.kill()
            self.proc.wait()
        if self._go is not None:
            os.close(self._go)
        os.close(self._marks)
        self._out.close()
        self._err.close()

    def stderr(self):
        self._err.seek(0)
        return self._err.read()
