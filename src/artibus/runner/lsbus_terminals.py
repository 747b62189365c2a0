"""What an FMI-LS-BUS FMU declares (``read_terminals``: its network terminals, ``Terminal``: the
value references of a terminal's four members and its Tx clock's form, period and shift;
``check_mime``: the CAN MIME type of a terminal's binaries) and the network's error
(``LsBusError``); artibus.runner.lsbus runs the network."""
import math
import xml.etree.ElementTree as ET
import zipfile

from artibus.base import ArtibusError

NETWORK_TERMINAL = "org.fmi-ls-bus.network-terminal"
MEMBERS = ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock")
EPS = 1e-9           # s: two times this close are one instant


class LsBusError(ArtibusError):
    """A bad network, bad input or a refused call; the message names the FMU and the variable
    (an ArtibusError: the command line says it in one line, no traceback)."""


class Terminal:
    """One bus terminal of an FMU: the value references of its four members and, for a
    time-based Tx clock, its period and shift."""

    def __init__(self, fmu_name, name, members, variables, clocks, max_sizes=None):
        self.name = name
        missing = [m for m in MEMBERS if m not in members]
        if missing:
            raise LsBusError(f"{fmu_name}: terminal {name} has no member {', '.join(missing)}")
        v = {m: variables[members[m]] for m in MEMBERS}
        self.rx_data, self.tx_data = v["Rx_Data"].valueReference, v["Tx_Data"].valueReference
        self.rx_clock, self.tx_clock = v["Rx_Clock"].valueReference, v["Tx_Clock"].valueReference
        tx = v["Tx_Clock"]
        self.tx_kind = tx.intervalVariability
        self.period = self.shift = None
        if self.tx_kind in ("constant", "fixed"):
            interval, shift = clocks.get(tx.name, (None, None))
            try:
                self.period, self.shift = float(interval), float(shift or 0.0)
            except (TypeError, ValueError):
                self.period = None
            if not self.period or self.period <= 0 or not math.isfinite(self.period):
                raise LsBusError(f"{fmu_name}: {tx.name} is {self.tx_kind} but has intervalDecimal="
                                 f"{interval!r}: no period to tick it with")
        elif self.tx_kind not in ("countdown", "triggered"):
            raise LsBusError(f"{fmu_name}: {tx.name} has intervalVariability={self.tx_kind!r}; "
                             "this master ticks constant, fixed, countdown and triggered clocks")
        self.tx_name = tx.name
        # a triggered output Tx clock: the FMU activates it (fmi-ls-bus 1.0, "Triggered Tx Clocks")
        self.tx_output = tx.causality == "output"
        # Rx_Data's maxSize (FMI 3.0.2, 2.4.7.6, Binary: "maximal size of a value" in bytes), None: unbounded
        size = (max_sizes or {}).get(v["Rx_Data"].name)
        self.rx_max = int(size) if size and size.isdigit() else None

    def next_tick(self, t0, t):
        """the first tick of a periodic Tx clock after the instant t, i.e. later than t + EPS
        (ticks at t0 + shift + k period), the same instants as ticks_at"""
        k = math.floor((t + EPS - t0 - self.shift) / self.period) + 1
        return t0 + self.shift + max(k, 0) * self.period

    def ticks_at(self, t0, t):
        if self.period is None:
            return False
        k = round((t - t0 - self.shift) / self.period)
        return k >= 0 and abs(t0 + self.shift + k * self.period - t) <= EPS


from artibus.bench.ssp2 import CAN_MIME_TYPE as CAN_MIME, is_can_mime   # noqa: E402 (one definition)


def check_mime(path, name, mime):
    """A terminal's Rx_Data/Tx_Data carries CAN operations of FMI-LS-BUS 1.x: the MIME type
    application/org.fmi-standard.fmi-ls-bus.can with a version parameter of major version 1
    (fmi-ls-bus v1.0.0 4____network_abstraction.adoc, "MIME Types": the version marks the set
    of operations and follows semantic versioning, so 1.x keeps 1.0.0's operations). A
    pre-release of it is taken too: the fmi-ls-bus-examples declare version="1.0.0-beta.1",
    and their headers (fmi-ls-bus 468127f) lay out every CAN operation as v1.0.0's do.
    Anything else (another bus, version 2, no version) is an LsBusError naming it."""
    if not is_can_mime(mime):
        raise LsBusError(f"{path}: {name} has mimeType {mime!r}; this master connects FMI-LS-BUS CAN "
                         f'terminals: {CAN_MIME}; version="1.x.y" (1.0.0 or a pre-release of it)')


def read_terminals(path, md, fmu_name):
    """{name: Terminal} of the network terminals in terminalsAndIcons/terminalsAndIcons.xml
    (FMI 3.0.2, 2.4.9; the terminal kind of 4____network_abstraction.adoc, "Bus Terminal")."""
    with zipfile.ZipFile(path) as z:
        try:
            root = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
        except KeyError:
            raise LsBusError(f"{path}: no terminalsAndIcons/terminalsAndIcons.xml: not an LS-BUS FMU") from None
        # the clocks' intervalDecimal and shiftDecimal, the binaries' mimeType (FMPy 0.3 reads neither)
        md_root = ET.fromstring(z.read("modelDescription.xml"))
        clocks = {c.get("name"): (c.get("intervalDecimal"), c.get("shiftDecimal")) for c in md_root.iter("Clock")}
        mimes = {b.get("name"): b.get("mimeType") for b in md_root.iter("Binary")}
        sizes = {b.get("name"): b.get("maxSize") for b in md_root.iter("Binary")}
    variables = {v.name: v for v in md.modelVariables}
    out = {}
    for t in root.iter("Terminal"):
        if t.get("terminalKind") != NETWORK_TERMINAL:
            continue
        members = {m.get("memberName"): m.get("variableName") for m in t.findall("TerminalMemberVariable")}
        for m, name in members.items():
            if name not in variables:
                raise LsBusError(f"{path}: terminal {t.get('name')} member {m} names {name!r}, "
                                 "which modelDescription.xml does not declare")
        for m in ("Rx_Data", "Tx_Data"):
            if m in members:
                check_mime(path, members[m], mimes.get(members[m]))
        out[t.get("name")] = Terminal(fmu_name, t.get("name"), members, variables, clocks, sizes)
    if not out:
        raise LsBusError(f"{path}: terminalsAndIcons.xml has no terminal of kind {NETWORK_TERMINAL}")
    return out
