#!/usr/bin/env python3
"""Assemble an FMU's tree and zip it (called by add_fmu in CMakeLists.txt after linking).

The tree <build>/fmu/<Name>/ already holds the build's own binary (binaries/linux64/<Name>.so
for --platform x86_64-linux and FMI 2.0). This adds

  modelDescription.xml     the repository's modelDescription/<Name>.xml (the single source,
                           kept whole) with author, version (artibus's, src/artibus/base.py), copyright,
                           license, generationTool, DisplayUnits (the table DISPLAY_UNITS
                           below) and, where sources/ is shipped, <SourceFiles>; its
                           elements in the order of the FMI version's schema
                           (ELEMENT_ORDER below), whatever the order written;
  model.png                src/models/<Name>/model.png (made by scripts/make_icons.py);
  documentation/index.html from the model description and src/models/<Name>/README.md;
  documentation/licenses/  artibus's LICENSE and the notices of the libraries inside;
  sources/                 the C sources, where the model needs nothing beyond the C library:
                           one flat folder, sources/ the only include path (FMPy's
                           `fmpy compile` compiles the listed files with no other), and for
                           FMI 3.0 sources/buildDescription.xml (build_description());
  resources/               the add_fmu RESOURCES;
  binaries/<folder>/<Name>.<ext>  for each --platform-dir PLATFORM=DIR whose DIR holds the
                           cross build's binary (the mingw build's <Name>.dll, the aarch64
                           build's <Name>.so), in the folder the FMI version names it
                           (binaries_folder());

With --fmi 3 the tree is the FMI 3.0 build's (<build>/fmu3/<Name>/, binaries/x86_64-linux and
x86_64-windows): its modelDescription.xml is written by fmi3_description.py from the same
completed FMI 2.0 description, and its sources/ (the same models as FMI 2.0's, with
fmi3Functions.c and the FMI 3.0 table) are described by sources/buildDescription.xml.

then writes the archive (entries in a fixed order with a fixed time stamp, so the same
inputs give the same bytes) through a temporary file, so a reader never sees half an FMU.

Only the Python standard library is used: this runs inside the CMake build.

usage: package_fmu.py --name N --root SRC --xml XML --gen GENDIR --tree TREE --fmu OUT.fmu
                      [--platform TUPLE] [--fmi-version 2|3] [--platform-dir TUPLE=DIR ...]
                      [--sources S...] [--resources R...]
"""

import argparse
import html
import math
import os
import re
import shutil
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fmi3_description  # noqa: E402  (src/fmi/, beside this script)
import lsbus_node  # noqa: E402

AUTHOR = "the artibus authors"
COPYRIGHT = "Copyright (c) 2026, the artibus authors"

#: unit -> (display unit, factor, offset): display value = factor * value + offset (FMI 2.0,
#: 2.2.2). Each display unit is added to the unit's <Unit> and set as displayUnit= on the
#: variables of that unit, except those whose description matches the pattern beside it
#: (a display unit that would make the variable read oddly: a lateral or piston velocity
#: or a slip-blend speed is no road speed in km/h).
DISPLAY_UNITS = {
    "rad": ("deg", 180.0 / math.pi, 0.0, None),
    "rad/s": ("deg/s", 180.0 / math.pi, 0.0, None),
    "m/s": ("km/h", 3.6, 0.0, re.compile(r"lateral|piston|slip angle", re.I)),
    "N": ("kN", 1e-3, 0.0, None),
    "N.m": ("kN.m", 1e-3, 0.0, None),
}

#: the children of <fmiModelDescription> in the order of each FMI version's schema (by the
#: major version of fmiVersion=): fmi2ModelDescription.xsd, and fmi3ModelDescription.xsd.
#: The FMI 2.0 schema lets its interface elements repeat (an outer sequence of up to two
#: ModelExchange / CoSimulation), so FMPy's XSD check accepts CoSimulation first; the FMI
#: Library (FMIL: libcosim, PyFMI, OMSimulator and many tools) does not: it skips a
#: ModelExchange after CoSimulation with an error and loads a Co-Simulation-only FMU.
#: The packer writes this order whatever the order in modelDescription/<Name>.xml.
ELEMENT_ORDER = {
    "2": ("ModelExchange", "CoSimulation", "UnitDefinitions", "TypeDefinitions", "LogCategories",
          "DefaultExperiment", "VendorAnnotations", "ModelVariables", "ModelStructure"),
    "3": ("ModelExchange", "CoSimulation", "ScheduledExecution", "UnitDefinitions", "TypeDefinitions",
          "LogCategories", "DefaultExperiment", "ModelVariables", "ModelStructure", "Annotations"),
}

#: libraries a binary may contain: (marker bytes in the binary, licence file, what)
SUNDIALS_MARKERS = (b"CVodeCreate", b"cvode_mem", b"arkode_mem", b"ERKStepCreate")
LICENSE_FILES = {
    "artibus": ("LICENSE", "artibus-BSD-2-Clause.txt"),
    "SUNDIALS": ("licenses/SUNDIALS-BSD-3-Clause.txt", "SUNDIALS-BSD-3-Clause.txt"),
    "Eigen": ("licenses/Eigen-MPL-2.0.txt", "Eigen-MPL-2.0.txt"),
    "GCC": ("licenses/GCC-runtime-library-exception-3.1.txt", "GCC-runtime-library-exception-3.1.txt"),
    "mingw-w64": ("licenses/mingw-w64-runtime.txt", "mingw-w64-runtime.txt"),
}
LICENSE_TEXT = {
    "artibus": "BSD-2-Clause",
    "SUNDIALS": "SUNDIALS (BSD-3-Clause, linked statically)",
    "Eigen": "Eigen (MPL-2.0, header-only)",
    "GCC": "GCC's runtime libraries (GPL-3.0 with the GCC Runtime Library Exception 3.1)",
    "mingw-w64": "the mingw-w64 runtime (ZPL-2.1, MIT, BSD-3-Clause; win64)",
}

