"""Portable packs: a bench as other SSP masters run it (``artibus pack --portable``).

Our runner applies everything SSP 1.0 lets a bench say about its parameters:
several bindings per component, .ssv files, parameter mappings (.ssm, with
their transformations), system-level bindings, and our variants. Other masters
apply less: ecos applies one named parameter set (``init(parameter_set=...)``),
libcosim the first (or one named) parameter set of each component, and FMPy's
``simulate_ssp`` none. A portable pack gives every master the same bench: each
component carries every parameter as one inline parameter set named
``PARAMETER_SET``, the values as our runner resolves them (the bench's
bindings, its .ssv files and mappings, system-level bindings, and the chosen
variants, later ones winning), typed as the FMU declares the variable, in the
FMU variable's own unit. The components, connectors, connections (with their
transformations), units and annotations are those of the bench; the .ssv and
.ssm files and variants/ are left out (resolved); the FMUs and every other
resource stay, but a file a String parameter names goes into the FMU that reads
it, the value its bare name (_files_into_fmus). Each component's communication step is written where the Open
Simulation Platform's libcosim reads it (an ``osp:StepSizeHint`` annotation,
and the base step as the DefaultExperiment's ``osp:FixedStepAlgorithm``),
besides our own annotation. The pack is validated against the SSP 1.0 XSDs
(FMPy's reader) before it is handed out.
"""
import math
import zipfile
from pathlib import Path

from lxml import etree

from artibus.base import ArtibusError, fmu_dir
from artibus.bench import ssp as ssp_mod
from artibus.bench.ssp import NS

#: the one parameter set of each component (ecos: ``EcosSimulation.init(parameter_set=PARAMETER_SET)``);
#: the name our benches' inline sets carry already
PARAMETER_SET = "bench"
#: the Open Simulation Platform's annotations (libcosim's SSP parser)
OSP_TYPE = "com.opensimulationplatform"
OSP_NS = "http://opensimulationplatform.com/SSP/OSPAnnotations"
SSD, SSC, SSV = NS["ssd"], NS["ssc"], NS["ssv"]


def portable_path(bench, variants=None, out_dir=None):
    """fmus/<Bench>.portable.ssp, or <Bench>_<variant>....portable.ssp with variants."""
    stem = Path(str(bench)).stem if str(bench).endswith(".ssp") else str(bench)
    name = "_".join([stem] + list(variants or [])) + ".portable.ssp"
    return Path(out_dir or fmu_dir()) / name


def _text(value, v):
    """(SSV element name, value attribute) of a parameter value for the FMU variable v
    (fmpy's ScalarVariable; None: typed by the Python value)."""
    t = v.kind if v is not None else ("Boolean" if isinstance(value, bool) else "Integer" if isinstance(value, int)
                                      else "Real" if isinstance(value, float) else "String")
    if t == "Real":
        return "Real", repr(float(value))
    if t == "Integer":
        return "Integer", str(int(value))
    if t == "Boolean":
        b = value if isinstance(value, bool) else str(value).strip() in ("true", "1")
        return "Boolean", "true" if b else "false"
    if t == "Enumeration":                       # the item's value: see integer_view
        byname = {i.name: int(i.value) for i in v.declaredType.items} if v.declaredType else {}
        return "Integer", str(byname.get(str(value), value))
    return "String", str(value)


