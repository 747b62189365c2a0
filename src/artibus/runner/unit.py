"""A component while it runs (``Unit``), the connections into it (``Link``),
and its calls into the FMU: fmi2GetReal/SetReal/DoStep (an FMI 3.0 FMU:
fmi3GetFloat64/SetFloat64/DoStep; a Model Exchange FMU: the ME facade's, artibus.fmu.me)
through ctypes on buffers allocated once (``_RawCalls``), Integer, Boolean, String and Enumeration variables through
FMPy's calls (``_TypedCalls``, the conversion of such a connection:
``_typed_convert``)."""
from ctypes import CDLL, c_double, c_int, c_size_t, c_uint, c_void_p
from dataclasses import dataclass, field
from itertools import accumulate

from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
from artibus.fmu import Fmu


@dataclass
class Link:
    """One connection, resolved to value references."""
    src: "Unit"
    src_index: int          # index into src.outputs
    dst: "Unit"
    dst_index: int          # index into dst.inputs
    factor: float
    offset: float
    name: str
    connection: object = None   # the bench's Connection (ssp.Connection)


@dataclass(eq=False)        # a unit is itself: compared by identity
class Unit:
    """A component while it runs."""
    path: str
    fmu: Fmu
    step: float
    ratio: int = 1                               # step / base step
    inputs: list = field(default_factory=list)   # the Float64 inputs the core sets (Variables)
    outputs: list = field(default_factory=list)  # the Float64 outputs the core reads (Variables)
    out_values: list = field(default_factory=list)
    in_values: list = field(default_factory=list)
    feeds: set = field(default_factory=set)      # (input name, output name) direct feedthrough
    links_in: list = field(default_factory=list)  # the Links into its inputs
    sources: list = field(default_factory=list)   # the same Links as (input index, source
                                                  # output buffer, output index, factor, offset)
    stimuli: list = field(default_factory=list)   # (input index, f(t), base value or None)
    wall: float = 0.0
    raw: object = None                           # _RawCalls, once the variables are known
    # the other types' variables (Integer, Boolean, String, Enumeration, Float32: _TypedCalls):
    tout: list = field(default_factory=list)     # outputs read (Variables)
    tin: list = field(default_factory=list)      # connected inputs (Variables)
    typed_sources: list = field(default_factory=list)  # (input index, source unit, output index, convert)

    in_names = property(lambda self: [v.name for v in self.inputs])
    in_vrs = property(lambda self: [v.valueReference for v in self.inputs])
    out_names = property(lambda self: [v.name for v in self.outputs])
    out_vrs = property(lambda self: [v.valueReference for v in self.outputs])

    def output_index(self, v):
        """The place of the Float64 output ``v`` in ``outputs``, added if not there yet."""
        if v not in self.outputs:
            self.outputs.append(v)
        return self.outputs.index(v)

    def input_index(self, v):
        """The place of the Float64 input ``v`` in ``inputs``, added if not there yet."""
        if v not in self.inputs:
            self.inputs.append(v)
        return self.inputs.index(v)

    def column(self, name):
        """The place of an output in raw.out (Float64 ones first, then the typed ones, an
        array's elements in row-major order, FMI 3.0 2.2.6.2); ``name`` an array's element as
        its result column names it (``y[2]``, ``A[1,2]``) or a scalar's name."""
        names = self.out_names
        if name in names:
            return names.index(name)
        v, k = self.element(name)
        place = len(names)
        for w in self.tout:
            if w is v:
                return place + k
            place += w.size
        raise ValueError(f"{self.path}.{name} is not read")

    def element(self, name):
        """(the Variable, the element's row-major offset) of a column's name: a variable's own
        name (0), or an array's element ``name[i,j]`` (1-based, FMI 3.0 2.4.7.6's convention)."""
        vars_ = self.fmu.vars
        if name in vars_ or not name.endswith("]") or "[" not in name:
            return self.fmu.var(name), 0
        base, _, idx = name[:-1].rpartition("[")
        v = self.fmu.var(base)
        index = [int(i) - 1 for i in idx.split(",")]
        if len(index) != len(v.shape) or not all(0 <= i < n for i, n in zip(index, v.shape)):
            raise ArtibusError(f"{self.path}.{name}: {base} is {v.type}[{','.join(map(str, v.shape))}]")
        k = 0
        for i, n in zip(index, v.shape):
            k = k * n + i
        return v, k

    def variable_of(self, name):
        """The Variable a column's name (a scalar's, or an array's element's) is of."""
        return self.element(name)[0]


