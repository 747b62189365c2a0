"""`artibus simulate` with the FMU in a process of its own (issue 38: "a crashing FMU kills only
its own process where `simulate` runs it (as sweeps do), and its partial result is kept").

An FMU is foreign code in our address space: a segmentation fault in its doStep would end the
whole program, no message, no result. ``simulate`` here runs artibus.fmu.simulate.simulate in a
forked child (the FMU loaded and called only there) and the parent waits on it:

- each row the child records goes at once to a file of the run's own temporary directory, raw
  float64s, one unbuffered write a row (and a String column's texts and a 64-bit integer column's
  exact values a JSON line a row, written before it): what a crash cannot lose, as the kernel
  holds what was written; the child's temporary files (the unpacked FMU) go to that directory
  too, removed by the parent however the child ended;
- its end comes back over a pipe: the Result, or the error (its message, partial Result, FMU
  log), or the interrupt's partial Result; the parent raises them as the run in-process would;
- a child ended by a signal (SIGSEGV, SIGBUS, SIGABRT...) or an exit without a word: a
  SimulationError naming the FMU, the signal and the last recorded time, with the rows so far
  (the command line saves them as OUT.partial.csv, artibus.cli.main);
- SIGINT and SIGTERM to the parent are passed to the child (in a process group of its own, so a
  terminal's Ctrl-C reaches it once, through the parent), which stops between two steps and
  sends its rows as an in-process run does (tests/test_simulate_partial.py).
The child dies with the parent (PR_SET_PDEATHSIG). Linux only (fork): elsewhere in-process."""
import json
import os
import shutil
import signal
import sys
import tempfile

from artibus.base import ArtibusError
from artibus.fmu.result import Result, SimulationError


def simulate(path, messages=None, **kwargs):
    """artibus.fmu.simulate.simulate(path, messages=messages, **kwargs) in a child process (see
    the module's docstring); in this process where there is no fork."""
    from artibus.fmu.simulate import simulate as run
    if not hasattr(os, "fork") or sys.platform != "linux":
        return run(path, messages=messages, **kwargs)
    import multiprocessing
    ctx = multiprocessing.get_context("fork")
    tmp = tempfile.mkdtemp(prefix="artibus-simulate-")
    reader, writer = ctx.Pipe(duplex=False)
    back_reader, back = ctx.Pipe(duplex=False)       # (the answer to the child's "sync")
    child = ctx.Process(target=_child, args=(writer, back_reader, tmp, path, messages is not None, kwargs),
                        daemon=True)
    try:
        child.start()
        writer.close()
        back_reader.close()
        head, end, interrupt = _wait(reader, back, child)
        child.join()
        if end is None:
            raise _crashed(path, child.exitcode, head, tmp)
        return _ended(end, messages, interrupt, tmp)
    finally:
        if child.is_alive():
            child.kill()
            child.join()
        reader.close()
        back.close()
        shutil.rmtree(tmp, ignore_errors=True)


def _wait(reader, back, child):
    """(the head, the end message or None where the child ended without one, the interrupt
    passed on to it or None): the child's messages until its end; an interrupt of this process
    (SIGINT, SIGTERM: KeyboardInterrupt) passed on to the child, which then ends with its rows.
    A "sync" (the child after a wait at a test's marker, artibus.runner.markers) answered on
    ``back``: a signal the test sent while the child waited has been passed on by then."""
    head = end = interrupt = None
    while end is None:
        try:
            reader.poll(None)            # (a signal here: nothing read, passed on below)
        except KeyboardInterrupt as e:
            interrupt = e
            _pass_on(child, e)
            continue
        from artibus.files import signals_held
        message = None
        try:
            with signals_held():         # (a message read whole: a signal taken after it)
                message = reader.recv()
        except EOFError:
            break
        except KeyboardInterrupt as e:
            interrupt = e
            _pass_on(child, e)
        if message is None:
            continue
        if message[0] == "sync":
            back.send(None)
        elif message[0] == "head":
            head = message[1]
        else:
            end = message
    return head, end, interrupt


def _pass_on(child, e):
    """The interrupt ``e`` (SIGINT, or the command line's SIGTERM) passed on to the child."""
    try:
        os.kill(child.pid, getattr(e, "signum", signal.SIGINT))
    except (ProcessLookupError, TypeError):      # (ended already; not started)
        pass


def _ended(end, messages, interrupt, tmp):
    """The child's end as this process raises or returns it (its Result's rows read from the
    run's file: a table, not a list pickled row by row)."""
    kind, result, log, text = end
    if result is not None:
        result = _with_rows(result, tmp)
    if messages is not None:
        messages.extend(log or ())
    if kind == "done":
        return result
    if kind == "interrupted":
        e = interrupt if interrupt is not None else KeyboardInterrupt()
        e.result = result
        raise e
    if kind == "simulation":
        raise SimulationError(text, result, log)
    if kind == "artibus":
        err = ArtibusError(text)
        if log:
            err.log = log
        if result is not None:
            err.result = result
        raise err
    raise RuntimeError(f"artibus simulate's child process failed:\n{text}")


