"""An FMI-LS-BUS 1.0 CAN network node's model description (issue 24), from the one
declaration of its model's variables and a short node file:

    modelDescription/lsbus/<Name>.xml
      <LsBusNode name="SteeringECU_LSBUS" base="SteeringECU" guid="{...}" terminal="SteeringCAN"
                 txInterval="0.01" description="...">
        <Received name="gamma1"/> ...          the base's inputs the frames fill
        <ModelVariables> <ScalarVariable .../> variables of the node only (optional)
      </LsBusNode>

- ``derive``: the node's variables in FMI 2.0 form (what gen_vars.py and package_fmu.py
  read): the base model's (modelDescription/<base>.xml, or the node file's own where it
  has no base) with each received input turned into a discrete local (the frames, not
  the importer, set it: the model's code reads it as before), the node's own variables,
  and the terminal's BusNotifications parameter (fmi-ls-bus v1.0.0, 4_4_1_can.adoc, "Bus
  Notification Parameter": Boolean, fixed, start false); no FMU state (the bus state is not
  saved);
- ``write_header``: model_lsbus.h, the value references of the four terminal variables
  (the next after every FMI 3.0 value reference of the table, gen_vars.fmi3_value_references)
  and Tx_Clock's interval, for src/models/common/lsbus_node.c;
- ``extend_fmi3`` (package_fmu.py --lsbus): the terminal's variables in the FMI 3.0 model
  description (4____network_abstraction.adoc, "Variables": Rx_Data and Tx_Data Binary with
  the CAN MIME type and maxSize, clocked by Rx_Clock, an input triggered clock, and
  Tx_Clock, an input time-based clock, periodic with the DBC's cycle: intervalVariability
  constant), terminalsAndIcons/terminalsAndIcons.xml (the Bus Terminal, "Bus Terminal"; the
  path of FMI 3.0.2, 2.4.9) and extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml (the
  manifest, 1____introduction.adoc; its description fixed by
  schema/fmi3LayeredStandardBusManifest.xsd).

Only the Python standard library is used: this runs inside the CMake build.
"""
import copy
import os
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gen_vars  # noqa: E402

MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
MANIFEST_DESCRIPTION = ("Layered Standard for the simulation of bus communication on a Physical Signal "
                        "Abstraction or Network Abstraction based level.")
MAX_SIZE = 1024          # bytes per Binary: LSNODE_BUFFER in src/models/common/lsbus_node.h
MEMBERS = ("Rx_Data", "Tx_Data", "Rx_Clock", "Tx_Clock")


class NodeError(Exception):
    pass


TX_CLOCK_FORMS = ("periodic", "triggered")


def _variant_root(path, root):
    """A variant's node file (<LsBusNode variantOf="<node file>" name= guid= txClock=
    description=>): the node file it names with those attributes replaced, so that the
    variables are declared once (the triggered Tx clock form of a node, see read_spec)."""
    base_path = os.path.join(os.path.dirname(path), root.get("variantOf"))
    try:
        base = ET.parse(base_path).getroot()
    except (OSError, ET.ParseError) as e:
        raise NodeError(f"{path}: variantOf=\"{root.get('variantOf')}\": {e}") from None
    if base.get("variantOf"):
        raise NodeError(f"{path}: variantOf names {base_path}, itself a variant")
    for k, v in root.attrib.items():
        if k != "variantOf":
            base.set(k, v)
    return base


def read_spec(path):
    """The node file: its attributes, received inputs and own variables. txClock= (default
    periodic) is the Tx clock's form: "periodic", an input time-based clock ticking every
    txInterval (fmi-ls-bus 1.0, 4____network_abstraction.adoc, "Time-based Tx Clocks"), or
    "triggered", an output triggered clock the node activates at those same ticks, signalled
    by eventHandlingNeeded of fmi3DoStep and nextEventTime ("Triggered Tx Clocks")."""
    root = ET.parse(path).getroot()
    if root.tag != "LsBusNode":
        raise NodeError(f"{path}: the root element is <{root.tag}>, expected <LsBusNode>")
    if root.get("variantOf"):
        root = _variant_root(path, root)
    spec = {k: root.get(k) for k in ("name", "base", "guid", "terminal", "txInterval", "description")}
    spec["txClock"] = root.get("txClock", "periodic")
    if spec["txClock"] not in TX_CLOCK_FORMS:
        raise NodeError(f"{path}: txClock=\"{spec['txClock']}\" is none of {', '.join(TX_CLOCK_FORMS)}")
    for k in ("name", "guid", "terminal", "txInterval", "description"):
        if not spec[k]:
            raise NodeError(f"{path}: <LsBusNode> has no {k}=")
    try:
        spec["txInterval"] = float(spec["txInterval"])
    except ValueError:
        raise NodeError(f"{path}: txInterval=\"{root.get('txInterval')}\" is not a time in s") from None
    spec["received"] = [r.get("name") for r in root.findall("Received")]
    mv = root.find("ModelVariables")
    spec["variables"] = [] if mv is None else mv.findall("ScalarVariable")
    spec["own"] = root          # a node without base: its UnitDefinitions, LogCategories, ... here
    spec["path"] = path
    return spec


