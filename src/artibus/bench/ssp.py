"""SSP 1.0 benches: packing a bench folder into a self-contained .ssp, and
reading a .ssp into a flat list of components and resolved connections.

A bench lives in ``ssp/benches/<Bench>/SystemStructure.ssd``; its components
refer to ``resources/<Name>.fmu`` and its parameter bindings to
``resources/<Set>.ssv``. ``pack`` copies the FMUs from ``fmus/`` and the
parameter sets from ``ssp/parameters/`` into ``fmus/<Bench>.ssp``; a bench
run by name is packed again when any of those files is newer.

A bench's variants (e.g. the damping options of one bench, or its driving
cases) are parameter sets of that bench, not copies of its .ssd:
``ssp/benches/<Bench>/variants/<name>.ssv``, each parameter named
``Component.variable``. They are packed into the .ssp (``variants/``) and
selected by name (``artibus run BENCH --variant NAME``), applied after the
bench's own bindings and before the user's ``--ssv``/``--set``. A variant may
give its own stop time (``<Variant stopTime="42"/>`` in an
``org.artibus.variant`` annotation) and rebind a parameter set (``Rebind``).

Parameter bindings are applied as SSP 1.0 (5.3.5) says: on components and on
systems at every level (names hierarchical, ``prefix`` put in front before the
mapping, a system connector's value to the variables it is connected to), a
later binding over an earlier one, a higher level over a lower one; a Real
value with a unit is converted to the FMU variable's unit (artibus.bench.units);
every value is checked against its FMU and every input has one source, by the
rule of SSP 1.0 and 2.0 benches alike (artibus.bench.rules), so that `artibus
check` refuses what `artibus run` refuses.

Reading validates the .ssd against the SSP XSDs FMPy ships (an SSP 2.0 .ssd against the
SSP 2.0 XSDs, its FMI-LS-BUS network left out: artibus.bench.ssp2.read_ssd) and the parameter
files it binds (artibus.bench.versions.parameter_root), then reads that one lxml tree in small
steps (read, _Reading): systems, components, connectors, bindings, connections, units, each
record keeping its source line.
"""
import math
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from artibus.base import ROOT, ArtibusError, fmu_dir, parse_real
from artibus.bench.bindings import Pack, bound_values, parameter_root
from artibus.bench.fmi import build_of, fmi_choice, pack_file
from artibus.bench.ssp2 import clocked   # an FMI-LS-BUS component keeps its FMI 3.0 build
from artibus.bench.ssd import (MAPPINGS, NS, _component_sources, _compose, _depth,  # noqa: F401
                               _number, origin, _sources_inside_components, map_transformation,
                               model_description)
from artibus.bench.packs import pack_unpacked, write_pack
from artibus.bench.versions import ssd_version
from artibus.bench.rules import bind_component, one_source
from artibus.bench.units import declared_unit, fmu_units, ssp_units, to_unit

BENCH_DIR = ROOT / "ssp" / "benches"
#: a bench's variants: <bench folder>/variants/<name>.ssv, packed as variants/<name>.ssv
VARIANT_DIR = "variants"
#: in a variant: <Rebind from="resources/A.ssv" to="resources/B.ssv"/> binds B wherever the bench binds A
#: (with the same parameter mapping), e.g. another vehicle for the plant and its controller at once
REBIND = "Rebind"
#: annotation type holding artibus-specific simulation settings of a component
ANNOTATION = "org.artibus.simulation"
#: annotation type routing connections over CAN: on the System, <Can source="resources/X.dbc"
#: period="0.01"/>; on a Connection, <Route message="..." signal="..."/> (see artibus.can)
CAN_ANNOTATION = "org.artibus.can"
#: the Open Simulation Platform's annotations (libcosim's; our portable packs carry its step-size hints too)
OSP_TYPE, OSP_NS = "com.opensimulationplatform", "http://opensimulationplatform.com/SSP/OSPAnnotations"


