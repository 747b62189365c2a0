"""CAN logs: the frames of a .blf or .asc log (python-can's readers), decoded
through the DBC with the receivers' E2E check of each frame (``decode_log``);
the writer of a run's log by its extension (``log_writer``: .blf, .asc, or .mf4,
ASAM MDF 4's CAN bus logging)."""
import math
import re
from pathlib import Path

from artibus.base import ArtibusError
from artibus.can.dbc import load_dbc

#: the extensions a run's CAN log (--can-log) is written as
LOG_SUFFIXES = (".blf", ".asc", ".mf4")


def log_writer(path, part=None):
    """python-can's writer of a CAN log by ``path``'s extension (LOG_SUFFIXES),
    writing to ``part`` (default ``path``: the caller renames a part when the log
    is complete). Times are simulated seconds, as the frames' time stamps."""
    import can
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in LOG_SUFFIXES:
        raise ArtibusError(f"{path}: the CAN log is written as {', '.join(LOG_SUFFIXES)} (by its suffix)")
    target = str(part or path)
    if suffix == ".mf4":
        return _mf4_writer()(target)
    return can.BLFWriter(target) if suffix == ".blf" else can.ASCWriter(target)


def _mf4_writer():
    """python-can's MF4Writer (asammdf: a CAN_DataFrame channel group whose source
    is a CAN bus, ASAM MDF 4.1 "bus logging") with the measurement's start at
    1970-01-01 00:00 UTC, so that a frame's time is its time stamp as given, the
    simulated seconds a .blf of the same run holds (python-can's own writer takes
    the wall clock at its opening as the start, and times from it). log_event's
    text goes to the file's comment (MF4Writer has no events)."""
    from datetime import datetime, timezone
    from can.io import MF4Writer

    class SimTimeMF4Writer(MF4Writer):
        def __init__(self, file, **kwargs):
            super().__init__(file, **kwargs)
            self._mdf.header.start_time = datetime.fromtimestamp(0, timezone.utc)
            self.last_timestamp = self._start_time = 0.0

        def log_event(self, message, timestamp=None):
            self._mdf.header.comment = message

    return SimTimeMF4Writer


def read_log(path):
    """The CAN frames of a .blf or .asc log (python-can's readers), in time
    order. Refused with an error naming the file and the frame: a log the
    library cannot read (its error wrapped, with the frame it stopped at), a
    time stamp that is NaN or infinite, time that goes backwards."""
    import can
    path = Path(path)
    if not path.is_file():
        raise ArtibusError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in (".blf", ".asc"):
        raise ArtibusError(f"{path}: a CAN log is .blf or .asc")
    if suffix == ".asc":
        _check_asc_stamps(path)
    frames, k, last = [], 0, -math.inf
    try:
        with (can.BLFReader(str(path)) if suffix == ".blf" else can.ASCReader(str(path))) as reader:
            for k, m in enumerate(reader, start=1):
                t = m.timestamp
                if not math.isfinite(t):
                    raise ArtibusError(f"{path}: frame {k} (ID 0x{m.arbitration_id:03X}): time stamp {t} "
                                       f"is not a finite number")
                if t < last:
                    raise ArtibusError(f"{path}: frame {k} (ID 0x{m.arbitration_id:03X}): time {t:.6f} s "
                                       f"is before the previous frame's {last:.6f} s (the log's time goes "
                                       f"backwards)")
                last = t
                if not m.is_error_frame and not m.is_remote_frame:
                    frames.append(m)
    except ArtibusError:
        raise
    except Exception as e:      # python-can's parse errors (BLFParseError, struct.error, ValueError, ...)
        at = f"frame {k + 1}" + (f", after t = {last:.6f} s" if k else ", the first")
        raise ArtibusError(f"{path}: cannot read the log at {at}: {type(e).__name__}: {e}") from None
    return frames


