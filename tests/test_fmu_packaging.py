"""What every FMU carries for an OEM toolchain (issue 14): the archive's contents
(binaries, documentation, licence notices, icon), the model description's metadata and
display units on top of the repository's XML, documentation listing every variable, and,
for the models that need only the C library, sources that compile to a binary giving the
same results as the shipped one. Packed by src/fmi/package_fmu.py."""
import importlib.util
import math
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from html.parser import HTMLParser
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from conftest import FMU_NAMES, ROOT, fmu_file, packer_inputs

# the version is written once, in artibus.base (pyproject.toml: dynamic = ["version"])
VERSION = re.search(r'^__version__ = "([^"]+)"$', (ROOT / "src" / "artibus" / "base.py").read_text(), re.M).group(1)

#: the display units an engineer expects, with their factors derived here, not read from the
#: packer: display value = factor * value (FMI 2.0, 2.2.2)
EXPECTED_DISPLAY = {
    ("rad", "deg"): 180.0 / math.pi,
    ("rad/s", "deg/s"): 180.0 / math.pi,
    ("m/s", "km/h"): 3600.0 / 1000.0,
    ("N", "kN"): 1.0 / 1000.0,
    ("N.m", "kN.m"): 1.0 / 1000.0,
}

#: the controllers and ECUs of the brief: plain C, so their sources must be inside
MUST_SHIP_SOURCES = {"TrainGuidance", "ForceMinimization", "DampingController", "SwayBaseline",
                     "SteeringECU", "SteeringActuator", "ZeroSideslipSteering"}

SYSTEM_LIBS = {"linux-vdso.so.1", "libc.so.6", "libm.so.6", "ld-linux-x86-64.so.2"}


def _model_files(name):
    return [p for p in (ROOT / "src" / "models" / name).iterdir() if p.is_file()]


def _uses_sundials(name):
    """the model integrates (the shared layer's ode.h, which wraps SUNDIALS)"""
    return any(p.suffix in (".c", ".cpp", ".h") and '#include "ode.h"' in p.read_text()
               for p in _model_files(name))


def _uses_eigen(name):
    return any(p.suffix in (".cpp", ".h", ".hpp") and "#include <Eigen/" in p.read_text()
               for p in _model_files(name))


def _fmu(name, fmi=2):
    """the FMI 2.0 FMU, or the FMI 3.0 one (fmus/fmi3/)"""
    if fmi == 2:
        return fmu_file(name)
    path = fmu_file(name).parent / "fmi3" / f"{name}.fmu"
    assert path.is_file(), f"{path} not built"
    return path


def _names(name, fmi=2):
    with zipfile.ZipFile(_fmu(name, fmi)) as z:
        return set(z.namelist())


def _read(name, member, fmi=2):
    with zipfile.ZipFile(_fmu(name, fmi)) as z:
        return z.read(member)


def _packed_md(name):
    return ET.fromstring(_read(name, "modelDescription.xml"))


def _repo_md(name):
    return ET.parse(ROOT / "modelDescription" / f"{name}.xml").getroot()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_archive_lists_binaries_documentation_licences_icon(name):
    names = _names(name)
    assert f"binaries/linux64/{name}.so" in names
    assert "documentation/index.html" in names
    assert "documentation/licenses/artibus-BSD-2-Clause.txt" in names
    assert "model.png" in names
    # the notices of what the binaries contain: SUNDIALS where its code is linked in (its
    # symbols in the shared object, its messages in a stripped DLL), Eigen where the model is
    # C++ with Eigen
    sundials = any(marker in _read(name, member) for member in names if member.startswith("binaries/")
                   for marker in (b"CVodeCreate", b"cvode_mem", b"arkode_mem"))
    assert ("documentation/licenses/SUNDIALS-BSD-3-Clause.txt" in names) == sundials
    assert ("documentation/licenses/Eigen-MPL-2.0.txt" in names) == _uses_eigen(name)
    if _uses_sundials(name):
        assert "documentation/licenses/SUNDIALS-BSD-3-Clause.txt" in names
    # the repository's copies are what is shipped
    assert _read(name, "documentation/licenses/artibus-BSD-2-Clause.txt") == (ROOT / "LICENSE").read_bytes()
    for member in names:
        if member.startswith("documentation/licenses/") and "artibus" not in member:
            assert _read(name, member) == (ROOT / "licenses" / member.rsplit("/", 1)[1]).read_bytes()
    # win64 and aarch64-linux only as the cross builds' binaries, nothing else under binaries/
    for member in names:
        if member.startswith("binaries/"):
            assert member in (f"binaries/linux64/{name}.so", f"binaries/win64/{name}.dll",
                              f"binaries/aarch64-linux/{name}.so"), member


