"""Parameter sets as SSP 1.0 parameter-value files (.ssv), and the values the
user sets on the command line (``--set NAME=VALUE``, ``parse_set``).

FMPy reads and validates them against the SSP XSD it ships; here they are
checked against an FMU's model description, so a misspelt name or a value out
of range is reported with the file, the element and the value.
"""
import math

from fmpy.ssp.ssd import read_ssv

from artibus.base import ArtibusError, ROOT, parse_integer, parse_real
from artibus.bench.fmi import INTEGER_RANGE

PARAMETER_DIR = ROOT / "ssp" / "parameters"


def find_ssv(name_or_path):
    """A parameter set by name (``Urbino18``) or by path."""
    from pathlib import Path
    p = Path(name_or_path)
    if p.suffix == ".ssv" and p.is_file():
        return p
    q = PARAMETER_DIR / f"{name_or_path}.ssv"
    if q.is_file():
        return q
    known = ", ".join(sorted(f.stem for f in PARAMETER_DIR.glob("*.ssv")))
    raise ArtibusError(f"{name_or_path}: no such parameter set (known: {known})")


def read_parameters(ssv, fmu=None, converted=None, keep_units=False):
    """{name: value} from an .ssv file; with ``fmu``, each name and value is
    checked against that FMU's model description, a value given with a unit
    (``<ssv:Real value="5128" unit="mm"/>``) converted to its variable's unit
    (the file's own <ssv:Units>, else the FMU's UnitDefinitions: see
    artibus.bench.units.to_unit; ``converted``: filled with {name: (value,
    unit, converted value, the variable's unit)} of those converted). Without
    an FMU a value with a unit is the number given (``keep_units``: a
    Quantity, converted where the variable is known, as ``artibus run --ssv``)."""
    from artibus.bench.units import Quantity, declared_unit, ssp_units, with_unit
    from artibus.bench.versions import parameter_root
    path = find_ssv(ssv)
    try:
        # version="2.0" on SSP 1.0 content (OMSimulator 3.x): read as 1.0, with a warning
        root = parameter_root(path.read_bytes(), str(path), "ParameterSet")
        pset = read_ssv(str(path), validate=False)
    except ArtibusError as e:
        raise ArtibusError(f"{e} (not a valid SSP parameter-value file)") from None
    except Exception as e:  # lxml errors carry the line
        raise ArtibusError(f"{path}: not a valid SSP parameter-value file: {e}") from None
    defs = ssp_units(root, str(path))
    # each value's line, by its name (the last of a name is the one that counts, as in FMPy's list)
    lines = {q.get("name"): q.sourceline for q in root.iterfind("{*}Parameters/{*}Parameter")}
    values, units = {}, {}
    for p in pset.parameters:
        try:
            values[p.name] = typed(p.type, p.value)
        except ValueError:
            raise ArtibusError(f"{path}:{lines.get(p.name, '?')}: Parameter '{p.name}': {p.type} value "
                               f"{p.value!r} is not a {p.type}") from None
        if p.type == "Real" and p.unit:
            units[p.name] = p.unit
    if fmu is not None:
        md = fmu if hasattr(fmu, "modelVariables") else _model_description(fmu)
        variables = {v.name: v for v in md.modelVariables}
        for name, unit in units.items():
            v = variables.get(name)
            x = with_unit(values[name], unit, defs, v, md,
                          f"{path}:{lines.get(name, '?')}: Parameter '{name}' = {values[name]!r} {unit}")
            if converted is not None and x is not values[name]:
                converted[name] = (values[name], unit, x, declared_unit(v))
            values[name] = x
        check_against(values, md, str(path), origins={n: f"{path}:{k}" for n, k in lines.items()})
    elif keep_units:
        for name, unit in units.items():
            values[name] = Quantity(values[name], unit, defs, f"{path}:{lines.get(name, '?')}")
    return values


def parse_set(items):
    """``--set NAME=VALUE`` items -> {NAME: VALUE} (text, stripped; later ones win);
    an item without "=" is an error naming it. The values are typed later, against
    the variables they set (check_against)."""
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep:
            raise ArtibusError(f"--set {item}: expected NAME=VALUE")
        values[name.strip()] = value.strip()
    return values