def _address(dll, name):
    """The address of the function ``name`` of a library, None when it lacks it."""
    from ctypes import cast
    try:
        return cast(getattr(dll, name), c_void_p).value
    except AttributeError:
        return None


class _RawCalls:
    """A unit's fmi2GetReal/SetReal/DoStep (FMI 3.0: fmi3GetFloat64/SetFloat64, whose
    nValues is nValueReferences for scalar Float64 variables, FMI 3.0 2.2.6.2;
    fmi3DoStep), from a handle of our own on the FMU's library (FMPy's are left as
    they are), with the value references and value buffers allocated once: the
    stepping core calls them through their addresses on these buffers
    (artibus.runner.core), Python's read and write only in the initialisation's
    exits. Whether a step ended the run is the core's to decide (core.c's
    unit_ended: FMI 3.0's terminateSimulation, FMI 2.0's fmi2Discard with
    fmi2Terminated, through status_functions)."""

    def __init__(self, unit):
        slave = unit.fmu.slave
        self.fmi, self.slave = unit.fmu.fmi, slave
        facade = getattr(unit.fmu.calls, "facade", None)    # Model Exchange (artibus.fmu.me)
        if facade is not None:
            self._me_calls(facade)
        else:
            dll = CDLL(slave.dll._name)      # the library FMPy loaded: the same instance
            v = "fmi3" if self.fmi == 3 else "fmi2"
            self._get, self._set, self._do = (getattr(dll, f"{v}{f}") for f in
                                              (("GetFloat64", "SetFloat64", "DoStep") if self.fmi == 3
                                               else ("GetReal", "SetReal", "DoStep")))
            self.comp = c_void_p(slave.component)
        for f in (self._get, self._set, self._do):
            f.restype = c_int
        self.n_out, self.n_in = len(unit.out_vrs), len(unit.in_vrs)
        self._n_out, self._n_in = c_size_t(self.n_out), c_size_t(self.n_in)
        # FMI 3.0: nValues after the values; fmi3DoStep's out-arguments
        self._nv_out, self._nv_in = ((self._n_out,), (self._n_in,)) if self.fmi == 3 else ((), ())
        self.terminate, self.last_successful_time = False, None     # (after the core's run: AC_ENDED)
        self.out_vrs = (c_uint * self.n_out)(*unit.out_vrs)
        self.out = (c_double * self.n_out)()
        self.in_vrs = (c_uint * self.n_in)(*unit.in_vrs)
        self.inp = (c_double * self.n_in)()
        self.written = None       # the input values last set (bytes): unchanged ones are not set again
        # FMI 2.0: fmi2GetBooleanStatus/fmi2GetRealStatus, whose fmi2Terminated says the FMU ended
        # the run (the stepping core asks them: core.h's ac_unit), None where the library lacks them
        if facade is not None:
            self.status_functions = (None, None) if self.fmi == 3 else (
                facade.functions["getBooleanStatus"], facade.functions["getRealStatus"])
        else:
            self.status_functions = (None, None) if self.fmi == 3 else tuple(
                _address(dll, f"fmi2Get{w}Status") for w in ("Boolean", "Real"))

    def _me_calls(self, facade):
        """A Model Exchange unit's calls: the ME facade's (src/runner_core/me.c), with the
        facade as the component: its step integrates the FMU, its get and set pass through."""
        names = (("artibus_me3_get_float64", "artibus_me3_set_float64", "artibus_me3_do_step") if self.fmi == 3
                 else ("artibus_me_get_real", "artibus_me_set_real", "artibus_me_do_step"))
        self._get, self._set, self._do = (facade.lib[n] for n in names)     # (objects of their own)
        self.comp = c_void_p(facade.component)

    def read(self):
        if self.n_out:
            status = self._get(self.comp, self.out_vrs, self._n_out, self.out, *self._nv_out)
            if status > 1:  # fmi2Discard or worse
                raise FMICallException(function="fmi3GetFloat64" if self.fmi == 3 else "fmi2GetReal",
                                       status=status)

    def write(self):
        if self.n_in:
            values = bytes(self.inp)
            if values == self.written:    # the FMU holds them already (FMI 2.0, 3.0: inputs keep their values)
                return
            status = self._set(self.comp, self.in_vrs, self._n_in, self.inp, *self._nv_in)
            if status > 1:
                raise FMICallException(function="fmi3SetFloat64" if self.fmi == 3 else "fmi2SetReal",
                                       status=status)
            self.written = values