@pytest.mark.parametrize("name", FMU_NAMES)
def test_icon_is_the_models_png(name):
    png = _read(name, "model.png")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
    assert 32 <= width <= 512 and 32 <= height <= 512
    assert png == (ROOT / "src" / "models" / name / "model.png").read_bytes()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_metadata(name):
    md = _packed_md(name)
    assert md.get("version") == VERSION
    assert md.get("generationTool") == f"artibus {VERSION}"
    assert md.get("author")
    assert "artibus" in md.get("copyright") and re.search(r"\b20\d\d\b", md.get("copyright"))
    assert "BSD-2-Clause" in md.get("license")
    assert ("MPL-2.0" in md.get("license")) == _uses_eigen(name)
    # no build time stamp unless the build asks for a reproducible one
    if "SOURCE_DATE_EPOCH" not in os.environ:
        assert md.get("generationDateAndTime") is None
    fmpy_md = read_model_description(str(fmu_file(name)))
    assert fmpy_md.version == VERSION and fmpy_md.author == md.get("author")


def _strip(el, drop_attrs=("displayUnit",), drop_children=("DisplayUnit", "SourceFiles")):
    """an element as comparable data, leaving out what the packer adds"""
    return (el.tag, {k: v for k, v in el.attrib.items() if k not in drop_attrs},
            (el.text or "").strip(),
            [_strip(c, drop_attrs, drop_children) for c in el
             if isinstance(c.tag, str) and c.tag not in drop_children])


@pytest.mark.parametrize("name", FMU_NAMES)
def test_packed_description_is_the_repository_xml_plus_additions(name):
    """everything in modelDescription/<Name>.xml is kept as written (another interface
    element, every variable, the model structure); only metadata, display units and
    source files are added"""
    repo, packed = _repo_md(name), _packed_md(name)
    meta = ("author", "version", "copyright", "license", "generationTool", "generationDateAndTime")
    for k, v in repo.attrib.items():
        if k not in meta:
            assert packed.get(k) == v, k
    # the top-level elements as the schema orders them (the packer does, test_element_order)
    order = _schema_order(repo.get("fmiVersion"))
    children = sorted((c for c in repo if isinstance(c.tag, str)), key=lambda c: order.index(c.tag))
    for c in list(repo):
        repo.remove(c)
    repo.extend(children)
    assert _strip(packed, meta + ("displayUnit",)) == _strip(repo, meta + ("displayUnit",))


XS = "{http://www.w3.org/2001/XMLSchema}"


def _schema_order(fmi_version):
    """the children of <fmiModelDescription> in the order of the FMI version's XSD (FMPy's
    copy of the standard's schema)"""
    major = fmi_version.split(".")[0]
    xsd = Path(fmpy.__file__).parent / "schema" / f"fmi{major}" / f"fmi{major}ModelDescription.xsd"
    root = next(e for e in ET.parse(xsd).iter(XS + "element") if e.get("name") == "fmiModelDescription")

    def walk(node):
        for c in node:
            if c.tag == XS + "element":
                yield c.get("name") or c.get("ref")
            elif c.tag in (XS + "complexType", XS + "sequence", XS + "choice", XS + "all"):
                yield from walk(c)
    return tuple(walk(root))


