"""The FMI 3.0 model description of an FMU, written from the same declarations as its
FMI 2.0 one (modelDescription/<Name>.xml, as src/fmi/package_fmu.py has completed it:
metadata, display units). Called by package_fmu.py --fmi 3; the FMI 3.0 build's C table
(gen_vars.py --fmi 3) has the same value references (gen_vars.fmi3_value_references).

What changes from FMI 2.0 to FMI 3.0 (FMI 3.0, 2.4):

- ``guid`` becomes ``instantiationToken``; ``numberOfEventIndicators`` goes (the event
  indicators are variables, listed in <ModelStructure><EventIndicator>);
- <ModelExchange>/<CoSimulation>: ``canGetAndSetFMUState``, ``canSerializeFMUState``,
  ``providesDirectionalDerivatives`` and ``providesAdjointDerivatives`` both as FMI 2.0's
  ``providesDirectionalDerivative`` (stated also where false, the default; a model with
  the hook model_directional_derivative serves both, fmu_core.c),
  ``needsCompletedIntegratorStep="false"``; Co-Simulation ``hasEventMode="true"`` (the FMU
  has nothing to do in Event Mode, it handles its events inside the step, so an importer
  may use either), ``canHandleVariableCommunicationStepSize`` as in FMI 2.0; no
  <SourceFiles> (FMI 3.0 describes sources in sources/buildDescription.xml);
- each <ScalarVariable> with its type child becomes one typed element (Real: Float64,
  Integer: Int32, Boolean, String with a <Start> child, Enumeration), the type's attributes
  on it, ``derivative=`` a value reference instead of an index; its value reference is the
  FMI 3.0 one (one space across types);
- the independent variable ``time`` is declared (FMI 3.0 wants one), and a Model Exchange
  model's event indicators as local Float64 ``eventIndicator[i]``;
- <TypeDefinitions>: <SimpleType><Enumeration> becomes <EnumerationType>, the others
  <Float64Type>, <Int32Type>, ...;
- <ModelStructure>: <Output>, <ContinuousStateDerivative>, <InitialUnknown>,
  <EventIndicator>, each by value reference, the dependencies as value references.

Only the Python standard library is used: this runs inside the CMake build.
"""

import copy
import xml.etree.ElementTree as ET

import gen_vars

TYPE = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String",
        "Enumeration": "Enumeration"}
#: attributes of an FMI 2.0 ScalarVariable that FMI 3.0 keeps on the variable
VAR_ATTRS = ("name", "valueReference", "description", "causality", "variability", "initial",
             "canHandleMultipleSetPerTimeInstant")
#: attributes of the FMI 2.0 type element that FMI 3.0 keeps on the variable
TYPE_ATTRS = ("declaredType", "quantity", "unit", "displayUnit", "relativeQuantity", "min", "max",
              "nominal", "unbounded", "start", "reinit")
ROOT_ATTRS = ("modelName", "description", "author", "version", "copyright", "license",
              "generationTool", "generationDateAndTime", "variableNamingConvention")


def _element(tag, attrs, tail="\n    "):
    e = ET.Element(tag, {k: v for k, v in attrs.items() if v is not None})
    e.tail = tail
    return e


def _interfaces(md2, md3):
    me = md2.find("ModelExchange")
    if me is not None:
        attrs = {"modelIdentifier": me.get("modelIdentifier"),
                 "needsCompletedIntegratorStep":
                     "false" if me.get("completedIntegratorStepNotNeeded") == "true" else "true",
                 "canGetAndSetFMUState": me.get("canGetAndSetFMUstate", "false"),
                 "canSerializeFMUState": me.get("canSerializeFMUstate", "false"),
                 "providesDirectionalDerivatives": me.get("providesDirectionalDerivative", "false"),
                 "providesAdjointDerivatives": me.get("providesDirectionalDerivative", "false")}
        md3.append(_element("ModelExchange", attrs, "\n  "))
    cs = md2.find("CoSimulation")
    attrs = {"modelIdentifier": cs.get("modelIdentifier"),
             "canGetAndSetFMUState": cs.get("canGetAndSetFMUstate", "false"),
             "canSerializeFMUState": cs.get("canSerializeFMUstate", "false"),
             "providesDirectionalDerivatives": cs.get("providesDirectionalDerivative", "false"),
             "providesAdjointDerivatives": cs.get("providesDirectionalDerivative", "false"),
             "canHandleVariableCommunicationStepSize": cs.get("canHandleVariableCommunicationStepSize",
                                                               "false"),
             "hasEventMode": "true"}
    md3.append(_element("CoSimulation", attrs, "\n  "))


