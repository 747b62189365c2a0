"""What every part of artibus uses: the version, the repository's root, the
user error, where the built FMUs are, the strict number syntax and the
command line's number options built on it. The package's modules import these
from here, never from ``artibus`` itself (which re-exports them), so that the
package's root is in no import cycle."""
import math
import os
import re
from argparse import ArgumentTypeError
from pathlib import Path

__version__ = "0.1.0"

#: what a wheel carries besides the code (setup.py's build_py): the clone's run-time
#: files in the clone's layout, so that every path below ROOT is the same in both
#: (``fmus/*.fmu``, ``fmus/fmi3/*.fmu``, ``ssp/``, ``build/lib/*.so``)
PACKAGE_DATA = Path(__file__).resolve().parent / "data"


def _root():
    """Where artibus's files are: the clone this package runs from (an editable
    install, or ``src/`` on the path: the clone's ``pyproject.toml`` and
    ``ssp/benches/`` beside ``src/``), else the files an installed wheel carries
    (PACKAGE_DATA). The FMUs' folder can be overridden ($ARTIBUS_FMU_DIR, fmu_dir);
    a bench's or an FMU's path on the command line is used as given."""
    clone = Path(__file__).resolve().parents[2]
    if (clone / "pyproject.toml").is_file() and (clone / "ssp" / "benches").is_dir():
        return clone
    return PACKAGE_DATA


#: the clone this package runs from, or the installed wheel's data (_root)
ROOT = _root()


class ArtibusError(Exception):
    """A user error: bad file, element or value. The CLI prints it without a traceback."""


def fmu_dir():
    """Where the built FMUs are: ``fmus/`` (the clone's, or the installed wheel's),
    or $ARTIBUS_FMU_DIR (the test suite points it at the sanitizer build to run
    the same tests under ASan; a user at FMUs of their own build)."""
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


# one strict number syntax for every value a user writes (--set, .ssv, a
# design, a CSV): Python's float() and int() also take "1_5" (as 15), "0x1A",
# other scripts' digits (U+0660..) and surrounding whitespace of any kind
_REAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                    r"|[+-]?(?:inf|infinity|nan)", re.IGNORECASE)
_INTEGER = re.compile(r"[+-]?[0-9]+")


def parse_real(text):
    """A decimal number (``-1.5``, ``2e-3``, ``.5``; ``inf`` and ``nan`` for
    the caller to refuse or keep) from ``text``, surrounding spaces and tabs
    allowed; ValueError otherwise: no underscores, no hex, no other digits."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    s = str(text).strip(" \t\r\n")
    if not _REAL.fullmatch(s):
        raise ValueError(f"{text!r} is not a decimal number")
    return float(s)


def parse_integer(text):
    """A decimal integer (``-3``, ``+12``), surrounding spaces allowed;
    ValueError otherwise (no underscores, no hex, no fraction)."""
    if isinstance(text, int) and not isinstance(text, bool):
        return text
    s = str(text).strip(" \t\r\n")
    if not _INTEGER.fullmatch(s):
        raise ValueError(f"{text!r} is not a decimal integer")
    return int(s)


# the command line's option types (argparse's type=, artibus.cli): a one-line
# usage error naming the value, never a traceback
def arg_seconds(text):
    """--stop-time, --step: a finite number > 0 (a one-line usage error otherwise, never a traceback)."""
    try:
        x = parse_real(text)
    except ValueError:
        raise ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(x) or x <= 0:
        raise ArgumentTypeError(f"{text}: expected a finite time > 0 s")
    return x


def arg_real(text):
    """A number option (artibus.base.parse_real's syntax: no "1_5", no hex)"""
    try:
        return parse_real(text)
    except ValueError:
        raise ArgumentTypeError(f"{text!r} is not a decimal number") from None


def arg_integer(text):
    """An integer option (parse_integer's syntax)."""
    try:
        return parse_integer(text)
    except ValueError:
        raise ArgumentTypeError(f"{text!r} is not a decimal integer") from None