def typed(type_, text):
    if type_ == "Real":
        return parse_real(text)
    if type_ == "Integer":
        return parse_integer(text)
    if type_ == "Enumeration":      # an item's name (SSP 1.0), or its value: see coerce
        return text
    if type_ == "Boolean":
        if text not in ("true", "false", "1", "0"):
            raise ValueError(text)
        return text in ("true", "1")
    return text


def coerce(v, value, finite=True):
    """``value`` (text from --set or an .ssv, or a Python number or bool) as a
    value of the FMU variable ``v``'s declared type, strictly: no rounding
    (3.7 is not an Integer), a Boolean is true, false, 1 or 0 (not "yes"), an
    Enumeration is one of its items, by name or by value; a Real finite
    unless ``finite`` is false (then the FMU refuses NaN and Inf itself).
    ValueError saying why otherwise."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):   # a NumPy scalar
        value = value.item()
    t = v.type
    text = value.strip() if isinstance(value, str) else None
    if t in ("Real", "Float64"):
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise ValueError(f"a Real is a number, not {type(value).__name__} {value!r}")
        try:
            x = parse_real(text if text is not None else value)
        except ValueError:
            raise ValueError("not a number") from None
        if finite and not math.isfinite(x):
            raise ValueError("not a finite number")
        return x
    if t == "Integer":
        return _integer(value, text)
    if t == "Float32":                     # FMI 3.0 (an FMU of others): a Real, as float32 holds it
        x = coerce(_Real, value, finite)
        if math.isfinite(x) and abs(x) > FLOAT32_MAX:
            raise ValueError(f"outside the range of an FMI 3.0 Float32 (+-{FLOAT32_MAX:.9g})")
        return x
    if t in INTEGER_RANGE:                 # FMI 3.0's other integer widths, in their range
        return _integer(value, text, INTEGER_RANGE[t], f"the range of an FMI 3.0 {t}")
    if t == "Boolean":
        if isinstance(value, bool):
            return value
        if isinstance(value, (int, float)) and value in (0, 1):
            return bool(value)
        if text in ("true", "false", "1", "0"):
            return text in ("true", "1")
        raise ValueError("a Boolean is true, false, 1 or 0")
    if t == "Enumeration":
        items = [(i.name, int(i.value)) for i in v.declaredType.items] if v.declaredType is not None else []
        known = ", ".join(f"{n} ({k})" for n, k in items)
        if text is not None and text in dict(items):
            return dict(items)[text]
        try:
            k = _integer(value, text)
        except ValueError:
            raise ValueError(f"not an item of {v.declaredType.name if v.declaredType else 'the enumeration'}"
                             f" (items: {known})") from None
        if items and k not in (x for _, x in items):
            raise ValueError(f"{k} is not an item of {v.declaredType.name} (items: {known})")
        return k
    if t == "String":
        if not isinstance(value, str):
            raise ValueError(f"a String is text, not {type(value).__name__} {value!r}")
        return value
    raise ValueError(f"type {t} is not supported")


FLOAT32_MAX = 3.4028234663852886e38         # the largest finite float32 (IEEE 754 binary32)


class _Real:                               # coerce's view of a Float32 (FMI 3.0)
    type = "Real"


def _integer(value, text, bounds=(-2**31, 2**31 - 1), what="the 32-bit range of an FMI 2.0 Integer"):
    if isinstance(value, bool):
        raise ValueError("a Boolean is not an Integer")
    if isinstance(value, int):
        k = value
    elif isinstance(value, float) or text is not None:
        try:
            k = parse_integer(text) if text is not None else None
        except ValueError:
            k = None
        if k is None:
            try:
                x = parse_real(text if text is not None else value)
            except ValueError:
                raise ValueError("not an integer") from None
            if not (math.isfinite(x) and x.is_integer()):
                raise ValueError("not an integer (an Integer is not rounded)")
            k = int(x)
    else:
        raise ValueError(f"not an integer: {type(value).__name__}")
    if not bounds[0] <= k <= bounds[1]:
        raise ValueError(f"outside {what} ({bounds[0]}..{bounds[1]})")
    return k


def suggest(name, known):
    """' (did you mean ...?)' for a misspelt name among ``known``, or ''."""
    import difflib
    close = difflib.get_close_matches(name, list(known), n=3, cutoff=0.6)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


def no_variable(md, name):
    """Why ``name`` is not a variable of the model description ``md``: an
    array element out of its range names the valid indices, a misspelt name
    the close ones."""
    import re
    names = [v.name for v in md.modelVariables]
    msg = f"{md.modelName} has no variable '{name}'"
    m = re.fullmatch(r"(.+)\[(\d+)\]", name)
    base = m.group(1) if m else name
    idx = sorted(int(mm.group(1)) for n in names for mm in [re.fullmatch(re.escape(base) + r"\[(\d+)\]", n)] if mm)
    if idx:
        return f"{msg}: {base} has indices {idx[0]}..{idx[-1]}" + (
            "" if idx == list(range(idx[0], idx[-1] + 1)) else f" ({', '.join(map(str, idx))})")
    return msg + suggest(name, dict.fromkeys(re.sub(r"\[\d+\]$", "", n) for n in names))


def check_against(values, fmu, source, prefix="", origins=None):
    """Each name must be a parameter or input of the FMU (a model description
    or a path) and each value of its type (see coerce) and within its range;
    errors name the source (``origins[name]`` where given: the file and
    element the value came from), the parameter (``prefix`` + name, e.g. a
    component path) and the value. The values are replaced by their typed
    form in ``values``."""
    from artibus.bench.units import Quantity
    md = _configured(fmu if hasattr(fmu, "modelVariables") else _model_description(fmu), values)
    variables = {v.name: v for v in md.modelVariables}
    for name, value in list(values.items()):
        v = variables.get(name)
        quantity = isinstance(value, Quantity)        # its file's line, and "2.0 mm", not the record
        origin = value.origin if quantity else (origins or {}).get(name, source)
        label = f"{origin}: Parameter '{prefix}{name}' = {value if quantity else repr(value)}"
        if v is None:
            raise ArtibusError(f"{label}: {no_variable(md, name)}")
        if v.causality not in ("parameter", "input", "structuralParameter"):
            raise ArtibusError(f"{label}: it is an {v.causality} of {md.modelName} and cannot be set")
        if quantity:                         # (one on a Real is converted before: artibus.bench.rules)
            raise ArtibusError(f"{label}: a value with a unit ('{value.unit}') for {md.modelName}.{name}, an "
                               f"{v.type}: a unit belongs to a Real value (give the value without a unit)")
        values[name] = _checked_value(v, value, label, md)
    return values


def _configured(md, values):
    """The model ``md`` with its arrays sized by the structural parameters among ``values``
    (FMI 3.0 2.3, Configuration Mode), the arrays' values then checked against those sizes."""
    from artibus.fmu.model import Model, model_of
    md = model_of(md)
    sizes = {}
    for v in md.modelVariables:
        if v.causality == "structuralParameter" and v.name in values:
            try:
                sizes[v.valueReference] = int(str(values[v.name]).strip())
            except ValueError:
                pass                                   # (its own check names it)
    return Model(md.description, structural=sizes) if sizes else md