def bench_names():
    return sorted(p.parent.name for p in BENCH_DIR.glob("*/SystemStructure.ssd"))


def ssp_path(bench, fmi=None):
    """A bench by name (``Urbino18_Circle``) or the path of an .ssp file. A
    bench of ssp/benches/ by name is ``<fmu_dir>/<bench>.ssp`` (with ``fmi``
    "3" every FMU's FMI 3.0 build: fmus/fmi3/<bench>.ssp, artibus.bench.fmi),
    packed again first when it is missing or older than any file it packs
    (its .ssd, the FMUs, parameter sets, roads), as make would: a rebuilt FMU
    or an edited parameter set is what runs, never a stale copy."""
    p, fmi = Path(bench), fmi_choice(fmi)
    if p.suffix.lower() == ".ssd" or p.is_dir():
        if fmi is not None:
            raise ArtibusError(f"--fmi {fmi}: {p} is an SSP of its own, run with the FMUs it names (--fmi "
                               f"picks the build of a bench of ssp/benches by name)")
        return pack_unpacked(p)
    if p.suffix == ".ssp":
        if not p.is_file():
            raise ArtibusError(f"{p}: no such file")
        if fmi is not None:
            raise ArtibusError(f"--fmi {fmi}: {p} is a pack, run with the FMUs inside it (--fmi picks the "
                               f"build of a bench of ssp/benches by name)")
        return p
    q = fmu_dir() / f"{bench}.ssp"
    if bench in bench_names():
        ssd_file, files = _sources(bench, fmi)
        q = pack_file(bench, fmi, files)
        packed = q.stat().st_mtime_ns if q.is_file() else None
        if packed is None or any(f.stat().st_mtime_ns > packed for f in (ssd_file, *files.values())):
            write_pack(q, ssd_file, files)
        return q
    # not a bench of ssp/benches: an error, also where a pack of that name is left in fmus/
    import difflib
    close = difflib.get_close_matches(str(bench), bench_names(), n=3, cutoff=0.6)
    # a variant typed as a bench of its own (Bus36m_Circle_GuidedForceMin: the variant
    # guidedForceMin of Bus36m_Circle), the case aside: the bench and the variant first
    as_variant = {f"{b}_{v}".lower(): f"{b} --variant {v}" for b in bench_names()
                  for v in sorted(f.stem for f in (BENCH_DIR / b / VARIANT_DIR).glob("*.ssv"))}
    near = difflib.get_close_matches(str(bench).lower(), as_variant, n=3, cutoff=0.8)
    close = [as_variant[k] for k in near] + close
    hint = f"; did you mean {' or '.join(close[:3])}?" if close else ""
    stale = (f"; {q} is a pack left from an earlier build (give its path to run it anyway)"
             if q.is_file() else "")
    raise ArtibusError(f"{bench}: no such bench{hint}{stale} (known: {', '.join(bench_names()) or 'none'})")