class _TypedCalls(_RawCalls):
    """_RawCalls of a unit with Integer, Boolean, String or Enumeration
    variables connected or recorded: those go through FMPy's calls (one per
    type), after the Real ones. Their values as read are in ``tout_values``
    (Python values) and, for the recording, as numbers after the Real outputs
    in ``out``: a Boolean as 0/1, an Integer or Enumeration as its value, a
    String as the number of its text in ``texts`` (the order in which each
    text was first seen). The inputs to set are in ``tin_values``; unchanged
    ones are not set again. The C stepping core sets and gets the Real ones and calls
    back for the others (read_typed, write_typed: artibus.runner.core._Hooks)."""

    def __init__(self, unit):
        super().__init__(unit)
        n_real = self.n_out
        self.n_real, self.n_out = n_real, n_real + sum(v.size for v in unit.tout)   # (an array: its elements)
        # each typed output's first place in ``out``
        self.tout_places = list(accumulate((v.size for v in unit.tout), initial=n_real))[:-1]
        self.out = (c_double * self.n_out)()
        self.tout_values = [None] * len(unit.tout)
        self.tin_values = [None] * len(unit.tin)
        self.tin_written = None
        self.texts = {}
        self._get_groups = self._groups(unit.tout, self.fmi)
        self._set_groups = self._groups(unit.tin, self.fmi)
        # a Model Exchange unit's inputs through its instance (artibus.fmu.me: a discrete one
        # changed after the initialisation in an input event of its own, FMI 3.0 3.2.1)
        self._me = unit.fmu.calls if getattr(unit.fmu.calls, "facade", None) is not None else None
        self._tin = list(unit.tin)
        self._string_out = [i for i, v in enumerate(unit.tout) if v.kind == "String"]

    @staticmethod
    def _groups(variables, fmi=2):
        """[(the get/set call's type, [indices], [value references], [sizes])] per type (each FMI
        version's calls: artibus.fmu.fmi2.ACCESSOR, artibus.fmu.fmi3.ACCESSOR); a size is the
        number of values a variable moves (an array's elements: FMI 3.0 2.2.6.2, nValues)."""
        from artibus.fmu import fmi2, fmi3
        accessor = (fmi3 if fmi == 3 else fmi2).ACCESSOR
        groups = {}
        for i, v in enumerate(variables):
            g = groups.setdefault(accessor[v.type], ([], [], []))
            g[0].append(i)
            g[1].append(v.valueReference)
            g[2].append(v.size if v.shape else 0)     # (0: a scalar)
        return [(t, idx, vrs, sizes) for t, (idx, vrs, sizes) in groups.items()]

    def read(self):
        if self.n_real:
            status = self._get(self.comp, self.out_vrs, self._n_out, self.out, *self._nv_out)
            if status > 1:  # fmi2Discard or worse
                raise FMICallException(function="fmi3GetFloat64" if self.fmi == 3 else "fmi2GetReal",
                                       status=status)
        self.read_typed()

    def read_typed(self):
        """The typed outputs (FMPy's calls), after the Real ones (the stepping core's
        AC_HOOK_READ: the core reads the Real ones)."""
        for t, idx, vrs, sizes in self._get_groups:
            n_values = sum(max(1, n) for n in sizes)
            get = getattr(self.slave, f"get{t}")
            values = get(vrs, n_values) if n_values != len(vrs) else get(vrs)   # (FMI 2.0: no nValues)
            k = 0
            for i, n in zip(idx, sizes):
                place = self.tout_places[i]
                if n:                   # an array: its values row-major, each in its own place
                    xs = [self._number(t, x, place + j) for j, x in enumerate(values[k:k + n])]
                    self.tout_values[i] = xs
                else:
                    self.tout_values[i] = self._number(t, values[k], place)
                k += max(1, n)

    def _number(self, t, x, place):
        """A value as Python has it, its number put in out[place] (a Boolean 0/1, a String the
        number of its text)."""
        if t == "String":               # (FMI 3.0: FMPy's str already)
            x = x.decode("utf-8", errors="replace") if isinstance(x, bytes) else x or ""
            self.out[place] = self.texts.setdefault(x, len(self.texts))
        else:
            x = bool(x) if t == "Boolean" else float(x) if t in ("Float32", "Float64") else int(x)
            self.out[place] = x
        return x

    def write(self):
        super().write()
        self.write_typed()

    def write_typed(self):
        """The typed inputs that changed (FMPy's calls), after the Real ones (the
        stepping core's AC_HOOK_WRITE)."""
        if self.tin_values and self.tin_values != self.tin_written and self._me is not None:
            self._me.set(self._tin, self.tin_values)
            self.tin_written = list(self.tin_values)
        elif self.tin_values and self.tin_values != self.tin_written:
            for t, idx, vrs, sizes in self._set_groups:
                getattr(self.slave, f"set{t}")(vrs, [x for i, n in zip(idx, sizes)
                                                     for x in (self.tin_values[i] if n else (self.tin_values[i],))])
            self.tin_written = list(self.tin_values)

    def text(self, number):
        """The String whose number (see above) a recorded column holds."""
        if not hasattr(self, "_by_number") or len(self._by_number) != len(self.texts):
            self._by_number = {k: x for x, k in self.texts.items()}
        return self._by_number.get(number, "")