def integer_view(fmu):
    """The FMI 2.0 FMU ``fmu`` (bytes) with each Enumeration variable declared as an Integer
    (bytes; the FMU itself where it has none): the same value reference, min and max its
    items' smallest and largest value, its description followed by the items. Only
    modelDescription.xml changes. The binary cannot tell: FMI 2.0 reads and writes an
    Enumeration with fmi2GetInteger/fmi2SetInteger, in the Integer value references (FMI
    2.0.4, 2.1.7 and 2.2.7), so every master sets the choice by its value. Why: neither
    libcosim (its FMU loader ignores FMI 2.0 Enumeration variables, with a warning) nor ecos
    (it sets no Integer parameter on an Enumeration) applies a parameter to an Enumeration,
    and none of the three other masters reads SSP 1.0's ssv:Enumeration (the item's name:
    ecos "Unknown XML node in ssv:Parameter", libcosim an internal error, FMPy's
    simulate_ssp converts the value with int())."""
    import io
    with zipfile.ZipFile(io.BytesIO(fmu)) as z:
        md = etree.fromstring(z.read("modelDescription.xml"))
        types = {st.get("name"): [(i.get("name"), int(i.get("value"))) for i in st.iter("Item")]
                 for st in md.iterfind("TypeDefinitions/SimpleType") if st.find("Enumeration") is not None}
        changed = False
        for sv in md.iterfind("ModelVariables/ScalarVariable"):
            en = sv.find("Enumeration")
            if en is None or en.get("declaredType") not in types:
                continue
            items = types[en.get("declaredType")]
            attrs = {"min": en.get("min", str(min(v for _, v in items))),
                     "max": en.get("max", str(max(v for _, v in items)))}
            if en.get("start") is not None:
                attrs["start"] = en.get("start")
            integer = etree.Element("Integer", attrs)
            integer.tail = en.tail
            sv.replace(en, integer)
            sv.set("description", f"{sv.get('description', '')}; an Integer here, the items of "
                   f"{en.get('declaredType')}: " + ", ".join(f"{v} = {n}" for n, v in items))
            changed = True
        if not changed:
            return fmu
        out = io.BytesIO()
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as o:
            for info in z.infolist():
                data = z.read(info)
                if info.filename == "modelDescription.xml":
                    data = etree.tostring(md, xml_declaration=True, encoding="UTF-8")
                o.writestr(info, data)
    return out.getvalue()


def _steps(bench, z):
    """{component path: its communication step} as our runner takes it without
    --step: our annotation, else its FMU's default experiment's stepSize."""
    import tempfile

    from fmpy import read_model_description

    from artibus.fmu.model import model_of
    steps, mds = {}, {}
    with tempfile.TemporaryDirectory(prefix="artibus-") as tmp:
        for path, c in bench.components.items():
            if c.source not in mds:
                f = Path(tmp) / Path(c.source).name
                f.write_bytes(z.read(c.source))
                mds[c.source] = model_of(read_model_description(str(f)))
            de = mds[c.source].defaultExperiment
            steps[path] = c.step or (float(de.stepSize) if de is not None and de.stepSize else None)
    return steps, mds


def pack_portable(bench, variants=None, out=None):
    """The bench (a name or an .ssp) with its variants resolved into a portable
    pack (see the module's docstring), written to ``out`` (default
    portable_path). Returns its path."""
    src = ssp_mod.ssp_path(bench)
    variants = list(variants or [])
    b = ssp_mod.read(src)
    with zipfile.ZipFile(src) as z:
        names = z.namelist()
        root = etree.fromstring(z.read("SystemStructure.ssd"))
        steps, mds = _steps(b, z)
        files = {n: z.read(n) for n in names
                 if n != "SystemStructure.ssd" and not n.endswith((".ssv", ".ssm"))
                 and not n.startswith(f"{ssp_mod.VARIANT_DIR}/")}
    files = {n: integer_view(data) if n.endswith(".fmu") else data for n, data in files.items()}
    where = f"{src}/SystemStructure.ssd"
    variables = {p: mds[c.source] for p, c in b.components.items()}
    values = _values(b, ssp_mod.variant_overrides(src, variants), variables, where)
    _portable_or_refused(b, where)
    _files_into_fmus(b, values, files)
    _rewrite_ssd(root, b, values, variables, steps, ssp_mod.variant_stop_time(src, variants))
    root.set("version", "1.0")          # what it holds (read_as): the other masters read SSP 1.0 only
    ssd = etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    out = _write(Path(out) if out is not None else portable_path(bench, variants), bench, ssd, files)
    _warn_measured(out, bench, variants)
    return out


