"""SSP 2.0 benches (issue 24): a SystemStructure.ssd of version="2.0", validated against the
SSP 2.0 XML schemas, whose FMI-LS-BUS network is read from its components and connections.

SSP 2.0 keeps SSP 1.0's namespaces and adds, among others, the connector types ``ssc:Binary``
(with ``mime-type``) and ``ssc:Clock``, and a connector's association to its clock
(``ssd:Clock name=``; SSP 2.0 4.4.4 "Binary", "Clock", 5.3.2 "Connectors"). The schemas are the
standard's normative files, vendored unchanged under schema/ssp2/ (SOURCE.md: the release and
commit; LICENSE.txt: BSD 2-Clause), as FMPy ships SSP 1.0's; the wrapper below imports the SSD,
SSV and SSM schemas at once so that inline parameter sets are validated as well.

What reads what:

- ``read_ssd(ssp, where)``: the .ssd's lxml tree, SSP 1.0 validated against FMPy's SSP 1.0
  XSDs; for SSP 2.0 the file validated against the SSP 2.0 XSDs, then its *plant view*: the
  .ssd without the FMI-LS-BUS components (those with an ssc:Binary or ssc:Clock connector) and
  without every connection to them; the parameter files it binds validated too. artibus.bench.ssp
  reads that tree as it reads every SSP 1.0 bench; the network is the runner's
  (artibus.runner.lsbus_bench).
- ``read_network(root, where, fmu)``: the network of the LS-BUS components: the bus simulation
  FMU (its fmi-ls-manifest.xml says isBusSimulationFMU="true"), the nodes, their parameters
  (inline parameter values), the Real connections between the plant and the nodes, and the
  nodes' Tx clock period, each checked against the FMUs' modelDescription.xml and
  terminalsAndIcons.xml (fmi-ls-bus 1.0, 4____network_abstraction.adoc "Bus Terminal": four
  members Tx_Data, Tx_Clock, Rx_Data, Rx_Clock; Tx connected to Rx and vice versa, the variable
  types equal; 2____common_concepts.adoc "Composition with dedicated Bus Simulation FMU").

The nodes' and the bus's bindings and the inputs' sources follow the rule of every bench,
SSP 1.0's too (artibus.bench.rules: each value of its variable's type and in its range, a unit
converted, one source per input); each connector's clock association names its variable's
clock. A bad .ssd is an ArtibusError naming the file, the line, the element and the value.
"""
import copy
import io
import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError, parse_real
from artibus.fmu.model import model_of
from artibus.bench.rules import bind, one_source, ssv_value
from artibus.bench.ssd import NS
from artibus.bench.units import ssp_units

SCHEMA_DIR = Path(__file__).parent / "schema" / "ssp2"
#: the LS-BUS CAN MIME type of Rx_Data/Tx_Data (fmi-ls-bus 1.0, 4_4_1_can.adoc)
CAN_MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
CAN_MIME_TYPE = "application/org.fmi-standard.fmi-ls-bus.can"      # the type, without its parameters
SEMVER = re.compile(r"(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)(-[0-9A-Za-z.-]+)?(\+[0-9A-Za-z.-]+)?")


def is_can_mime(mime):
    """whether mime is the FMI-LS-BUS CAN MIME type of major version 1 (fmi-ls-bus v1.0.0
    4____network_abstraction.adoc, "MIME Types": the version follows semantic versioning, so
    1.x keeps 1.0.0's operations; a pre-release such as the fmi-ls-bus-examples' 1.0.0-beta.1
    too): a bench's connectors here, an FMU's terminals in artibus.runner.lsbus.check_mime"""
    parts = [s.strip() for s in (mime or "").split(";")]
    params = dict(p.split("=", 1) for p in parts[1:] if "=" in p)
    m = SEMVER.fullmatch(params.get("version", "").strip().strip('"'))
    return parts[0].lower() == CAN_MIME_TYPE and m is not None and m.group(1) == "1"


