"""What every part of artibus uses: the version, the repository's root, the
user error, and where the built FMUs are. The package's modules import these
from here, never from ``artibus`` itself (which re-exports them), so that the
package's root is in no import cycle."""
import os
from pathlib import Path

__version__ = "0.1.0"

#: the repository this package was installed from (editable install)
ROOT = Path(__file__).resolve().parents[2]


class ArtibusError(Exception):
    """A user error: bad file, element or value. The CLI prints it without a traceback."""


def fmu_dir():
    """Where the built FMUs are: ``fmus/``, or $ARTIBUS_FMU_DIR (the test suite
    points it at the sanitizer build to run the same tests under ASan)."""
    return Path(os.environ.get("ARTIBUS_FMU_DIR", ROOT / "fmus"))


def fmu_path(name):
    """Path of a built FMU, ``<fmu_dir>/<name>.fmu``."""
    path = fmu_dir() / f"{name}.fmu"
    if not path.is_file():
        import difflib
        known = sorted(p.stem for p in fmu_dir().glob("*.fmu"))
        close = difflib.get_close_matches(str(name), known, n=3, cutoff=0.6)
        if close:
            raise ArtibusError(f"{name}: no such FMU; did you mean {' or '.join(close)}?")
        raise ArtibusError(f"{path}: FMU not built (run the set-up command of the README)")
    return path