def _warn_measured(out, bench, variants):
    """A warning for each master that runs this pack differently from our runner, with the measured
    difference (artibus.bench.masters.MEASURED): the pack is written, but nobody runs it silently wrong."""
    import sys
    from artibus.bench.masters import differences
    name = Path(str(bench)).stem if str(bench).endswith(".ssp") else str(bench)
    for d in differences(name, variants):
        print(f"warning: {out}: {d.text()} (measured; `artibus check {name}`)", file=sys.stderr)


def _values(bench, overrides, variables, where):
    """{component path: {variable: value}}: the values our runner resolves for each component
    (its bindings, files, mappings, system-level bindings), the variants' ``overrides`` on top
    (array names expanded: artibus.bench.names.expand_all)"""
    from artibus.bench.names import expand_all
    values = {p: dict(c.parameters) for p, c in bench.components.items()}

    def variables_of(full):
        comp = full.split("[", 1)[0].rpartition(".")[0]
        return (comp + ".", [v.name for v in variables[comp].modelVariables]) if comp in variables else None
    for full, value in expand_all(overrides, variables_of).items():
        comp, _, var = full.rpartition(".")
        if comp not in values:
            raise ArtibusError(f"--variant: parameter '{full}': no component '{comp}' in {where}")
        values[comp][var] = value
    return values


def _portable_or_refused(b, where):
    """an ArtibusError for a bench no other master runs: SSP 2.0 content (an FMI-LS-BUS network; by what
    the file holds, Bench.read_as: OMSimulator 3.x's version="2.0" on SSP 1.0 content is SSP 1.0), CAN routing"""
    if b.read_as != "1.0":
        raise ArtibusError(f"{where}: an SSP {b.read_as} system structure (an FMI-LS-BUS network, artibus.bench.ssp2): "
                           "the other masters (ecos, libcosim, fmpy.ssp) read SSP 1.0 only; a portable pack holds "
                           "SSP 1.0 benches")
    if any(c.can is not None for c in b.connections) or b.can is not None:
        raise ArtibusError(f"{where}: the bench routes connections over CAN (artibus.can, an annotation of "
                           f"ours): no other master runs that network; a portable pack holds CAN-free benches")


def _rewrite_ssd(root, b, values, variables, steps, stop):
    """The .ssd's tree made portable in place: system-level bindings out (read() gave their
    values to the components), each component's bindings replaced by its one inline set, the
    OSP step-size hints and base step, the variants' stop time, the prefixes other masters'
    readers expect declared once at the top (libcosim reads "ssd:", "ssv:" and "osp:" as written)"""
    for bindings in root.iterfind(".//ssd:System/ssd:ParameterBindings", NS):
        bindings.getparent().remove(bindings)

    def walk(system, prefix):
        for el in system.findall("ssd:Elements/*", NS):
            path = f"{prefix}.{el.get('name')}" if prefix else el.get("name")
            kind = etree.QName(el).localname
            if kind == "System":
                walk(el, path)
            elif kind == "Component" and path in b.components:
                _rewrite_component(el, values[path], variables[path], steps.get(path))
    walk(root.find("ssd:System", NS), "")

    known = [s for s in steps.values() if s]
    if known:
        base = min(known)
        de = root.find("ssd:DefaultExperiment", NS)
        if de is None:
            de = etree.SubElement(root, f"{{{SSD}}}DefaultExperiment")
        _osp_annotation(de, "Algorithm").append(etree.Element(f"{{{OSP_NS}}}FixedStepAlgorithm",
                                                               baseStepSize=repr(base)))
    if stop is not None:
        root.find("ssd:DefaultExperiment", NS).set("stopTime", repr(stop))
    etree.cleanup_namespaces(root, top_nsmap={"ssd": SSD, "ssc": SSC, "ssv": SSV, "osp": OSP_NS})
    etree.indent(root, space="  ")


def _write(out, bench, ssd, files):
    """The pack written to ``out`` (a temporary name, renamed), read back before it is handed out"""
    from artibus.files import atomic_path
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out, fsync=False) as tmp:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("SystemStructure.ssd", ssd)
            for n, data in sorted(files.items()):
                z.writestr(n, data)
        try:
            ssp_mod.read(tmp)          # valid against the SSP 1.0 XSDs, and readable as a bench
        except ArtibusError as e:
            raise ArtibusError(f"{out}: the portable pack of {bench} is not valid: {e}") from None
    return out


