"""CAN logs: the frames of a .blf or .asc log (python-can's readers), decoded
through the DBC with the receivers' E2E check of each frame (``decode_log``)."""
from pathlib import Path

from artibus.base import ArtibusError
from artibus.can.dbc import load_dbc


def read_log(path):
    """The CAN frames of a .blf or .asc log (python-can's readers)."""
    import can
    path = Path(path)
    if not path.is_file():
        raise ArtibusError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in (".blf", ".asc"):
        raise ArtibusError(f"{path}: a CAN log is .blf or .asc")
    reader = can.BLFReader(str(path)) if suffix == ".blf" else can.ASCReader(str(path))
    try:
        return [m for m in reader if not m.is_error_frame and not m.is_remote_frame]
    except Exception as e:
        raise ArtibusError(f"{path}: cannot read the log: {e}") from None


def decode_log(path, dbc):
    """Rows (time s, message, signal, value, unit, e2e) of every frame of a log
    that the DBC knows; e2e is 'ok', or why a receiver checking every frame of
    the log would reject it (never use it): 'crc', 'repeated' (counter equal
    to the last), 'sequence' (counter ahead by more than the cycles elapsed
    since the last good frame, from the timestamps and the cycle time) -- the
    check of ``Network._deliver``."""
    from cantools.autosar.end_to_end import compute_profile2_crc
    db = load_dbc(dbc) if not hasattr(dbc, "messages") else dbc
    rows, last, good = [], {}, {}
    for frame in read_log(path):
        try:
            m = db.get_message_by_frame_id(frame.arbitration_id)
        except KeyError:
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