NETWORK_TERMINAL = "org.fmi-ls-bus.network-terminal"
MEMBERS = ("Tx_Data", "Tx_Clock", "Rx_Data", "Rx_Clock")
#: the member each member is connected to (4____network_abstraction.adoc, "Bus Terminal")
PEER = {"Tx_Data": "Rx_Data", "Tx_Clock": "Rx_Clock", "Rx_Data": "Tx_Data", "Rx_Clock": "Tx_Clock"}
REAL = {"Real", "Float64", "Float32"}
#: SSP connector types -> the FMI 3.0 variable elements they stand for
FMI3_TYPE = {"Real": "Float64", "Float64": "Float64", "Float32": "Float32", "Binary": "Binary", "Clock": "Clock",
             "Boolean": "Boolean", "String": "String", "Integer": "Int32"}
#: the CanBus parameters a bench may bind (artibus.runner.lsbus_bench.LsBusSteering._network; the
#: fault parameters come from --can-fault, artibus.runner.lsbus_faults)
BUS_PARAMETERS = {"nNodes", "wireTime"}
_SCHEMA = []


def schema():
    """the SSP 2.0 SSD schema with SSV and SSM (inline parameter values and mappings), once"""
    if not _SCHEMA:
        imports = "".join(f'<xs:import namespace="{NS[p]}" schemaLocation="{(SCHEMA_DIR / f).as_uri()}"/>'
                          for p, f in (("ssd", "SystemStructureDescription.xsd"),
                                       ("ssv", "SystemStructureParameterValues.xsd"),
                                       ("ssm", "SystemStructureParameterMapping.xsd")))
        _SCHEMA.append(etree.XMLSchema(etree.fromstring(
            f'<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">{imports}</xs:schema>')))
    return _SCHEMA[0]


def validate(root, where):
    """the .ssd's root against the SSP 2.0 XSDs: an ArtibusError naming the line and what is wrong"""
    s = schema()
    if not s.validate(root):
        e = s.error_log.last_error
        raise ArtibusError(f"{where}:{e.line}: not a valid SSP 2.0 system structure: {e.message}")


def _type(connector):
    """the connector's type element (ssc:Real, ssc:Binary, ssc:Clock, ...) or None"""
    return next((c for c in connector if isinstance(c.tag, str) and etree.QName(c).namespace == NS["ssc"]), None)


def clocked(component):
    """an FMI-LS-BUS component: one with an ssc:Binary or ssc:Clock connector"""
    return any(t is not None and etree.QName(t).localname in ("Binary", "Clock")
               for t in map(_type, component.iterfind("ssd:Connectors/ssd:Connector", NS)))


def lsbus_components(root):
    """the System's FMI-LS-BUS components (SSP 2.0 only), in the file's order"""
    if root.get("version") != "2.0":
        return []
    return [c for c in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS) if clocked(c)]


def plant_view(root):
    """a copy of the .ssd without its FMI-LS-BUS components and the connections to them"""
    view = copy.deepcopy(root)                 # (lxml's copy keeps the source lines)
    system = view.find("ssd:System", NS)
    gone = lsbus_components(view)
    names = {c.get("name") for c in gone}
    for c in gone:
        c.getparent().remove(c)
    for c in list(system.iterfind("ssd:Connections/ssd:Connection", NS)):
        if c.get("startElement") in names or c.get("endElement") in names:
            c.getparent().remove(c)
    return view


def read_ssd(ssp, where):
    """The lxml root artibus.bench.ssp reads of the .ssp's .ssd, validated: SSP 1.0 against the
    SSP 1.0 XSDs FMPy ships; SSP 2.0 against the SSP 2.0 XSDs, then its plant view; each
    parameter set and mapping it binds from a file against SSP 1.0's (versions.parameter_root)."""
    from fmpy.ssp.ssd import validate_tree
    from artibus.bench.ssd import _sources_inside_components
    try:
        with zipfile.ZipFile(ssp) as z:
            root = etree.fromstring(z.read("SystemStructure.ssd"))
        if root.get("version") != "2.0":
            validate_tree(root, "SystemStructureDescription.xsd")
    except Exception as e:
        _sources_inside_components(ssp, where)   # the reason, where it is that
        raise ArtibusError(f"{where}: not a readable SSP system structure: {e}") from None
    if root.get("version") == "2.0":
        validate(root, where)
    _sources_inside_components(ssp, where)
    view = root if root.get("version") != "2.0" else plant_view(root)
    _parameter_files(ssp, view, where)
    return view