#: the platforms artibus builds or could build, by their FMI 3.0 platform tuple (FMI 3.0,
#: 2.5.1.1: <arch>-<sys>), with the shared library's file extension
SHARED_LIBRARY_EXT = {
    "x86_64-linux": ".so",
    "aarch64-linux": ".so",
    "x86_64-windows": ".dll",
    "x86_64-darwin": ".dylib",
    "aarch64-darwin": ".dylib",
}

#: FMI 2.0's names for binaries/ folders (FMI 2.0.4, 2.3: "win32", "win64", "linux32",
#: "linux64", "darwin32", "darwin64"; "further names can be introduced by vendors"). A platform
#: FMI 2.0 does not name keeps its FMI 3.0 tuple: 64-bit ARM Linux is binaries/aarch64-linux
#: (FMI 3.0's table of platform tuples, 2.5.1, gives "Linux on ARM64" no FMI 2.0 name and
#: linux64 to "Linux on 64-bit x86"). An importer must know that name: FMPy 0.3.32
#: loads an FMI 2.0 binary from linux64 on any 64-bit Linux, so on ARM it takes the FMI 3.0
#: FMU or compiles the source FMU (docs/developer/building.md).
FMI2_FOLDERS = {
    "x86_64-linux": "linux64",
    "x86_64-windows": "win64",
    "x86_64-darwin": "darwin64",
}

#: the FMI headers the importer brings: not in sources/ (FMI 2.0.4, 2.3: "all needed C sources
#: and C header files ... with exception of fmi2TypesPlatform.h, fmi2FunctionTypes.h and
#: fmi2Functions.h"; FMI 3.0, 2.5.1: the same for fmi3*.h)
STANDARD_HEADERS = {
    "2": ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    "3": ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}

INCLUDE_RE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)


def project_version(root):
    """artibus's version: __version__ = "..." of src/artibus/base.py, the one place it is
    written (pyproject.toml takes it from there: dynamic = ["version"])."""
    text = open(os.path.join(root, "src", "artibus", "base.py"), encoding="utf-8").read()
    m = re.search(r'^__version__\s*=\s*"([^"]+)"', text, re.M)
    if not m:
        sys.exit("package_fmu.py: no __version__ = \"...\" in src/artibus/base.py")
    return m.group(1)


# ---------------------------------------------------------------------------
# which files the model is made of, and what they need


def includes(path):
    with open(path, encoding="utf-8") as f:
        return INCLUDE_RE.findall(f.read())


def closure(root, name, sources, fmi_version="2"):
    """The model's C files and every local header they include (transitively), with the FMI
    layer of that FMI version (src/fmi/fmi<v>Functions.c), as repository-relative paths, and the
    system headers named."""
    inc_dirs = [os.path.join(root, d) for d in
                ("src/fmi", f"src/models/{name}", "src/models/common", f"include/fmi{fmi_version}")]
    inc_dirs += sorted({os.path.dirname(os.path.join(root, s)) for s in sources})   # as add_fmu
    todo = [os.path.normpath(os.path.join(root, s)) for s in sources]
    todo.append(os.path.join(root, f"src/fmi/fmi{fmi_version}Functions.c"))
    todo.append(os.path.join(root, "src/fmi/fmu_core.c"))
    files, system = set(), set()
    while todo:
        path = todo.pop()
        if path in files:
            continue
        files.add(path)
        for kind, inc in includes(path):
            if inc == "model_vars.h":
                continue
            cands = [os.path.join(os.path.dirname(path), inc)] + [os.path.join(d, inc) for d in inc_dirs]
            found = next((os.path.normpath(c) for c in cands if os.path.isfile(c)), None)
            if kind == '"' and found:
                todo.append(found)
            else:
                system.add(inc)
    return sorted(os.path.relpath(f, root) for f in files), system


def needs_beyond_libc(files, system):
    """Why the model cannot be shipped as C sources alone (None: it can)."""
    why = []
    for f in files:
        if os.path.basename(f) == "ode.h":
            why.append("it integrates with SUNDIALS (ode.h)")
        elif not f.endswith((".c", ".h")):
            why.append(f"{os.path.basename(f)} is not C")
    why += [f"it includes <{inc}>" for inc in sorted(system) if "/" in inc or not inc.endswith(".h")]
    return "; ".join(why) or None


def uses_eigen(root, files):
    return any(inc.startswith("Eigen/") for f in files for _, inc in includes(os.path.join(root, f)))


# ---------------------------------------------------------------------------
# modelDescription.xml


def parse(xml_path):
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return ET.parse(xml_path, parser)


def add_display_units(md):
    """DisplayUnits on <UnitDefinitions> and displayUnit= on the variables that read well in
    them. Returns {variable name: display unit}."""
    units = {u.get("name"): u for u in md.iter("Unit")}
    used = {}
    for sv in md.iter("ScalarVariable"):
        real = sv.find("Real")
        if real is None or real.get("unit") not in DISPLAY_UNITS or real.get("displayUnit"):
            continue
        unit = real.get("unit")
        dname, _, _, skip = DISPLAY_UNITS[unit]
        if unit not in units or (skip and skip.search(sv.get("description", ""))):
            continue
        real.set("displayUnit", dname)
        used.setdefault(unit, set()).add(sv.get("name"))
    for unit in used:
        dname, factor, offset, _ = DISPLAY_UNITS[unit]
        u = units[unit]
        if any(d.get("name") == dname for d in u.findall("DisplayUnit")):
            continue
        d = ET.SubElement(u, "DisplayUnit", {"name": dname, "factor": repr(factor)})
        if offset:
            d.set("offset", repr(offset))
    return {n: DISPLAY_UNITS[u][0] for u, names in used.items() for n in names}


