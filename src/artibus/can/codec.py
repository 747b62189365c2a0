"""A frame's E2E CRC (AUTOSAR profile 2), its bits on the wire, and the
worst-case response times of periodic messages (Davis et al. 2007)."""
import functools
import math


def _crc8h2f_table():
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = ((c << 1) ^ 0x2F) & 0xFF if c & 0x80 else (c << 1) & 0xFF
        table.append(c)
    return table


_CRC8H2F = _crc8h2f_table()


def e2e_crc(data, data_id):
    """AUTOSAR E2E profile 2's CRC of a frame: CRC-8H2F (polynomial 0x2F,
    start and final XOR 0xFF) over bytes 1.. and the data ID; the same number
    as cantools.autosar.end_to_end.compute_profile2_crc(data, data_id), with a
    table (the tests compare them), 10 x faster."""
    crc = 0xFF
    for b in data[1:]:
        crc = _CRC8H2F[crc ^ b]
    return _CRC8H2F[crc ^ data_id] ^ 0xFF


@functools.lru_cache(maxsize=1 << 16)
def frame_bits(can_id, data):
    """Bits a classic data frame with an 11-bit identifier takes on the wire:
    SOF to CRC with its stuff bits counted exactly (a complement bit after
    five equal bits), CRC delimiter, ACK, EOF, 3 bits of interframe space.
    data: bytes."""
    head = (can_id << 7) | len(data)            # SOF 0, ID, RTR 0, IDE 0, r0 0, DLC
    n = 19 + 8 * len(data)
    v = (head << (8 * len(data))) | int.from_bytes(data, "big")
    crc = 0
    for i in range(n - 1, -1, -1):              # CRC-15, polynomial 0x4599 (ISO 11898-1)
        if ((v >> i) & 1) ^ (crc >> 14):
            crc = ((crc << 1) & 0x7FFF) ^ 0x4599
        else:
            crc = (crc << 1) & 0x7FFF
    bits = format((v << 15) | crc, f"0{n + 15}b")
    stuff, run, prev = 0, 0, ""
    for b in bits:
        if b == prev:
            run += 1
            if run == 5:                            # a complement bit; it starts the next run
                stuff += 1
                prev, run = ("1" if b == "0" else "0"), 1
        else:
            prev, run = b, 1
    return n + 15 + stuff + 10 + 3


def worst_case_bits(dlc):
    """Davis et al. 2007, eq. (1) with g = 34 (11-bit identifiers): the longest
    frame of dlc data bytes, worst-case stuffing, interframe space included."""
    return 34 + 8 * dlc + 13 + (34 + 8 * dlc - 1) // 4


def response_times(messages, bitrate):
    """Worst-case response times (s) of periodic messages on CAN, Davis et al.
    2007, section 4: messages = [(identifier, dlc, period s)], priority by
    identifier, no jitter, deadline = period. Returns {identifier: R} (inf
    when the busy period does not end)."""
    tau = 1.0 / bitrate
    msgs = sorted((i, worst_case_bits(d) * tau, T) for i, d, T in messages)
    out = {}
    for n, (mid, C, T) in enumerate(msgs):
        hp = msgs[:n]
        B = max((c for _, c, _ in msgs[n + 1:]), default=0.0)
        if sum(Ck / Tk for _, Ck, Tk in msgs[:n + 1]) >= 1.0:   # the busy period never ends
            out[mid] = math.inf
            continue
        t = C                                       # busy period, eq. (8)
        for _ in range(10000):
            t_new = B + sum(math.ceil(t / Tk) * Ck for _, Ck, Tk in msgs[:n + 1])
            if t_new == t:
                break
            t = t_new
        else:
            out[mid] = math.inf
            continue
        R = 0.0
        for q in range(math.ceil(t / T)):           # every instance in the busy period, eqs. (9)-(11)
            w = B + q * C
            for _ in range(10000):
                w_new = B + q * C + sum(math.ceil((w + tau) / Tk) * Ck for _, Ck, Tk in hp)
                if w_new == w:
                    break
                w = w_new
            R = max(R, w - q * T + C)
        out[mid] = R
    return out