def _crashed(path, exitcode, head, tmp):
    """The SimulationError of a child that ended without a word: killed by a signal (the FMU's
    crash), or an exit of its own; its rows so far from the run's files."""
    result = _rows_written(head, tmp) if head is not None else None
    if exitcode is not None and exitcode < 0:
        try:
            how = f"was killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            how = f"was killed by signal {-exitcode}"
    else:
        how = f"exited ({exitcode}) without a result"
    model = head["model"] if head else path
    where = f" after t = {result.rows[-1][0]:g} s" if result is not None and result.rows else " before its first row"
    return SimulationError(f"{path}: the process running {model} {how}{where} (a fault of the FMU's "
                           "code: only the process that ran it ended)", result if result is not None else Result(["time"]), [])


def _table(tmp, width):
    """The rows written to rows.f64: whole ones, a row of ``width`` values each."""
    import numpy as np
    try:
        raw = np.fromfile(os.path.join(tmp, "rows.f64"), dtype=np.float64)
    except OSError:
        raw = np.zeros(0)
    n = len(raw) // width
    return raw[:n * width].reshape(n, width)


def _with_rows(result, tmp):
    """The child's Result (its rows left out: ``n_rows``) with the rows it wrote."""
    n = getattr(result, "n_rows", None)
    if n is None:                     # (rows of its own: a Result made before the first row)
        return result
    full = Result.from_array(result.names, _table(tmp, len(result.names))[:n])
    full.strings, full.integers = result.strings, result.integers
    full.units, full.descriptions = result.units, result.descriptions
    full.terminated = result.terminated
    return full


def _rows_written(head, tmp):
    """The Result of the rows the child wrote (whole rows, and for String and 64-bit integer
    columns whole lines)."""
    names, strings, integers = head["names"], head["strings"], head["integers"]
    table = _table(tmp, len(names))
    n = len(table)
    texts = []
    if strings or integers:
        try:
            with open(os.path.join(tmp, "strings.jsonl"), encoding="utf-8") as f:
                for line in f:
                    if not line.endswith("\n"):
                        break
                    texts.append(json.loads(line))
        except OSError:
            pass
        n = min(n, len(texts))
    result = Result(names, [list(r) for r in table[:n]])
    result.units, result.descriptions = head["units"], head["descriptions"]
    result.strings = {c: [t[k] for t in texts[:n]] for k, c in enumerate(strings)}
    result.integers = {c: [t[k] for t in texts[:n]] for k, c in enumerate(integers, len(strings))}
    return result


class _Written(list):
    """Result.rows in the child: each row appended also written to rows.f64 at once, its
    texts and exact integers first to strings.jsonl (record() adds them before the row)."""

    def __init__(self, result, tmp):
        super().__init__()
        self.result = result
        self.fd = os.open(os.path.join(tmp, "rows.f64"), os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
        self.text_fd = (os.open(os.path.join(tmp, "strings.jsonl"), os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
                        if result.strings or result.integers else None)
        import struct
        self.pack = struct.Struct(f"={len(result.names)}d").pack      # (native float64s, as numpy reads them)

    def append(self, row):
        if self.text_fd is not None:
            k = len(self)
            line = json.dumps([c[k] if k < len(c) else "" for c in self.result.strings.values()]
                              + [c[k] if k < len(c) else None for c in self.result.integers.values()])
            os.write(self.text_fd, (line + "\n").encode())
        super().append(row)
        os.write(self.fd, self.pack(*row))


def _child(writer, back, tmp, path, keep_messages, kwargs):
    """The child: the run, its rows written as they come (_Written), its end sent; an exit
    without the interpreter's clean-up of the parent's objects (multiprocessing's)."""
    os.setpgid(0, 0)                 # a terminal's Ctrl-C: to the parent, which passes it on
    _die_with_parent()
    tempfile.tempdir = tmp           # (the unpacked FMU: removed by the parent whatever happens)
    from artibus.fmu.simulate import simulate as run
    from artibus.runner import markers

    def sync():                      # (a signal the parent passes on meanwhile: raised here)
        writer.send(("sync",))
        back.recv()
    markers.after_wait = sync
    messages = [] if keep_messages else None

    def started(result, model):
        result.rows = _Written(result, tmp)
        writer.send(("head", {"names": result.names, "units": result.units, "descriptions": result.descriptions,
                              "strings": list(result.strings), "integers": list(result.integers),
                              "model": model}))
    try:
        result = run(path, messages=messages, on_result=started, **kwargs)
        end = ("done", _plain(result), messages, None)
    except KeyboardInterrupt as e:
        end = ("interrupted", _plain(getattr(e, "result", None)), messages, None)
    except SimulationError as e:
        end = ("simulation", _plain(e.result), e.log, str(e))
    except ArtibusError as e:
        end = ("artibus", _plain(getattr(e, "result", None)), getattr(e, "log", None) or messages, str(e))
    except BaseException:
        import traceback
        end = ("exception", None, messages, traceback.format_exc())
    writer.send(end)
    writer.close()


def _plain(result):
    """A Result to send: its rows left out where they are in rows.f64 (their number
    ``n_rows``: an interrupt's Result drops a last row whose texts were not all taken), or None."""
    if result is not None and isinstance(result.rows, _Written):
        result.n_rows = len(result.rows)
        result.rows = []
        result.__dict__.pop("_array", None)
    return result


def _die_with_parent():
    """SIGKILL to this child when the parent dies (Linux prctl PR_SET_PDEATHSIG): no orphan
    left running an FMU after a `kill -9` of artibus."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)     # (1: PR_SET_PDEATHSIG)
    except (OSError, AttributeError):
        pass