def indent_unit_children(md):
    """Keep the written layout: a <Unit> given on one line stays on one line."""
    for u in md.iter("Unit"):
        for child in u:
            child.tail = None


def set_metadata(md, version, libraries):
    md.set("author", AUTHOR)
    md.set("version", version)
    md.set("copyright", COPYRIGHT)
    lic = "BSD-2-Clause (artibus)"
    extra = [LICENSE_TEXT[lib] for lib in libraries if lib != "artibus"]
    if extra:
        lic += "; the binaries also contain " + " and ".join(extra)
    md.set("license", lic + ": see documentation/licenses/")
    md.set("generationTool", f"artibus {version}")
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch:
        md.set("generationDateAndTime", time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(int(epoch))))
    elif "generationDateAndTime" in md.attrib:
        del md.attrib["generationDateAndTime"]


def add_source_files(md, c_files):
    """<SourceFiles> in each interface element (FMI 2.0, 2.3 / 3.2.1 / 4.3.1)."""
    for kind in ("ModelExchange", "CoSimulation"):
        el = md.find(kind)
        if el is None:
            continue
        for old in el.findall("SourceFiles"):
            el.remove(old)
        sf = ET.Element("SourceFiles")
        # SourceFiles precedes the other children of the interface element in the XSD
        el.insert(0, sf)
        sf.text = "\n      "
        for i, f in enumerate(c_files):
            e = ET.SubElement(sf, "File", {"name": f})
            e.tail = "\n      " if i + 1 < len(c_files) else "\n    "
        sf.tail = "\n  " if len(el) == 1 else "\n    "
        if len(el) == 1:
            el.text = "\n    "


def order_elements(md):
    """Put the children of <fmiModelDescription> into ELEMENT_ORDER's order for its
    fmiVersion. A comment travels with the element after it; the layout (each position's
    whitespace) stays as written. An element the schema does not have, or one given twice,
    is an error (the schema allows neither)."""
    version = md.get("fmiVersion", "")
    order = ELEMENT_ORDER.get(version.split(".")[0])
    if order is None:
        raise ValueError(f"fmiVersion = {version!r}: no element order known (ELEMENT_ORDER)")
    nodes = list(md)
    groups, pending = [], []
    for node in nodes:
        pending.append(node)
        if isinstance(node.tag, str):
            if node.tag not in order:
                raise ValueError(f"<{node.tag}> is no child of <fmiModelDescription> in FMI {version}")
            if any(tag == node.tag for tag, _ in groups):
                raise ValueError(f"<{node.tag}> given twice in <fmiModelDescription>")
            groups.append((node.tag, pending))
            pending = []
    groups.sort(key=lambda g: order.index(g[0]))   # stable; trailing comments stay last
    ordered = [n for _, g in groups for n in g] + pending
    tails = [n.tail for n in nodes]
    for node in nodes:
        md.remove(node)
    for node, tail in zip(ordered, tails):
        node.tail = tail
        md.append(node)


def write_xml(tree, path):
    tree.write(path, encoding="UTF-8", xml_declaration=True)
    with open(path, "ab") as f:
        f.write(b"\n")


# ---------------------------------------------------------------------------
# documentation/index.html


def inline_md(text):
    """escape, then `code`, **bold**, [text](url)"""
    out = []
    for i, part in enumerate(re.split(r"(`[^`]*`)", text)):
        if i % 2:
            out.append("<code>" + html.escape(part[1:-1]) + "</code>")
            continue
        s = html.escape(part, quote=False)
        s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
        s = re.sub(r"(?<![\w*])\*([^*\s][^*]*?)\*(?![\w*])", r"<em>\1</em>", s)
        s = re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", r'<a href="\2">\1</a>', s)
        out.append(s)
    return "".join(out)


def markdown(text):
    """A small subset of Markdown: #-headings (shifted one level down), paragraphs, - and 1.
    lists, ``` code blocks, | tables |, inline code, bold, italics, links."""
    out, para, lst = [], [], None
    lines = text.splitlines()

    def flush():
        nonlocal para, lst
        if para:
            out.append("<p>" + inline_md(" ".join(para)) + "</p>")
            para = []
        if lst:
            tag, items = lst
            out.append(f"<{tag}>" + "".join(f"<li>{inline_md(' '.join(it))}</li>" for it in items) + f"</{tag}>")
            lst = None

    i = 0
    while i < len(lines):
        line = lines[i]
        s = line.strip()
        if s.startswith("```"):
            flush()
            code = []
            i += 1
            while i < len(lines) and not lines[i].strip().startswith("```"):
                code.append(lines[i])
                i += 1
            out.append("<pre><code>" + html.escape("\n".join(code)) + "</code></pre>")
        elif not s:
            flush()
        elif s.startswith("|"):
            flush()
            rows = []
            while i < len(lines) and lines[i].strip().startswith("|"):
                cells = [c.strip() for c in lines[i].strip().strip("|").split("|")]
                if not all(re.fullmatch(r":?-+:?", c) for c in cells):
                    rows.append(cells)
                i += 1
            i -= 1
            head, body = rows[0], rows[1:]
            out.append("<table><tr>" + "".join(f"<th>{inline_md(c)}</th>" for c in head) + "</tr>"
                       + "".join("<tr>" + "".join(f"<td>{inline_md(c)}</td>" for c in r) + "</tr>" for r in body)
                       + "</table>")
        elif m := re.match(r"(#{1,5})\s+(.*)", s):
            flush()
            level = min(len(m.group(1)) + 1, 6)
            out.append(f"<h{level}>{inline_md(m.group(2))}</h{level}>")
        elif m := re.match(r"([-*]|\d+\.)\s+(.*)", s):
            tag = "ol" if m.group(1)[0].isdigit() else "ul"
            if para:
                out.append("<p>" + inline_md(" ".join(para)) + "</p>")
                para = []
            if lst and lst[0] != tag:
                flush()
            if not lst:
                lst = (tag, [])
            lst[1].append([m.group(2)])
        elif lst and line.startswith((" ", "\t")):
            lst[1][-1].append(s)
        else:
            if lst:
                flush()
            para.append(s)
        i += 1
    flush()
    return "\n".join(out)