def _sources(bench, fmi=None):
    """The bench's SystemStructure.ssd and {name inside the .ssp: file} for
    every file it references: components' FMUs (with ``fmi`` their build of
    that FMI version, artibus.bench.fmi.build_of), parameter sets, and files
    named by String parameters whose value starts with "resources/" (found in
    the bench folder, fmus/, ssp/parameters/ or ssp/roads/)."""
    src = BENCH_DIR / bench
    ssd_file = src / "SystemStructure.ssd"
    tree = etree.parse(str(ssd_file))
    files = {}
    for el in tree.iter(tag=etree.Element):      # elements only: comments and PIs have no tag name
        ref = el.get("source")
        if ref is None and etree.QName(el).localname == "String":
            ref = el.get("value")     # a file a component reads, e.g. a road: see resolve_resources
        if ref is None or not ref.startswith("resources/"):
            continue
        name = ref[len("resources/"):]
        if fmi is not None and name.endswith(".fmu") and etree.QName(el).localname == "Component" and not clocked(el):
            files[ref] = build_of(ref, fmi, f"{ssd_file}:{el.sourceline}: <{etree.QName(el).localname}>")
            continue
        candidates = [src / ref, fmu_dir() / name, ROOT / "ssp" / "parameters" / name,
                      ROOT / "ssp" / "roads" / name, ROOT / "ssp" / "can" / name]
        found = next((c for c in candidates if c.is_file()), None)
        if found is None:
            hint = " (FMUs are built by the set-up command of the README)" if name.endswith(".fmu") else ""
            raise ArtibusError(f"{ssd_file}:{el.sourceline}: <{etree.QName(el).localname} "
                               f"source=\"{ref}\">: no such file (looked in "
                               f"{', '.join(str(c.parent) for c in candidates)}){hint}")
        files[ref] = found
    for v in sorted((src / VARIANT_DIR).glob("*.ssv")):
        files[f"{VARIANT_DIR}/{v.name}"] = v
        for rebind in etree.parse(str(v)).iterfind(f".//artibus:{REBIND}", NS):
            ref = rebind.get("to", "")
            found = next((c for c in (src / ref, ROOT / "ssp" / "parameters" / ref[len("resources/"):])
                          if ref.startswith("resources/") and c.is_file()), None)
            if found is None:
                raise ArtibusError(f"{v}:{rebind.sourceline}: <{REBIND} to=\"{ref}\">: no such parameter set "
                                   f"(resources/<name>.ssv, from the bench folder or ssp/parameters)")
            files[ref] = found
    return ssd_file, files


def variants(ssp):
    """The names of a packed bench's variants (see the module's docstring)."""
    with zipfile.ZipFile(ssp) as z:
        return sorted(Path(n).stem for n in z.namelist()
                      if n.startswith(f"{VARIANT_DIR}/") and n.endswith(".ssv"))


def variant_stop_time(ssp, names):
    """The stop time the last of the named variants gives (an
    ``org.artibus.variant`` annotation ``<Variant stopTime="..."/>``), or None."""
    stop = None
    if not names:
        return stop
    ssp = ssp_path(ssp)
    with zipfile.ZipFile(ssp) as z:
        for name in names:
            ref = f"{VARIANT_DIR}/{name}.ssv"
            if ref not in z.namelist():
                continue             # variant_overrides names the unknown variant
            for v in etree.fromstring(z.read(ref)).iterfind(".//artibus:Variant", NS):
                if v.get("stopTime") is not None:
                    try:
                        stop = parse_real(v.get("stopTime"))
                    except ValueError:
                        stop = math.nan
                    if not stop > 0:
                        raise ArtibusError(f"{ssp}/{ref}:{v.sourceline}: <Variant stopTime="
                                           f"\"{v.get('stopTime')}\">: must be a time > 0 s")
    return stop


