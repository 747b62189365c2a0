"""What a user installs (issue 42): a wheel made from the clone after the set-up
carries the built FMUs (fmus/, fmus/fmi3/), the benches (ssp/) and the stepping
core's libraries as package data; installed into a fresh venv in another folder,
`artibus list`, `run BENCH --report` (KPIs graded) and `simulate FMU` find them
inside the package, $ARTIBUS_FMU_DIR still overrides; a clone without built FMUs
stops `pip wheel`/`pip install .` with a message saying what to run; the version
is written in one place.

Nothing is downloaded: the wheel is built without build isolation (the set-up puts
setuptools >= 77 in .venv) and installed with --no-index --no-deps; the fresh venv
sees .venv's third-party packages through a .pth file appended after its own
site-packages, so the artibus it imports is the wheel's (checked). The expected
facts come from the clone's files (ssp/benches/*, fmus/*.fmu, the model
descriptions' DefaultExperiment), not from artibus."""
import os
import re
import shutil
import site
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest
from lxml import etree

from artibus.base import ROOT
from conftest import exclusive

pytestmark = pytest.mark.slow

FMUS = ROOT / "fmus"
BENCHES = sorted(p.parent.name for p in (ROOT / "ssp" / "benches").glob("*/SystemStructure.ssd"))
PIP = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-input"]


def _run(cmd, cwd, env=None, timeout=120):
    """cmd run in cwd; (exit code, stdout + stderr)."""
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    return r.returncode, r.stdout + r.stderr


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The wheel `pip wheel <clone> --no-deps -w DIR` makes from the clone as the set-up left it."""
    if not (FMUS / "BusDynamics.fmu").is_file():
        pytest.skip("the FMUs are not built (the set-up)")
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:
        return _wheel_into(tmp_path_factory.mktemp("dist"))
    # pytest-xdist: each worker running this module's tests has the fixture, and two `pip wheel`
    # of the clone at once collide in its one scratch folder, build-wheel/ ("File exists:
    # 'build-wheel/bdist.linux-x86_64/wheel/artibus-0.1.0.dist-info'"): the first worker makes
    # the run's wheel, under a lock, and the others take it
    shared = tmp_path_factory.getbasetemp().parent / f"wheel-{run}"
    shared.mkdir(exist_ok=True)
    with exclusive(shared / "lock"):
        made = sorted(shared.glob("artibus-*.whl"))
        return made[0] if made else _wheel_into(shared)


def _wheel_into(out):
    code, text = _run(PIP + ["wheel", ROOT, "--no-deps", "--no-build-isolation", "--no-index", "-q", "-w", out],
                      cwd=out, timeout=240)
    assert code == 0, text
    (whl,) = out.glob("artibus-*.whl")
    return whl


@pytest.fixture(scope="module")
def user(tmp_path_factory, wheel):
    """(the fresh venv's bin folder, a work folder outside the clone, its environment)."""
    home = tmp_path_factory.mktemp("user")
    venv = home / "venv"
    code, text = _run([sys.executable, "-m", "venv", "--without-pip", venv], cwd=home)
    assert code == 0, text
    py = venv / "bin" / "python"
    code, text = _run(PIP + ["--python", py, "install", "--no-deps", "--no-index", "-q", wheel], cwd=home)
    assert code == 0, text
    # the third-party packages of .venv, after the venv's own (so its artibus is the wheel's)
    purelib = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "zz_artibus_test_deps.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    work = home / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ARTIBUS_", "PYTHON", "VIRTUAL_ENV"))}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return venv / "bin", work, env


def _version_of(whl):
    with zipfile.ZipFile(whl) as z:
        meta = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        return re.search(r"^Version: (\S+)$", z.read(meta).decode(), re.M).group(1)