CSS = """body{font-family:sans-serif;max-width:72em;margin:1em auto;padding:0 1em;color:#222}
h1{display:flex;align-items:center;gap:.5em}h1 img{width:64px;height:64px}
table{border-collapse:collapse;margin:.5em 0 1.5em}td,th{border:1px solid #ccc;padding:2px 6px;vertical-align:top;text-align:left}
th{background:#eee}td.num{text-align:right;white-space:nowrap}code,td.name{font-family:monospace}
td.name{white-space:nowrap}pre{background:#f4f4f4;padding:.5em;overflow-x:auto}.du{color:#666}"""

CAUSALITY_TITLES = (
    ("parameter", "Parameters"),
    ("calculatedParameter", "Calculated parameters"),
    ("input", "Inputs"),
    ("output", "Outputs"),
    ("local", "Local variables"),
    ("independent", "Independent variable"),
)


def fmt_display(value, unit, md_units):
    """the value in its display unit, e.g. 0.75 rad -> "(42.97 deg)" """
    if not value or unit not in md_units:
        return ""
    try:
        x = float(value)
    except ValueError:
        return ""
    dname, factor, offset = md_units[unit]
    y = factor * x + offset
    return f' <span class="du">({y:.6g} {html.escape(dname)})</span>'


def enumerations(md):
    """{type name: (description, [(item name, value, description)])} of the model
    description's <TypeDefinitions><SimpleType><Enumeration>s, in their order."""
    out = {}
    for st in md.iterfind("TypeDefinitions/SimpleType"):
        en = st.find("Enumeration")
        if en is not None:
            out[st.get("name")] = (st.get("description", ""),
                                   [(i.get("name"), i.get("value"), i.get("description", ""))
                                    for i in en.findall("Item")])
    return out