def variant_overrides(ssp, names):
    """{"Component.variable": value} of the named variants of a bench (a
    name or an .ssp), later names winning; an unknown name is an error that
    lists the bench's variants."""
    from fmpy.ssp.ssd import read_ssv
    from artibus.bench.parameters import typed
    if not names:
        return {}
    ssp = ssp_path(ssp)
    known = variants(ssp)
    values, given = {}, {}
    for name in names:
        if name not in known:
            raise ArtibusError(f"--variant {name}: {ssp} has no such variant "
                               f"(known: {', '.join(known) or 'none'})")
        where = f"{ssp}/{VARIANT_DIR}/{name}.ssv"
        with zipfile.ZipFile(ssp) as z, tempfile.TemporaryDirectory(prefix="artibus-") as tmp:
            f = Path(tmp) / f"{name}.ssv"
            f.write_bytes(z.read(f"{VARIANT_DIR}/{name}.ssv"))
            try:
                parameter_root(f.read_bytes(), where, "ParameterSet")    # (version="2.0": see parameter_root)
                pset = read_ssv(str(f), validate=False)
            except ArtibusError as e:
                raise ArtibusError(f"{e} (not a valid SSP parameter-value file)") from None
            except Exception as e:
                raise ArtibusError(f"{where}: not a valid SSP parameter-value file: {e}") from None
        with zipfile.ZipFile(ssp) as z:
            rebinds = etree.fromstring(z.read(f"{VARIANT_DIR}/{name}.ssv")).findall(f".//artibus:{REBIND}", NS)
        for rebind in rebinds:
            values.update(_rebound(ssp, rebind.get("from", ""), rebind.get("to", ""), f"{where}:{rebind.sourceline}"))
        with zipfile.ZipFile(ssp) as z:
            defs = ssp_units(etree.fromstring(z.read(f"{VARIANT_DIR}/{name}.ssv")), where)
        for p in pset.parameters:
            if "." not in p.name:
                raise ArtibusError(f"{where}: parameter '{p.name}': a variant names "
                                   f"Component.variable")
            try:
                values[p.name] = typed(p.type, p.value)
            except ValueError:
                raise ArtibusError(f"{where}: parameter '{p.name}' = {p.value!r} is not a {p.type}") from None
            if p.type == "Real" and p.unit:
                given[p.name] = (p.unit, defs, where)
            else:
                given.pop(p.name, None)
    if given:      # a value with a unit: in the unit of the variable it sets
        sources = _component_sources(ssp)
        for full, (unit, defs, where) in given.items():
            comp, _, var = full.rpartition(".")
            if comp not in sources:
                continue                   # the runner names the unknown component
            md = model_description(ssp, sources[comp])
            v = next((v for v in md.modelVariables if v.name == var), None)
            if v is not None and v.kind == "Real":
                values[full] = to_unit(values[full], unit, defs, declared_unit(v), fmu_units(md),
                                       f"{where}: Parameter '{full}' = {values[full]!r} {unit}")
    return values


def pack(bench, out_dir=None, fmi=None):
    """ssp/benches/<bench>/ -> <fmu_dir>/<bench>.ssp with every file it references (_sources; fmi: see ssp_path)."""
    ssd_file, files = _sources(bench, fmi_choice(fmi))
    return write_pack(Path(out_dir) / f"{bench}.ssp" if out_dir else pack_file(bench, fmi_choice(fmi), files),
                       ssd_file, files)


def _rebound(ssp, old, new, where):
    """{"Component.variable": value} of every component that binds the
    parameter set ``old``, as they are when it binds ``new`` instead (through
    the same mapping): the bench read once more with that one change; only
    the values that change, so the variants named before or after it keep
    theirs."""
    with zipfile.ZipFile(ssp) as z:
        names = z.namelist()
        if new not in names:
            raise ArtibusError(f"{where}: <{REBIND} to=\"{new}\">: not in {ssp}")
        ssd = etree.fromstring(z.read("SystemStructure.ssd"))
        bindings = [b for b in ssd.iterfind(".//ssd:ParameterBinding", NS) if b.get("source") == old]
        if not bindings:
            raise ArtibusError(f"{where}: <{REBIND} from=\"{old}\">: the bench binds no such parameter set")
        for b in bindings:
            b.set("source", new)
        with tempfile.TemporaryDirectory(prefix="artibus-") as tmp:
            copy = Path(tmp) / Path(ssp).name
            with zipfile.ZipFile(copy, "w") as out:
                for n in names:
                    out.writestr(n, etree.tostring(ssd) if n == "SystemStructure.ssd" else z.read(n))
            bench = read(copy)
    paths = list(bench.components)                # every component: system-level bindings too
    before = read(ssp)
    return {f"{path}.{k}": v for path in paths for k, v in bench.components[path].parameters.items()
            if before.components[path].parameters.get(k) != v}     # what the other set changes, only