def _checked_value(v, value, label, md):
    """``value`` as the variable ``v`` takes it, in its range: a scalar, or for an FMI 3.0 array
    (its shape from the model: artibus.fmu.model) a list of its values, given as a sequence or
    as FMI 3.0 writes an array's start (values separated by blanks, 2.4.7.6; commas too)."""
    shape = getattr(v, "shape", ())
    items = value if not shape else (value.replace(",", " ").split() if isinstance(value, str) else list(value))
    if shape and len(items) != v.size:
        raise ArtibusError(f"{label}: {md.modelName}.{v.name} is an array of {v.size} values "
                           f"({'x'.join(map(str, shape))}), given {len(items)}")
    out = []
    for x in (items if shape else [value]):
        try:
            x = coerce(v, x)
        except ValueError as e:
            raise ArtibusError(f"{label}: not a valid {v.type} for {md.modelName}.{v.name}: {e}") from None
        if v.kind in ("Real", "Integer"):
            if v.min is not None and float(x) < float(v.min) or v.max is not None and float(x) > float(v.max):
                raise ArtibusError(f"{label} is outside [{v.min}, {v.max}] of {md.modelName}")
        out.append(x)
    return out if shape else out[0]


def _model_description(path):
    from pathlib import Path
    if not Path(str(path)).is_file():
        raise ArtibusError(f"{path}: no such FMU file")
    try:
        from artibus.fmu.model import read_description
        md = read_description(str(path))
    except Exception as e:
        raise ArtibusError(f"{path}: not a readable FMI 2.0 or 3.0 FMU: {e}") from None
    from artibus.fmu.model import model_of      # FMI 2.0 and 3.0 alike, by kind
    return model_of(md)
