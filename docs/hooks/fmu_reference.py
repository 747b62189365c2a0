"""MkDocs hook: the FMU reference, one page per FMU, made at build time.

Each page ``fmus/<Name>.md`` comes from ``modelDescription/<Name>.xml`` (the
single source of an FMU's variables) and ``src/models/<Name>/README.md`` (its
text), as the FMU's own ``documentation/index.html`` does
(``src/fmi/package_fmu.py``): the same display units (that module's
``add_display_units``) and, per causality, the same columns: name, type, unit,
display unit, start, min, max, variability, description. No generated page is
kept in the repository: ``on_files`` adds them as generated files, ``on_config``
puts them into the nav under "FMU reference", after its hand-written pages.
"""
import html
import importlib.util
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[2]
SECTION = "FMU reference"
DIR = "fmus"

_package_fmu = None


def package_fmu():
    """src/fmi/package_fmu.py as a module (a script, not part of a package)."""
    global _package_fmu
    if _package_fmu is None:
        spec = importlib.util.spec_from_file_location("package_fmu", ROOT / "src" / "fmi" / "package_fmu.py")
        _package_fmu = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(_package_fmu)
    return _package_fmu


def fmu_names():
    return sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))


def cell(text):
    """Text for a Markdown table cell: HTML escaped, no table or emphasis syntax."""
    s = html.escape(" ".join(str(text).split()), quote=False)
    return re.sub(r"([|*_\[\]`\\])", r"\\\1", s)


def code(text):
    return f"<code>{html.escape(text)}</code>" if text else ""


def number(value, display):
    """'0.75' and the display unit (deg, factor, offset) -> '0.75 (42.9718 deg)'."""
    if not value:
        return ""
    if display is None:
        return cell(value)
    try:
        y = display[1] * float(value) + display[2]
    except ValueError:
        return cell(value)
    return f"{cell(value)} ({y:.6g} {cell(display[0])})"


def variable_tables(md):
    units = {}
    for u in md.iter("Unit"):
        for d in u.findall("DisplayUnit"):
            units[(u.get("name"), d.get("name"))] = (d.get("name"), float(d.get("factor", "1")),
                                                      float(d.get("offset", "0")))
    types = {t.get("name"): next((c for c in t if isinstance(c.tag, str)), None)
             for t in md.iter("SimpleType")}
    out = []
    for causality, title in package_fmu().CAUSALITY_TITLES:
        svs = [sv for sv in md.iter("ScalarVariable") if sv.get("causality", "local") == causality]
        if not svs:
            continue
        out += [f"## {title} ({len(svs)}) {{#{causality}}}", "",
                "| name | type | unit | display unit | start | min | max | variability | description |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for sv in svs:
            t = next(c for c in sv if isinstance(c.tag, str))
            declared = types.get(t.get("declaredType"))
            def attr(a):
                return t.get(a) or (declared.get(a) if declared is not None else None) or ""
            unit, disp = attr("unit"), attr("displayUnit")
            du = units.get((unit, disp))
            kind = t.tag + (f" ({t.get('declaredType')})" if t.get("declaredType") else "")
            out.append("| " + " | ".join([
                code(sv.get("name")), cell(kind), cell(unit), cell(disp),
                number(t.get("start", ""), du), number(attr("min"), du), number(attr("max"), du),
                cell(sv.get("variability", "continuous")), cell(sv.get("description", ""))]) + " |")
        out.append("")
    enums = package_fmu().enumerations(md)
    if enums:
        out += [f"## Enumerations ({len(enums)}) {{#enumerations}}", ""]
        for tname, (tdesc, items) in enums.items():
            out += [f"### {tname}", "", cell(tdesc), "", "| value | item | description |", "| --- | --- | --- |"]
            out += [f"| {cell(v)} | {code(n)} | {cell(d)} |" for n, v, d in items]
            out.append("")
    return out


def page(name):
    pf = package_fmu()
    tree = pf.parse(ROOT / "modelDescription" / f"{name}.xml")
    md = tree.getroot()
    pf.add_display_units(md)            # the display units the packed FMU declares
    readme = ROOT / "src" / "models" / name / "README.md"
    text = readme.read_text(encoding="utf-8") if readme.is_file() else f"# {name}\n"
    lines = text.splitlines()
    title, body = (lines[0], lines[1:]) if lines and lines[0].startswith("# ") else (f"# {name}", lines)

    interfaces = [label for kind, label in (("CoSimulation", "Co-Simulation"), ("ModelExchange", "Model Exchange"))
                  if md.find(kind) is not None]
    de = md.find("DefaultExperiment")
    meta = [("FMI version", f"{md.get('fmiVersion')} ({', '.join(interfaces)})"),
            ("model name", md.get("modelName", name)),
            ("GUID", md.get("guid", ""))]
    if de is not None:
        meta.append(("default experiment", ", ".join(f"{k} = {v}" for k, v in de.attrib.items())))
    meta.append(("run it alone", f"<code>.venv/bin/fmpy simulate fmus/{html.escape(name)}.fmu --output-file out/{html.escape(name)}.csv</code> "
                 "(from the repository root, after <code>./run.sh</code>)"))
    rows = [f"| {k} | {v if k == 'run it alone' else cell(v)} |" for k, v in meta]
    out = [title, "", cell(md.get("description", "")), "", rows[0], "| --- | --- |", *rows[1:]]
    out += ["", *body, ""]
    out += variable_tables(md)
    out += [f"*Generated when the site is built, from `modelDescription/{name}.xml` and "
            f"`src/models/{name}/README.md`, as the FMU's own `documentation/index.html` is. "
            "Display units: value in display unit = factor x value + offset, as the packed FMU's "
            "`<UnitDefinitions>` declare them.*", ""]
    return "\n".join(out)


def _section(nav):
    for entry in nav or []:
        if isinstance(entry, dict) and SECTION in entry:
            return entry
    raise ValueError(f"mkdocs.yml: the nav has no section '{SECTION}' for the generated FMU pages")


def on_config(config):
    entry = _section(config["nav"])
    pages = entry[SECTION] if isinstance(entry[SECTION], list) else [entry[SECTION]]
    known = {p if isinstance(p, str) else next(iter(p.values())) for p in pages}
    pages += [{name: f"{DIR}/{name}.md"} for name in fmu_names() if f"{DIR}/{name}.md" not in known]
    entry[SECTION] = pages
    return config


def on_files(files, config):
    for name in fmu_names():
        files.append(File.generated(config, f"{DIR}/{name}.md", content=page(name)))
    return files