@dataclass
class Component:
    path: str                      # e.g. "Bus" or "Sub.Bus"
    source: str                    # resources/X.fmu inside the .ssp
    line: int                      # line in SystemStructure.ssd
    step: float | None = None      # communication step from our annotation
    parameters: dict = field(default_factory=dict)  # name -> value from bindings
    origins: dict = field(default_factory=dict)     # name -> the file (and mapping) its value is from
    outputs: list = field(default_factory=list)     # names of its declared output connectors
    connectors: list = field(default_factory=list)  # names of all its declared connectors
    converted: dict = field(default_factory=dict)   # name -> (value, its unit, converted, the FMU's unit)


@dataclass
class Connection:
    start: tuple                   # (component path, variable name)
    end: tuple
    factor: float = 1.0
    offset: float = 0.0
    line: int = 0
    can: dict | None = None        # routed over CAN: {"message", "signal", "line"}
    mapping: tuple | None = None   # SSP 1.0 Boolean/Integer/EnumerationMappingTransformation:
                                   # ("Boolean" | "Integer" | "Enumeration", {source: target})
    indices: tuple = (None, None)  # SSP 2.0 startIndices, endIndices as written (artibus.runner.setup)


@dataclass
class Bench:
    name: str
    file: str
    components: dict               # path -> Component
    connections: list              # Connection, component to component
    start_time: float = 0.0
    stop_time: float | None = None
    can: dict | None = None        # the CAN network: {"source" (DBC in the .ssp), "period", "line"}
    version: str = "1.0"           # the .ssd's SSP version: "2.0" may hold an FMI-LS-BUS network (ssp2)
    read_as: str = "1.0"           # the version of its content: "1.0" for version="2.0" on SSP 1.0 content (versions.ssd_version)
    units: dict = field(default_factory=dict)   # unit -> its UnitDef (None: unknown), of the values with one
    system_values: dict = field(default_factory=dict)   # "Sub.connector" -> the value bound to a system
                                                        # connector connected to no FMU variable (SSP 1.0 5.3.5)


def read(ssp):
    """A .ssp as components (with their bound parameters) and connections
    resolved through nested systems to component variables: the archive
    checked, the .ssd validated and read as one lxml tree (_Reading's steps:
    systems, components, connections, system bindings), each component's
    values bound and each input's source checked (artibus.bench.rules)."""
    ssp = str(ssp)
    where = origin(ssp)
    root, names = _open(ssp, where)
    bench = Bench(name=root.get("name"), file=where, components={}, connections=[], version=root.get("version"),
                  read_as=ssd_version(ssp, where))
    _experiment(bench, root, where)
    bench.can = _can(root)
    r = _Reading(Pack(ssp, where, ssp_units(root, where)), names, bench, _systems(root.find("ssd:System", NS)))
    r.walk("")
    r.collect_edges()
    r.connect()
    r.system_bindings(r.xml_systems[""].get("name"))
    for path, c in bench.components.items():
        bind_component(ssp, c, r.given_units[path], bench.units)
    one_source((".".join(c.start), ".".join(c.end),
                f"{where}:{c.line}: Connection {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}")
               for c in bench.connections)
    return bench


def _open(ssp, where):
    """(the .ssd's validated lxml root, the .ssp's member names): the archive's members checked
    before any is read (a second .ssd, a link); SSP 1.0, or 2.0 without its FMI-LS-BUS
    network (artibus.bench.ssp2.read_ssd)."""
    from artibus.bench.ssp2 import read_ssd
    from artibus.files import check_archive
    try:
        with zipfile.ZipFile(ssp) as z:
            check_archive(z, ssp)
            if "SystemStructure.ssd" not in z.namelist():
                raise ArtibusError(f"{ssp}: no SystemStructure.ssd in it (not an SSP archive)")
    except (zipfile.BadZipFile, OSError) as e:
        raise ArtibusError(f"{ssp}: not a readable SSP archive (a zip file): {e}") from None
    root = read_ssd(ssp, where)
    with zipfile.ZipFile(ssp) as z:
        return root, set(z.namelist())


