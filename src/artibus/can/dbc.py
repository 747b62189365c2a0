"""The DBC of a bench that routes connections over CAN, loaded with cantools
and checked for what the network needs (``load_dbc``; see artibus.can.network),
the E2E signals every frame carries, and the units a signal or a connected
variable may carry (``UNITS``, ``_conversion``)."""
import math
from pathlib import Path

from artibus.base import ArtibusError

#: units a signal or a connected variable may carry: (SI unit, factor to it)
UNITS = {
    "": ("", 1.0), "1": ("", 1.0),
    "rad": ("rad", 1.0), "deg": ("rad", math.pi / 180),
    "rad/s": ("rad/s", 1.0), "deg/s": ("rad/s", math.pi / 180),
    "m": ("m", 1.0), "mm": ("m", 1e-3),
    "m/s": ("m/s", 1.0), "km/h": ("m/s", 1 / 3.6),
    "m/s2": ("m/s2", 1.0),
    "N": ("N", 1.0), "kN": ("N", 1e3), "N.m": ("N.m", 1.0),
}
CRC_SIGNAL, COUNTER_SIGNAL = "CRC", "AliveCounter"
DEFAULT_BITRATE = 500_000


def _conversion(unit_from, unit_to, where):
    """factor k with value_to = k * value_from."""
    a, b = UNITS.get(unit_from or ""), UNITS.get(unit_to or "")
    if a is None or b is None or a[0] != b[0]:
        raise ArtibusError(f"{where}: cannot convert '{unit_from or ''}' to '{unit_to or ''}' "
                           f"(units known to the CAN path: {', '.join(u for u in UNITS if u)})")
    return a[1] / b[1]


def load_dbc(path, label=None):
    """The DBC as a cantools database, checked for what the network needs
    (see the module's docstring); errors name the file, message and signal."""
    import cantools
    label = label or str(path)
    try:
        db = cantools.database.load_file(str(path), database_format="dbc", strict=True)
    except FileNotFoundError:
        raise ArtibusError(f"{label}: no such file") from None
    except Exception as e:      # cantools' parse and consistency errors
        raise ArtibusError(f"{label}: not a valid DBC: {e}") from None
    if not db.messages:
        raise ArtibusError(f"{label}: the DBC defines no message")
    # cantools keeps both of two messages with one identifier or name (the
    # last wins its look-ups, with a logged warning only): refused here
    ids, names = {}, {}
    for m in db.messages:
        if m.frame_id in ids:
            raise ArtibusError(f"{label}: messages {ids[m.frame_id]} and {m.name} have the same identifier "
                               f"0x{m.frame_id:03X}")
        if m.name in names:
            raise ArtibusError(f"{label}: two messages are named {m.name} (0x{names[m.name]:03X} and "
                               f"0x{m.frame_id:03X})")
        ids[m.frame_id], names[m.name] = m.name, m.frame_id
    attr = db.dbc.attributes.get("Baudrate") if db.dbc else None
    if attr is not None and not (isinstance(attr.value, int) and 0 < attr.value <= 1_000_000):
        raise ArtibusError(f"{label}: Baudrate {attr.value!r}: expected a bit rate in bit/s (1 .. 1000000)")
    for m in db.messages:
        head = f"{label}: message {m.name} (0x{m.frame_id:03X})"
        if m.is_extended_frame or m.is_fd:
            raise ArtibusError(f"{head}: only classic CAN frames with 11-bit identifiers are supported")
        if m.is_multiplexed():
            raise ArtibusError(f"{head}: multiplexed messages are not supported")
        sig = {s.name: s for s in m.signals}
        for name, start, length in ((CRC_SIGNAL, 0, 8), (COUNTER_SIGNAL, 8, 4)):
            s = sig.get(name)
            if s is None or s.start != start or s.length != length or s.is_signed or s.byte_order != "little_endian":
                raise ArtibusError(f"{head}: signal {name}: every frame needs an unsigned {length}-bit "
                                   f"{name} at bit {start} (E2E profile 2 layout)")
        if m.length < 2:
            raise ArtibusError(f"{head}: DLC {m.length}: CRC and counter need 2 bytes")
        attr = m.dbc.attributes.get("E2EDataID") if m.dbc else None
        if attr is None:
            raise ArtibusError(f"{head}: no E2EDataID attribute (the data ID of its CRC)")
        if not (isinstance(attr.value, int) and 0 <= attr.value <= 255):
            raise ArtibusError(f"{head}: E2EDataID {attr.value!r}: expected an integer 0 .. 255 "
                               f"(the data ID of its CRC, E2E profile 2)")
        if not (isinstance(m.cycle_time, int) and m.cycle_time > 0):
            raise ArtibusError(f"{head}: no GenMsgCycleTime (the network sends cyclically)")
    return db


def dbc_in(ssp_dir, spec):
    return Path(ssp_dir) / (spec.get("source") or "")