def _parameter_files(ssp, root, where):
    """each .ssv and .ssm a ParameterBinding of ``root`` names, validated (SSP 1.0 5.3.5)"""
    from artibus.bench.bindings import member_root
    for b in root.iterfind(".//ssd:ParameterBinding", NS):
        refs = [(b, b.get("source"))] + [(m, m.get("source")) for m in b.iterfind("ssd:ParameterMapping", NS)]
        for el, ref in refs:
            if ref is not None:
                member_root(ssp, ref, f"{where}:{el.sourceline}: <{etree.QName(el).localname} source=\"{ref}\">")


# ---- the network ----------------------------------------------------------------------------

@dataclass
class Fmu3:
    """what read_network needs of an LS-BUS FMU"""
    variables: dict                 # name -> its modelDescription.xml element
    terminals: dict                 # network terminal name -> {member: variable name}
    is_bus: bool                    # fmi-ls-manifest.xml: isBusSimulationFMU="true"
    md: object = None               # FMPy's description, in FMI 2.0's type names (bindings: artibus.bench.rules)


def read_fmu(file, where):
    """file: a path or a file object of the FMU"""
    from fmpy import read_model_description
    try:
        with zipfile.ZipFile(file) as z:
            md = etree.fromstring(z.read("modelDescription.xml"))
            names = set(z.namelist())
            tai = (etree.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
                   if "terminalsAndIcons/terminalsAndIcons.xml" in names else None)
            m = "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"
            manifest = etree.fromstring(z.read(m)) if m in names else None
        if hasattr(file, "seek"):
            file.seek(0)
        described = model_of(read_model_description(file, validate=False))
    except (zipfile.BadZipFile, KeyError, OSError, etree.XMLSyntaxError) as e:
        raise ArtibusError(f"{where}: not a readable FMU: {e}") from None
    except Exception as e:            # FMPy's reader: not FMI XML
        raise ArtibusError(f"{where}: not a readable FMU: {type(e).__name__}: {e}") from None
    variables = {v.get("name"): v for v in md.iterfind("ModelVariables/*")}
    terminals = {}
    for t in [] if tai is None else tai.iter("Terminal"):
        if t.get("terminalKind") == NETWORK_TERMINAL:
            terminals[t.get("name")] = {m.get("memberName"): m.get("variableName")
                                        for m in t.findall("TerminalMemberVariable")}
    return Fmu3(variables, terminals, manifest is not None and manifest.get("isBusSimulationFMU") == "true",
                described)


@dataclass
class Network:
    """An FMI-LS-BUS network of an SSP 2.0 bench."""
    period: float                   # s: the nodes' time-based Tx_Clock interval (the runner's tick)
    bus: tuple                      # (component name, source, {parameter: value})
    nodes: dict                     # name -> (source, {parameter: value}), in the bus's terminal order
    inputs: list = field(default_factory=list)    # (node, variable, "Component.output")
    outputs: list = field(default_factory=list)   # (node, variable, "Component.input")
    terminals: dict = field(default_factory=dict)  # node -> (its terminal, the bus's terminal)


def _label(c):
    return (f'<Connection startElement="{c.get("startElement")}" startConnector="{c.get("startConnector")}" '
            f'endElement="{c.get("endElement")}" endConnector="{c.get("endConnector")}">')


def _value(el, where):
    """an inline ssv:Parameter's (value as its element types it, the unit given with it or None):
    a number or a Boolean (artibus.bench.rules.ssv_value)"""
    value, unit, kind = ssv_value(el, f"{where}:{el.sourceline}")
    if kind in ("Enumeration", "String", "Binary"):
        raise ArtibusError(f"{where}:{el.sourceline}: <Parameter name=\"{el.get('name')}\"> <{kind} value="
                           f"\"{value}\">: an LS-BUS FMU's parameter must be a Real, an integer or a Boolean")
    return value, unit


