"""The parameter bindings of an SSP 1.0 system structure (SSP 1.0 5.3.5 "ParameterBindings",
7 "SSM"): the values an element's ssd:ParameterBinding elements bind (inline ssv:ParameterSet or
an .ssv in the .ssp), through a parameter mapping (inline or an .ssm), each value with the line
it is written at and the unit it is given in; artibus.bench.ssp applies them to the components,
artibus.bench.rules checks them against the FMUs."""
import zipfile
from dataclasses import dataclass

from lxml import etree

from artibus.base import ArtibusError
from artibus.bench.rules import ssv_value
from artibus.bench.ssd import MAPPINGS, NS, _number, map_transformation
from artibus.bench.units import ssp_units
from artibus.bench.versions import parameter_root


def member_root(ssp, ref, file):
    """parameter_root of the member ``ref`` of the .ssp ``ssp`` (``file`` names the reference)."""
    with zipfile.ZipFile(ssp) as z:
        if ref not in z.namelist():
            raise ArtibusError(f"{file}: \"{ref}\" is not in the .ssp")
        data = z.read(ref)
    return parameter_root(data, f"{ssp}/{ref}")


@dataclass
class Pack:
    """the .ssp being read, as the binding functions need it"""
    ssp: str                       # its path
    where: str                     # its .ssd as messages name it (<ssp>/SystemStructure.ssd)
    units: dict                    # the .ssd's own unit definitions (artibus.bench.units.ssp_units)


def bound_values(pack, xml_element, what, origins=None, units=None):
    """The values {name: value, as its file types it} the ParameterBindings of ``xml_element``
    (a Component or System of the .ssp ``pack``) bind, later bindings over earlier ones;
    ``what`` names it in messages.
    origins: filled with {name: where its value comes from (file:line, mapping)};
    units: with {name: (unit, the file's unit definitions, a mapping's
    LinearTransformation to apply after the conversion or None, origin)} of
    the values given with a unit (converted to the FMU's unit at the end)."""
    values = {}
    xml_bindings = xml_element.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS)
    for xb in xml_bindings:
        prefix = xb.get("prefix") or ""
        source, given, lines = {}, {}, {}
        file = f"{pack.ssp}/{xb.get('source')}" if xb.get("source") else pack.where
        if xb.get("source"):
            with zipfile.ZipFile(pack.ssp) as z:
                pset_xml = [etree.fromstring(z.read(xb.get("source")))]
        else:
            pset_xml = xb.findall("ssd:ParameterValues/ssv:ParameterSet", NS)
        suffix = ""
        if xb.find("ssd:ParameterMapping", NS) is not None:
            m = xb.find("ssd:ParameterMapping", NS)
            suffix = (f" mapped by {pack.ssp}/{m.get('source')}" if m.get("source")
                      else f" mapped at {pack.where}:{m.sourceline}")
        for px in pset_xml:          # (read_ssd has validated them: parameter_root)
            defs = {**pack.units, **ssp_units(px, file)}
            for q in px.iterfind("ssv:Parameters/ssv:Parameter", NS):
                name = prefix + q.get("name")
                source[name], unit, _ = ssv_value(q, f"{file}:{q.sourceline}: {what}")
                lines[name] = q.sourceline
                if unit:
                    given[name] = (unit, defs)
                else:
                    given.pop(name, None)
        mapping = xb.find("ssd:ParameterMapping", NS)
        got, then = (source, {}) if mapping is None else mapped(pack, source, mapping, what, given)
        values.update(got)
        for name in got:
            src = name if mapping is None else then[name][0]
            origin = f"{file}:{lines.get(src, xb.sourceline)}{suffix}"
            if origins is not None:
                origins[name] = origin
            if units is not None:
                if src in given and (mapping is None or not then[name][2]):
                    units[name] = (*given[src], None if mapping is None else then[name][1], origin)
                else:
                    units.pop(name, None)
    return values

def mapped(pack, source, mapping, what, given=()):
    """SSP's parameter mapping (SSP 1.0, ssd:ParameterMapping, SSM): only
    the mapped values are applied, under their target names, after the
    entry's linear transformation; the others are not applied. The mapping
    is inline or a .ssm file in the .ssp. A value with a unit (in
    ``given``) is converted to the target's unit first and transformed
    after (SSP 1.0, 7.1.1), unless the entry says suppressUnitConversion:
    returns ({target: value}, {target: (source, its LinearTransformation
    (factor, offset) still to apply or None, unit conversion suppressed)})."""
    ref = mapping.get("source")
    if ref is None:
        file, root_m = pack.where, mapping.find("ssm:ParameterMapping", NS)
        entries = [] if root_m is None else root_m.findall("ssm:MappingEntry", NS)
    else:
        file = f"{pack.ssp}/{ref}"    # there: read_ssd has validated it (parameter_root)
        with zipfile.ZipFile(pack.ssp) as z:
            entries = etree.fromstring(z.read(ref)).findall("ssm:MappingEntry", NS)
    out, then = {}, {}
    for e in entries:
        src, dst = e.get("source"), e.get("target")
        head = f"{file}:{e.sourceline}: {what}: MappingEntry source=\"{src}\" target=\"{dst}\""
        if src not in source:
            raise ArtibusError(f"{head}: the parameter source has no '{src}'")
        if dst in out:
            raise ArtibusError(f"{head}: '{dst}' is mapped to twice")
        value = source[src]
        suppress = e.get("suppressUnitConversion") in ("true", "1")
        later = None
        for tr in e:
            kind = etree.QName(tr).localname if isinstance(tr.tag, str) else None
            if kind == "LinearTransformation":
                if not isinstance(value, float):
                    raise ArtibusError(f"{head}: a LinearTransformation needs a Real, got {value!r}")
                factor, offset = _number(tr, "factor", 1.0, file), _number(tr, "offset", 0.0, file)
                if src in given and not suppress:
                    later = (factor, offset)         # after the unit's conversion
                else:
                    value = factor * value + offset
            elif kind in MAPPINGS:
                mkind, table = map_transformation(e, head)
                ok = {"Boolean": isinstance(value, bool),
                      "Integer": isinstance(value, int) and not isinstance(value, bool),
                      "Enumeration": isinstance(value, (str, int)) and not isinstance(value, bool)}[mkind]
                if not ok:
                    raise ArtibusError(f"{head}: the {kind} does not apply to the value {value!r}")
                value = table.get(value, value)
            elif kind not in (None, "Annotations"):
                raise ArtibusError(f"{head}: {kind} is not supported (LinearTransformation and "
                                   f"the Boolean-, Integer- and EnumerationMappingTransformation are)")
        out[dst] = value
        then[dst] = (src, later, suppress)
    return out, then