def _packer():
    spec = importlib.util.spec_from_file_location("package_fmu", ROOT / "src/fmi/package_fmu.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_packer_element_order_is_the_schemas():
    """the packer's table of element order per FMI version (FMI 2.0, and FMI 3.0 for the
    builds to come) is the order of the standard's XSDs"""
    order = _packer().ELEMENT_ORDER
    assert order["2"] == _schema_order("2.0")
    assert order["3"] == _schema_order("3.0")
    for version in order.values():
        assert version.index("ModelExchange") < version.index("CoSimulation")


@pytest.mark.parametrize("name", FMU_NAMES)
def test_element_order(name):
    """Model Exchange before Co-Simulation, every element in the schema's order, none twice
    (the FMI Library, under libcosim, PyFMI, OMSimulator, skips a ModelExchange after
    CoSimulation with an error; FMPy's XSD check allows it: issue 29)"""
    md = _packed_md(name)
    order = _schema_order(md.get("fmiVersion"))
    tags = [c.tag for c in md if isinstance(c.tag, str)]
    assert [order.index(t) for t in tags] == sorted({order.index(t) for t in tags}), tags


def test_packer_writes_model_exchange_first(tmp_path):
    """a model description written with CoSimulation first is packed in the schema's order:
    the same modelDescription.xml as the one written in order (comments and layout kept)"""
    name = "BusKinematics"
    src = (ROOT / "modelDescription" / f"{name}.xml").read_text(encoding="utf-8")
    me = re.search(r"^  <ModelExchange [^\n]*/>\n", src, re.M).group(0)
    cs = re.search(r"^  <CoSimulation [^\n]*/>\n", src, re.M).group(0)
    assert src.index(me) < src.index(cs)
    old = src.replace(me + cs, cs + me)
    assert old != src
    xml = tmp_path / f"{name}.xml"
    xml.write_text(old, encoding="utf-8")
    tree = tmp_path / "tree"
    with zipfile.ZipFile(fmu_file(name)) as z:
        z.extractall(tree)
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "SOURCE_DATE_EPOCH")}
    win64 = tmp_path / "win64"           # the cross build's folder, as the build passes it (its DLL, so
    win64.mkdir()                        # the licences name the same runtimes)
    dll = tree / "binaries" / "win64" / f"{name}.dll"
    if dll.is_file():
        shutil.copy(dll, win64 / dll.name)
    subprocess.run([sys.executable, str(ROOT / "src/fmi/package_fmu.py"), "--name", name,
                    "--root", str(ROOT), "--xml", str(xml), "--gen", str(tmp_path), "--tree", str(tree),
                    "--fmu", str(tmp_path / "out.fmu"), f"--win64-dir={win64}",
                    "--sources", f"src/models/{name}/model.c", f"src/models/{name}/kinematics.c",
                    "--resources"], check=True, env=env)
    with zipfile.ZipFile(tmp_path / "out.fmu") as z:
        packed = z.read("modelDescription.xml")
    assert packed == _read(name, "modelDescription.xml")


@pytest.mark.parametrize("name", FMU_NAMES)
def test_display_units_defined_and_right(name):
    md = _packed_md(name)
    display = {}
    for u in md.iter("Unit"):
        for d in u.findall("DisplayUnit"):
            key = (u.get("name"), d.get("name"))
            assert key in EXPECTED_DISPLAY, key
            assert float(d.get("factor", "1")) == pytest.approx(EXPECTED_DISPLAY[key], rel=1e-15)
            assert float(d.get("offset", "0")) == 0.0
            display[key] = d
    used = set()
    n_display = 0
    for sv in md.iter("ScalarVariable"):
        real = sv.find("Real")
        if real is None or real.get("displayUnit") is None:
            continue
        key = (real.get("unit"), real.get("displayUnit"))
        assert key in display, f"{sv.get('name')}: display unit {key} not defined"
        used.add(key)
        n_display += 1
    assert used == set(display), "a DisplayUnit no variable uses"
    # every angle is shown in degrees
    for sv in md.iter("ScalarVariable"):
        real = sv.find("Real")
        if real is not None and real.get("unit") in ("rad", "rad/s"):
            assert real.get("displayUnit") in ("deg", "deg/s"), sv.get("name")
    # FMPy reads them (what a tool's parameter dialogue shows)
    fmpy_md = read_model_description(str(fmu_file(name)))
    for unit in fmpy_md.unitDefinitions:
        for du in unit.displayUnits:
            assert du.factor == pytest.approx(EXPECTED_DISPLAY[(unit.name, du.name)], rel=1e-15)