def _parameters(comp, where, fmu=None, units=None):
    """the component's inline parameter values; with fmu (read_fmu's), each bound by the rule
    of every bench (artibus.bench.rules.bind: a parameter or an input of the FMU, of its type,
    in its range, a unit converted; ``units``: the .ssd's own unit definitions)"""
    out, origins, given = {}, {}, {}
    for b in comp.iterfind("ssd:ParameterBindings/ssd:ParameterBinding", NS):
        if b.get("source") is not None or b.find("ssd:ParameterMapping", NS) is not None:
            raise ArtibusError(f"{where}:{b.sourceline}: <ParameterBinding source=\"{b.get('source')}\"> of the "
                               f"FMI-LS-BUS component {comp.get('name')}: only inline parameter values (without "
                               "a mapping) are applied to LS-BUS FMUs")
        for pset in b.iterfind("ssd:ParameterValues/ssv:ParameterSet", NS):
            defs = {**(units or {}), **ssp_units(pset, where)}
            for p in pset.iterfind("ssv:Parameters/ssv:Parameter", NS):
                v = fmu.variables.get(p.get("name")) if fmu is not None else None
                if fmu is not None and (v is None or v.get("causality") not in ("parameter", "input")):
                    what = "no such variable" if v is None else f"a variable of causality {v.get('causality')}"
                    raise ArtibusError(f"{where}:{p.sourceline}: <Parameter name=\"{p.get('name')}\"> of the "
                                       f"FMI-LS-BUS component {comp.get('name')}: {what} in {comp.get('source')} "
                                       "(a parameter or an input is set)")
                name = p.get("name")
                out[name], unit = _value(p, where)
                origins[name] = f"{where}:{p.sourceline}"
                if unit:
                    given[name] = (unit, defs)
                else:
                    given.pop(name, None)
    if fmu is None:
        return out
    return bind(out, fmu.md, origins, prefix=f"{comp.get('name')}.", units=given)


def _check_connector(comp, conn, var, where):
    """the connector's type and kind against the FMU variable it names (SSP 2.0 5.3.2: a type
    other than the variable's is an error)"""
    name, t = conn.get("name"), _type(conn)
    head = f"{where}:{conn.sourceline}: <Connector name=\"{name}\"> of {comp.get('name')}"
    if var is None:
        raise ArtibusError(f"{head}: the FMU has no variable {name!r}")
    if t is None:
        raise ArtibusError(f"{head}: no type; the connectors of an FMI-LS-BUS FMU give theirs (ssc:Binary with "
                           "its mime-type, ssc:Clock, ssc:Float64, ...)")
    kind = etree.QName(t).localname
    if FMI3_TYPE.get(kind, kind) != var.tag:
        raise ArtibusError(f"{head}: an ssc:{kind}, but the FMU's {name} is a {var.tag}")
    if conn.get("kind") != var.get("causality"):
        raise ArtibusError(f"{head}: kind=\"{conn.get('kind')}\", but the FMU's {name} has causality "
                           f"\"{var.get('causality')}\"")
    if kind == "Binary" and t.get("mime-type") != var.get("mimeType"):
        raise ArtibusError(f"{head}: <Binary mime-type=\"{t.get('mime-type')}\">, but the FMU's {name} has "
                           f"mimeType=\"{var.get('mimeType')}\"")
    if kind == "Clock":
        for a in ("intervalVariability", "intervalDecimal"):
            if t.get(a) is not None and t.get(a) != var.get(a) and not (
                    a == "intervalDecimal" and var.get(a) and _same_number(t.get(a), var.get(a))):
                raise ArtibusError(f"{head}: <Clock {a}=\"{t.get(a)}\">, but the FMU's {name} has {a}="
                                   f"\"{var.get(a)}\"")
    return kind, t