def _experiment(bench, root, where):
    """the DefaultExperiment's start and stop time onto ``bench`` (SSP 1.0 5.2)"""
    de = root.find("ssd:DefaultExperiment", NS)
    if de is not None:
        bench.start_time = _number(de, "startTime", 0.0, where)
        bench.stop_time = _number(de, "stopTime", None, where)


def _can(root):
    """the top system's CAN network (our CAN_ANNOTATION) or None"""
    can = root.find(f"ssd:System/ssd:Annotations/ssc:Annotation[@type='{CAN_ANNOTATION}']/artibus:Can", NS)
    return None if can is None else {"source": can.get("source"), "period": can.get("period"), "line": can.sourceline}


def _systems(system, prefix="", out=None):
    """{system path ("" the root, "Sub", "Sub.Inner"): its element} of ``system`` and its sub-systems"""
    out = {} if out is None else out
    out[prefix] = system
    for sub in system.findall("ssd:Elements/ssd:System", NS):
        _systems(sub, _join(prefix, sub.get("name")), out)
    return out


def _join(prefix, name):
    """a hierarchical name: ``name`` inside the system ``prefix`` ("" the root)"""
    return f"{prefix}.{name}" if prefix else name


def _end(element, connector):
    """A connection's end as messages name it: element.connector, or the connector alone when it
    is the system's own (no element, or "" as OMSimulator writes it)."""
    return f"{element}.{connector}" if element else connector


def _connectors(element, kind=None):
    """the names of the Connectors an element (Component or System) declares, of ``kind`` if given"""
    return [k.get("name") for k in element.findall("ssd:Connectors/ssd:Connector", NS)
            if kind is None or k.get("kind") == kind]


def _step(xml_el, path, where):
    """a component's communication step from our ANNOTATION (<artibus:Simulation stepSize=>), else from
    the Open Simulation Platform's (<osp:StepSizeHint value=>, as libcosim reads it), or None"""
    attr, ann = "stepSize", xml_el.find(f"ssd:Annotations/ssc:Annotation[@type='{ANNOTATION}']/artibus:Simulation", NS)
    if ann is None or not ann.get(attr):
        osp = f"ssd:Annotations/ssc:Annotation[@type='{OSP_TYPE}']/{{{OSP_NS}}}StepSizeHint"
        attr, ann = "value", xml_el.find(osp, NS)
    if ann is None or not ann.get(attr):
        return None
    step = _number(ann, attr, None, where)
    if not step > 0:
        raise ArtibusError(f"{where}:{ann.sourceline}: Component '{path}': "
                           f"{attr} = {ann.get(attr)} must be > 0")
    return step


def _transformation(xc, label, where):
    """(factor, offset, mapping) of a Connection: its ssc:LinearTransformation (SSP 1.0 5.3.7; FMPy's
    reader looks for it in the wrong namespace) and its mapping transformation (ssd.map_transformation)"""
    lt = xc.find("ssc:LinearTransformation", NS)
    factor = _number(lt, "factor", 1.0, where) if lt is not None else 1.0
    offset = _number(lt, "offset", 0.0, where) if lt is not None else 0.0
    return factor, offset, map_transformation(xc, label)


def _route(xc):
    """a Connection's CAN route (our CAN_ANNOTATION: <artibus:Route message= signal=>) or None"""
    route = xc.find(f"ssd:Annotations/ssc:Annotation[@type='{CAN_ANNOTATION}']/artibus:Route", NS)
    if route is None:
        return None
    return {"message": route.get("message"), "signal": route.get("signal"), "line": route.sourceline}