def test_display_units_only_where_they_read_well():
    """a road speed in km/h, a lateral or piston velocity not; forces in kN"""
    def du(name, var):
        for sv in _packed_md(name).iter("ScalarVariable"):
            if sv.get("name") == var:
                return sv.find("Real").get("displayUnit")
        raise KeyError(var)
    assert du("BusDynamics", "vx[1]") == "km/h" and du("BusDynamics", "v") == "km/h"
    assert du("BusDynamics", "vy[1]") is None and du("BusDynamics", "vy_start") is None
    assert du("MultiAxle3DOF", "v") is None          # lateral velocity there
    assert du("MultiAxle3DOF", "u") == "km/h"
    assert du("ArticulationDamper", "Ldot[1]") is None and du("ArticulationDamper", "v0") is None
    assert du("BusDynamics", "Fy[1]") == "kN" and du("ArticulationDamper", "Mjoint") == "kN.m"
    assert du("BusDynamics", "artAngle[1]") == "deg"


class _Rows(HTMLParser):
    """the cell texts of every table row"""
    def __init__(self):
        super().__init__()
        self.rows, self._row, self._cell = [], None, None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_documentation_lists_every_variable(name):
    page = _read(name, "documentation/index.html").decode("utf-8")
    parser = _Rows()
    parser.feed(page)
    rows = {r[0]: r for r in parser.rows if len(r) == 9}
    header = next(r for r in parser.rows if len(r) == 9 and r[0] == "name")
    # every enumeration of the model description, with each item's value, name and description
    items = {st.get("name"): {i.get("value"): i.get("name") for i in st.iter("Item")}
             for st in _repo_md(name).iter("SimpleType") if st.find("Enumeration") is not None}
    for tname, by_value in items.items():
        assert f'<h3 id="type-{tname}">{tname}</h3>' in page, tname
        table = page.split(f'<h3 id="type-{tname}">', 1)[1].split("</table>", 1)[0]
        for value, item in by_value.items():
            assert f'<td class="num">{value}</td><td class="name">{item}</td>' in table, (tname, item)
    assert header[:5] == ["name", "type", "unit", "display unit", "start"]
    for sv in _repo_md(name).iter("ScalarVariable"):
        t = next(c for c in sv if isinstance(c.tag, str))
        row = rows.get(sv.get("name"))
        assert row is not None, f"{sv.get('name')} not in index.html"
        if t.tag == "Enumeration":      # the type, and the start value's item name after it
            assert row[1] == f"Enumeration {t.get('declaredType')}"
            if t.get("start") is not None:
                assert row[4] == f"{t.get('start')} ({items[t.get('declaredType')][t.get('start')]})", row
        else:
            assert row[1] == t.tag
        assert row[2] == t.get("unit", "")
        # the value as written, then its display-unit value in brackets where it has one
        for col, attr in ((4, "start"), (5, "min"), (6, "max")):
            if t.get(attr) is not None:
                assert row[col] == t.get(attr) or row[col].startswith(t.get(attr) + " ("), (attr, row)
        # the papers as numbered references (tests/test_fmu_documentation.py checks them)
        refs = re.compile(r"\b[Ss]eeds? \d{3}\b|\bref\. \d+\b")
        assert refs.sub("REF", row[8]) == refs.sub("REF", sv.get("description", ""))
    # the model's own text is in it, and the licences are linked
    readme = (ROOT / "src" / "models" / name / "README.md").read_text()
    first_heading = next(line.lstrip("#").strip() for line in readme.splitlines() if line.startswith("#"))
    assert first_heading.replace("`", "") in re.sub(r"<[^>]+>", "", page)
    assert 'href="licenses/artibus-BSD-2-Clause.txt"' in page
    assert "<script" not in page


def _ships_sources(name):
    return not _uses_sundials(name) and not any(p.suffix == ".cpp" for p in _model_files(name))


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_controllers_ship_sources(fmi):
    """the models that need only the C library ship sources/ in both FMI versions; the plants
    (SUNDIALS, Eigen) do not, and their documentation says why"""
    assert MUST_SHIP_SOURCES <= set(FMU_NAMES)
    for name in FMU_NAMES:
        has = any(n.startswith("sources/") for n in _names(name, fmi))
        assert has == _ships_sources(name), name
        assert (name in MUST_SHIP_SOURCES) <= has
        page = _read(name, "documentation/index.html", fmi).decode()
        if not has:
            why = re.search(r"<th>sources</th><td>not shipped: ([^<]*)</td>", page)
            assert why, name
            if _uses_sundials(name):
                assert "SUNDIALS" in why.group(1), name
            if _uses_eigen(name):
                assert "Eigen" in why.group(1), name