def _check_clocks(comp, fmu, kinds, where):
    """each connector's clock associations (SSP 2.0 5.3.2, ssd:Connector's ssd:Clock name=: a
    clock of the same element) against the clocks of its FMU variable (FMI 3.0, a clocked
    variable's clocks=, the value references of its Clock variables): a clocked variable's
    connector names each of its clocks, each an ssc:Clock connector of the component; no
    other association (kinds: _connectors', this component's connectors already in it)"""
    name = comp.get("name")
    for k in comp.iterfind("ssd:Connectors/ssd:Connector", NS):
        var = fmu.variables[k.get("name")]           # (_check_connector: every connector has its variable)
        head = f"{where}:{k.sourceline}: <Connector name=\"{k.get('name')}\"> of {name}"
        vrs = (var.get("clocks") or "").split()
        want = [n for n, v in fmu.variables.items() if v.tag == "Clock" and v.get("valueReference") in vrs]
        by = f"clocked by {', '.join(want)}" if want else "not clocked"
        given = [c.get("name") for c in k.iterfind("ssd:Clock", NS)]
        for g in given:
            if (name, g) not in kinds:
                raise ArtibusError(f"{head}: <Clock name=\"{g}\">: {name} has no connector {g!r} (a clock "
                                   "association names an ssc:Clock connector of its component)")
            if kinds[(name, g)][0] != "Clock":
                raise ArtibusError(f"{head}: <Clock name=\"{g}\">: {g} is {_kind_name(kinds[(name, g)][0])} "
                                   "connector, not an ssc:Clock (a clock association names a clock)")
            if g not in want:
                raise ArtibusError(f"{head}: <Clock name=\"{g}\">: the FMU's {k.get('name')} is {by} "
                                   "(its clocks= in modelDescription.xml)")
        for w in want:
            if w not in given:
                raise ArtibusError(f"{head}: no clock association <Clock name=\"{w}\">: the FMU's "
                                   f"{k.get('name')} is {by} (its clocks= in modelDescription.xml); its "
                                   "connector names the clock it ticks with")


def _kind_name(kind):
    return f"an ssc:{kind}" if kind else "a connector without a type"


def _connectors(comps, fmus, where):
    """({(component, connector): (its type's name, the type element)} of the LS-BUS components,
    each checked against its FMU variable; {(component, connector): (terminal, member)} of the
    terminal members, each terminal complete: its four members (4, "Bus Terminal") as connectors
    of their types, the data of the LS-BUS CAN MIME type)"""
    kinds, member = {}, {}
    for c in comps:
        name, f = c.get("name"), fmus[c.get("name")]
        for k in c.iterfind("ssd:Connectors/ssd:Connector", NS):
            kinds[(name, k.get("name"))] = _check_connector(c, k, f.variables.get(k.get("name")), where)
        _check_clocks(c, f, kinds, where)
        for term, members in f.terminals.items():
            if f.is_bus and not any((name, members.get(m)) in kinds for m in MEMBERS):
                continue                     # a terminal of the bus no node is connected to
            for m in MEMBERS:
                key = (name, members.get(m))
                if key not in kinds:
                    raise ArtibusError(f"{where}:{c.sourceline}: <Component name=\"{name}\">: no <Connector "
                                       f"name=\"{members.get(m)}\">, the member {m} of its bus terminal {term} "
                                       "(terminalsAndIcons.xml; fmi-ls-bus 1.0, \"Bus Terminal\")")
                kind, t = kinds[key]
                want = "Binary" if m.endswith("_Data") else "Clock"
                head = f"{where}:{t.getparent().sourceline}: <Connector name=\"{members[m]}\"> of {name}"
                if kind != want:
                    raise ArtibusError(f"{head}: an ssc:{kind}, but the terminal member {m} is an ssc:{want}")
                if want == "Binary" and not is_can_mime(t.get("mime-type")):
                    raise ArtibusError(f"{head}: <Binary mime-type=\"{t.get('mime-type')}\">: the runner's master "
                                       f"runs FMI-LS-BUS CAN ({CAN_MIME}, or another 1.x version)")
                member[key] = (term, m)
    return kinds, member


def _plant_kinds(system, by_name, kinds):
    """kinds completed with the other components' connectors that connections name"""
    for c in system.iterfind("ssd:Connections/ssd:Connection", NS):
        for e, k in (("startElement", "startConnector"), ("endElement", "endConnector")):
            el = by_name.get(c.get(e))
            if el is None or (c.get(e), c.get(k)) in kinds or etree.QName(el).localname != "Component":
                continue
            conn = next((x for x in el.iterfind("ssd:Connectors/ssd:Connector", NS) if x.get("name") == c.get(k)),
                        None)                  # (compared, not put into an XPath: any name is safe)
            if conn is not None:
                t = _type(conn)
                kinds[(c.get(e), c.get(k))] = (etree.QName(t).localname if t is not None else None, t)