def documentation(md, name, readme, libraries, platforms, source_files, version, why_not, with_sundials=(),
                  fmi_version=None, papers=None):
    """documentation/index.html: the metadata, the model's text (src/models/<Name>/README.md),
    the references in full, the licences, every variable; written for a reader of the FMU
    alone (for_outside: the papers by name, no repository paths)."""
    e = html.escape
    papers = papers or {}
    cited = {}

    def outside(text):
        return for_outside(text or "", papers, cited)

    # the model's text first: its references are numbered before the variables'
    readme_html = markdown(outside(readme)) if readme else "<p>(no model text)</p>"
    description = outside(md.get("description", ""))
    units = {}
    for u in md.iter("Unit"):
        for d in u.findall("DisplayUnit"):
            units[(u.get("name"), d.get("name"))] = (d.get("name"), float(d.get("factor", "1")),
                                                      float(d.get("offset", "0")))
    interfaces = [k for k in ("CoSimulation", "ModelExchange") if md.find(k) is not None]
    de = md.find("DefaultExperiment")
    rows = [
        ("FMI version", (fmi_version or md.get("fmiVersion")) + " (" + ", ".join(
            {"CoSimulation": "Co-Simulation", "ModelExchange": "Model Exchange"}[k] for k in interfaces) + ")"),
        ("version", md.get("version")),
        ("author", md.get("author")),
        ("copyright", md.get("copyright")),
        ("license", md.get("license")),
        ("generation tool", md.get("generationTool")),
        ("instantiation token" if fmi_version == "3.0" else "GUID", md.get("guid")),
        ("platforms", ", ".join(f"binaries/{p}" for p in platforms)),
    ]
    if de is not None:
        rows.append(("default experiment", ", ".join(f"{k} = {v}" for k, v in de.attrib.items())))
    listed = "sources/buildDescription.xml" if fmi_version == "3.0" else "&lt;SourceFiles&gt;"
    rows.append(("sources", f"sources/ ({len(source_files)} C files listed in {listed}, "
                 "one flat folder: compile them with sources/ and your importer's FMI headers as the "
                 "include path, or <code>fmpy compile</code> the FMU)" if source_files else
                 f"not shipped: {e(why_not or '')}"))
    provides = any(md.find(k) is not None and md.find(k).get(a) == "true" for k in interfaces
                   for a in ("providesDirectionalDerivative", "providesDirectionalDerivatives"))
    if provides:
        calls = ("fmi3GetDirectionalDerivative and fmi3GetAdjointDerivative" if fmi_version == "3.0"
                 else "fmi2GetDirectionalDerivative")
        rows.append(("derivatives", f"{calls}: the exact partial derivatives (to rounding) of the state "
                     "derivatives and outputs with respect to the continuous states and the inputs, by "
                     "forward-mode automatic differentiation (dual numbers) through the model's own "
                     "equations; the <ModelStructure> dependencies are exact"))
    elif fmi_version == "3.0":
        rows.append(("derivatives", "providesDirectionalDerivatives and providesAdjointDerivatives are false: "
                     "the model exports no analytic Jacobian (its equations are integrated inside the FMU, "
                     "and no model derives its partial derivatives), so fmi3GetDirectionalDerivative and "
                     "fmi3GetAdjointDerivative answer fmi3Error; an importer that needs a Jacobian takes "
                     "finite differences of the outputs"))
    if fmi_version == "3.0":
        rows.append(("arrays", "none: every vector (axle angles, forces, positions) is a set of scalar "
                     "variables named x[1], x[2], ... as in FMI 2.0, so the same connections and parameter "
                     "files serve both versions and every importer that reads scalars"))
    meta = "".join(f"<tr><th>{e(k)}</th><td>{v if k == 'sources' else e(v or '')}</td></tr>" for k, v in rows)

    lic_items = []
    for lib in libraries:
        fname = LICENSE_FILES[lib][1]
        what = {"artibus": "artibus itself (BSD-2-Clause)",
                "SUNDIALS": "SUNDIALS CVODE/ARKODE, linked statically into " + " and ".join(with_sundials)
                            + " (BSD-3-Clause)",
                "Eigen": "Eigen 3, header-only, compiled into the binaries (MPL-2.0; its source: "
                         "https://gitlab.com/libeigen/eigen)",
                "GCC": "GCC's runtime libraries libgcc and libstdc++ where linked statically "
                       "(GPL-3.0 or later with the GCC Runtime Library Exception 3.1, which lets the "
                       "combination be conveyed under the terms of the FMU's licences)",
                "mingw-w64": "the mingw-w64 runtime (C runtime start-up code, winpthreads) linked "
                             "statically into binaries/win64 (ZPL-2.1, MIT, BSD-3-Clause; public domain parts)"}[lib]
        lic_items.append(f'<li><a href="licenses/{fname}">{fname}</a>: {e(what)}</li>')

    sections = []
    enums = enumerations(md)
    for causality, title in CAUSALITY_TITLES:
        svs = [sv for sv in md.iter("ScalarVariable") if sv.get("causality", "local") == causality]
        if not svs:
            continue
        body = []
        for sv in svs:
            t = next(c for c in sv if isinstance(c.tag, str))
            unit = t.get("unit", "")
            disp = t.get("displayUnit", "")
            du = units.get((unit, disp))
            dmap = {unit: du} if du else {}
            start = t.get("start", "")
            items = enums.get(t.get("declaredType"), (None, []))[1] if t.tag == "Enumeration" else []
            names = {v: n for n, v, _ in items}
            item = f" ({e(names[start])})" if start in names else ""
            cells = [
                f'<td class="name">{e(sv.get("name"))}</td>',
                f"<td>{e(t.tag)}"
                + (f' <a href="#type-{e(t.get("declaredType"))}">{e(t.get("declaredType"))}</a>' if items else "")
                + "</td>",
                f"<td>{e(unit)}</td>",
                f"<td>{e(disp)}</td>",
                f'<td class="num">{e(start)}{item}{fmt_display(start, unit, dmap)}</td>',
                f'<td class="num">{e(t.get("min", ""))}{fmt_display(t.get("min"), unit, dmap)}</td>',
                f'<td class="num">{e(t.get("max", ""))}{fmt_display(t.get("max"), unit, dmap)}</td>',
                f"<td>{e(sv.get('variability', 'continuous'))}</td>",
                f"<td>{e(outside(sv.get('description', '')))}</td>",
            ]
            body.append("<tr>" + "".join(cells) + "</tr>")
        sections.append(
            f'<h2 id="{causality}">{e(title)} ({len(svs)})</h2>\n<table class="variables">'
            "<tr><th>name</th><th>type</th><th>unit</th><th>display unit</th><th>start</th>"
            "<th>min</th><th>max</th><th>variability</th><th>description</th></tr>\n"
            + "\n".join(body) + "</table>")

    if enums:
        # the items of each choice (FMI 2.0, 2.2.3 <SimpleType><Enumeration>; FMI 3.0
        # <EnumerationType>): a tool shows the names, the FMU reads and writes the values
        # (FMI 2.0: fmi2GetInteger/fmi2SetInteger; FMI 3.0: fmi3GetInt64/fmi3SetInt64)
        body = []
        for tname, (tdesc, items) in enums.items():
            rows_ = "".join(f'<tr><td class="num">{e(v)}</td><td class="name">{e(n)}</td>'
                            f"<td>{e(outside(d))}</td></tr>" for n, v, d in items)
            body.append(f'<h3 id="type-{e(tname)}">{e(tname)}</h3>\n<p>{e(outside(tdesc))}</p>\n'
                        f"<table><tr><th>value</th><th>item</th><th>description</th></tr>{rows_}</table>")
        sections.append(f'<h2 id="enumerations">Enumerations ({len(enums)})</h2>\n'
                        "<p>The choices among the parameters: a variable of one of these types takes the "
                        "value of an item; set it by the value (FMI 2.0: <code>fmi2SetInteger</code>, "
                        "FMI 3.0: <code>fmi3SetInt64</code>) or, in a tool that reads the type, by the "
                        "item's name.</p>\n" + "\n".join(body))

    return f"""<!DOCTYPE html>
<html lang="en">
<head><meta charset="utf-8"><title>{e(name)} {e(version)}</title>
<style>{CSS}</style></head>
<body>
<h1><img src="../model.png" alt="">{e(name)}</h1>
<p>{e(description)}</p>
<table class="meta">{meta}</table>
{readme_html}
{references(papers, cited)}
<h2>Licences</h2>
<p>What this FMU contains and under which licence (the texts are in <code>documentation/licenses/</code>):</p>
<ul>{"".join(lic_items)}</ul>
{chr(10).join(sections)}
<p>Generated by {e(md.get("generationTool") or "artibus")} from the model description and the
model's text. Display units: value in display unit = factor &times; value + offset,
as declared in <code>&lt;UnitDefinitions&gt;</code>.</p>
</body>
</html>
"""


# ---------------------------------------------------------------------------
# the documentation for someone outside the repository: the papers cited in full,
# no repository paths