def _type_definitions(td2):
    td3 = ET.Element("TypeDefinitions")
    td3.text, td3.tail = "\n    ", "\n  "
    for st in td2.findall("SimpleType"):
        t = next(c for c in st if isinstance(c.tag, str))
        attrs = {"name": st.get("name"), "description": st.get("description")}
        if t.tag == "Enumeration":
            e = _element("EnumerationType", dict(attrs, quantity=t.get("quantity")))
            e.text = "\n      "
            items = t.findall("Item")
            for i, item in enumerate(items):
                e.append(_element("Item", dict(item.attrib),
                                  "\n      " if i + 1 < len(items) else "\n    "))
        else:
            e = _element(TYPE[t.tag] + "Type", dict(attrs, **{k: v for k, v in t.attrib.items()}))
        td3.append(e)
    if len(td3):
        td3[-1].tail = "\n  "
    return td3


def _variables(md2, model, refs, has_seconds):
    svs = md2.find("ModelVariables").findall("ScalarVariable")
    vr_of_index = {i + 1: refs["vars"][i] for i in range(len(svs))}
    mv = ET.Element("ModelVariables")
    mv.text, mv.tail = "\n    ", "\n  "
    mv.append(_element("Float64", {
        "name": "time", "valueReference": str(refs["time"]), "causality": "independent",
        "variability": "continuous", "description": "simulation time [s]",
        "unit": "s" if has_seconds else None}))
    for i, sv in enumerate(svs):
        t = next(c for c in sv if isinstance(c.tag, str))
        attrs = {k: sv.get(k) for k in VAR_ATTRS}
        attrs["valueReference"] = str(refs["vars"][i])
        for k in TYPE_ATTRS:
            if t.get(k) is not None and not (k == "start" and t.tag == "String"):
                attrs[k] = t.get(k)
        if t.get("derivative") is not None:
            attrs["derivative"] = str(vr_of_index[int(t.get("derivative"))])
        e = _element(TYPE[t.tag], attrs)
        if t.tag == "String" and t.get("start") is not None:
            e.text = "\n      "
            e.append(_element("Start", {"value": t.get("start")}, "\n    "))
        mv.append(e)
    for k, vr in enumerate(refs["z"], start=1):
        mv.append(_element("Float64", {
            "name": f"eventIndicator[{k}]", "valueReference": str(vr), "causality": "local",
            "variability": "continuous",
            "description": f"event indicator {k} of {model['identifier']}'s Model Exchange "
                           f"interface (a state event where it changes sign; FMI 2.0: "
                           f"fmi2GetEventIndicators z[{k - 1}]) [1]"}))
    mv[-1].tail = "\n  "
    return mv, vr_of_index


def _structure(md2, refs, vr_of_index):
    ms2 = md2.find("ModelStructure")
    ms3 = ET.Element("ModelStructure")
    ms3.text, ms3.tail = "\n    ", "\n"

    def unknowns(section, tag):
        el = ms2.find(section) if ms2 is not None else None
        for u in ([] if el is None else el.findall("Unknown")):
            attrs = {"valueReference": str(vr_of_index[int(u.get("index"))])}
            deps = u.get("dependencies")
            if deps is not None:
                attrs["dependencies"] = " ".join(str(vr_of_index[int(d)]) for d in deps.split())
            if u.get("dependenciesKind") is not None:
                attrs["dependenciesKind"] = u.get("dependenciesKind")
            ms3.append(_element(tag, attrs))

    unknowns("Outputs", "Output")
    unknowns("Derivatives", "ContinuousStateDerivative")
    unknowns("InitialUnknowns", "InitialUnknown")
    for vr in refs["z"]:
        ms3.append(_element("EventIndicator", {"valueReference": str(vr)}))
    if len(ms3):
        ms3[-1].tail = "\n  "
    return ms3


def fmi3_model_description(md2, xml_path):
    """The FMI 3.0 <fmiModelDescription> (an Element) from the completed FMI 2.0 one md2
    of modelDescription/<Name>.xml (xml_path: read again by gen_vars for the value
    references, so the table and the description cannot differ)."""
    model = gen_vars.read(xml_path)
    refs = gen_vars.fmi3_value_references(model)
    md3 = ET.Element("fmiModelDescription", {"fmiVersion": "3.0"})
    for k in ROOT_ATTRS:
        if md2.get(k) is not None:
            md3.set(k, md2.get(k))
            if k == "modelName":
                md3.set("instantiationToken", md2.get("guid"))
    md3.text = "\n  "
    _interfaces(md2, md3)
    units = md2.find("UnitDefinitions")
    if units is not None:
        u = copy.deepcopy(units)
        u.tail = "\n  "
        md3.append(u)
    td = md2.find("TypeDefinitions")
    if td is not None:
        md3.append(_type_definitions(td))
    for tag in ("LogCategories", "DefaultExperiment"):
        el = md2.find(tag)
        if el is not None:
            el = copy.deepcopy(el)
            el.tail = "\n  "
            md3.append(el)
    has_seconds = units is not None and any(x.get("name") == "s" for x in units.findall("Unit"))
    mv, vr_of_index = _variables(md2, model, refs, has_seconds)
    md3.append(mv)
    md3.append(_structure(md2, refs, vr_of_index))
    return md3
