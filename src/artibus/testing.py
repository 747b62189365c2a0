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


def make_ssp(tmp_path, elements, connections, stop=10.0, ssv=None, name="bench", fmu=True):
    """<tmp_path>/<name>.ssp: one system of ``elements`` and ``connections``, its default
    experiment to ``stop``, with resources/BusKinematics.fmu (unless fmu=False) and ssv's
    {file name: text} in resources/."""
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?><ssd:SystemStructureDescription {NS} version="1.0" name="{name}">'
           f'<ssd:System name="root"><ssd:Elements>{elements}</ssd:Elements>'
           f'<ssd:Connections>{connections}</ssd:Connections></ssd:System>'
           f'<ssd:DefaultExperiment startTime="0" stopTime="{stop}"/></ssd:SystemStructureDescription>')
    path = tmp_path / f"{name}.ssp"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        if fmu:
            z.write(fmu_path("BusKinematics"), "resources/BusKinematics.fmu")
        for fname, text in (ssv or {}).items():
            z.writestr(f"resources/{fname}", text)
    return path