def load_papers(root):
    """src/models/papers.json: {"000": {short, authors, title, venue, year, doi, ...}}"""
    import json
    with open(os.path.join(root, "src", "models", "papers.json"), encoding="utf-8") as f:
        return {k: v for k, v in json.load(f).items() if not k.startswith("_")}


SEED_RE = re.compile(r"\b[Ss]eeds? (\d{3})\b")
#: repository paths as the model texts and descriptions write them -> what a reader
#: outside the repository has (the names of artibus's benches and parameter sets)
PATH_RULES = (
    (re.compile(r"\.venv/bin/(\w+)"), r"\1"),
    (re.compile(r"\bfmus/fmi3/(\w+\.fmu)"), r"\1"),
    (re.compile(r"\bfmus/(\w+\.fmu)"), r"\1"),
    (re.compile(r"`ssp/parameters/(\w+\.ssv)`"), r"artibus's parameter set `\1`"),
    (re.compile(r"`ssp/benches/(\w+)`"), r"artibus's bench `\1`"),
    (re.compile(r"`ssp/can/(\w+\.dbc)`"), r"artibus's CAN database `\1`"),
    (re.compile(r"\bssp/parameters/(\w+\.ssv)"), r"\1 (an artibus parameter set)"),
    (re.compile(r"\bssp/benches/(\w+)"), r"\1"),
    (re.compile(r"\bssp/can/(\w+\.dbc)"), r"\1"),
)
#: what no FMU's documentation may contain (tests/test_fmu_documentation.py checks the same)
REPO_PATH_RE = re.compile(r"(?<![\w/.])(?:src|ssp|tests|scripts|docs|modelDescription|benchmarks|build[\w-]*|fmus|\.venv)/")


def for_outside(text, papers, cited):
    """``text`` (Markdown or plain) as a reader of the FMU alone reads it: "seed NNN" as a
    numbered reference "ref. n" (``cited``: {paper: n}, numbered in the order of first use; the
    references section gives each in full), repository paths as the names artibus's
    benches and parameter sets go by."""
    def seed(m):
        key = m.group(1)
        if key not in papers:
            return m.group(0)
        n = cited.setdefault(key, len(cited) + 1)
        return f"ref. {n}"
    text = SEED_RE.sub(seed, text)
    for rx, repl in PATH_RULES:
        text = rx.sub(repl, text)
    return text


def citation(p):
    """One paper's full entry, HTML: authors, title, venue, year, DOI, as far as known."""
    e = html.escape
    if p.get("authors"):
        parts = [e(p["authors"]), f"<em>{e(p['title'])}</em>", e(p.get("venue", ""))]
    else:                                   # a text known by where it was written, not its title
        parts = [e(p.get("venue", "")), "on " + e(p.get("subject", ""))]
    if p.get("year"):
        parts.append(e(p["year"]))
    out = ", ".join(x for x in parts if x) + "."
    if p.get("after"):
        out += f" {e(p['after'][0].upper() + p['after'][1:])}."
    if p.get("doi"):
        out += f' DOI: <a href="https://doi.org/{e(p["doi"])}">{e(p["doi"])}</a>.'
    if p.get("what"):
        out += f" About {e(p['what'])}."
    return out


def references(papers, cited):
    """The references section: each cited paper in full, in the order of its number."""
    if not cited:
        return ""
    items = "".join(f'<li id="ref-{k}" value="{n}">{citation(papers[k])}</li>'
                    for k, n in sorted(cited.items(), key=lambda kv: kv[1]))
    return f'<h2 id="references">References</h2>\n<ol>{items}</ol>'


def stale_input(dll, inputs):
    """The newest of ``inputs`` (the files a binary is built from) that is newer than
    ``dll``, or None: a DLL older than its sources is not this build's and is not packed."""
    t = os.path.getmtime(dll)
    newer = [f for f in inputs if os.path.isfile(f) and os.path.getmtime(f) > t]
    return max(newer, key=os.path.getmtime) if newer else None


# ---------------------------------------------------------------------------
# the tree and the archive


def reset_dir(path):
    if os.path.isdir(path):
        shutil.rmtree(path)
    os.makedirs(path)


def copy(src, dst):
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    shutil.copyfile(src, dst)


def ship_sources(root, gen, tree, files, fmi_version="2"):
    """sources/: the model's files (closure()) and the generated model_vars.c/.h in one flat
    folder, so sources/ alone is the include path: every local #include names a file by its
    name alone (the build puts each source's folder on the include path), and no two files
    share a name. The FMI headers stay out (STANDARD_HEADERS: the importer's own are used).
    Returns the C files to compile, the FMI layer first."""
    dst = os.path.join(tree, "sources")
    reset_dir(dst)
    skip = STANDARD_HEADERS[fmi_version]
    flat = {}
    for f in list(files) + [os.path.join(os.path.relpath(gen, root), g) for g in ("model_vars.c", "model_vars.h")]:
        base = os.path.basename(f)
        if base in skip:
            continue
        if base in flat:
            raise ValueError(f"sources/: {flat[base]} and {f} have the same name {base}")
        flat[base] = f
        copy(os.path.join(root, f), os.path.join(dst, base))
        for kind, inc in includes(os.path.join(root, f)):
            if kind == '"' and "/" in inc:
                raise ValueError(f"{f}: #include \"{inc}\" names a folder; sources/ is flat")
    layer = {f"fmi{fmi_version}Functions.c": 0}
    return sorted((c for c in flat if c.endswith(".c")), key=lambda c: (layer.get(c, 1), c))


