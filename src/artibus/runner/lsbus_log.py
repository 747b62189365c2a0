"""The CAN frames of an FMI-LS-BUS network for its log (artibus.runner.lsbus): the Transmit
operations of a buffer, and the frames on the wire written with python-can."""
import struct
from pathlib import Path

from artibus.base import ArtibusError


def can_transmits(buf):
    """[(id, ide, data)] of the CAN Transmit operations of a buffer (fmi-ls-bus v1.0.0
    4_4_1_can.adoc, Transmit: OP Code 0x10 u32, Length u32, ID u32, Ide u8, Rtr u8, DL u16,
    Data); the other operations skipped by their Length; a malformed rest ends the scan (the
    receiver answers it with a Format Error, 4____network_abstraction.adoc)"""
    out, pos = [], 0
    while pos + 8 <= len(buf):
        code, length = struct.unpack_from("<II", buf, pos)
        if length < 8 or pos + length > len(buf):
            break
        if code == 0x10 and length >= 16:
            can_id, ide, _, dl = struct.unpack_from("<IBBH", buf, pos + 8)
            if length == 16 + dl:
                out.append((can_id, ide, bytes(buf[pos + 16:pos + length])))
        pos += length
    return out


def write_can_log(frames, path):
    """The frames on the wire, [(t, id, ide, data)] (Network.wire_frames), into a .blf,
    .asc or .mf4 log by python-can's writers (artibus.can.logs.log_writer), as the
    Real-wired bench's --can-log writes them."""
    import can
    from artibus.can.logs import LOG_SUFFIXES, log_writer
    path = Path(path)
    if path.suffix.lower() not in LOG_SUFFIXES:
        raise ArtibusError(f"{path}: the CAN log is written as {', '.join(LOG_SUFFIXES)} (by its suffix)")
    path.parent.mkdir(parents=True, exist_ok=True)
    part = path.with_name(path.name + ".part")    # renamed when complete: a failed write leaves nothing
    writer = log_writer(path, part)
    try:
        for t, can_id, ide, data in frames:
            writer.on_message_received(can.Message(timestamp=t, arbitration_id=can_id, is_extended_id=bool(ide),
                                                   dlc=len(data), data=data, channel=0))
        writer.stop()
        part.replace(path)
    except BaseException:               # (a full disk: OSError, for the caller to say)
        try:
            writer.file.close()
        except Exception:
            pass
        part.unlink(missing_ok=True)
        raise
