"""The time-based input clocks of one FMI 3.0 Co-Simulation FMU that runs alone (``Schedule``):
when `artibus simulate` activates each, in Event Mode (issue 38).

FMI 3.0 2.2, "Clocks" ("Clock Types", the table "Overview of Clock types"): an input Clock is
activated by the importer with fmi3SetClock in Event Mode; a time-based one at times the FMU
defines:
- periodic (intervalVariability constant, fixed, tunable): t_0 = t_start + T_shift,
  t_i = t_{i-1} + T_interval ("Periodic Clock"); T_interval and T_shift from intervalDecimal and
  shiftDecimal (else intervalCounter and shiftCounter over resolution), else, where the model
  description gives no interval ("fixed"/"tunable" Clocks without intervalDecimal), from
  fmi3GetIntervalDecimal and fmi3GetShiftDecimal in Initialization Mode. Here
  t_i = t_0 + i T_interval (no drift from a sum of doubles);
- aperiodic (changing, countdown): the next activation at the current event's time plus the
  interval fmi3GetIntervalDecimal returns qualified fmi3IntervalChanged ("In Event Mode ... the
  new Clock interval is always relative to the time of the current Event Mode"), asked in
  Initialization Mode and after each Event Mode's update (a countdown Clock: "in every Event
  Mode");
- triggered input Clocks are activated by another FMU or the importer's own logic: a lone FMU
  has none of either, they stay inactive;
- an output Clock (always triggered) is activated by the FMU, in an Event Mode it asks for
  (fmi3DoStep's eventHandlingNeeded; its nextEventTime, where it says one, cuts the steps): "The
  importer calls fmi3GetClock to inquire the Clock's activation state" ("Output Clock").
A periodic Clock is active for one fmi3UpdateDiscreteStates per Event Mode (2.3, "Event Mode":
"Periodic Clocks must not be active for more than one call of fmi3UpdateDiscreteStates per
Event Mode"): each activation is one tick here."""
import ctypes
import math
import zipfile

from artibus.base import ArtibusError

PERIODIC = ("constant", "fixed", "tunable")
APERIODIC = ("changing", "countdown")
#: fmi3IntervalQualifier (fmi3FunctionTypes.h): fmi3IntervalChanged
CHANGED = 2


class Clock:
    """One time-based input Clock: ``vr``, ``name``, ``variability`` (intervalVariability),
    ``interval`` and ``shift`` in s (None: the FMU says, in Initialization Mode), ``due`` the
    time of its next activation (inf: none known), ``ticks`` its activations so far."""

    def __init__(self, el):
        self.vr, self.name = int(el.get("valueReference")), el.get("name")
        self.variability = el.get("intervalVariability")
        resolution = el.get("resolution")
        self.interval = _seconds(el.get("intervalDecimal"), el.get("intervalCounter"), resolution)
        self.shift = _seconds(el.get("shiftDecimal"), el.get("shiftCounter"), resolution) or 0.0
        self.t0, self.due, self.ticks = None, math.inf, 0

    def __repr__(self):
        return f"Clock({self.name}: {self.variability}, interval {self.interval}, next {self.due})"


def _seconds(decimal, counter, resolution):
    """A time from its decimal attribute, else its counter over the resolution, else None."""
    if decimal is not None:
        return float(decimal)
    if counter is not None and resolution:
        return int(counter) / int(resolution)
    return None


def read_clocks(path):
    """(the time-based input Clocks, the value references of the output Clocks) of the FMU file
    ``path`` (FMPy 0.3 reads no intervalDecimal nor shiftDecimal: read from its
    modelDescription.xml here)."""
    from lxml import etree
    with zipfile.ZipFile(str(path)) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    clocks = root.findall("ModelVariables/Clock")
    return ([Clock(el) for el in clocks
             if el.get("causality") == "input" and el.get("intervalVariability") in PERIODIC + APERIODIC],
            [int(el.get("valueReference")) for el in clocks if el.get("causality") == "output"])