def build_description(name, c_files):
    """sources/buildDescription.xml (FMI 3.0, 2.5.1.2 "Build Configurations", the schema
    fmi3BuildDescription.xsd): one build configuration for the model identifier, one C99
    source file set (FMPy's `fmpy compile` compiles the first set only), FMI_VERSION=3
    defined, sources/ (".") its only include directory (FMPy passes sources/ and its own FMI
    headers, whatever the set names). Returns the document's text.
    (FMI 2.0.4, 2.3 lets an FMI 2.0 FMU carry it too; FMPy reads it for FMI 3.0 only, so an
    FMI 2.0 FMU says the same with <SourceFiles>.)"""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    conf = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": name})
    fset = ET.SubElement(conf, "SourceFileSet", {"language": "C99"})
    for f in c_files:
        ET.SubElement(fset, "SourceFile", {"name": f})
    # the sources define it themselves too (model_vars.h's MODEL_FMI_VERSION, which fmu.h
    # takes where no FMI_VERSION is defined): an importer that passes no definition builds
    # FMI 3.0 as well; the exports are the unprefixed fmi3* names (no FMI3_FUNCTION_PREFIX)
    ET.SubElement(fset, "PreprocessorDefinition", {"name": "FMI_VERSION", "value": "3"})
    ET.SubElement(fset, "IncludeDirectory", {"name": "."})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def binaries_folder(platform, fmi_version="2"):
    """The binaries/ folder of a platform (its FMI 3.0 tuple) in an FMU of that FMI version."""
    if platform not in SHARED_LIBRARY_EXT:
        raise ValueError(f"platform {platform!r}: not one of {', '.join(SHARED_LIBRARY_EXT)}")
    return FMI2_FOLDERS.get(platform, platform) if fmi_version == "2" else platform


def described_by(xml, lsbus, root):
    """The files a binary's model description comes from: the description itself, or for an
    FMI-LS-BUS node the files each build derives it from (its node file, the base models'
    descriptions, src/fmi/lsbus_node.py; CMakeLists.txt's add_fmu LSBUS), never the derived
    copy in this build's folder, written anew by each build (after a cross build made beside it)."""
    if not lsbus:
        return [xml]
    md = os.path.join(root, "modelDescription")
    nodes = os.path.join(md, "lsbus")          # a variant's node file names another (lsbus_node.read_spec)
    node_files = sorted(os.path.join(nodes, f) for f in os.listdir(nodes) if f.endswith(".xml")) \
        if os.path.isdir(nodes) else []
    return [lsbus, os.path.join(root, "src", "fmi", "lsbus_node.py")] + sorted(
        os.path.join(md, f) for f in os.listdir(md) if f.endswith(".xml")) + node_files


def add_binaries(tree, name, platform_dirs, fmi_version="2", inputs=(), root=""):
    """binaries/<folder>/<name>.<ext> of each cross-built platform whose folder (platform_dirs:
    {tuple: dir}, empty dirs skipped) holds <name>.<ext>; a platform without it gets no folder
    (an old one is removed). A binary older than any of ``inputs`` (the files it is built
    from) is another build's: left out, with a warning naming both (stale_input). Returns
    the binaries copied."""
    copied = []
    for platform, src_dir in sorted(platform_dirs.items()):
        fname = name + SHARED_LIBRARY_EXT[platform]
        dst = os.path.join(tree, "binaries", binaries_folder(platform, fmi_version))
        if os.path.isdir(dst):
            shutil.rmtree(dst)
        src = os.path.join(src_dir, fname) if src_dir else ""
        if not src or not os.path.isfile(src):
            continue
        newer = stale_input(src, inputs)
        if newer:
            print(f"package_fmu.py: warning: {name}: binaries/{binaries_folder(platform, fmi_version)} left out: "
                  f"{src} is older than {os.path.relpath(newer, root or '.')} (scripts/setup.sh "
                  "--all-platforms rebuilds it)", file=sys.stderr)
            continue
        copy(src, os.path.join(dst, fname))
        copied.append(src)
    return copied