def _connections(system, by_name, fmus, kinds, member, bus, where):
    """({terminal member: the member it is connected to}, the Real inputs of the nodes, their
    outputs) of the connections with an LS-BUS component at an end, each checked: the types equal
    (a Binary to a Binary of its MIME type, a Clock to a Clock, a number to a number), a terminal
    member from Tx to Rx (4, "Bus Terminal"), once; a Real one from an output to an input, with
    no transformation"""
    links, inputs, outputs = {}, [], []
    for c in system.iterfind("ssd:Connections/ssd:Connection", NS):
        a, b = (c.get("startElement"), c.get("startConnector")), (c.get("endElement"), c.get("endConnector"))
        if a[0] not in fmus and b[0] not in fmus:
            continue
        head = f"{where}:{c.sourceline}: {_label(c)}"
        for end in (a, b):
            if end[0] not in by_name:
                raise ArtibusError(f"{head}: no element {end[0]!r} in the System")
            if end not in kinds:
                raise ArtibusError(f"{head}: {end[0]} has no connector {end[1]!r}")
        (ka, ta), (kb, tb) = kinds[a], kinds[b]
        if not ((ka == kb) if {ka, kb} & {"Binary", "Clock"} else (ka in REAL and kb in REAL)):
            raise ArtibusError(f"{head}: connects {_kind_name(ka)} ({'.'.join(a)}) to {_kind_name(kb)} "
                               f"({'.'.join(b)})")
        if ka == "Binary" and ta.get("mime-type") != tb.get("mime-type"):
            raise ArtibusError(f"{head}: connects mime-type=\"{ta.get('mime-type')}\" to "
                               f"mime-type=\"{tb.get('mime-type')}\"")
        if a in member or b in member:
            if not (a in member and b in member and member[a][1].startswith("Tx")
                    and PEER[member[a][1]] == member[b][1]):
                what = " to ".join(f"{'.'.join(x)} ({'member ' + member[x][1] if x in member else 'no terminal member'})"
                                   for x in (a, b))
                raise ArtibusError(f"{head}: connects {what}; a terminal's Tx member is connected to a terminal's "
                                   "Rx member, from Tx to Rx (fmi-ls-bus 1.0, \"Bus Terminal\": Tx_Data -> Rx_Data, "
                                   "Tx_Clock -> Rx_Clock)")
            for x, y in ((a, b), (b, a)):
                if x in links:
                    raise ArtibusError(f"{head}: {'.'.join(x)} is connected twice")
                links[x] = y
            continue
        if any(isinstance(t.tag, str) and etree.QName(t).localname.endswith("Transformation") for t in c):
            raise ArtibusError(f"{head}: a transformation on a connection to an FMI-LS-BUS FMU is not applied")
        if bus in (a[0], b[0]):
            raise ArtibusError(f"{head}: the bus simulation FMU {bus}'s signals are not connected by the runner")
        for end, t, want in ((a, ta, "output"), (b, tb, "input")):
            if end[0] in fmus and t.getparent().get("kind") != want:
                raise ArtibusError(f"{head}: {'.'.join(end)} has kind=\"{t.getparent().get('kind')}\", not {want}")
        if b[0] in fmus:
            inputs.append((b[0], b[1], ".".join(a)))
        else:
            outputs.append((a[0], a[1], ".".join(b)))
    return links, inputs, outputs


def _one_source(system, by_name, kinds, where):
    """every input of a top-level component with one source (artibus.bench.rules.one_source),
    the plant's and the network's connections together: a plant input fed by a node and by
    another component, a node's input fed twice (the terminals' members: _connections)"""
    def ends():
        for c in system.iterfind("ssd:Connections/ssd:Connection", NS):
            a, b = (c.get("startElement"), c.get("startConnector")), (c.get("endElement"), c.get("endConnector"))
            el = by_name.get(b[0])
            if (el is None or etree.QName(el).localname != "Component"
                    or kinds.get(b, (None,))[0] in ("Binary", "Clock")):
                continue
            frm, to = f"{a[0]}.{a[1]}", f"{b[0]}.{b[1]}"
            yield frm, to, f"{where}:{c.sourceline}: Connection {frm} -> {to}"
    one_source(ends())