class Schedule:
    """When the Clocks of one FMU (``calls``: artibus.fmu.fmi3.Calls) tick: ``next_time()``,
    ``due(t)`` the value references to activate at t, ``ticked(vrs)`` after activating them,
    ``update(t)`` after each Event Mode's update (the aperiodic Clocks' new intervals),
    ``active_outputs()`` the output Clocks the FMU activated. ``next_event``: the FMU's
    nextEventTime counts as a time to stop at (an FMU that takes variable steps)."""

    def __init__(self, calls, clocks, where, outputs=(), next_event=False):
        self.calls, self.clocks, self.where = calls, clocks, where
        self.outputs, self.next_event = list(outputs), next_event

    def start(self, start_time):
        """In Initialization Mode: each periodic Clock's interval and shift (asked of the FMU where
        the model description has none), its first activation t_start + T_shift; the aperiodic
        Clocks' first intervals, relative to t_start."""
        unknown = [c for c in self.clocks if c.variability in PERIODIC and c.interval is None]
        if unknown:
            intervals, _ = self._intervals(unknown)
            shifts = self._shifts(unknown)
            for c, iv, sh in zip(unknown, intervals, shifts):
                c.interval, c.shift = iv, sh
        for c in self.clocks:
            if c.variability in PERIODIC:
                if not (c.interval is not None and c.interval > 0 and math.isfinite(c.interval)):
                    raise ArtibusError(f"{self.where}: Clock {c.name}: interval {c.interval} s; a periodic "
                                       "Clock's interval must be > 0 (FMI 3.0 2.2, \"Periodic Clock\")")
                c.t0 = c.due = start_time + c.shift
        self.update(start_time)

    def next_time(self):
        """The time of the next activation (inf: none), or of the FMU's next event if sooner"""
        t = min((c.due for c in self.clocks), default=math.inf)
        return min(t, self.calls.next_event) if self.next_event else t

    def active_outputs(self):
        """The value references of the output Clocks active now (fmi3GetClock, in Event Mode)"""
        if not self.outputs:
            return []
        return [vr for vr, on in zip(self.outputs, self.calls.slave.getClock(self.outputs)) if on]

    def due(self, t):
        """The value references of the Clocks to activate at t (their time reached, within 1e-9
        relative, as the steps' points are compared)."""
        return [c.vr for c in self.clocks if c.due <= t or math.isclose(c.due, t)]

    def ticked(self, vrs):
        """The Clocks ``vrs`` activated: a periodic one's next time t_0 + i T_interval, an
        aperiodic one none until the FMU gives a new interval."""
        for c in self.clocks:
            if c.vr in vrs:
                c.ticks += 1
                c.due = c.t0 + c.ticks * c.interval if c.variability in PERIODIC else math.inf

    def update(self, t):
        """After an update at t (and in Initialization Mode): each aperiodic Clock's interval, where
        the FMU says fmi3IntervalChanged, its next activation at t + interval."""
        aperiodic = [c for c in self.clocks if c.variability in APERIODIC]
        if not aperiodic:
            return
        intervals, qualifiers = self._intervals(aperiodic)
        for c, iv, q in zip(aperiodic, intervals, qualifiers):
            if q == CHANGED:
                if not (iv >= 0 and math.isfinite(iv)):
                    raise ArtibusError(f"{self.where}: Clock {c.name}: fmi3GetIntervalDecimal gave {iv} s at "
                                       f"t = {t:g} s; an interval is >= 0")
                c.due = t + iv

    def _intervals(self, clocks):
        n = len(clocks)
        vrs = (ctypes.c_uint32 * n)(*[c.vr for c in clocks])
        iv, q = (ctypes.c_double * n)(), (ctypes.c_int * n)()
        self.calls.slave.getIntervalDecimal(vrs, iv, q)
        return list(iv), list(q)

    def _shifts(self, clocks):
        n = len(clocks)
        vrs = (ctypes.c_uint32 * n)(*[c.vr for c in clocks])
        sh = (ctypes.c_double * n)()
        self.calls.slave.getShiftDecimal(vrs, sh)
        return list(sh)