def test_version_written_once():
    """pyproject.toml takes the version from the package (dynamic), so it is written in one place."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" not in project and "version" in project.get("dynamic", [])


def test_wheel_carries_fmus_benches_and_core(wheel):
    """Every built FMU (FMI 2.0 and 3.0, the LS-BUS nodes' triggered forms), every bench folder's
    files, the core library and the licences of what it links are in the wheel."""
    names = set(zipfile.ZipFile(wheel).namelist())
    data = "artibus/data/"
    fmus = [p.name for p in FMUS.glob("*.fmu")]
    fmus3 = [p.name for p in (FMUS / "fmi3").glob("*.fmu")]
    assert len(fmus) >= 13 and len(fmus3) >= 17
    assert {f"{data}fmus/{n}" for n in fmus} <= names
    assert {f"{data}fmus/fmi3/{n}" for n in fmus3} <= names
    ssp_files = {f"{data}{p.relative_to(ROOT).as_posix()}" for p in (ROOT / "ssp").rglob("*")
                 if p.is_file() and "__pycache__" not in p.parts}
    assert ssp_files <= names
    assert f"{data}build/lib/libartibus_core.so" in names
    # the core library links SUNDIALS (Model Exchange): its licence goes with it, as in every FMU
    assert {f"{data}licenses/{p.name}" for p in (ROOT / "licenses").glob("*.txt")} <= names
    assert {f"{data}fmus/fmi3/lsbus-triggered/{p.name}" for p in (FMUS / "fmi3" / "lsbus-triggered").glob("*.fmu")} \
        <= names
    assert not [n for n in names if n.endswith(".ssp") or "__pycache__" in n]   # packs are made on use


def test_installed_list_finds_benches_and_fmus(user, wheel):
    """From a folder outside the clone the fresh venv imports the wheel's artibus (its version), and
    `artibus list` lists every bench and FMU, from inside the package."""
    bin_, work, env = user
    code, text = _run([bin_ / "python", "-c", "import artibus; print(artibus.__file__)"], cwd=work, env=env)
    assert code == 0 and Path(text.strip()).is_relative_to(bin_.parent), text
    code, text = _run([bin_ / "artibus", "--version"], cwd=work, env=env)
    assert code == 0 and text.strip() == f"artibus {_version_of(wheel)}", text
    code, text = _run([bin_ / "artibus", "list"], cwd=work, env=env)
    assert code == 0, text
    listed = set(re.findall(r"^  (\w+):", text, re.M))
    assert set(BENCHES) <= listed and {p.stem for p in FMUS.glob("*.fmu")} <= listed, text
    assert str(bin_.parent) in text and str(ROOT) not in text


def test_installed_run_grades_kpis(user, wheel):
    """`artibus run Bus36m_Circle --report out/b`: the report with KPIs graded against the papers, the version."""
    bin_, work, env = user
    code, text = _run([bin_ / "artibus", "run", "Bus36m_Circle", "--report", "out/b"], cwd=work, env=env)
    assert code == 0, text
    m = re.search(r"(\d+) ✔, (\d+) ✘", text)
    assert m and int(m[1]) + int(m[2]) > 0, text
    page = (work / "out" / "b" / "index.html").read_text()
    assert "✔" in page and _version_of(wheel) in page
    assert (work / "out" / "b" / "kpis.csv").is_file()


def test_installed_simulate_runs_an_fmu(user, tmp_path):
    """`artibus simulate BusDynamics` runs the packaged FMU to its DefaultExperiment's stop time;
    $ARTIBUS_FMU_DIR still wins over the package's FMUs: an empty one has no BusDynamics (one line)."""
    bin_, work, env = user
    stop = float(etree.parse(str(ROOT / "modelDescription" / "BusDynamics.xml"))
                 .find("DefaultExperiment").get("stopTime"))
    code, text = _run([bin_ / "artibus", "simulate", "BusDynamics", "-o", "bd.csv"], cwd=work, env=env)
    assert code == 0, text
    last = (work / "bd.csv").read_text().strip().splitlines()[-1]
    assert float(last.split(",")[0]) == pytest.approx(stop)
    code, text = _run([bin_ / "artibus", "simulate", "BusDynamics"], cwd=work,
                      env={**env, "ARTIBUS_FMU_DIR": str(tmp_path)})
    assert code != 0 and str(tmp_path) in text and "Traceback" not in text, text


def test_clone_without_fmus_says_what_to_run(tmp_path):
    """`pip wheel` (as `pip install .`) of a clone with no built FMUs stops and names the command to run."""
    clone = tmp_path / "clone"
    clone.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        if (ROOT / name).is_file():
            shutil.copy2(ROOT / name, clone / name)
    for d in ("src/artibus", "ssp", "modelDescription"):
        shutil.copytree(ROOT / d, clone / d, ignore=shutil.ignore_patterns("__pycache__"))
    code, text = _run(PIP + ["wheel", clone, "--no-deps", "--no-build-isolation", "--no-index", "-w", tmp_path / "d"],
                      cwd=tmp_path, timeout=240)
    assert code != 0 and "./run.sh" in text, text
    assert not list((tmp_path / "d").glob("*.whl"))


#: run in a process of its own: the performance suite's modules loaded with the test tools
#: and tests/ unavailable (an import of pytest, hypothesis or a module of tests/ refused)
_NO_TESTS = r"""
import importlib.abc, importlib.machinery, runpy, sys
TESTS, BLOCKED = sys.argv[1], {"pytest", "hypothesis", "_pytest"}
class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"{name}: a test tool")
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is not None and (spec.origin or "").startswith(TESTS):
            raise ImportError(f"{name}: imported from tests/ ({spec.origin})")
        return None
sys.meta_path.insert(0, Refuse())
runpy.run_path(sys.argv[2], run_name="suite_loaded")      # its modules, not main()
"""


def test_benchmarks_need_no_tests():
    """benchmarks/suite.py (and the modules it loads) imports nothing from tests/ and no test tool."""
    code, text = _run([sys.executable, "-c", _NO_TESTS, ROOT / "tests", ROOT / "benchmarks" / "suite.py"],
                      cwd=ROOT / "benchmarks")
    assert code == 0, text


@pytest.mark.parametrize("cwd", ["docs", "."])
def test_notebook_runs_under_nbconvert_from_any_folder(cwd, tmp_path):
    """`jupyter nbconvert --execute docs/python-example.ipynb` (the set-up's Jupyter) from docs/ and
    from the root: it runs and writes its plot into the clone's out/, whatever the working folder."""
    jupyter = Path(sys.executable).parent / "jupyter"
    if not (Path(sys.executable).parent / "jupyter-nbconvert").is_file():
        pytest.fail("jupyter nbconvert is not installed: the set-up installs it (the docs extra)")
    plot = ROOT / "out" / "artangle.png"
    t0 = plot.stat().st_mtime_ns if plot.is_file() else -1
    code, text = _run([jupyter, "nbconvert", "--to", "notebook", "--execute", ROOT / "docs" / "python-example.ipynb",
                       "--output-dir", tmp_path], cwd=ROOT / cwd, timeout=300)
    assert code == 0, text
    assert plot.is_file() and plot.stat().st_mtime_ns > t0


def test_cross_binary_made_before_the_derived_lsbus_description_is_packed(tmp_path):
    """./run.sh cross-builds beside the linux build: an FMI-LS-BUS node's DLL made before the
    linux build derived the node's model description (build/lsbus/<Name>.xml, the same content)
    is still packed; only a change of what the description comes from (the node file, the base
    models' descriptions) makes it stale."""
    sys.path.insert(0, str(ROOT / "src" / "fmi"))
    import package_fmu
    node = ROOT / "modelDescription" / "lsbus" / "SteeringECU_LSBUS.xml"
    dll = tmp_path / "win64" / "fmi3" / "SteeringECU_LSBUS.dll"
    dll.parent.mkdir(parents=True)
    dll.write_bytes(b"MZ")
    derived = tmp_path / "build" / "lsbus" / "SteeringECU_LSBUS.xml"   # the linux build's, written after
    derived.parent.mkdir(parents=True)
    derived.write_text(node.read_text())
    sources = [node, ROOT / "src" / "fmi" / "lsbus_node.py", *(ROOT / "modelDescription").glob("*.xml")]
    newest = max(f.stat().st_mtime_ns for f in sources)
    os.utime(dll, ns=(newest + 10**9,) * 2)
    os.utime(derived, ns=(newest + 2 * 10**9,) * 2)
    tree = tmp_path / "tree"
    (tree / "binaries").mkdir(parents=True)
    inputs = package_fmu.described_by(str(derived), str(node), str(ROOT))
    copied = package_fmu.add_binaries(str(tree), "SteeringECU_LSBUS", {"x86_64-windows": str(dll.parent)},
                                      "3", inputs, str(ROOT))
    assert copied == [str(dll)] and (tree / "binaries" / "x86_64-windows" / dll.name).is_file()
    os.utime(dll, ns=(node.stat().st_mtime_ns - 10**9,) * 2)    # older than the node file: stale
    assert package_fmu.add_binaries(str(tree), "SteeringECU_LSBUS", {"x86_64-windows": str(dll.parent)},
                                    "3", inputs, str(ROOT)) == []