def _files_into_fmus(bench, values, files):
    """Each file a String parameter names in the pack ("resources/<file>": a road CSV, a DBC) moved
    into the FMU of the component that reads it, at resources/<file> inside that FMU, and the value
    made the bare <file>. Why: other masters hand the value to the FMU as written, and our FMUs
    read a relative file name in their own resources folder (FMI 2.0.4 2.3 and FMI 3.0 2.5 "FMU
    Distribution": its path given to fmi2Instantiate/fmi3Instantiate): "resources/<file>" was
    looked for in the FMU's resources/resources/ (issue 40: ecos ran Bus36m_Slalom with the
    Driver in its error state and the bus driving straight). Our runner finds the bare name the same way. ``values`` ({path:
    {var: value}}) and ``files`` ({member: bytes}) are changed in place."""
    extra, moved = {}, set()
    for path, vals in values.items():
        for var, value in vals.items():
            if isinstance(value, str) and value.startswith("resources/") and value in files \
                    and not value.endswith(".fmu"):
                bare = value[len("resources/"):]
                extra.setdefault(bench.components[path].source, {})[bare] = files[value]
                vals[var] = bare
                moved.add(value)
    for source, added in extra.items():
        files[source] = _with_resources(files[source], added)
    for ref in moved:
        del files[ref]


def _with_resources(fmu, added):
    """The FMU ``fmu`` (bytes) with {name: bytes} written as resources/<name> (in place of any
    file of that name there); every other entry as it was."""
    import io
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(fmu)) as z, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as o:
        for info in z.infolist():
            if info.filename not in {f"resources/{n}" for n in added}:
                o.writestr(info, z.read(info))
        for name, data in sorted(added.items()):
            o.writestr(f"resources/{name}", data)
    return out.getvalue()


def _rewrite_component(el, values, md, step):
    """One component: its ParameterBindings replaced by one binding with one inline
    set of ``values`` (each typed as md declares it), and the OSP step-size hint."""
    old = el.find("ssd:ParameterBindings", NS)
    at = list(el).index(old) if old is not None else None
    if old is not None:
        el.remove(old)
    if values:
        byname = {v.name: v for v in md.modelVariables}
        bindings = etree.Element(f"{{{SSD}}}ParameterBindings")
        pv = etree.SubElement(etree.SubElement(bindings, f"{{{SSD}}}ParameterBinding"), f"{{{SSD}}}ParameterValues")
        pset = etree.SubElement(pv, f"{{{SSV}}}ParameterSet", version="1.0", name=PARAMETER_SET)
        params = etree.SubElement(pset, f"{{{SSV}}}Parameters")
        for name, value in values.items():
            kind, text = _text(value, byname.get(name))
            if kind == "Real" and not math.isfinite(float(text)):
                raise ArtibusError(f"component '{el.get('name')}': parameter '{name}' = {text} is not finite")
            p = etree.SubElement(params, f"{{{SSV}}}Parameter", name=name)
            etree.SubElement(p, f"{{{SSV}}}{kind}", value=text)
        if at is None:    # after Connectors and ElementGeometry, before Annotations (SSP 1.0's order)
            ann = el.find("ssd:Annotations", NS)
            at = list(el).index(ann) if ann is not None else len(el)
        el.insert(at, bindings)
    if step:
        _osp_annotation(el, "StepSizeHint", value=repr(step))


def _osp_annotation(el, child, **attrs):
    """An osp:<child> inside an ssc:Annotation of type OSP_TYPE in el's ssd:Annotations
    (made where missing, last of el's children as SSP 1.0 orders them); returns the child."""
    anns = el.find("ssd:Annotations", NS)
    if anns is None:
        anns = etree.SubElement(el, f"{{{SSD}}}Annotations")
    ann = etree.SubElement(anns, f"{{{SSC}}}Annotation", type=OSP_TYPE)
    return etree.SubElement(ann, f"{{{OSP_NS}}}{child}", **attrs)