def _base_root(spec, md_dir):
    if spec["base"]:
        return ET.parse(os.path.join(md_dir, spec["base"] + ".xml")).getroot()
    own = spec["own"]
    md = ET.Element("fmiModelDescription", {"fmiVersion": "2.0", "generationTool": "artibus",
                                            "variableNamingConvention": "structured",
                                            "numberOfEventIndicators": "0"})
    ET.SubElement(md, "CoSimulation")
    for tag in ("UnitDefinitions", "LogCategories", "DefaultExperiment"):
        el = own.find(tag)
        if el is not None:
            md.append(copy.deepcopy(el))
    ET.SubElement(md, "ModelVariables")
    ET.SubElement(md, "ModelStructure")
    return md


def derive(spec_path, md_dir, out_xml):
    """The node's FMI 2.0 variables (see the module's docstring) into out_xml."""
    spec = read_spec(spec_path)
    md = _base_root(spec, md_dir)
    md.set("modelName", spec["name"])
    md.set("guid", spec["guid"])
    md.set("description", spec["description"])
    cs = md.find("CoSimulation")
    cs.attrib.clear()
    cs.attrib.update({"modelIdentifier": spec["name"], "canHandleVariableCommunicationStepSize": "true",
                      "canGetAndSetFMUstate": "false", "canSerializeFMUstate": "false",
                      "canNotUseMemoryManagementFunctions": "false"})
    mv = md.find("ModelVariables")
    svs = mv.findall("ScalarVariable")
    by_name = {sv.get("name"): sv for sv in svs}
    for name in spec["received"]:
        sv = by_name.get(name)
        if sv is None or sv.get("causality") != "input":
            raise NodeError(f"{spec_path}: <Received name=\"{name}\">: the base {spec['base']} has no input {name}")
        sv.set("causality", "local")
        sv.set("variability", "discrete")
        sv.set("initial", "exact")
        sv.set("description", sv.get("description", "") + " -- here from the frames received on " +
               spec["terminal"] + " (Rx_Data), not set by the importer")
    own = [copy.deepcopy(v) for v in spec["variables"]]
    vr_used = {int(sv.get("valueReference")) for sv in svs}
    nxt = max(vr_used | {0}) + 1
    bn = ET.Element("ScalarVariable", {
        "name": f"{spec['terminal']}.BusNotifications", "valueReference": str(max(nxt, 900)),
        "causality": "parameter", "variability": "fixed", "initial": "exact",
        "description": "fmi-ls-bus 4_4_1_can.adoc, Bus Notification Parameter: false, the node is "
                       "fire-and-forget (it never waits for Confirm and ignores the bus's notifications); "
                       "a bus simulation that sends notifications finds true; this node ignores them either way"})
    ET.SubElement(bn, "Boolean", {"start": "false"})
    for sv in own + [bn]:
        mv.append(sv)
    # every output discrete, computed at the samples: no direct feedthrough
    svs = mv.findall("ScalarVariable")
    ms = md.find("ModelStructure")
    for child in list(ms):
        ms.remove(child)
    outs = [i + 1 for i, sv in enumerate(svs) if sv.get("causality") == "output"]
    if outs:
        o = ET.SubElement(ms, "Outputs")
        for i in outs:
            ET.SubElement(o, "Unknown", {"index": str(i), "dependencies": ""})
        iu = ET.SubElement(ms, "InitialUnknowns")
        for i in outs:
            ET.SubElement(iu, "Unknown", {"index": str(i)})
    ET.indent(md, "  ")
    ET.ElementTree(md).write(out_xml, encoding="UTF-8", xml_declaration=True)
    return out_xml


