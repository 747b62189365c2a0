"""The small readers of an SSP 1.0 pack that artibus.bench.ssp builds on: the
namespaces, SSP's mapping transformations (ssc:*MappingTransformation), the
components' sources from the .ssd alone, and the model description of an FMU
inside the pack (read once a pack)."""
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError, parse_integer, parse_real

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "ssm": "http://ssp-standard.org/SSP1/SystemStructureParameterMapping",
    "artibus": "urn:artibus",
}
MAPPINGS = {"BooleanMappingTransformation": "Boolean", "IntegerMappingTransformation": "Integer",
            "EnumerationMappingTransformation": "Enumeration"}


#: {an unpacked SSP's pack: its .ssd} (artibus.bench.packs.pack_unpacked): the file messages name
_UNPACKED = {}


def origin(ssp):
    """The file messages name for the .ssd of ``ssp``: an unpacked SSP's own .ssd (a folder or an
    .ssd given to run, packed by artibus.bench.ssp), else ``<ssp>/SystemStructure.ssd``."""
    return _UNPACKED.get(str(ssp), f"{ssp}/SystemStructure.ssd")


def _number(el, attr, default, where, integer=False):
    """Attribute ``attr`` of element ``el`` as a number (the strict syntax of
    artibus.base.parse_real), ``default`` when absent; ArtibusError naming the
    file, line, element, attribute and value otherwise."""
    text = el.get(attr)
    if text is None:
        return default
    try:
        return parse_integer(text) if integer else parse_real(text)
    except ValueError:
        raise ArtibusError(f"{where}:{el.sourceline}: <{etree.QName(el).localname} {attr}=\"{text}\">: "
                           f"not {'an integer' if integer else 'a number'}") from None


def map_transformation(element, where):
    """SSP 1.0's mapping transformation on a Connection or a MappingEntry
    (ssc:Boolean-, Integer- or EnumerationMappingTransformation, a table of
    MapEntry source -> target): (kind, {source: target}) or None."""
    for kind, name in MAPPINGS.items():
        el = element.find(f"ssc:{kind}", NS)
        if el is None:
            continue
        table = {}
        for e in el.findall("ssc:MapEntry", NS):
            src, dst = e.get("source"), e.get("target")
            if name == "Boolean":
                src, dst = src in ("true", "1"), dst in ("true", "1")
            elif name == "Integer":
                src, dst = _number(e, "source", None, where, True), _number(e, "target", None, where, True)
            if src in table:
                raise ArtibusError(f"{where}: {kind}: MapEntry source=\"{e.get('source')}\" is given twice")
            table[src] = dst
        return name, table
    return None


def _compose(first, second, line):
    """Two mapping transformations one after the other (through a system's connector)."""
    if first is None or second is None:
        return first or second
    if first[0] != second[0]:
        raise ArtibusError(f"line {line}: a {first[0]} mapping followed by a {second[0]} mapping")
    table = {k: second[1].get(v, v) for k, v in first[1].items()}
    table.update({k: v for k, v in second[1].items() if k not in first[1]})
    return first[0], table


def _sources_inside_components(ssp, where):
    """An error naming a ParameterBinding or ParameterMapping whose source lies
    inside the component's FMU (sourceBase="component"): not read by the runner."""
    try:
        with zipfile.ZipFile(ssp) as z:
            root = etree.fromstring(z.read("SystemStructure.ssd"))
    except Exception:
        return
    for el in root.iter(tag=etree.Element):
        if el.get("sourceBase") == "component":
            raise ArtibusError(f"{where}:{el.sourceline}: <{etree.QName(el).localname} source=\"{el.get('source')}\" "
                               f"sourceBase=\"component\">: a source inside the component's FMU is not read by "
                               f"the artibus runner (pack it into the .ssp and give its path there)")


def _depth(prefix):
    return 0 if not prefix else prefix.count(".") + 1


_MD_CACHE = {}


def _component_sources(ssp):
    """{component path: its source in the .ssp} from the .ssd alone."""
    with zipfile.ZipFile(ssp) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
    out = {}

    def walk(system, prefix):
        for el in system.findall("ssd:Elements/*", NS):
            path = f"{prefix}.{el.get('name')}" if prefix else el.get("name")
            if etree.QName(el).localname == "Component":
                out[path] = el.get("source")
            elif etree.QName(el).localname == "System":
                walk(el, path)
    walk(root.find("ssd:System", NS), "")
    return out


def model_description(ssp, source):
    """The model of the FMU ``source`` inside the .ssp (FMPy's description, read once a pack,
    with artibus's Variables: artibus.fmu.model)."""
    from artibus.fmu.model import model_of, read_description
    st = Path(ssp).stat()
    key = (str(ssp), st.st_mtime_ns, st.st_size, source)
    if key not in _MD_CACHE:
        try:
            with zipfile.ZipFile(ssp) as z, zipfile.ZipFile(z.open(source)) as fmu, \
                    tempfile.TemporaryDirectory(prefix="artibus-") as tmp:
                xml = Path(tmp) / "modelDescription.xml"
                xml.write_bytes(fmu.read("modelDescription.xml"))
                _MD_CACHE[key] = model_of(read_description(str(xml), validate=False))
        except Exception as e:      # not a zip, no modelDescription.xml, not FMI XML: named, no traceback
            raise ArtibusError(f"{ssp}: {source}: not an FMU whose modelDescription.xml can be read "
                               f"({type(e).__name__}: {e})") from None
    return _MD_CACHE[key]
