"""What of a bench our runner does not apply, and what of it is artibus's own.

SSP 1.0 lets a tool ignore what it does not implement; a user of our benches
must be told. ``not_applied(ssp)``: every element, attribute or annotation of
the bench's .ssd and of the parameter files and mappings it binds that the
runner does not apply, each once, naming the file, the line and the element
(the runner prints them as warnings: ``warn``). ``artibus_specific(ssp)``: what
the bench uses that only artibus reads (multi-rate steps, variants, rebinds,
CAN routes), each with what another SSP master does instead (``artibus check
BENCH`` lists both).

Geometry and meta-data (ElementGeometry, ConnectorGeometry, SystemGeometry,
GraphicalElements, descriptions, ids, authors) have no effect on a run and are
accepted without a word.
"""
import sys
import zipfile
from dataclasses import dataclass

from lxml import etree

from artibus.bench.ssp import ANNOTATION, CAN_ANNOTATION, NS, OSP_TYPE, REBIND, VARIANT_DIR, origin, variants

META = {"id", "description", "author", "fileversion", "copyright", "license", "generationTool",
        "generationDateAndTime", "version", "name"}
#: elements with no effect on a run (drawn, not simulated)
GEOMETRY = {"ElementGeometry", "ConnectorGeometry", "SystemGeometry", "ConnectionGeometry", "GraphicalElements"}
#: what the runner applies: element (local name) -> its attributes it applies (META aside)
APPLIED = {
    "SystemStructureDescription": set(), "System": set(), "Elements": set(), "Connectors": set(),
    "Connector": {"kind"}, "Component": {"source", "type", "implementation"},
    "ParameterBindings": set(), "ParameterBinding": {"source", "type", "prefix", "sourceBase"},
    "ParameterValues": set(), "ParameterMapping": {"source", "type"},
    "Connections": set(), "Connection": {"startElement", "startConnector", "endElement", "endConnector",
                                         "suppressUnitConversion", "startIndices",
                                         "endIndices"},     # (the latter refused by name: ssp._indices)
    "Annotations": set(), "Annotation": {"type"}, "DefaultExperiment": {"startTime", "stopTime"},
    "Units": set(), "Unit": set(), "BaseUnit": {"kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor", "offset"},
    "Enumerations": set(), "Enumeration": {"value"}, "Item": {"value"},
    "Real": {"unit", "value"}, "Integer": {"value"}, "Boolean": {"value"}, "String": {"value"},
    # SSP 2.0 (artibus.bench.ssp2): an FMI-LS-BUS network's connectors, run by artibus.runner.lsbus_bench
    "Float64": {"unit", "value"}, "Binary": {"mime-type"}, "Clock": {"intervalVariability", "intervalDecimal", "name"},
    "LinearTransformation": {"factor", "offset"}, "BooleanMappingTransformation": set(),
    "IntegerMappingTransformation": set(), "EnumerationMappingTransformation": set(),
    "MapEntry": {"source", "target"},
    "ParameterSet": set(), "Parameters": set(), "Parameter": set(),
    "MappingEntry": {"source", "target", "suppressUnitConversion"},
}
#: annotation types artibus reads (the others' content is not applied)
ANNOTATIONS = {ANNOTATION: "per-component communication steps",
               CAN_ANNOTATION: "connections routed over CAN",
               "org.artibus.variant": "a variant's stop time",
               "org.artibus.source": "where a value is from (documentation)",
               # (a component's osp:StepSizeHint where ours gives no step; the DefaultExperiment's
               # osp:FixedStepAlgorithm baseStepSize is the shortest of them, the base step the runner takes)
               OSP_TYPE: "the Open Simulation Platform's step-size hints"}
#: attribute values the runner does not implement: (element, attribute) -> {value: why}, or a
#: function of the value giving why (None: applied)
UNSUPPORTED_VALUES = {
    ("ParameterBinding", "sourceBase"): lambda v: None if v == "SSD" else
    "a parameter source inside the component's FMU is not read",
    ("ParameterMapping", "sourceBase"): lambda v: None if v == "SSD" else
    "a parameter mapping inside the component's FMU is not read",
    ("Component", "type"): lambda v: None if v == "application/x-fmu-sharedlibrary" else
    "only FMUs (application/x-fmu-sharedlibrary) are run",
    ("Connection", "suppressUnitConversion"): lambda v: None if v in ("false", "0") else
    "the runner converts connected values between the connectors' units all the same",
    ("ParameterBinding", "type"): lambda v: None if v == "application/x-ssp-parameter-set" else
    "only SSP parameter sets (application/x-ssp-parameter-set) are read",
}


@dataclass(frozen=True)
class Notice:
    file: str
    line: int
    element: str
    what: str

    def text(self):
        return f"{self.file}:{self.line}: <{self.element}>: {self.what}"