def _stimulus(md, t):
    """every Real input moved within its range: a sine around its start value"""
    cols = []
    for k, v in enumerate(md.modelVariables):
        if v.causality != "input" or v.type not in ("Real", "Float64"):
            continue
        start = float(v.start or 0.0)
        lo = float(v.min) if v.min is not None else -math.inf
        hi = float(v.max) if v.max is not None else math.inf
        u = start + 0.1 * (1.0 + abs(start)) * np.sin(2 * np.pi * t / 3.0 + k)
        cols.append((v.name, np.clip(u, lo, hi)))
    return cols


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", [n for n in FMU_NAMES if _ships_sources(n)])
def test_sources_are_one_flat_set(name, fmi):
    """sources/ is one folder, the only include path: every file of <SourceFiles> (FMI 2.0) or
    of sources/buildDescription.xml's one source file set (FMI 3.0, 2.5.1.2, valid against
    fmi3BuildDescription.xsd) is in it, every local #include of every file there names a file
    there, and the FMI headers are not shipped (FMI 2.0.4, 2.3; FMI 3.0, 2.5.1: the importer's
    own are used)"""
    names = _names(name, fmi)
    shipped = {n[len("sources/"):] for n in names if n.startswith("sources/") and n != "sources/"}
    assert shipped and all("/" not in f for f in shipped), sorted(shipped)
    assert not shipped & {f"fmi{fmi}Functions.h", f"fmi{fmi}FunctionTypes.h",
                          "fmi2TypesPlatform.h", "fmi3PlatformTypes.h"}
    md = read_model_description(str(_fmu(name, fmi)), validate=True)
    assert len(md.buildConfigurations) == 1 and len(md.buildConfigurations[0].sourceFileSets) == 1
    fset = md.buildConfigurations[0].sourceFileSets[0]
    files = fset.sourceFiles
    assert files[0] == f"fmi{fmi}Functions.c" and "model_vars.c" in files
    assert set(files) <= shipped
    assert {f for f in shipped if f.endswith(".c")} == set(files)   # nothing left uncompiled
    if fmi == 3:
        assert "buildDescription.xml" in shipped
        assert md.buildConfigurations[0].modelIdentifier == name and fset.language == "C99"
        assert [(d.name, d.value) for d in fset.preprocessorDefinitions] == [("FMI_VERSION", "3")]
        assert fset.includeDirectories == ["."]
    # the table says the FMI version itself (model_vars.h), for an importer that passes no -D
    assert f"#define MODEL_FMI_VERSION {fmi}\n" in _read(name, "sources/model_vars.h", fmi).decode()
    for f in shipped:
        for inc in re.findall(r'^\s*#\s*include\s*"([^"]+)"', _read(name, f"sources/{f}", fmi).decode(), re.M):
            # the FMI headers are the importer's: fmu.h includes FMI 2.0's or 3.0's by FMI_VERSION
            assert inc in shipped or inc.startswith(("fmi2", "fmi3")), (f, inc)


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", [n for n in FMU_NAMES if _ships_sources(n)])
def test_fmpy_compile_gives_the_shipped_results(name, fmi, tmp_path):
    """A copy of the FMU with its binaries removed, compiled by `fmpy compile` (FMPy's CMake
    project: the first source file set, its preprocessor definitions, sources/ and FMPy's FMI
    headers as the include path, warnings as errors), gets a linux64 (FMI 3.0: x86_64-linux)
    binary that needs only libc/libm and exports the unprefixed fmiN* functions only, and
    gives the shipped binary's results bit for bit on a co-simulation of (at most 3 s of) its
    default experiment with every input moving"""
    if not shutil.which("cmake"):
        pytest.skip("cmake is not installed (fmpy compile runs it; scripts/setup.sh installs it)")
    shipped_fmu = _fmu(name, fmi)
    copy = tmp_path / f"{name}.fmu"
    with zipfile.ZipFile(shipped_fmu) as zin, zipfile.ZipFile(copy, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            if not item.filename.startswith("binaries/"):
                zout.writestr(item, zin.read(item))
    assert fmpy.supported_platforms(str(copy)) == ["c-code"]
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    out = subprocess.run([sys.executable, "-m", "fmpy.cli", "compile", "--warning-as-error", str(copy)],
                         capture_output=True, text=True, env=env, cwd=tmp_path)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    folder = "linux64" if fmi == 2 else "x86_64-linux"
    with zipfile.ZipFile(copy) as z:
        assert f"binaries/{folder}/{name}.so" in z.namelist()
        so = tmp_path / f"{name}.so"
        so.write_bytes(z.read(f"binaries/{folder}/{name}.so"))
    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True, env=env).stdout
    libs = {line.split()[0].rsplit("/", 1)[-1] for line in ldd.splitlines() if line.strip()}
    assert libs <= SYSTEM_LIBS, libs
    if shutil.which("nm"):
        # every function of the standard's header, by its own name (no FMIn_FUNCTION_PREFIX:
        # FMI 2.0.4, 2.1.1; FMI 3.0, 2.2.1), and no prefixed one
        nm = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True,
                            check=True, env=env).stdout
        exported = {line.split()[-1] for line in nm.splitlines() if line.split()[1:2] == ["T"]}
        header = (ROOT / f"include/fmi{fmi}/fmi{fmi}Functions.h").read_text()
        api = set(re.findall(rf"FMI{fmi}_Export\s+\w+TYPE\s+(fmi{fmi}\w+);", header))
        assert len(api) > 20 and api <= exported, sorted(api - exported)
        assert not [f for f in exported if re.search(rf"\w+_fmi{fmi}[A-Z]", f)]

    md = read_model_description(str(shipped_fmu))
    stop = min(float(md.defaultExperiment.stopTime), 3.0)
    step = float(md.defaultExperiment.stepSize or 0.01)
    t = np.arange(0.0, stop + step, step)
    cols = _stimulus(md, t)
    inputs = None
    if cols:
        inputs = np.array(list(zip(t, *[c[1] for c in cols])),
                          dtype=[("time", np.float64)] + [(c[0], np.float64) for c in cols])
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type != "String"]
    kw = dict(stop_time=stop, output_interval=step, input=inputs, output=outputs, fmi_type="CoSimulation")
    shipped = simulate_fmu(str(shipped_fmu), **kw)
    ours = simulate_fmu(str(copy), **kw)
    assert len(shipped) == len(t) or len(shipped) > 10
    moved = False
    for v in outputs:
        a, b = shipped[v], ours[v]
        assert np.array_equal(a, b), f"{v}: largest difference {np.max(np.abs(a - b))}"
        moved |= bool(np.ptp(a.astype(float)) > 0)
    assert moved, "no output moved: the comparison would say nothing"


