"""Small SSP benches made in code, for the tests and the benchmarks (benchmarks/suite.py,
benchmarks/runner.py): components with Real connectors around the built BusKinematics FMU,
connections (with a linear transformation, SSP 1.0 5.3.3), packed into an .ssp with parameter
files beside. Needs no test tools: the performance suite runs with what the set-up installs."""
import zipfile

from artibus.base import fmu_path

#: the SSP 1.0 namespaces of an .ssd, .ssv or .ssm written here
NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
      'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
      'xmlns:ssm="http://ssp-standard.org/SSP1/SystemStructureParameterMapping"')


def component(name, connectors, extra=""):
    """An <ssd:Component> of BusKinematics named ``name``, its connectors [(name, kind)] Real."""
    conns = "".join(f'<ssd:Connector name="{n}" kind="{k}"><ssc:Real/></ssd:Connector>' for n, k in connectors)
    return (f'<ssd:Component name="{name}" source="resources/BusKinematics.fmu" type="application/x-fmu-sharedlibrary">'
            f'<ssd:Connectors>{conns}</ssd:Connectors>{extra}</ssd:Component>')


def connection(a, ca, b, cb, tr=""):
    """An <ssd:Connection> from a.ca to b.cb (an empty element name: the system's connector), with
    ``tr`` the attributes of a linear transformation (e.g. 'factor="2.0" offset="0.01"')."""
    sa = f'startElement="{a}" ' if a else ""
    eb = f'endElement="{b}" ' if b else ""
    body = f'<ssc:LinearTransformation {tr}/>' if tr else ""
    return f'<ssd:Connection {sa}startConnector="{ca}" {eb}endConnector="{cb}">{body}</ssd:Connection>'


def ssd_text(elements, connections="", stop=10.0, name="bench", *, version="1.0", system="", after="",
             system_name="root", outer=""):
    """A SystemStructure.ssd: one system ``system_name`` holding ``system`` (its Connectors,
    ParameterBindings) before its ``elements``, then its ``connections`` (None: no Connections
    element) and ``after`` them (its SystemGeometry, Annotations...); ``outer`` after the system
    (the description's Enumerations, Units); a default experiment from 0 to ``stop``; SSP
    ``version`` (SSP 2.0 keeps SSP 1.0's namespaces)."""
    conns = "" if connections is None else f"<ssd:Connections>{connections}</ssd:Connections>"
    return (f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="{version}" '
            f'name="{name}"><ssd:System name="{system_name}">{system}<ssd:Elements>{elements}</ssd:Elements>'
            f'{conns}{after}</ssd:System>{outer}<ssd:DefaultExperiment startTime="0" stopTime="{stop}"/>'
            f'</ssd:SystemStructureDescription>')


def make_ssp(tmp_path, elements, connections="", stop=10.0, ssv=None, name="bench", fmu=True, *, fmus=(), **ssd):
    """<tmp_path>/<name>.ssp: ssd_text(elements, connections, stop, name, **ssd) with, in
    resources/, BusKinematics.fmu (unless fmu=False), the FMUs ``fmus`` (a built FMU's name, or a
    path: under its file name) and ``ssv``'s files ({file name: text or bytes, or the path of a file})."""
    files = {}
    for f in (["BusKinematics"] if fmu else []) + list(fmus):
        f = fmu_path(f) if isinstance(f, str) else f
        files[f"resources/{f.name}"] = f
    files.update({f"resources/{fname}": content for fname, content in (ssv or {}).items()})
    return pack_ssp(tmp_path / f"{name}.ssp", ssd_text(elements, connections, stop, name, **ssd), files)


def pack_ssp(path, ssd, files=None):
    """An .ssp at ``path``: its SystemStructure.ssd ``ssd`` (text) and ``files`` {name in the
    archive: text or bytes, or the path of a file}."""
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for arcname, content in (files or {}).items():
            if isinstance(content, (str, bytes)):
                z.writestr(arcname, content)
            else:
                z.write(content, arcname)
    return path