def _scan(root, file, out):
    for el in root.iter(tag=etree.Element):
        name = etree.QName(el).localname
        parent = el.getparent()
        if any(etree.QName(a).localname in GEOMETRY for a in el.iterancestors()) or name in GEOMETRY:
            continue
        if parent is not None and etree.QName(parent).localname == "Annotation":
            continue                     # an annotation's content: its type says whether it is read
        if any(etree.QName(a).localname == "Annotation" for a in el.iterancestors()):
            continue
        if name == "Annotation":
            t = el.get("type")
            if t not in ANNOTATIONS:
                out.append(Notice(file, el.sourceline, f'Annotation type="{t}"',
                                  "an annotation type the runner does not read: its content is not applied"))
            continue
        if name not in APPLIED:
            out.append(Notice(file, el.sourceline, name, f"the runner does not implement <{name}>: not applied"))
            continue
        for attr, value in el.attrib.items():
            a = etree.QName(attr).localname
            if attr.startswith("{") or a in META:
                continue
            if a not in APPLIED[name]:
                out.append(Notice(file, el.sourceline, f'{name} {a}="{value}"',
                                  f"the runner does not implement the attribute {a}: not applied"))
                continue
            check = UNSUPPORTED_VALUES.get((name, a))
            why = check(value) if check else None
            if why:
                out.append(Notice(file, el.sourceline, f'{name} {a}="{value}"', f"{why}: not applied"))


def not_applied(ssp):
    """[Notice] of what the bench (an .ssp) holds that the runner does not
    apply: in its SystemStructure.ssd and in each parameter file (.ssv) and
    mapping (.ssm) it binds, and its variants."""
    ssp = str(ssp)
    out = []
    with zipfile.ZipFile(ssp) as z:
        names = z.namelist()
        root = etree.fromstring(z.read("SystemStructure.ssd"))
        _scan(root, origin(ssp), out)
        refs = [el.get("source") for el in root.iter(tag=etree.Element)
                if etree.QName(el).localname in ("ParameterBinding", "ParameterMapping") and el.get("source")]
        refs += [n for n in names if n.startswith(f"{VARIANT_DIR}/") and n.endswith(".ssv")]
        for ref in dict.fromkeys(refs):
            if ref in names:
                _scan(etree.fromstring(z.read(ref)), f"{ssp}/{ref}", out)
    return list(dict.fromkeys(out))


_WARNED = set()


def warn(ssp, stream=None):
    """Print each of ``not_applied(ssp)`` as a warning, once a process."""
    from pathlib import Path
    st = Path(ssp).stat()
    seen = (str(ssp), st.st_mtime_ns, st.st_size)
    if seen in _WARNED:
        return                           # this pack, scanned already
    _WARNED.add(seen)
    for n in not_applied(ssp):
        key = (str(ssp), n)
        if key in _WARNED:
            continue
        _WARNED.add(key)
        print(f"warning: {n.text()}", file=stream or sys.stderr)


def artibus_specific(ssp, bench=None):
    """[(what, what another SSP master does instead)] of the artibus-specific
    features the bench (an .ssp) uses: the per-component communication steps
    of the org.artibus.simulation annotation (multi-rate), the variants, the
    rebinds in them, the CAN routes."""
    from artibus.bench import ssp as ssp_mod
    bench = bench or ssp_mod.read(ssp)
    out = []
    steps = {}
    for p, c in bench.components.items():     # the annotation's step, else the FMU's default experiment's
        de = ssp_mod.model_description(ssp, c.source).defaultExperiment
        h = c.step or (float(de.stepSize) if de is not None and de.stepSize else None)
        if h is not None:
            steps[p] = h
    if len(set(steps.values())) > 1:
        h = min(steps.values())
        rates = ", ".join(f"{p} {s:g} s" for p, s in steps.items())
        out.append((f"multi-rate steps (org.artibus.simulation stepSize, else the FMU's default experiment): {rates}",
                    f"libcosim and ecos step each component at the osp:StepSizeHint of the bench's portable pack "
                    f"(`artibus pack --portable`; measured: libcosim gives our --algorithm jacobi run, ecos our "
                    f"Gauss-Seidel run where our order is its order, the components' names'); fmpy.ssp steps every "
                    f"component at its one step, e.g. {h:g} s: the slower components then step "
                    f"{max(steps.values()) / h:g} times as often (`artibus run BENCH --single-rate` runs it so; "
                    f"the bench's report page gives the KPI deviation)"))
    elif steps:
        out.append((f"communication step (org.artibus.simulation stepSize): {min(steps.values()):g} s",
                    "takes its own step size: give it this one"))
    names = variants(ssp)
    if names:
        out.append((f"variants ({VARIANT_DIR}/ in the .ssp, not referenced by the .ssd): {', '.join(names)}",
                    "runs the bench's own bindings only, i.e. none of the variants: a variant's values must "
                    "be made the bench's own bindings for it"))
    with zipfile.ZipFile(ssp) as z:
        for n in names:
            for r in etree.fromstring(z.read(f"{VARIANT_DIR}/{n}.ssv")).iterfind(f".//artibus:{REBIND}", NS):
                out.append((f"variant {n} rebinds {r.get('from')} to {r.get('to')}",
                            "binds the parameter set the .ssd names"))
    if bench.read_as == "2.0":      # (version="2.0" on SSP 1.0 content is read as SSP 1.0: artibus.bench.versions.ssd_version)
        out.append(("an SSP 2.0 system structure (its FMI-LS-BUS network: ssc:Binary and ssc:Clock connectors, "
                    "artibus.bench.ssp2)", "reads SSP 1.0 only (ecos, libcosim, fmpy.ssp): not this bench; an "
                    "SSP 2.0 master with FMI 3.0 clocks and Event Mode runs its network"))
    if bench.can is not None or any(c.can for c in bench.connections):
        routed = sum(1 for c in bench.connections if c.can)
        out.append((f"{routed} connections routed over CAN (org.artibus.can, {bench.can and bench.can.get('source')})",
                    "passes them directly, without the bus's quantisation, period and delays"))
    return out
