"""A Simulation's set-up (``Simulation.__init__``'s work, ``_Setup``): the
units and their steps, the parameters (the bench's bindings, then the user's
overrides, resolved and checked), the connections (with SSP's transformations
or the units' conversion; Integer, Boolean, String and Enumeration ones
exactly), the CAN network of a bench that routes connections over CAN, the
order, the recording and the stimuli."""
from pathlib import Path

import numpy as np

from artibus.base import ArtibusError
from artibus.bench.parameters import check_against, suggest
from artibus.bench.units import Quantity, convert, declared_unit, unit_conversion
from artibus.fmu import Fmu
from artibus.runner.plan import feedthrough, gauss_seidel_order, loop_warning, wire
from artibus.runner.unit import Link, Unit, _RawCalls, _TypedCalls, _typed_convert


def resolve_resources(tmp, where, values, origins=None):
    """A String parameter "resources/<file>" names a file inside the .ssp: its
    value in ``values`` becomes that file's path in the unpacked copy ``tmp``.
    An error names the bench (``where``) and where the value is from
    (``origins[var]``: the parameter file and its element, or --set) where given."""
    for var, value in values.items():
        if isinstance(value, str) and value.startswith("resources/"):
            f = Path(tmp) / value
            if not f.is_file():
                origin = (origins or {}).get(var)
                raise ArtibusError(f"{where}: parameter '{var}' = {value!r}"
                                   + (f" (from {origin})" if origin else "") + ": no such file in the .ssp")
            values[var] = str(f)