def zip_tree(tree, fmu):
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", "315532800"))  # 1980-01-01 without it
    stamp = time.gmtime(max(epoch, 315532800))[:6]
    entries = []
    for dirpath, dirnames, filenames in os.walk(tree):
        dirnames.sort()
        for fn in sorted(filenames):
            full = os.path.join(dirpath, fn)
            entries.append((os.path.relpath(full, tree).replace(os.sep, "/"), full))
    # modelDescription.xml first, then the rest in path order
    entries.sort(key=lambda e: (e[0] != "modelDescription.xml", e[0]))
    os.makedirs(os.path.dirname(os.path.abspath(fmu)), exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".", suffix=".fmu.tmp", dir=os.path.dirname(os.path.abspath(fmu)))
    os.close(fd)
    try:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            for arc, full in entries:
                info = zipfile.ZipInfo(arc, date_time=stamp)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = (0o755 if arc.startswith("binaries/") else 0o644) << 16
                with open(full, "rb") as f:
                    z.writestr(info, f.read())
        os.chmod(tmp, 0o644)
        os.replace(tmp, fmu)
    except BaseException:
        os.unlink(tmp)
        raise


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--name", required=True)
    ap.add_argument("--root", required=True, help="the repository")
    ap.add_argument("--xml", required=True)
    ap.add_argument("--gen", required=True, help="the folder of the generated model_vars.c/.h")
    ap.add_argument("--tree", required=True)
    ap.add_argument("--fmu", required=True)
    ap.add_argument("--sources", nargs="*", default=[])
    ap.add_argument("--resources", nargs="*", default=[])
    ap.add_argument("--platform", default="x86_64-linux", choices=sorted(SHARED_LIBRARY_EXT),
                    help="the platform of the binary already in the tree (the build's own)")
    ap.add_argument("--fmi-version", "--fmi", dest="fmi_version", default="2", choices=("2", "3"),
                    help="the FMI version of the tree")
    ap.add_argument("--platform-dir", action="append", default=[], metavar="TUPLE=DIR",
                    help="a cross build's folder of <Name>.<ext> for platform TUPLE (DIR may be empty)")
    ap.add_argument("--win64-dir", default="", help="the same as --platform-dir x86_64-windows=DIR")
    ap.add_argument("--lsbus", default="", help="FMI 3.0: an FMI-LS-BUS network node's file "
                    "(modelDescription/lsbus/<Name>.xml): its bus terminal (src/fmi/lsbus_node.py)")
    a = ap.parse_args(argv)
    name, root, tree = a.name, os.path.abspath(a.root), os.path.abspath(a.tree)
    version = project_version(root)
    model_dir = os.path.join(root, "src", "models", name)
    if a.lsbus and not os.path.isdir(model_dir):     # a node's variant (variantOf=): the node's text and icon
        base = ET.parse(a.lsbus).getroot().get("variantOf")
        if base:
            model_dir = os.path.join(root, "src", "models", os.path.splitext(base)[0])

    own = os.path.join(tree, "binaries", binaries_folder(a.platform, a.fmi_version),
                       name + SHARED_LIBRARY_EXT[a.platform])
    if not os.path.isfile(own):
        sys.exit(f"package_fmu.py: {own} missing")

    # the cross builds' binaries, where their folders hold this FMU's
    platform_dirs = {"x86_64-windows": a.win64_dir}
    for item in a.platform_dir:
        platform, sep, d = item.partition("=")
        if platform == a.platform and sep and not d:
            continue        # the build's own platform, no cross build of it (a native ARM build)
        if not sep or platform not in SHARED_LIBRARY_EXT or platform == a.platform:
            sys.exit(f"package_fmu.py: --platform-dir {item!r}: not TUPLE=DIR with TUPLE one of "
                     f"{', '.join(p for p in SHARED_LIBRARY_EXT if p != a.platform)}")
        platform_dirs[platform] = d or platform_dirs.get(platform, "")
    files, system = closure(root, name, a.sources, a.fmi_version)
    # a cross build's binary older than what it is built from is another build's: never
    # packed silently beside this build's own binary
    inputs = [os.path.join(root, f) for f in files] + described_by(a.xml, a.lsbus, root) + [
        os.path.join(root, "src", "fmi", f) for f in ("ode.c", "ode.h", "gen_vars.py")]
    binaries = [own] + add_binaries(tree, name, platform_dirs, a.fmi_version, inputs, root)
    platforms = sorted(d for d in os.listdir(os.path.join(tree, "binaries")))
    libraries = ["artibus"]
    with_sundials = [os.path.basename(b) for b in binaries
                     if any(m in open(b, "rb").read() for m in SUNDIALS_MARKERS)]
    if with_sundials:
        libraries.append("SUNDIALS")
    if uses_eigen(root, files):
        libraries.append("Eigen")
    libraries.append("GCC")
    if "win64" in platforms or "x86_64-windows" in platforms:   # FMI 2.0's folder, FMI 3.0's tuple
        libraries.append("mingw-w64")
    why_not = needs_beyond_libc(files, system)

    tree_md = parse(a.xml)
    md = tree_md.getroot()
    try:
        order_elements(md)
    except ValueError as e:
        sys.exit(f"package_fmu.py: {a.xml}: {e}")
    set_metadata(md, version, libraries)
    add_display_units(md)
    indent_unit_children(md)

    # the plain parts of the tree, rebuilt each time
    for sub in ("documentation", "resources", "sources", "terminalsAndIcons", "extra"):
        p = os.path.join(tree, sub)
        if os.path.isdir(p):
            shutil.rmtree(p)
    for res in a.resources:
        copy(os.path.join(root, res), os.path.join(tree, "resources", os.path.basename(res)))
    os.makedirs(os.path.join(tree, "resources"), exist_ok=True)
    try:
        c_files = ship_sources(root, a.gen, tree, files, a.fmi_version) if why_not is None else []
    except ValueError as e:
        sys.exit(f"package_fmu.py: {name}: {e}")
    if c_files and a.fmi_version == "2":
        add_source_files(md, c_files)
    elif c_files:   # FMI 3.0 has no <SourceFiles>: the build description says it
        with open(os.path.join(tree, "sources", "buildDescription.xml"), "w", encoding="utf-8") as f:
            f.write(build_description(name, c_files))
    if a.fmi_version == "3":
        md3 = fmi3_description.fmi3_model_description(md, a.xml)
        if a.lsbus:
            lsbus_node.extend_fmi3(md3, a.lsbus, a.xml, tree)
        order_elements(md3)
        write_xml(ET.ElementTree(md3), os.path.join(tree, "modelDescription.xml"))
    else:
        write_xml(tree_md, os.path.join(tree, "modelDescription.xml"))

    icon = os.path.join(model_dir, "model.png")
    if os.path.isfile(icon):
        copy(icon, os.path.join(tree, "model.png"))
    elif os.path.exists(os.path.join(tree, "model.png")):
        os.unlink(os.path.join(tree, "model.png"))
    for lib in libraries:
        src, fname = LICENSE_FILES[lib]
        copy(os.path.join(root, src), os.path.join(tree, "documentation", "licenses", fname))
    readme_path = os.path.join(model_dir, "README.md")
    readme = open(readme_path, encoding="utf-8").read() if os.path.isfile(readme_path) else ""
    page = documentation(md, name, readme, libraries, platforms, c_files, version, why_not, with_sundials,
                         fmi_version="3.0" if a.fmi_version == "3" else None,
                         papers=load_papers(root))
    with open(os.path.join(tree, "documentation", "index.html"), "w", encoding="utf-8") as f:
        f.write(page)

    zip_tree(tree, a.fmu)
    return 0


if __name__ == "__main__":
    sys.exit(main())