def _typed_convert(label, a, va, b, vb, mapping):
    """The conversion of a connection's value from the Integer, Boolean,
    String or Enumeration output va to the input vb: the types must be the
    same (an error naming both ends otherwise); an Enumeration to one of other
    items needs a mapping (SSP 1.0's EnumerationMappingTransformation by item
    names, or IntegerMappingTransformation by values); a mapping (SSP 1.0's
    Boolean-, Integer- or EnumerationMappingTransformation) maps the values
    it lists, the others pass unchanged."""
    ends = (f"{a.path}.{va.name} is {va.type}{' ' + va.declaredType.name if va.declaredType else ''}, "
            f"{b.path}.{vb.name} is {vb.type}{' ' + vb.declaredType.name if vb.declaredType else ''}")
    if va.kind != vb.kind:
        raise ArtibusError(f"{label}: the types differ ({ends}): a connection joins variables of one type")
    kind, table = mapping if mapping else (None, None)
    expect = {"Boolean": ("Boolean",), "Integer": ("Integer",), "Enumeration": ("Integer", "Enumeration")}
    if kind is not None and kind not in expect.get(va.kind, ()):
        raise ArtibusError(f"{label}: a {kind}MappingTransformation does not apply to {ends}")
    if va.kind == "Integer" and va.type != vb.type:       # (Int16 -> Int32, ...): in the input's range
        return _in_range(label, vb, None if kind is None else table)
    if va.kind == "Enumeration":
        items_a = {i.name: int(i.value) for i in va.declaredType.items}
        items_b = {i.name: int(i.value) for i in vb.declaredType.items}
        if kind == "Enumeration":
            for src, dst in table.items():
                if src not in items_a or dst not in items_b:
                    raise ArtibusError(f"{label}: EnumerationMappingTransformation {src} -> {dst}: "
                                       f"items of {va.declaredType.name}: {', '.join(items_a)}; "
                                       f"of {vb.declaredType.name}: {', '.join(items_b)}")
            names_a = {k: n for n, k in items_a.items()}
            table = {k: items_b[table.get(name, name)] for k, name in names_a.items()
                     if table.get(name, name) in items_b}
            kind = "Integer"
        elif kind is None and items_a != items_b:
            raise ArtibusError(f"{label}: the enumerations differ ({ends}: items "
                               f"{', '.join(f'{n}={k}' for n, k in items_a.items())} against "
                               f"{', '.join(f'{n}={k}' for n, k in items_b.items())}); "
                               f"an EnumerationMappingTransformation maps them")
    if kind is None:
        return None
    return lambda x: table.get(x, x)


def _in_range(label, vb, table):
    """The conversion into the integer input ``vb`` of another width (FMI 3.0: Int16 -> Int32,
    ...): the value mapped (``table``: an IntegerMappingTransformation), then refused, naming the
    connection, when outside ``vb``'s type (FMI 3.0 2.4.7.4.2), never wrapped."""
    from artibus.bench.fmi import INTEGER_RANGE
    low, high = INTEGER_RANGE.get(vb.type, INTEGER_RANGE["Int32"])

    def convert(x):
        y = table.get(x, x) if table else x
        if not low <= y <= high:
            raise ArtibusError(f"{label}: {y} is outside the range of {vb.name}'s {vb.type} [{low}, {high}]")
        return y
    return convert


def _last_message(log):
    """The FMU's last error message, else its last message."""
    errors = [m for m in log if m.startswith(("[Error]", "[Fatal]"))]
    return errors[-1] if errors else log[-1] if log else "no message"