@dataclass
class _Reading:
    """read's steps over one .ssd tree and what they build up: the components with the values
    bound on them (walk), the connections resolved through the systems' connectors to
    component variables (collect_edges, connect), the values bound at system level
    (system_bindings)"""
    pack: Pack                     # the .ssp (artibus.bench.bindings)
    names: set                     # the .ssp's members
    bench: Bench                   # being filled
    xml_systems: dict              # system path ("" the root, "Sub", "Sub.Inner") -> its lxml element (_systems)
    inherited: list = field(default_factory=list)    # (prefix, values, origins, units, xml) of each system
    given_units: dict = field(default_factory=dict)  # component path -> {var: (unit, defs, then, origin)}
    edges: list = field(default_factory=list)        # (a, b, factor, offset, line, route, mapping)
    outgoing: dict = field(default_factory=dict)     # node -> [(b, factor, offset, line, route, mapping)]
    indices: dict = field(default_factory=dict)      # (a, b, line) -> (startIndices, endIndices) of an edge

    def walk(self, prefix):
        """the components of the system ``prefix`` and of its sub-systems (its components
        first, then each sub-system's, in the file's order), with the values bound on them;
        the system's own bindings kept for system_bindings"""
        xml = self.xml_systems[prefix]
        sys_origins, sys_units = {}, {}
        values = bound_values(self.pack, xml, f"System '{xml.get('name')}'", sys_origins, sys_units)
        self.inherited.append((prefix, values, sys_origins, sys_units, xml))
        for el in xml.findall("ssd:Elements/ssd:Component", NS):
            self.component(el, _join(prefix, el.get("name")))
        for el in xml.findall("ssd:Elements/ssd:System", NS):
            self.walk(_join(prefix, el.get("name")))

    def component(self, xml_el, path):
        """one Component: its source in the .ssp, its connectors, step and bound values"""
        where, source = self.pack.where, xml_el.get("source")
        if source not in self.names:
            raise ArtibusError(f"{where}:{xml_el.sourceline}: Component '{path}': source "
                               f"\"{source}\" is not in the .ssp")
        c = Component(path=path, source=source, line=xml_el.sourceline)
        self.given_units[path] = {}
        c.parameters = bound_values(self.pack, xml_el, f"Component '{path}'", c.origins, self.given_units[path])
        c.outputs = _connectors(xml_el, "output")
        c.connectors = _connectors(xml_el)
        c.step = _step(xml_el, path, where)
        self.bench.components[path] = c

    def _node(self, prefix, element, connector):
        if not element:            # a connector of the system itself (no startElement/endElement, or "" as
                                   # OMSimulator writes it: SSP 1.0 5.3.7, the enclosing system)
            return ("sys", prefix, connector)
        path = _join(prefix, element)
        if path in self.bench.components:
            return ("comp", path, connector)
        return ("sys", path, connector)

    def _connections(self):
        """(system prefix, Connection element) of every system's connections, a system's own
        before its sub-systems' (the order of _systems)"""
        for prefix, xml in self.xml_systems.items():
            for xc in xml.findall("ssd:Connections/ssd:Connection", NS):
                yield prefix, xc

    def _check_end(self, n, label):
        """an error unless node n's element exists and declares its connector"""
        if n[0] == "sys" and n[1] not in self.xml_systems:
            raise ArtibusError(f"{label}: no element '{n[1]}'")
        declared = (self.bench.components[n[1]].connectors if n[0] == "comp" else _connectors(self.xml_systems[n[1]]))
        if n[2] not in declared:
            raise ArtibusError(f"{label}: '{n[1] or 'the system'}' declares no connector '{n[2]}'")

    def collect_edges(self):
        """every connection of every system as an edge between nodes (a component's or a
        system's connector), each end checked to be declared"""
        where = self.pack.where
        for prefix, xc in self._connections():
            start = (xc.get("startElement"), xc.get("startConnector"))
            end = (xc.get("endElement"), xc.get("endConnector"))
            a, b = self._node(prefix, *start), self._node(prefix, *end)
            label = f"{where}:{xc.sourceline}: Connection {_end(*start)} -> {_end(*end)}"
            for n in (a, b):
                self._check_end(n, label)
            factor, offset, mapping = _transformation(xc, label, where)
            if xc.get("startIndices") is not None or xc.get("endIndices") is not None:
                if a[0] != "comp" or b[0] != "comp":
                    raise ArtibusError(f"{label}: startIndices/endIndices through a system's connector: "
                                       "the runner takes them between two components' connectors")
                self.indices[(a, b, xc.sourceline)] = (xc.get("startIndices"), xc.get("endIndices"))
            self.edges.append((a, b, factor, offset, xc.sourceline, _route(xc), mapping))
        for a, b, f, o, line, route, mp in self.edges:
            self.outgoing.setdefault(a, []).append((b, f, o, line, route, mp))

    def ends(self, n, f, o, line, route, mp, seen):
        """the component variables node n leads to, through system connectors: comp -> sys ... -> comp"""
        if n[0] == "comp":
            yield n, f, o, line, route, mp
            return
        if n in seen:
            return
        for m, f2, o2, l2, r2, mp2 in self.outgoing.get(n, []):
            yield from self.ends(m, f2 * f, f2 * o + o2, line, route or r2, _compose(mp, mp2, line), seen | {n})

    def connect(self):
        """the bench's connections: each from a component's variable to those it reaches"""
        for a, b, f, o, line, route, mp in self.edges:
            if a[0] != "comp":
                continue
            for end, f2, o2, l2, r2, mp2 in self.ends(b, f, o, line, route, mp, frozenset()):
                self.bench.connections.append(Connection(start=(a[1], a[2]), end=(end[1], end[2]),
                                                         factor=f2, offset=o2, line=l2, can=r2, mapping=mp2,
                                                         indices=self.indices.get((a, b, line), (None, None))))

    def _connector_targets(self, full):
        """the component variables the system connector ``full`` ("Sub.connector") reaches, either
        way along its connections; None when ``full`` is not a system connector"""
        sys_path, _, conn = full.rpartition(".")
        if sys_path not in self.xml_systems or conn not in _connectors(self.xml_systems[sys_path]):
            return None
        node = ("sys", sys_path, conn)
        return ([(n[1], n[2]) for n, *_ in self.ends(node, 1.0, 0.0, 0, None, None, frozenset())]
                + [(a[1], a[2]) for a, b, *_ in self.edges if b == node and a[0] == "comp"])

    def system_bindings(self, root_name):
        """the values bound on systems (SSP 1.0, 5.3.5): a higher level takes precedence over a
        lower one (the deepest sub-system's applied first, the root's last), a later binding
        over an earlier one at the same level; a name ("Comp.var", "Sub.Comp.var", relative to
        its system) is a component's variable by its hierarchical name or a system connector
        ("Sub.connector", "connector"), which applies to the component variables it is
        connected to; applied after the components' own"""
        for prefix, values, sys_origins, sys_units, xml in sorted(self.inherited, key=lambda i: -_depth(i[0])):
            for name, value in values.items():
                self._system_value(prefix, name, value, sys_origins, sys_units, root_name)

    def _system_value(self, prefix, name, value, sys_origins, sys_units, root_name):
        """one value bound at the system ``prefix`` onto the component variables it names"""
        components = self.bench.components
        full = _join(prefix, name)
        targets = [(p, full[len(p) + 1:]) for p in components if full.startswith(p + ".")]
        through = self._connector_targets(full)
        if through is not None:
            targets += through
            if not targets:        # a system connector connected to no FMU: the value stays its own
                self.bench.system_values[full] = value
                return
        if not targets:
            raise ArtibusError(f"{sys_origins.get(name, self.pack.where)}: parameter '{name}' = {value!r} bound at "
                               f"system '{prefix or root_name}': no component variable or system "
                               f"connector of that name (components: {', '.join(components)})")
        for comp_path, var in dict.fromkeys(targets):
            c = components[comp_path]
            c.parameters[var] = value
            c.origins[var] = sys_origins.get(name, self.pack.where)
            if name in sys_units:
                self.given_units[comp_path][var] = sys_units[name]
            else:
                self.given_units[comp_path].pop(var, None)
