"""The Dask side of a sweep: a local cluster made quiet, or an existing
scheduler (``_client``), the bench's bytes on every worker (``_scatter``), the
cases handed out as tasks of several (``_Chunks``) and the progress line
(``_Progress``)."""
import logging
import math
import os
import sys
import time
import weakref
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError


_SCATTERED = weakref.WeakKeyDictionary()     # a client -> (.ssp hash, the future of its bytes on the workers)


def _scatter(client, info, again=False):
    """The bench's bytes on every worker (a future). On a client the caller gave,
    the copy is kept for the next sweep of the same bench, as the workers keep
    their instances (release() on the workers frees them: client.run(release))."""
    got = _SCATTERED.get(client)
    if again or got is None or got[0] != info.ssp_hash or got[1].status != "finished":
        got = (info.ssp_hash, client.scatter(info.ssp_bytes, broadcast=True, hash=False))
        try:
            _SCATTERED[client] = got
        except TypeError:
            pass
    return got[1]


def scheduler_lost(client, wait_s=30.0):
    """True when ``client`` has lost its scheduler (killed, its machine gone):
    Dask's client tries to reconnect for distributed.comm.timeouts.connect
    (status "connecting"), waited for here (up to ``wait_s``), then closes
    itself. False while it is running (a worker died: the sweep sends its
    cases again)."""
    t0 = time.monotonic()
    while getattr(client, "status", "running") == "connecting" and time.monotonic() - t0 < wait_s:
        time.sleep(0.05)
    return getattr(client, "status", "running") != "running"


def lost_message(client, scheduler, out, done, e):
    """The one line a sweep says when its scheduler is lost: which, why, what
    is kept (``done`` cases of this run, each in out/cases, written as it came
    back) and how to go on (the same command: finished cases are skipped)."""
    where = scheduler or getattr(getattr(client, "scheduler", None), "address", None) or "of the sweep"
    why = " ".join(str(e).split())          # (Dask's text has lines: one line here)
    return (f"the Dask scheduler {where} was lost mid-sweep ({type(e).__name__}: {why}); the {done} case(s) "
            f"finished in this run are kept in {Path(out) / 'cases'}; run the same command again to resume "
            f"(finished cases are skipped)")


def _client(scheduler, workers):
    from dask.distributed import Client, LocalCluster
    if scheduler:
        # a lost scheduler is said by the sweep in one line (lost_message), not by Dask's client log too,
        # nor by its batched comm's (CommClosedError with a traceback, when the loss meets a send)
        for name in ("distributed.client", "distributed.batched"):
            logging.getLogger(name).setLevel(logging.CRITICAL)
        try:
            return Client(scheduler, timeout="5s"), None
        except (OSError, TimeoutError) as e:
            raise ArtibusError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({e})") from None
        except ValueError as e:
            raise ArtibusError(f"--scheduler {scheduler}: not a scheduler address ({e})") from None
    import dask
    n = workers or os.cpu_count() or 1
    with dask.config.set(QUIET):
        # no dashboard; the scheduler's HTTP server (health routes) on a free port of
        # 127.0.0.1, not on Dask's 8787 (taken by a user's own dashboard: a warning)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                               silence_logs=logging.CRITICAL)
    return Client(cluster), cluster


#: a local cluster's settings: Dask's periodic work off or rare (the workers' stack
#: sampling every 10 ms, the event loops' 20 ms health tick, the 100 ms memory and
#: 500 ms system monitors): idle, a cluster of two workers took ~15 % of a core with
#: the defaults (on the cores its workers run on), ~2 % with these
QUIET = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
         "distributed.worker.memory.monitor-interval": "1s", "distributed.admin.system-monitor.interval": "5s",
         "distributed.admin.system-monitor.gil.enabled": False}


class _Chunks:
    """The cases to run, handed out as tasks of several cases: a task's fixed
    cost (Dask's scheduler and client, ~10 ms of CPU a task on this 2-core
    machine, taken from the cores the workers run on) is then spread over its
    cases. The first tasks hold one case each (a case's time is not known yet),
    until one result a worker has come back (each such task costs ~20 ms of CPU
    more than its case);
    later ones a 1 / (2 workers) share of the cases left (so the workers finish
    together), but at least as many cases as run in MIN_S seconds and at most as
    many as in MAX_S seconds (by the median CPU time of the cases so far: an
    interrupted sweep loses about that much a worker). MIN_S is small: it sets
    the last tasks' size, and one worker waits up to that long for the other at
    the end (0.25 s cost 2 workers 10-25 % on a sweep of 60 cases of 20 ms; a
    task costs ~20 ms of CPU on this machine). IN_FLIGHT tasks a worker
    are submitted at once (one runs, the next waits on the worker). The cases
    of a task whose worker died go out again one a task (`alone`): only the
    case that kills its worker fails, not the others it shared a task with."""
    MIN_S, MAX_S = 0.1, 2.0
    IN_FLIGHT = 2

    def __init__(self, items, client):
        from collections import deque
        self.pending = deque(items)
        self.alone = deque()
        self.client = client
        self.cpu = []
        self.workers = 1
        self.asked = -math.inf

    def _workers(self):
        now = time.monotonic()
        if now - self.asked > 5.0:               # workers may join or leave an external cluster
            self.asked = now
            try:
                self.workers = max(1, sum(self.client.nthreads().values()))
            except Exception:
                pass
        return self.workers

    def in_flight(self):
        return self.IN_FLIGHT * self._workers()

    def took(self, cpu):
        if math.isfinite(cpu):
            self.cpu.append(cpu)
            del self.cpu[:-64]

    def left(self):
        return bool(self.pending or self.alone)

    def next(self):
        if self.alone:
            return [self.alone.popleft()]
        n = 1
        if len(self.cpu) >= self._workers():
            per_case = max(float(np.median(self.cpu)), 1e-6)
            share = math.ceil(len(self.pending) / (2 * self._workers()))
            n = max(1, int(self.MIN_S / per_case), min(share, int(self.MAX_S / per_case)))
        return [self.pending.popleft() for _ in range(min(n, len(self.pending)))]


class _Progress:
    def __init__(self, total, done_before, stream=sys.stderr):
        self.total, self.before, self.stream = total, done_before, stream
        self.done = self.failed = 0
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def update(self, failed, final=False):
        self.done += 1
        self.failed += failed
        now = time.perf_counter()
        if not final and not self.tty and now - self.last < 2.0 and self.done < self.total:
            return
        self.last = now
        rate = 60 * self.done / max(now - self.t0, 1e-9)
        left = self.total - self.done
        eta = f", {left / rate:.1f} min left" if rate > 0 and left else ""
        line = (f"sweep: {self.done + self.before}/{self.total + self.before} done "
                f"({self.before} before), {self.failed} failed, {rate:.1f} cases/min{eta}")
        self.stream.write(("\r" + line) if self.tty else line + "\n")
        if self.tty and self.done == self.total:
            self.stream.write("\n")
        self.stream.flush()