_ASC_FRAME = re.compile(r"\s*(\S+)\s+(\d+|CANFD)\s+([0-9A-Fa-f]+)x?\s+(Rx|Tx)\b")
_ASC_ERROR = re.compile(r"\s*(\S+)\s+\d+\s+ErrorFrame\b")
_ASC_STAMP = re.compile(r"-?[0-9]+(\.[0-9]*)?")


def _check_asc_stamps(path):
    """python-can's ASC reader skips, without a word, a frame line whose time
    stamp is not a plain unsigned number (nan, inf, -0.5): refused here,
    naming the line. Time that goes back is named as read_log names it (the
    frame, both times), here already, as a stamp below 0 is one python-can
    skips; a first frame below 0 is before the log's start (its Begin
    Triggerblock). Frames are counted as read_log counts them (error frames
    too)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            k, last = 0, None
            for n, line in enumerate(f, start=1):
                m = _ASC_FRAME.match(line) or _ASC_ERROR.match(line)
                if not m:
                    continue
                k += 1
                text = m.group(1)
                if not _ASC_STAMP.fullmatch(text):
                    raise ArtibusError(f"{path}, line {n}: time stamp {text!r} is not a finite "
                                       f"number of seconds (a frame line)")
                t = float(text)
                if last is not None and t < last:
                    ident = m.group(3) if m.re is _ASC_FRAME and m.group(2) != "CANFD" else None
                    what = f"frame {k}" + (f" (ID 0x{int(ident, 16):03X})" if ident else "")
                    raise ArtibusError(f"{path}: {what}: time {t:.6f} s is before the previous frame's "
                                       f"{last:.6f} s (the log's time goes backwards; line {n})")
                if t < 0:
                    raise ArtibusError(f"{path}, line {n}: frame {k}: time {t:.6f} s is before the log's "
                                       f"start (0 s)")
                last = t
    except OSError as e:
        raise ArtibusError(f"{path}: cannot read the log: {e.strerror or e}") from None


def decode_log(path, dbc, unknown=None):
    """Rows (time s, message, signal, value, unit, e2e) of every frame of a log
    that the DBC knows; e2e is 'ok', or why a receiver checking every frame of
    the log would reject it (never use it): 'crc', 'repeated' (counter equal
    to the last), 'sequence' (counter ahead by more than the cycles elapsed
    since the last good frame, from the timestamps and the cycle time) -- the
    check of ``Network._deliver``. unknown: a dict that receives {identifier:
    frames} of the frames whose identifier the DBC does not know (skipped)."""
    from cantools.autosar.end_to_end import compute_profile2_crc
    db = load_dbc(dbc) if not hasattr(dbc, "messages") else dbc
    rows, last, good = [], {}, {}
    for frame in read_log(path):
        try:
            m = db.get_message_by_frame_id(frame.arbitration_id)
        except KeyError:        # skipped, as every log viewer does; counted for the caller's warning
            if unknown is not None:
                unknown[frame.arbitration_id] = unknown.get(frame.arbitration_id, 0) + 1
            continue
        data = bytes(frame.data)
        if len(data) != m.length:
            raise ArtibusError(f"{path}: frame 0x{frame.arbitration_id:03X} at t = {frame.timestamp:g} s: "
                               f"{len(data)} bytes, message {m.name} has {m.length}")
        data_id = int(m.dbc.attributes["E2EDataID"].value)
        counter = data[1] & 0x0F
        e2e = "ok"
        if compute_profile2_crc(data, data_id) != data[0]:
            e2e = "crc"
        elif m.frame_id in last:
            delta = (counter - last[m.frame_id]) % 16
            cycles = round((frame.timestamp - good[m.frame_id]) / (m.cycle_time / 1000.0))
            if delta == 0:
                e2e = "repeated"
            elif delta > min(max(cycles, 1), 15):
                e2e = "sequence"
                last[m.frame_id] = counter
        if e2e == "ok":
            last[m.frame_id], good[m.frame_id] = counter, frame.timestamp
        for name, v in m.decode(data, scaling=True, decode_choices=False).items():
            rows.append((frame.timestamp, m.name, name, v, m.get_signal_by_name(name).unit or "", e2e))
    return rows
