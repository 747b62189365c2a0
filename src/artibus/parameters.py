"""Parameter sets as SSP 1.0 parameter-value files (.ssv).

FMPy reads and validates them against the SSP XSD it ships; here they are
checked against an FMU's model description, so a misspelt name or a value out
of range is reported with the file, the element and the value.
"""
from fmpy import read_model_description
from fmpy.ssp.ssd import read_ssv

from artibus import ArtibusError, ROOT

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


def read_parameters(ssv, fmu=None):
    """{name: value} from an .ssv file; with ``fmu``, each name and value is
    checked against that FMU's model description."""
    path = find_ssv(ssv)
    try:
        pset = read_ssv(str(path), validate=True)
    except Exception as e:  # lxml / XSD errors carry the line
        raise ArtibusError(f"{path}: not a valid SSP parameter-value file: {e}") from None
    values = {}
    for p in pset.parameters:
        try:
            values[p.name] = typed(p.type, p.value)
        except ValueError:
            raise ArtibusError(f"{path}: Parameter '{p.name}': {p.type} value "
                               f"{p.value!r} is not a {p.type}") from None
    if fmu is not None:
        check_against(values, fmu, str(path))
    return values


def typed(type_, text):
    if type_ == "Real":
        return float(text)
    if type_ in ("Integer", "Enumeration"):
        return int(text)
    if type_ == "Boolean":
        if text not in ("true", "false", "1", "0"):
            raise ValueError(text)
        return text in ("true", "1")
    return text


def check_against(values, fmu, source, prefix=""):
    """Each name must be a parameter or input of the FMU (a model description
    or a path) and each number within its range; errors name the source, the
    parameter (``prefix`` + name, e.g. a component path) and the value."""
    md = fmu if hasattr(fmu, "modelVariables") else read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    for name, value in values.items():
        v = variables.get(name)
        label = f"{source}: Parameter '{prefix}{name}' = {value!r}"
        if v is None:
            raise ArtibusError(f"{label}: {md.modelName} has no variable '{name}'")
        if v.causality not in ("parameter", "input"):
            raise ArtibusError(f"{label}: it is an {v.causality} of {md.modelName} and cannot be set")
        if v.type in ("Real", "Integer"):
            x = float(value)
            if v.min is not None and x < float(v.min) or v.max is not None and x > float(v.max):
                raise ArtibusError(f"{label} is outside [{v.min}, {v.max}] of {md.modelName}")
