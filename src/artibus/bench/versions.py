"""SSP version mixing (SSP 2.0 2 "Version Mixing": each file has its own version): OMSimulator
3.x writes version="2.0" on files of SSP 1.0 content; such an .ssd (``ssd_version``) and such an
.ssv or .ssm (``parameter_root``) are read as SSP 1.0, with a warning once a file a process."""
import sys
import zipfile
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError
from artibus.bench.ssd import NS


#: the SSP 1.0 XSD of each parameter file's root element (FMPy's copy of the standard's schemas)
SCHEMAS = {"ParameterSet": "SystemStructureParameterValues.xsd",
           "ParameterMapping": "SystemStructureParameterMapping.xsd"}
_WARNED = set()
_SCHEMA = {}        # XSD file -> its compiled schema, once a process


def parameter_root(data, file, expect=None):
    """The root of an .ssv or .ssm (its bytes; ``file`` names it in messages) validated against
    SSP 1.0's XSD. OMSimulator 3.x writes version="2.0" on files of SSP 1.0 content, which SSP 2.0
    allows (2 "Version Mixing": each file has its own version; 6 "SSV", ParameterSet version: 1.0
    or 2.0): such a file, valid against SSP 1.0's schema once its version is read as 1.0, is read
    as SSP 1.0 with a warning (once a file a process); anything else invalid is an ArtibusError
    naming the file, the line and what is wrong (so is a root other than ``expect``, if given)."""
    from fmpy.ssp.ssd import __file__ as fmpy_ssd
    try:
        root = etree.fromstring(data)
    except etree.XMLSyntaxError as e:
        raise ArtibusError(f"{file}:{e.lineno}: not well-formed XML: {e.msg}") from None
    xsd = SCHEMAS.get(etree.QName(root).localname)
    if xsd is None or expect not in (None, etree.QName(root).localname):
        raise ArtibusError(f"{file}:{root.sourceline}: <{etree.QName(root).localname}>: not an SSP parameter "
                           f"set or mapping (ssv:ParameterSet or ssm:ParameterMapping)")
    if xsd not in _SCHEMA:
        _SCHEMA[xsd] = etree.XMLSchema(file=str(Path(fmpy_ssd).parent / "schema" / xsd))
    schema = _SCHEMA[xsd]
    version = root.get("version")
    checked = root
    if version == "2.0":
        checked = etree.fromstring(data)
        checked.set("version", "1.0")
    if not schema.validate(checked):
        e = schema.error_log.last_error
        raise ArtibusError(f"{file}:{e.line}: not a valid SSP 1.0 {etree.QName(root).localname}: {e.message}")
    if version == "2.0" and file not in _WARNED:
        _WARNED.add(file)
        print(f"warning: {file}:{root.sourceline}: <{etree.QName(root).localname} version=\"2.0\">: SSP 1.0 "
              f"content only (as OMSimulator 3.x writes its files): read as SSP 1.0", file=sys.stderr)
    return root


#: SSP 1.0's connector types (SSP 1.0 5.3.2 "Connectors"); SSP 2.0 adds Float32, Int8 ... Binary, Clock
SSP1_TYPES = {"Real", "Integer", "Boolean", "String", "Enumeration"}
_VERSION_WARNED = set()


def ssd_version(ssp, where):
    """The .ssd's SSP version as it is read (Bench.read_as): "2.0" only for a file with SSP 2.0
    content (a connector of a type SSP 1.0 does not have: Binary, Clock, Float32, ...). OMSimulator
    3.x writes version="2.0" on files of SSP 1.0 content in the namespaces both versions share
    (SSP 2.0 2.2 "Version Mixing"): read as SSP 1.0, with a warning once a process. (The whole file: read_ssd's
    view of an SSP 2.0 bench leaves its FMI-LS-BUS components out.)"""
    with zipfile.ZipFile(ssp) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
    if root.get("version") != "2.0" or any(_connector_type(k) not in SSP1_TYPES
                                           for k in root.iter(f"{{{NS['ssd']}}}Connector")):
        return root.get("version")
    if where not in _VERSION_WARNED:
        import sys
        _VERSION_WARNED.add(where)
        print(f"warning: {where}:{root.sourceline}: <SystemStructureDescription version=\"2.0\">: SSP 1.0 "
              f"content only (no connector of an SSP 2.0 type, no FMI-LS-BUS network; as OMSimulator 3.x "
              f"writes its files): read as SSP 1.0", file=sys.stderr)
    return "1.0"


def _connector_type(connector):
    """The local name of a Connector's type element (ssc:Real, ...), "Real" when it has none."""
    for c in connector:
        if isinstance(c.tag, str) and etree.QName(c).namespace == NS["ssc"]:
            return etree.QName(c).localname
    return "Real"