class _Setup:
    """The set-up of a Simulation (see the module's docstring); Simulation
    (artibus.runner.simulation) runs what it set up."""

    def _setup(self, step, overrides, record, where, stimuli, can_interface=None, can_log=None, can_faults=None,
               cut=frozenset(), input_file=None):
        """The set-up, part by part: units and steps, parameters, connections (and the CAN
        network), the order, the recording, the stimuli (and the input file's), the value
        buffers, the columns."""
        units = self._units(step, where)
        self._parameters(units, overrides, where)
        self._check_cut(units, cut, where)
        routed_before = any(c.can is not None for c in self.bench.connections)
        self._connections(units, cut, where)
        self._setup_can(where, can_interface, can_log, can_faults, routed_before)
        self._feedthrough_order(where)
        self._recording(units, record, where)
        self._stimuli(units, stimuli, where)
        self._input_file(units, input_file, stimuli, where)
        self._buffers()
        self._columns()

    def _units(self, step, where):
        """{path: Unit} of the bench's components, each with its step and its ratio to the base step."""
        units, defaults = {}, []
        for path, c in self.bench.components.items():
            try:
                fmu = Fmu(Path(self._tmp) / c.source, instance_name=path,
                          interface=_interface(getattr(self, "fmi_type", None), path, Path(self._tmp) / c.source))
            except ArtibusError as e:    # a corrupt or missing FMU: named as the bench names it
                raise ArtibusError(f"{where}:{c.line}: Component '{path}' source=\"{c.source}\": "
                                   + str(e).replace(f"{Path(self._tmp) / c.source}: ", "")) from None
            de = fmu.md.defaultExperiment
            h = c.step or (step if step is not None else
                           float(de.stepSize) if de is not None and de.stepSize else None)
            units[path] = Unit(path=path, fmu=fmu, step=h)
            # sampled: a period the bench states, of a component without Model Exchange (runner.plan.stated_timing)
            units[path].sampled = bool(c.step) and fmu.md.modelExchange is None
            defaults.append(c.step or (float(de.stepSize) if de is not None and de.stepSize else None))
            self.units = list(units.values())     # (closed by close() if a later one fails)
        self._default_steps(units, where)
        self.units = list(units.values())
        self.base_step = step if step is not None else min(u.step for u in self.units)
        if getattr(self, "single_rate", False):      # every component at the one step
            for u in self.units:
                u.step = self.base_step
        for u in self.units:
            r = u.step / self.base_step
            if abs(r - round(r)) > 1e-9 or round(r) < 1:
                raise ArtibusError(f"{where}: Component '{u.path}': step {u.step} s is not a "
                                   f"multiple of the base step {self.base_step} s")
            u.ratio = int(round(r))
        known = [d for d in defaults if d]      # the bench's own base step: its sampled units' timing (_run)
        self.default_base = min(known) if len(known) == len(defaults) else None
        return units

    def _default_steps(self, units, where):
        """A component without a step (its FMU's default experiment has no stepSize, FMI 2.0
        allows it; no annotation, no --step): the others' shortest, else the bench's
        span / DEFAULT_STEPS."""
        from artibus.fmu import DEFAULT_STEPS
        known = [u.step for u in units.values() if u.step is not None]
        for u in units.values():
            if u.step is None:
                if known:
                    u.step = min(known)
                elif self.bench.stop_time is not None and self.bench.stop_time > self.bench.start_time:
                    u.step = (self.bench.stop_time - self.bench.start_time) / DEFAULT_STEPS
                else:
                    c = self.bench.components[u.path]
                    raise ArtibusError(f"{where}:{c.line}: Component '{u.path}': no communication step "
                                       f"(give --step or a stepSize annotation)")

    def _parameters(self, units, overrides, where):
        """self.parameters: the bench's bindings, then the user's overrides ("comp.var" -> value),
        resources resolved, quantities converted, each checked against its variable."""
        self.parameters = {p: dict(c.parameters) for p, c in self.bench.components.items()}
        origins = {p: dict(c.origins) for p, c in self.bench.components.items()}
        from artibus.bench.names import expand_all      # Bus.mu[*], Bus.mu[1:6]: each element

        def variables_of(full):
            comp = full.split("[", 1)[0].rpartition(".")[0]
            return (comp + ".", list(units[comp].fmu.vars)) if comp in units else None
        overrides = expand_all(overrides, variables_of)
        for full, value in overrides.items():
            comp, _, var = full.rpartition(".")
            if comp not in self.parameters:
                raise ArtibusError(f"--set {full}={value}: no component '{comp}' in {where}"
                                   f"{suggest(comp, self.parameters)} (components: {', '.join(self.parameters)})")
            self.parameters[comp][var] = value
            origins.setdefault(comp, {})[var] = "--set/--ssv/--variant"
        for path, values in self.parameters.items():
            resolve_resources(self._tmp, where, values, origins.get(path))
            for var, value in values.items():     # --ssv FILE's values with a unit: in the variable's
                v = units[path].fmu.vars.get(var)
                if isinstance(value, Quantity) and v is not None and v.kind == "Real":
                    values[var] = convert(value, v, units[path].fmu.md, f"{path}.{var}")
        for path, values in self.parameters.items():
            _configure(units[path], values, where, origins.get(path))
            check_against(values, units[path].fmu.md, where, prefix=f"{path}.", origins=origins.get(path))
            for name in [n for n, v in units[path].fmu.vars.items() if v.causality == "structuralParameter"]:
                values.pop(name, None)    # (set in Configuration Mode, _configure: not again at the initialisation)

    def _check_cut(self, units, cut, where):
        """self.cut: the inputs whose connection the run leaves out, each a connected input."""
        connected = {f"{c.end[0]}.{c.end[1]}" for c in self.bench.connections}
        for name in sorted(cut):
            comp, _, var = name.rpartition(".")
            v = units[comp].fmu.vars.get(var) if comp in units else None
            if v is None or v.causality != "input":
                raise ArtibusError(f"cut {name}: not an input of a component of {where}")
            if name not in connected:
                raise ArtibusError(f"cut {name}: the input is not connected in {where}")
        self.cut = sorted(cut)

    def _connections(self, units, cut, where):
        """self.links: the bench's connections (those into a cut input left out), checked and
        resolved to value references; typed ones through _typed_link."""
        self.links = []
        for c in self.bench.connections:
            if f"{c.end[0]}.{c.end[1]}" in cut:
                continue
            label = f"{where}:{c.line}: Connection {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}"
            a, b = units[c.start[0]], units[c.end[0]]
            va, vb = self._connection_ends(c, label, a, b)
            if not (_in_core(va) and _in_core(vb)):
                self._typed_link(c, label, a, va, b, vb)
                continue
            f, o = _real_factor(c, label, a, va, b, vb)
            if vb in b.inputs:
                raise ArtibusError(f"{label}: input {c.end[0]}.{c.end[1]} is connected twice")
            self.links.append(Link(a, a.output_index(va), b, b.input_index(vb), f, o, f"{c.end[0]}.{c.end[1]}", c))
            if c.can is None:                 # a connection routed over CAN goes through self.can
                b.links_in.append(self.links[-1])

    @staticmethod
    def _connection_ends(c, label, a, b):
        """The two variables a connection joins: both there, of one type, output -> input."""
        va, vb = a.fmu.vars.get(c.start[1]), b.fmu.vars.get(c.end[1])
        if va is None or vb is None:
            from artibus.bench.parameters import no_variable
            u, var = (a, c.start[1]) if va is None else (b, c.end[1])
            raise ArtibusError(f"{label}: no variable '{u.path}.{var}' ({no_variable(u.fmu.md, var)})")
        if va.kind != vb.kind:
            raise ArtibusError(f"{label}: types {va.type} -> {vb.type} ({c.start[0]}.{c.start[1]} is "
                               f"{va.type}, {c.end[0]}.{c.end[1]} is {vb.type}): a connection joins "
                               f"variables of one type")
        start = f"{c.start[0]}.{c.start[1]}"
        if _start_element(c, label, va) is not None:       # one element (startIndices) into a scalar
            start, shape_a = f"{start}[{','.join(c.indices[0].split())}]", ()
        else:
            shape_a = va.shape
        if shape_a != vb.shape:
            # SSP 2.0 5.x "Connections": without startIndices/endIndices "this connection applies
            # to the whole connector", element by element (FMI 3.0 2.2.6.2: row-major): one shape on both ends
            raise ArtibusError(f"{label}: the shapes differ ({start} is {_shaped(va, shape_a)}, "
                               f"{c.end[0]}.{c.end[1]} is {_shaped(vb)}): a connection joins a whole array "
                               "to an array of the same shape, a scalar (or an array's element) to a scalar")
        for u, v in ((a, va), (b, vb)):
            _scalar_number(v, f"{label}: {u.path}.{v.name}", arrays=True)
        if va.causality not in ("output", "parameter", "calculatedParameter") or vb.causality != "input":
            raise ArtibusError(f"{label}: connects a {va.causality} to a {vb.causality} "
                               f"(expected output -> input)")
        return va, vb

    def _feedthrough_order(self, where):
        """Each unit's direct feedthrough from its model description (artibus.runner.plan.feedthrough),
        then self.order: Jacobi's is the bench's (every connection one step delayed: no order, no
        loop check); Gauss-Seidel's from the connections (artibus.runner.plan.gauss_seidel_order:
        a loop through assumed feedthrough broken at one connection, named in a warning and in
        self.broken; an algebraic loop an error)."""
        feeds = {}
        for u in self.units:
            feeds[u.path] = feedthrough(u.fmu.md)
            u.feeds.update(feeds[u.path])
        self.broken = []
        if self.algorithm == "jacobi":
            self.order = list(self.units)
            return
        into = {c.end: c for c in self.bench.connections}
        wires = [wire(where, l.connection) for l in self.links if l.connection.can is None]
        wires += [wire(where, into[(u.path, u.tin[i].name)]) for u in self.units for i, *_ in u.typed_sources]
        order = gauss_seidel_order([u.path for u in self.units], wires, feeds, where)
        by_path = {u.path: u for u in self.units}
        self.order = [by_path[p] for p in order.paths]
        self.broken = order.broken
        for broken, loop in order.broken:
            _warn_once(loop_warning(where, broken, loop))

    def _recording(self, units, record, where):
        """self.record: (unit, variable) of every column: what was asked for, else every
        output connector the bench declares and every connected output; each unit's
        outputs to read (Float64 ones in outputs, the others in tout)."""
        self.record = []
        for name in record or []:
            comp, _, var = name.rpartition(".")
            if comp not in units:
                raise ArtibusError(f"--record {name}: no component '{comp}' in {where}"
                                   f"{suggest(comp, units)} (components: {', '.join(units)})")
            if var not in units[comp].fmu.vars:
                from artibus.bench.parameters import no_variable
                raise ArtibusError(f"--record {name}: {comp}: {no_variable(units[comp].fmu.md, var)}")
            self.record.append((units[comp], var))
        if not record:
            for u in self.units:
                for n in dict.fromkeys(self.bench.components[u.path].outputs + u.out_names
                                       + [v.name for v in u.tout]):
                    if n not in u.fmu.vars:
                        raise ArtibusError(f"{where}: Component '{u.path}': connector '{n}' is "
                                           f"not a variable of {u.fmu.md.modelName}")
                    self.record.append((u, n))
        for u, n in self.record:
            v = u.fmu.var(n)
            _scalar_number(v, f"{where}: recording {u.path}.{n}", arrays=True)
            if not _in_core(v):
                if v not in u.tout:
                    u.tout.append(v)
            else:
                u.output_index(v)
        from artibus.fmu.simulate import columns      # an array: a column per element, row-major (FMI 3.0 2.4.7.6)
        self.record = [(u, e) for u, n in self.record for e in columns(u.fmu.var(n))]

    def _stimuli(self, units, stimuli, where):
        """Each stimulus {"comp.input": f(t)} on its unit: added to the input's connection,
        or to its base value (its parameter or start) when it is not connected."""
        for name, f in stimuli.items():
            comp, _, var = name.rpartition(".")
            v = units[comp].fmu.vars.get(var) if comp in units else None
            if v is None or v.causality != "input" or not _in_core(v):
                raise ArtibusError(f"stimulus {name}: not a Real (Float64) input of a component of {where}")
            u = units[comp]
            if self.can is not None and any(l.dst is u and l.name == name for l in self.can_links):
                raise ArtibusError(f"stimulus {name}: the input is routed over CAN in {where}")
            if v in u.inputs:
                u.stimuli.append((u.inputs.index(v), f, None))
            else:
                base = float(self.parameters[comp].get(var, v.start))
                u.stimuli.append((u.input_index(v), f, base))

    def _input_file(self, units, path, stimuli, where):
        """--input-file of `run` (issue 38): the bench's free inputs (the end of no connection, fed
        by no stimulus) driven by the file's columns COMPONENT.VARIABLE as `simulate` reads them
        (artibus.fmu.inputs: a continuous input interpolated, a discrete one held), each a stimulus
        on a base of 0 (the input is the file's value), sampled at the start of each of its
        component's steps; a free input that no column and no parameter (--set, a binding)
        gives is named in a warning."""
        if path is None:
            return
        from artibus.fmu.inputs import Named, read_inputs
        fed = {f"{c.end[0]}.{c.end[1]}" for c in self.bench.connections} | set(stimuli)
        owner = {f"{p}.{v.name}": (u, v) for p, u in units.items() for v in u.fmu.md.modelVariables
                 if v.causality == "input" and f"{p}.{v.name}" not in fed}
        table = read_inputs(path, [Named(n, v) for n, (_, v) in owner.items()],
                            f"{where} free to drive (one no connection feeds)")
        for n in table.columns:
            if not _in_core(n.variable):
                raise ArtibusError(f"{path}:1: column {n.name!r}: the input is a{'n array' if n.shape else ''} "
                                   f"{n.type}; a bench's input file drives its scalar Float64 inputs")
        for n, f in table.functions().items():
            u, v = owner[n]
            u.stimuli.append((u.input_index(v), f, 0.0))
        missing = [n for n in table.missing if owner[n][1].name not in self.parameters[owner[n][0].path]]
        if missing:
            _warn_once(f"--input-file {path} gives no column for the free input{'s' if len(missing) > 1 else ''} "
                       f"{', '.join(missing)} of {where}: {'they keep their' if len(missing) > 1 else 'it keeps its'} "
                       "start value")

    def _buffers(self):
        """Each unit's calls and value buffers (_RawCalls, _TypedCalls), its sources into
        them, the CAN network bound to them."""
        for u in self.units:
            u.raw = (_TypedCalls if u.tout or u.tin else _RawCalls)(u)
            u.out_values = u.raw.out      # read and written in place
            u.in_values = u.raw.inp
        for u in self.units:
            u.sources = [(l.dst_index, l.src.raw.out, l.src_index, l.factor, l.offset) for l in u.links_in]
        if self.can is not None:
            self.can.bind()

    def _columns(self):
        """The result's column names and units; per unit, which outputs go to which columns
        (self._rec); the String columns (self._text_cols: their texts, _with_texts)."""
        self.names = ["time"] + [f"{u.path}.{n}" for u, n in self.record]
        self._col_units = {"time": "s", **{f"{u.path}.{n}": declared_unit(u.variable_of(n)) or ""
                                           for u, n in self.record}}
        self._col_descriptions = {"time": "simulation time", **{f"{u.path}.{n}": u.variable_of(n).description or ""
                                                                 for u, n in self.record}}
        self._rec = []
        for u in self.units:
            cols = [k + 1 for k, (v, _) in enumerate(self.record) if v is u]
            idx = [u.column(n) for v, n in self.record if v is u]
            if cols:
                self._rec.append((u, np.array(idx), np.array(cols)))
        self._text_cols = {f"{u.path}.{n}": u for u, n in self.record if u.variable_of(n).kind == "String"}

    def _typed_link(self, c, label, a, va, b, vb):
        """A connection of Integer, Boolean, String or Enumeration variables (see
        _typed_convert): read and set in Python (_TypedCalls), exact values."""
        convert = _typed_convert(label, a, va, b, vb, c.mapping)
        if va.shape and va.kind == "Real":    # a Float64/Float32 array: as a scalar Real connection, each element
            convert = _real_conversion(c, label, a, va, b, vb)
        elif c.factor != 1.0 or c.offset != 0.0:
            raise ArtibusError(f"{label}: a LinearTransformation on {va.type} variables "
                               + ("(artibus applies it to Float64 ones)" if va.kind == "Real" else
                                  "(SSP 1.0: it applies to Real ones)"))
        if c.can is not None:
            raise ArtibusError(f"{label}: routed over CAN: the runner routes Real variables only")
        if vb in b.tin or vb in b.inputs:
            raise ArtibusError(f"{label}: input {c.end[0]}.{c.end[1]} is connected twice")
        if va not in a.tout:
            a.tout.append(va)
        b.tin.append(vb)
        convert = _over_elements(convert, va, _start_element(c, label, va))
        b.typed_sources.append((len(b.tin) - 1, a, a.tout.index(va), convert))

    def _setup_can(self, where, interface, log, faults=None, routed=True):
        """The CAN network of a bench that routes connections over CAN (see artibus.can);
        none when every route was cut (routed: the bench routes some)."""
        self.can_links = [l for l in self.links if l.connection.can is not None]
        spec = self.bench.can
        if spec is not None and routed and not self.can_links:
            if interface is not None or log is not None or faults:
                raise ArtibusError(f"--can/--can-log/--can-fault: every connection {where} routes over CAN "
                                   f"is cut: the run has no network")
            return
        if spec is None:
            if self.can_links:
                c = self.can_links[0].connection
                raise ArtibusError(f"{where}:{c.can['line']}: Connection {c.start[0]}.{c.start[1]} -> "
                                   f"{c.end[0]}.{c.end[1]} is routed over CAN but the System has no "
                                   f"org.artibus.can annotation naming the DBC")
            if interface is not None or log is not None or faults:
                raise ArtibusError(f"--can/--can-log/--can-fault: {where} routes no connection over CAN")
            return
        from artibus import can as can_mod
        self.can = can_mod.Network(self.bench, can_mod.dbc_in(self._tmp, spec), self.can_links,
                                   interface or "virtual", log, faults)
        r = self.can.period / self.base_step
        if abs(r - round(r)) > 1e-9 or round(r) < 1:
            raise ArtibusError(f"{where}:{spec['line']}: the CAN tick {self.can.period} s is not a "
                               f"multiple of the base step {self.base_step} s")
        self.can_ratio = int(round(r))

    # --- the algorithm ---------------------------------------------------------------