def _placement(comps, fmus, links, member, bus, where):
    """[(node, its terminal, the bus terminal)] in the bus's terminal order: each node's one
    terminal as its four connections to one terminal of the bus, the nodes on the bus's first
    terminals (artibus.runner.lsbus.Network: the k-th node on the k-th terminal)"""
    bus_terms, placed = list(fmus[bus].terminals), {}
    for c in comps:
        name = c.get("name")
        if name == bus:
            continue
        head = f"{where}:{c.sourceline}: <Component name=\"{name}\">"
        terms = fmus[name].terminals
        if len(terms) != 1:
            raise ArtibusError(f"{head}: {len(terms)} bus terminals; the runner's master connects nodes of one")
        ((term, members),) = terms.items()
        peers = set()
        for m in MEMBERS:
            peer = links.get((name, members[m]))
            if peer is None:
                raise ArtibusError(f"{head}: its terminal {term}'s member {m} ({members[m]}) is connected to "
                                   "nothing; each terminal is its four connections to a terminal of the bus "
                                   "simulation FMU")
            if peer[0] != bus:
                raise ArtibusError(f"{head}: {members[m]} is connected to {'.'.join(peer)}, not to the bus "
                                   f"simulation FMU {bus}")
            peers.add(member[peer][0])
        if len(peers) != 1:
            raise ArtibusError(f"{head}: its terminal {term} is connected to several terminals of {bus} "
                               f"({', '.join(sorted(peers))})")
        placed[bus_terms.index(peers.pop())] = (name, term)
    if sorted(placed) != list(range(len(placed))):
        raise ArtibusError(f"{where}: the nodes are on {bus}'s terminals {', '.join(bus_terms[k] for k in sorted(placed))}; "
                           f"the runner's master connects them to its first terminals in order "
                           f"({', '.join(bus_terms[:len(placed)])})")
    return [(*placed[k], bus_terms[k]) for k in sorted(placed)]


def _same_number(a, b):
    """two decimal texts of the same number; False where either is none"""
    try:
        return parse_real(a) == parse_real(b)
    except ValueError:
        return False


def _period(net, fmus, where):
    """the runner's tick: the nodes' time-based Tx clocks' interval, one for all; a node whose
    Tx_Clock is a triggered output clock (fmi-ls-bus 1.0, "Triggered Tx Clocks") ticks itself
    and is served within the tick (artibus.runner.lsbus), so at least one other node gives it"""
    periods, triggered = {}, []
    for name, (term, _) in net.terminals.items():
        tx = fmus[name].variables[fmus[name].terminals[term]["Tx_Clock"]]
        if tx.get("causality") == "output" and tx.get("intervalVariability") == "triggered":
            triggered.append(name)
            continue
        try:
            if tx.get("intervalVariability") in ("constant", "fixed"):
                periods[name] = parse_real(tx.get("intervalDecimal"))
        except (TypeError, ValueError):
            pass
    if triggered and not periods:
        raise ArtibusError(f"{where}: every node's Tx_Clock is a triggered output clock ({', '.join(triggered)}): "
                           "the runner ticks the network with the interval of the nodes' time-based (constant or "
                           "fixed) Tx_Clock, and none has one")
    if len(set(periods.values())) != 1 or len(periods) + len(triggered) != len(net.nodes) \
            or not min(periods.values()) > 0:
        raise ArtibusError(f"{where}: the nodes' Tx_Clock periods {periods or 'none'}: the runner ticks the network "
                           "with one period, every node's time-based (constant or fixed) Tx_Clock interval")
    return next(iter(periods.values()))


