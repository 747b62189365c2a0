"""The wheel's build steps beyond pyproject.toml's (setuptools' build backend):

- ``build_py`` puts the clone's run-time files into the wheel as the package's data,
  ``artibus/data/`` in the clone's layout (artibus.base.PACKAGE_DATA, ROOT): the
  built FMUs (``fmus/*.fmu``, ``fmus/fmi3/*.fmu``), the benches, parameter sets,
  roads and the DBC (``ssp/``), the stepping core's and the roads' libraries
  (``build/lib/*.so``) and the licences of what they link (``licenses/``: SUNDIALS, in the core
  for Model Exchange). The FMUs are built by CMake with SUNDIALS and Eigen (the
  set-up, scripts/setup.sh), not here: a clone without them stops with a message
  saying what to run, never a wheel that finds no bench. An editable install
  (``pip install -e .``, the set-up's) reads the clone itself and copies nothing.
- ``bdist_wheel`` tags the wheel with this machine's platform (the libraries are
  x86_64-linux binaries; the FMUs carry every platform's), for any Python 3.
- The build's scratch folder is ``build-wheel/``: ``build/`` is CMake's.
"""
import shutil
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.bdist_wheel import bdist_wheel
from setuptools.command.build_py import build_py

CLONE = Path(__file__).resolve().parent
#: what the wheel carries, relative to the clone: (folder, glob)
DATA = [("fmus", "*.fmu"), ("fmus/fmi3", "*.fmu"), ("fmus/fmi3/lsbus-triggered", "*.fmu"), ("ssp", "**/*"),
        ("build/lib", "*.so"), ("licenses", "*")]     # (the core library links SUNDIALS: its licence with it)
SETUP = "./run.sh (or scripts/setup.sh) in the clone"


def _missing():
    """The first file the wheel needs that is not built, or None: every FMU of
    modelDescription/ and the stepping core's and the roads' libraries."""
    needed = [Path("fmus", f"{md.stem}.fmu") for md in sorted((CLONE / "modelDescription").glob("*.xml"))]
    needed += [Path("build/lib/libartibus_core.so"), Path("build/lib/libartibus_roads.so")]
    return next((p for p in needed if not (CLONE / p).is_file()), None)


class BuildPyWithData(build_py):
    """build_py, then the built FMUs, the benches and the libraries into artibus/data/."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        missing = _missing()
        if missing is not None:
            raise SystemExit(f"artibus: {missing} is not built; the wheel carries the built FMUs and the "
                             f"benches: run {SETUP} first, then `pip install .` or `pip wheel .` again")
        data = Path(self.build_lib, "artibus", "data")
        shutil.rmtree(data, ignore_errors=True)        # nothing left from an earlier build
        for folder, pattern in DATA:
            for f in sorted((CLONE / folder).glob(pattern)):
                if f.is_file() and "__pycache__" not in f.parts:
                    target = data / f.relative_to(CLONE)
                    target.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(f, target)


class PlatformDistribution(Distribution):
    """The stepping core's libraries are binaries: a wheel for this platform, its files at its root."""

    def has_ext_modules(self):
        return True


class PlatformWheel(bdist_wheel):
    """A wheel for any Python 3 on this platform (py3-none-linux_x86_64): no Python extension inside."""

    def get_tag(self):
        return ("py3", "none", super().get_tag()[2])


setup(distclass=PlatformDistribution, cmdclass={"build_py": BuildPyWithData, "bdist_wheel": PlatformWheel},
      options={"build": {"build_base": "build-wheel"}})