def _interface(fmi_type, path, source):
    """The interface component ``path`` runs in (Simulation's fmi_type): "me" where asked for by
    name, or for every FMU that has Model Exchange with fmi_type "me"; else "cs"."""
    if isinstance(fmi_type, dict):
        return "me" if fmi_type.get(path) in ("me", "ModelExchange") else "cs"
    if fmi_type in ("me", "ModelExchange"):
        from artibus.fmu.instance import read_model
        return "me" if read_model(str(source)).modelExchange is not None else "cs"
    return "cs"


_WARNED = set()


def _warn_once(text):
    """A warning on stderr, once a process (a sweep's runs of one bench print it once)."""
    import sys
    if text not in _WARNED:
        _WARNED.add(text)
        print(f"warning: {text}", file=sys.stderr)


def _configure(u, values, where, origins=None):
    """The FMI 3.0 unit's structural parameters among its bound ``values`` set in Configuration
    Mode (FMI 3.0 2.3, "State: Configuration Mode"), before anything reads its arrays' shapes:
    the arrays they dimension (2.4.7.6, <Dimension valueReference>) are resized from then on
    (Fmu.configure), the connections and the recording use the new shapes."""
    structural = {n: x for n, x in values.items()
                  if n in u.fmu.vars and u.fmu.vars[n].causality == "structuralParameter"}
    if not structural:
        return
    try:
        u.fmu.configure(structural)
    except ArtibusError as e:
        origin = "; ".join(f"{n} from {origins[n]}" for n in structural if origins and n in origins)
        raise ArtibusError(f"{where}: Component '{u.path}': {e}" + (f" ({origin})" if origin else "")) from None