def read_network(root, where, fmu):
    """The Network of the .ssd's FMI-LS-BUS components (lsbus_components), or None without any.
    fmu(component element) -> the FMU (a path or a file object)."""
    comps = lsbus_components(root)
    if not comps:
        return None
    system = root.find("ssd:System", NS)
    for s in system.iterfind("ssd:Elements/ssd:System", NS):
        if any(clocked(c) for c in s.iter(f"{{{NS['ssd']}}}Component")):
            raise ArtibusError(f"{where}:{s.sourceline}: <System name=\"{s.get('name')}\">: FMI-LS-BUS components "
                               "in a sub-system; the runner connects them in the top-level System only")
    by_name = {c.get("name"): c for c in system.iterfind("ssd:Elements/*", NS)}
    fmus = {c.get("name"): read_fmu(fmu(c), f"{where}:{c.sourceline}: <Component name=\"{c.get('name')}\" "
                                            f"source=\"{c.get('source')}\">") for c in comps}
    buses = [c.get("name") for c in comps if fmus[c.get("name")].is_bus]
    if len(buses) != 1:
        raise ArtibusError(f"{where}: {len(buses)} bus simulation FMUs (isBusSimulationFMU=\"true\" in "
                           f"fmi-ls-manifest.xml) among the FMI-LS-BUS components "
                           f"{', '.join(c.get('name') for c in comps)}; the runner connects the nodes through one")
    (bus,) = buses
    units = ssp_units(root, where)
    kinds, member = _connectors(comps, fmus, where)
    _plant_kinds(system, by_name, kinds)
    links, inputs, outputs = _connections(system, by_name, fmus, kinds, member, bus, where)
    _one_source(system, by_name, kinds, where)
    comp = {c.get("name"): c for c in comps}
    net = Network(period=None, bus=None, nodes={}, inputs=inputs, outputs=outputs)
    for name, term, bus_term in _placement(comps, fmus, links, member, bus, where):
        net.nodes[name] = (comp[name].get("source"), _parameters(comp[name], where, fmus[name], units))
        net.terminals[name] = (term, bus_term)
    params = _parameters(comp[bus], where, fmus[bus], units)
    head = f"{where}:{comp[bus].sourceline}: <Component name=\"{bus}\">"
    extra = set(params) - BUS_PARAMETERS
    if extra:
        raise ArtibusError(f"{head}: parameter {', '.join(sorted(extra))}: the runner sets only "
                           f"{', '.join(sorted(BUS_PARAMETERS))} of the bus simulation FMU")
    if params.get("nNodes", len(net.nodes)) != len(net.nodes):
        raise ArtibusError(f"{head}: <Parameter name=\"nNodes\"> {params['nNodes']}, but {len(net.nodes)} nodes "
                           "are connected to it")
    if "wireTime" not in params:
        w = fmus[bus].variables.get("wireTime")
        params["wireTime"] = w is not None and w.get("start") == "true"
    net.bus = (bus, comp[bus].get("source"), params)
    net.period = _period(net, fmus, where)
    return net


def network_of_ssp(ssp):
    """read_network of a packed .ssp (its FMUs read from the archive), or None"""
    where = f"{ssp}/SystemStructure.ssd"
    with zipfile.ZipFile(ssp) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
        names = set(z.namelist())

        def fmu(c):
            if c.get("source") not in names:
                raise ArtibusError(f"{where}:{c.sourceline}: <Component name=\"{c.get('name')}\" "
                                   f"source=\"{c.get('source')}\">: not in the .ssp")
            return io.BytesIO(z.read(c.get("source")))
        return read_network(root, where, fmu)


def network_lines(ssp):
    """what ``artibus info``/``artibus check`` print of a packed bench's FMI-LS-BUS network ([] without)"""
    net = network_of_ssp(ssp)
    if net is None:
        return []
    bus, source, params = net.bus
    out = [f"FMI-LS-BUS network (SSP 2.0): {len(net.nodes)} nodes on {bus} ({source}, wireTime "
           f"{'on' if params['wireTime'] else 'off'}), ticked every {net.period:g} s (the nodes' Tx_Clock); "
           "each terminal as its four connections:"]
    for name, (src, p) in net.nodes.items():
        term, bus_term = net.terminals[name]
        values = ", ".join(f"{k} = {v}" for k, v in p.items())
        out.append(f"  {name}: {src}, {term} <-> {bus}.{bus_term}" + (f"; {values}" if values else ""))
    out += [f"  {frm} -> {node}.{var}" for node, var, frm in net.inputs]
    out += [f"  {node}.{var} -> {to}" for node, var, to in net.outputs]
    return out
