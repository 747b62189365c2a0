"""One typing rule for a bench's parameter bindings and connections, SSP 1.0 and 2.0 alike
(issue 41): artibus.bench.ssp (every SSP 1.0 bench, an SSP 2.0 bench's plant) and
artibus.bench.ssp2 (an SSP 2.0 bench's FMI-LS-BUS components) both bind and connect through
these functions, so `artibus run` and `artibus check` refuse the same bench with the same
message, whichever version of SSP it is written in.

- A binding's value is of its variable's type, exactly (artibus.bench.parameters.coerce:
  2.7 is no Integer and no Boolean, an Integer 2 no Boolean), within the variable's min and
  max, and a value given with a unit is converted to the variable's unit (artibus.bench.units;
  SSP 1.0 5.3.5 and 7.1.1, a unit belongs to a Real: on any other variable it is an error).
- An input has one source: two connections into one input are an error at the second
  (SSP 1.0 5.3.3: a connection joins one output to one input; FMI-LS-BUS 1.0 "Bus Terminal":
  the same for a terminal's members).

Every message names the file and line the value or the connection is written at.
"""
from artibus.base import ArtibusError, parse_integer, parse_real
from artibus.bench.parameters import check_against
from artibus.bench.ssd import model_description, origin as ssd_origin
from artibus.bench.units import declared_unit, fmu_units, with_unit


#: the ssv value elements of SSP 1.0 and 2.0 (SSP 2.0 adds FMI 3.0's widths), by what they hold
REALS = ("Real", "Float64", "Float32")
INTEGERS = ("Integer", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")


def ssv_value(parameter, label):
    """(value, unit or None, kind) of an ssv:Parameter element, typed as its value element says:
    a Real (Float64, Float32) a float, an integer type an int, a Boolean a bool (true, false,
    1 or 0), an Enumeration or a String (or a Binary) its text; ``label``: the file and line
    for the error of a value that is not of its element's type"""
    v = next((c for c in parameter if isinstance(c.tag, str)), None)
    kind = v.tag.rpartition("}")[2] if v is not None else None
    text = v.get("value") if v is not None else None
    try:
        if kind in REALS:
            return parse_real(text), v.get("unit") or None, kind
        if kind in INTEGERS:
            return parse_integer(text), None, kind
        if kind == "Boolean" and text in ("true", "false", "1", "0"):
            return text in ("true", "1"), None, kind
        if kind in ("Enumeration", "String", "Binary") and text is not None:
            return text, None, kind
    except (TypeError, ValueError):
        pass
    raise ArtibusError(f"{label}: <Parameter name=\"{parameter.get('name')}\"> <{kind} value=\"{text}\">: "
                       f"not {'a value' if kind is None else 'an ' + kind if kind[0] in 'AEIOU' else 'a ' + kind}")


def bind(values, md, origins, prefix="", units=None):
    """The values {name: value, as its file types it} of one component's bindings as its FMU
    ``md`` (artibus.fmu.model's Model) takes them, in a new dict: each
    value with a unit (``units``: {name: (unit, the file's unit definitions)}) converted
    (with_unit), then each checked: a parameter or input of the FMU, of its type and in its
    range (artibus.bench.parameters.check_against). ``origins``: {name: "file:line"};
    ``prefix``: the component's path and a dot, as messages name the parameter."""
    variables = {v.name: v for v in md.modelVariables}
    out = dict(values)
    for name, (unit, definitions) in (units or {}).items():
        raw = out[name]
        out[name] = with_unit(raw, unit, definitions, variables.get(name), md,
                              f"{origins.get(name, '?')}: Parameter '{prefix}{name}' = {raw!r} {unit}")
    return check_against(out, md, "?", prefix=prefix, origins=origins)


def one_source(connections):
    """connections: (start "A.x", end "B.y", label) in the file's order, label the file, the
    line and the connection; an error at the second connection into one input"""
    seen = set()
    for start, end, label in connections:
        if end in seen:
            raise ArtibusError(f"{label}: input {end} is connected twice")
        seen.add(end)


def bind_component(ssp, c, given, used):
    """An SSP 1.0 reader's component (artibus.bench.ssp.Component of the .ssp ``ssp``) bound as
    the runner sets its values: a value given with a unit (SSP 1.0: ssv:Real unit=) in the unit of
    the FMU's variable (``given``: {name: (unit, the file's definitions, a mapping's
    LinearTransformation to apply after or None, origin)}; ``used``: filled with {unit: its
    definition or None} of those units), then every value checked against the FMU (type,
    range); the values kept as their files type them (the runner types them again, with the
    user's --set)."""
    try:
        md = model_description(ssp, c.source)
    except ArtibusError as e:          # named as the bench names the component
        reason = str(e).removeprefix(f"{ssp}: ").removeprefix(f"{c.source}: ")
        raise ArtibusError(f"{ssd_origin(ssp)}:{c.line}: Component '{c.path}' source=\"{c.source}\": "
                           f"not a readable FMU: {reason}") from None
    fmu_defs = fmu_units(md)
    variables = {v.name: v for v in md.modelVariables}
    for var, (unit, defs, then, origin) in given.items():
        v, raw = variables.get(var), c.parameters[var]
        used.setdefault(unit, defs.get(unit) or fmu_defs.get(unit))
        x = with_unit(raw, unit, defs, v, md, f"{origin}: Parameter '{c.path}.{var}' = {raw!r} {unit}")
        if x is not raw:
            c.converted[var] = (raw, unit, x, declared_unit(v))
        if then is not None:
            x = then[0] * x + then[1]
        c.parameters[var] = x
    origins = {k: c.origins.get(k, f"{ssd_origin(ssp)}:{c.line}") for k in c.parameters}
    bind(c.parameters, md, origins, prefix=f"{c.path}.")