def _in_core(v):
    """Whether the stepping core gets and sets ``v`` itself: a scalar Float64 (FMI 2.0's Real,
    FMI 3.0's Float64); the other types go through the core's hooks (_TypedCalls)."""
    return v.type in ("Real", "Float64") and not v.shape


def _real_factor(c, label, a, va, b, vb):
    """(factor, offset) of a Real connection: its LinearTransformation (SSP 1.0 5.3.4.1), else
    the units' conversion (unit_conversion); a MappingTransformation is refused."""
    if c.mapping is not None:
        raise ArtibusError(f"{label}: a {c.mapping[0]}MappingTransformation on Real variables "
                           f"(a LinearTransformation applies to them)")
    if c.factor != 1.0 or c.offset != 0.0:
        return c.factor, c.offset
    return unit_conversion(a.fmu.md, va, b.fmu.md, vb, label)


def _real_conversion(c, label, a, va, b, vb):
    """The conversion of one value of a Real array connection (each element's), as a scalar Real
    connection has it (_real_factor); None where it is the identity."""
    f, o = _real_factor(c, label, a, va, b, vb)
    return None if f == 1.0 and o == 0.0 else (lambda x: f * x + o)


def _start_element(c, label, va):
    """The row-major offset (FMI 3.0 2.2.6.2) of the element a connection's startIndices name in
    the array ``va``, None without them. SSP 2.0 "Connections": startIndices, "the list of
    indices of an array connector that this connection is restricted to" (without them "the
    whole connector"): read as the one element of the start's array, an index per dimension,
    1-based as FMI 3.0's structured names count them (2.4.7.6, ``y[1,2]``); into a scalar only:
    endIndices refused by name. An error naming the connection where they do not fit."""
    text, end = getattr(c, "indices", (None, None))
    if end is not None:
        raise ArtibusError(f"{label}: endIndices=\"{end}\": the runner connects into a whole array or a "
                           "scalar (an element of an array as the start: startIndices)")
    if text is None:
        return None
    try:
        index = [int(i) for i in text.split()]
    except ValueError:
        index = []
    if len(index) != len(va.shape) or not all(1 <= i <= n for i, n in zip(index, va.shape)):
        raise ArtibusError(f"{label}: startIndices=\"{text}\" do not name an element of "
                           f"{c.start[0]}.{c.start[1]}, {_shaped(va)} (1-based, an index per dimension)")
    k = 0
    for i, n in zip(index, va.shape):
        k = k * n + i - 1
    return k


