"""CAN in the loop: connections of a bench that travel over a CAN network.

- ``dbc``: the DBC (cantools), checked for what the network needs; the units a
  signal may carry;
- ``network``: ``Network``, the CAN path of one run (ticks, frames, the
  receivers' E2E check, bus load and response times);
- ``codec``: the E2E CRC, a frame's bits on the wire, worst-case response times;
- ``faults``: faults injected into the network (``parse_fault``, ``Fault``);
- ``logs``: .blf/.asc logs read and decoded through the DBC;
- ``replay``: a recorded log (CSV or CAN) drives a bench, and the model is
  compared with what the log measured.
"""
from artibus.can.codec import e2e_crc, frame_bits, response_times, worst_case_bits          # noqa: F401
from artibus.can.dbc import COUNTER_SIGNAL, CRC_SIGNAL, DEFAULT_BITRATE, UNITS, dbc_in, load_dbc   # noqa: F401
from artibus.can.faults import (BUSOFF_ATTEMPTS, CORRUPT_MODES, ERROR_FRAME_BITS, FAULT_KINDS,  # noqa: F401
                                FAULT_SYNTAX, RECOVERY_BITS, Fault, parse_fault)
from artibus.can.logs import decode_log, read_log                                       # noqa: F401
from artibus.can.network import Network                                                 # noqa: F401