def bus_value_references(xml_path):
    """{member: value reference} of the terminal's four variables: the next numbers after
    the FMI 3.0 value references the table has (time the last of them)."""
    refs = gen_vars.fmi3_value_references(gen_vars.read(xml_path))
    base = max([refs["time"]] + refs["vars"] + refs["z"]) + 1
    return {m: base + i for i, m in enumerate(MEMBERS)}


def write_header(spec_path, xml_path, out_h):
    spec = read_spec(spec_path)
    vr = bus_value_references(xml_path)
    lines = [f"/* Generated by src/fmi/lsbus_node.py from {os.path.basename(spec_path)}: the value references",
             " * of the node's bus terminal (one after the variable table's) and Tx_Clock's interval. */",
             "#ifndef MODEL_LSBUS_H", "#define MODEL_LSBUS_H", ""]
    for m in MEMBERS:
        lines.append(f"#define LSBUS_VR_{m.upper()} {vr[m]}u   /* {spec['terminal']}.{m} */")
    lines += [f"#define LSBUS_TERMINAL \"{spec['terminal']}\"   /* the bus terminal's name, for messages */",
              f"#define LSBUS_MAX_SIZE {MAX_SIZE}   /* maxSize of Rx_Data and Tx_Data */",
              f"#define LSBUS_TX_INTERVAL {gen_vars.c_double(repr(spec['txInterval']))}   "
              "/* s, the Tx ticks' interval */",
              f"#define LSBUS_TX_TRIGGERED {int(spec['txClock'] == 'triggered')}   "
              "/* 1: Tx_Clock is an output triggered clock (read_spec) */", "", "#endif", ""]
    with open(out_h, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def _el(tag, attrs, tail="\n    "):
    e = ET.Element(tag, attrs)
    e.tail = tail
    return e


def extend_fmi3(md3, spec_path, xml_path, tree):
    """The terminal's variables into md3 (the FMI 3.0 <fmiModelDescription>), and the
    terminal and manifest files into the FMU tree."""
    spec = read_spec(spec_path)
    t = spec["terminal"]
    vr = bus_value_references(xml_path)
    cs = md3.find("CoSimulation")
    cs.set("hasEventMode", "true")                  # 2____common_concepts.adoc: networked FMUs
    cs.set("canHandleVariableCommunicationStepSize", "true")   # time-based Tx clocks
    cs.set("canGetAndSetFMUState", "false")
    cs.set("canSerializeFMUState", "false")
    mv = md3.find("ModelVariables")
    mv[-1].tail = "\n    "
    desc = {
        "Rx_Data": "the operations the bus hands this node (CAN Transmit of the other nodes' frames, "
                   "Confirm, ...), set while Rx_Clock is active",
        "Tx_Data": "the operations this node sends at each Tx_Clock tick: a Configuration (baud rate) before "
                   "the first frame, then one CAN Transmit per message (ssp/can/Bus36m.dbc's bytes, E2E CRC and "
                   "alive counter), a Format Error for a malformed operation received; size 0 when none",
        "Rx_Clock": "active when the bus has operations for this node (triggered)",
        "Tx_Clock": f"the node's send cycle, periodic every {spec['txInterval']:g} s (the DBC's "
                    "GenMsgCycleTime); the importer activates it"}
    triggered = spec["txClock"] == "triggered"
    if triggered:
        desc["Tx_Clock"] = (f"the node's send cycle, every {spec['txInterval']:g} s from the start (the DBC's "
                            "GenMsgCycleTime): a triggered output clock, active in the Event Mode at a tick, "
                            "which fmi3DoStep signals by eventHandlingNeeded (and fmi3UpdateDiscreteStates "
                            "announces as nextEventTime); read it with fmi3GetClock")
    mv.append(_el("Binary", {
        "name": f"{t}.Rx_Data", "valueReference": str(vr["Rx_Data"]), "description": desc["Rx_Data"],
        "causality": "input", "variability": "discrete", "mimeType": MIME, "maxSize": str(MAX_SIZE),
        "clocks": str(vr["Rx_Clock"])}))
    mv[-1].text = "\n      "
    mv[-1].append(_el("Start", {"value": ""}, "\n    "))
    mv.append(_el("Binary", {
        "name": f"{t}.Tx_Data", "valueReference": str(vr["Tx_Data"]), "description": desc["Tx_Data"],
        "causality": "output", "variability": "discrete", "initial": "calculated", "mimeType": MIME,
        "maxSize": str(MAX_SIZE), "clocks": str(vr["Tx_Clock"])}))
    mv.append(_el("Clock", {
        "name": f"{t}.Rx_Clock", "valueReference": str(vr["Rx_Clock"]), "description": desc["Rx_Clock"],
        "causality": "input", "variability": "discrete", "intervalVariability": "triggered"}))
    # fmi-ls-bus 1.0, 4____network_abstraction.adoc, "Time-based Tx Clocks" / "Triggered Tx Clocks"
    tx = ({"causality": "output", "variability": "discrete", "intervalVariability": "triggered"} if triggered else
          {"causality": "input", "variability": "discrete", "intervalVariability": "constant",
           "intervalDecimal": repr(spec["txInterval"])})
    mv.append(_el("Clock", {"name": f"{t}.Tx_Clock", "valueReference": str(vr["Tx_Clock"]),
                            "description": desc["Tx_Clock"], **tx}, "\n  "))
    ms = md3.find("ModelStructure")
    first_other = next((i for i, e in enumerate(ms) if e.tag != "Output"), len(ms))
    out = _el("Output", {"valueReference": str(vr["Tx_Data"]), "dependencies": str(vr["Rx_Data"])})
    ms.insert(first_other, out)
    if triggered:     # FMI 3.0.2, 2.4.8 <Output>: every output, output clocks too; its activation: time only
        ms.insert(first_other + 1, _el("Output", {"valueReference": str(vr["Tx_Clock"]), "dependencies": ""}))
    ms[-1].tail = "\n  "

    ti = ET.Element("fmiTerminalsAndIcons", {"fmiVersion": "3.0"})
    terms = ET.SubElement(ti, "Terminals")
    term = ET.SubElement(terms, "Terminal", {
        "name": t, "terminalKind": "org.fmi-ls-bus.network-terminal",
        "matchingRule": "org.fmi-ls-bus.transceiver",
        "description": f"the CAN bus terminal of {spec['name']} (FMI-LS-BUS 1.0 CAN, Low-Cut)"})
    for m in MEMBERS:
        ET.SubElement(term, "TerminalMemberVariable", {"variableName": f"{t}.{m}", "memberName": m,
                                                       "variableKind": "signal"})
    conf = ET.SubElement(term, "Terminal", {"name": "Configuration",
                                            "terminalKind": "org.fmi-ls-bus.network-terminal.configuration",
                                            "matchingRule": "bus"})
    ET.SubElement(conf, "TerminalMemberVariable", {"variableName": f"{t}.BusNotifications",
                                                   "memberName": "BusNotifications", "variableKind": "signal"})
    ET.indent(ti, "  ")
    d = os.path.join(tree, "terminalsAndIcons")
    os.makedirs(d, exist_ok=True)
    ET.ElementTree(ti).write(os.path.join(d, "terminalsAndIcons.xml"), encoding="UTF-8", xml_declaration=True)

    ns = "http://fmi-standard.org/fmi-ls-manifest"
    ET.register_namespace("fmi-ls", ns)
    man = ET.Element("fmiLayeredStandardManifest", {
        f"{{{ns}}}fmi-ls-name": "org.fmi-standard.fmi-ls-bus", f"{{{ns}}}fmi-ls-version": "1.0.0",
        f"{{{ns}}}fmi-ls-description": MANIFEST_DESCRIPTION, "isBusSimulationFMU": "false"})
    d = os.path.join(tree, "extra", "org.fmi-standard.fmi-ls-bus")
    os.makedirs(d, exist_ok=True)
    ET.ElementTree(man).write(os.path.join(d, "fmi-ls-manifest.xml"), encoding="UTF-8", xml_declaration=True)


def main(argv):
    """lsbus_node.py SPEC MODEL_DESCRIPTION_DIR OUT_XML OUT_HEADER"""
    if len(argv) != 4:
        sys.exit("usage: lsbus_node.py SPEC MODEL_DESCRIPTION_DIR OUT_XML OUT_HEADER")
    spec, md_dir, out_xml, out_h = argv
    try:
        os.makedirs(os.path.dirname(out_xml) or ".", exist_ok=True)
        os.makedirs(os.path.dirname(out_h) or ".", exist_ok=True)
        derive(spec, md_dir, out_xml)
        write_header(spec, out_xml, out_h)
    except (NodeError, ET.ParseError, gen_vars.ModelDescriptionError) as e:
        sys.exit(f"lsbus_node.py: {e}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