def _over_elements(convert, va, k):
    """A connection's conversion of one value (None: none) applied to what the source's read
    gives: the element k of the array va (startIndices), each element of a whole array, or the scalar."""
    if k is not None:
        return (lambda x: x[k]) if convert is None else (lambda x: convert(x[k]))
    if va.shape and convert is not None:
        return lambda xs: [convert(x) for x in xs]
    return convert


def _shaped(v, shape=None):
    """A variable's type and shape (its own, or ``shape``) as an error names them: Float64[3],
    Float64[2,3], Float64"""
    shape = v.shape if shape is None else shape
    return f"{v.type}[{','.join(map(str, shape))}]" if shape else v.type


def _scalar_number(v, label, arrays=False):
    """An error unless ``v`` is a number a connection or a result column can carry (with
    ``arrays``: an FMI 3.0 array of numbers too, carried element by element): an array where
    none is taken, a Binary or a Clock (FMI-LS-BUS terminals carry those: an SSP 2.0
    bench's Bus) named with its type and shape."""
    from artibus.fmu.model import NOT_NUMBERS
    if v.shape and not arrays:
        raise ArtibusError(f"{label} is an array of {v.size} values ({v.type}, "
                           f"{'x'.join(map(str, v.shape))}): a connection or a column of the results "
                           f"carries one scalar variable")
    if v.kind in NOT_NUMBERS:
        raise ArtibusError(f"{label} is an FMI 3.0 {v.type}: not a number a connection or a result "
                           f"column carries (a Binary or Clock is connected through an FMI-LS-BUS terminal)")