def test_build_description_is_valid_fmi3(tmp_path):
    """the FMI 3.0 sources/buildDescription.xml the packer writes (for the FMI 3.0 build)
    passes FMI 3.0's fmi3BuildDescription.xsd (FMPy's copy) and FMPy reads back the files,
    the language and the one include directory"""
    spec = importlib.util.spec_from_file_location("package_fmu", ROOT / "src/fmi/package_fmu.py")
    pf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(pf)
    files = ["fmi3Functions.c", "model.c", "guidance.c", "model_vars.c"]
    xml = tmp_path / "buildDescription.xml"
    xml.write_text(pf.build_description("TrainGuidance", files), encoding="utf-8")
    from fmpy.model_description import read_build_description
    (conf,) = read_build_description(str(xml), validate=True)
    assert conf.modelIdentifier == "TrainGuidance"
    (fset,) = conf.sourceFileSets
    assert fset.sourceFiles == files and fset.language == "C99" and fset.includeDirectories == ["."]
    # the binaries/ folders by FMI version (FMI 2.0.4, 2.3; FMI 3.0, 2.5.1.1)
    assert [pf.binaries_folder(p, "2") for p in ("x86_64-linux", "x86_64-windows", "aarch64-linux")] \
        == ["linux64", "win64", "aarch64-linux"]
    assert [pf.binaries_folder(p, "3") for p in ("x86_64-linux", "x86_64-windows", "aarch64-linux")] \
        == ["x86_64-linux", "x86_64-windows", "aarch64-linux"]
    with pytest.raises(ValueError, match="sparc"):
        pf.binaries_folder("sparc-solaris")


