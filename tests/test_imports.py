"""Issue 30: a command imports what its verb uses, nothing more. `artibus run`
without --report draws nothing, so it imports no drawing library
(matplotlib, PIL), no sweep library (Dask), and, for a bench without CAN
routes, no CAN library (cantools, python-can); `artibus --version` imports
none of the heavy ones (not even NumPy or FMPy).

How: the command runs in a fresh interpreter (the console script's
``artibus.cli.main``) that writes the names of every module it imported
(``sys.modules`` at exit) to a file; the test checks that set. A top-level
``import matplotlib.pyplot`` in any module the run imports puts matplotlib
in that set: ``test_the_check_sees_a_top_level_import`` shows it, by making
one module of the run path (artibus.runner.results) import matplotlib.pyplot
as it is imported, and the same check failing."""
import json
import os
import subprocess
import sys

import pytest

from artibus import fmu_dir

#: what a run without --report must not import (top-level package names)
DRAWING = ("matplotlib", "PIL")
SWEEP = ("dask", "distributed")
CAN = ("cantools", "can")
#: what `artibus --version` must not import either
HEAVY = DRAWING + SWEEP + CAN + ("numpy", "fmpy", "lxml", "scipy")

_WRAPPER = """
import atexit, json, sys
out, inject = sys.argv[1], sys.argv[2]
atexit.register(lambda: open(out, "w").write(json.dumps(sorted(sys.modules))))
if inject:        # as if the module `inject` imported matplotlib.pyplot at its top
    import importlib.abc, importlib.util

    class Inject(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path, target=None):
            if name != inject:
                return None
            sys.meta_path.remove(self)
            spec = importlib.util.find_spec(name)
            original = spec.loader.exec_module

            def exec_module(module):
                import matplotlib.pyplot    # noqa: F401
                original(module)
            spec.loader.exec_module = exec_module
            return spec
    sys.meta_path.insert(0, Inject())
sys.argv = ["artibus"] + sys.argv[3:]
from artibus.cli import main
raise SystemExit(main())
"""


def imported(tmp_path, *args, inject=""):
    """The top-level package names of every module `artibus ARGS` imported,
    and the completed process."""
    out = tmp_path / "modules.json"
    r = subprocess.run([sys.executable, "-c", _WRAPPER, str(out), inject, *args], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300,
                       env={**os.environ, "MPLBACKEND": "Agg"})
    assert out.is_file(), r.stderr
    return {m.split(".")[0] for m in json.loads(out.read_text())}, r


def forbidden(modules, names):
    return sorted(set(names) & modules)


@pytest.fixture(scope="module")
def damping_built():
    if not (fmu_dir() / "BusDynamics.fmu").is_file():
        pytest.skip("FMUs not built")


def test_run_imports_no_drawing_sweep_or_can_library(tmp_path, damping_built):
    modules, r = imported(tmp_path, "run", "Scania18m_Damping", "-o", str(tmp_path / "x.csv"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "x.csv").is_file()
    assert "artibus.runner" in {m for m in json.loads((tmp_path / "modules.json").read_text())}
    assert forbidden(modules, DRAWING + SWEEP + CAN) == []


def test_the_check_sees_a_top_level_import(tmp_path, damping_built):
    """The check above fails when a module on the run path imports matplotlib.pyplot
    at its top (here artibus.runner.results, made to as it is imported)."""
    modules, r = imported(tmp_path, "run", "Scania18m_Damping", "-o", str(tmp_path / "x.csv"),
                          inject="artibus.runner.results")
    assert r.returncode == 0, r.stderr
    assert "matplotlib" in forbidden(modules, DRAWING + SWEEP + CAN)


def test_version_imports_nothing_heavy(tmp_path):
    modules, r = imported(tmp_path, "--version")
    assert r.returncode == 0 and r.stdout.strip().startswith("artibus "), r.stderr
    assert forbidden(modules, HEAVY) == []


def test_the_drawing_is_imported_when_asked_for(tmp_path):
    """The other side: the names a bench's bench.py uses (artibus.report.Kpi, ...)
    still import what they need when first used."""
    code = ("import sys; from artibus import report; assert 'matplotlib' not in sys.modules; "
            "report.signals; assert 'matplotlib' in sys.modules; from artibus.report import Kpi, plots")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "MPLBACKEND": "Agg"})
    assert r.returncode == 0, r.stderr