def test_packer_win64_hook_and_reproducible(tmp_path):
    """ARTIBUS_WIN64_DIR: a folder holding <Name>.dll gives binaries/win64/<Name>.dll, one
    without it none; the same inputs give the same bytes; SOURCE_DATE_EPOCH gives the
    generation time"""
    name = "TrainGuidance"
    tree, gen = packer_inputs(fmu_file(name), tmp_path)
    win = tmp_path / "win64"
    win.mkdir()
    dll = b"MZ not really a DLL, just what the mingw build would leave here"
    (win / f"{name}.dll").write_bytes(dll)
    sources = ["src/models/TrainGuidance/model.c", "src/models/TrainGuidance/guidance.c"]
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "SOURCE_DATE_EPOCH")}

    def pack(out, win64="", extra_env=None):
        subprocess.run([sys.executable, str(ROOT / "src/fmi/package_fmu.py"), "--name", name,
                        "--root", str(ROOT), "--xml", str(ROOT / "modelDescription" / f"{name}.xml"),
                        "--gen", str(gen), "--tree", str(tree), "--fmu", str(out),
                        f"--win64-dir={win64}", "--sources", *sources, "--resources"],
                       check=True, env={**env, **(extra_env or {})})
        return out.read_bytes()

    with_dll = pack(tmp_path / "a.fmu", str(win))
    with zipfile.ZipFile(tmp_path / "a.fmu") as z:
        assert z.read(f"binaries/win64/{name}.dll") == dll
        assert "binaries/win64" in z.read("documentation/index.html").decode()
    without = pack(tmp_path / "b.fmu", str(tmp_path / "empty"))
    with zipfile.ZipFile(tmp_path / "b.fmu") as z:
        assert not any(n.startswith("binaries/win64") for n in z.namelist())
    assert pack(tmp_path / "c.fmu") == without
    assert with_dll != without
    pack(tmp_path / "d.fmu", extra_env={"SOURCE_DATE_EPOCH": "1767225600"})
    with zipfile.ZipFile(tmp_path / "d.fmu") as z:
        md = ET.fromstring(z.read("modelDescription.xml"))
    assert md.get("generationDateAndTime") == "2026-01-01T00:00:00Z"


def test_packer_platform_dirs(tmp_path):
    """--platform-dir TUPLE=DIR packs DIR/<Name>.<ext> into the folder the FMI version names
    (FMI 2.0: aarch64-linux keeps its FMI 3.0 tuple, x86_64-windows is win64); an empty or
    missing one leaves the folder out (an old one removed); an unknown tuple is refused with
    a message naming it, no traceback"""
    name = "TrainGuidance"
    tree, gen = packer_inputs(fmu_file(name), tmp_path)
    arm, win = tmp_path / "arm", tmp_path / "win"
    arm.mkdir()
    win.mkdir()
    so = b"\x7fELF not really an aarch64 shared object"
    (arm / f"{name}.so").write_bytes(so)
    (win / f"{name}.dll").write_bytes(b"MZ")
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "SOURCE_DATE_EPOCH")}

    def pack(out, *dirs):
        return subprocess.run([sys.executable, str(ROOT / "src/fmi/package_fmu.py"), "--name", name,
                               "--root", str(ROOT), "--xml", str(ROOT / "modelDescription" / f"{name}.xml"),
                               "--gen", str(gen), "--tree", str(tree), "--fmu", str(out),
                               "--platform", "x86_64-linux", "--fmi-version", "2",
                               *[f"--platform-dir={d}" for d in dirs],
                               "--sources", "src/models/TrainGuidance/model.c",
                               "src/models/TrainGuidance/guidance.c", "--resources"],
                              capture_output=True, text=True, env=env)

    assert pack(tmp_path / "a.fmu", f"aarch64-linux={arm}", f"x86_64-windows={win}").returncode == 0
    with zipfile.ZipFile(tmp_path / "a.fmu") as z:
        assert z.read(f"binaries/aarch64-linux/{name}.so") == so
        assert z.read(f"binaries/win64/{name}.dll") == b"MZ"
        assert "binaries/aarch64-linux" in z.read("documentation/index.html").decode()
    assert pack(tmp_path / "b.fmu", "aarch64-linux=", f"x86_64-windows={tmp_path / 'none'}").returncode == 0
    with zipfile.ZipFile(tmp_path / "b.fmu") as z:
        assert sorted({n.split("/")[1] for n in z.namelist() if n.startswith("binaries/")}) == ["linux64"]
    bad = pack(tmp_path / "c.fmu", f"sparc-solaris={arm}")
    assert bad.returncode != 0 and "sparc-solaris" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "c.fmu").exists()
