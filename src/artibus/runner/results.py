"""A run's results in memory and on disk: the room its table needs
(``check_room``), files in the format of their extension with their units
(``save``, ``units_path``, ``read_units``; the formats: artibus.runner.formats)
and where the results of a run stopped midway go (``partial_path``,
``save_partial``)."""
from pathlib import Path

from artibus.base import ArtibusError


def _available_memory():
    """MemAvailable (bytes) from /proc/meminfo, or None where there is none."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_room(rows, cols, where, available=None):
    """The results are a table of rows x cols doubles in memory (every base
    step, every recorded signal): a run whose table would take more than half
    the memory available is refused before it starts, saying what to change,
    rather than ending in a MemoryError or the OOM killer hours later."""
    need = rows * cols * 8
    available = _available_memory() if available is None else available
    if available is not None and need > available // 2:
        raise ArtibusError(f"{where}: {rows} base steps x {cols} columns of results would take "
                           f"{need / 1e9:.3g} GB, more than half the memory available "
                           f"({available / 1e9:.3g} GB): give a larger --step, a shorter --stop-time, "
                           f"or fewer signals with --record")


def save(result, path):
    """By ``path``'s extension (artibus.runner.formats): CSV, Parquet, ASAM MDF 4
    (.mf4) or MATLAB (.mat: one variable per signal, names made MATLAB-safe),
    written to a temporary name beside ``path`` and renamed (artibus.files):
    ``path`` is the complete file or is left as it was, never torn by a
    Ctrl-C, a SIGTERM or a full disk. A Ctrl-C or SIGTERM while it writes is
    held until the file (and its units) are complete, then raised with
    ``e.written = path``.

    Units (Result.units): a CSV keeps its one header line of names; the units go
    to the sidecar ``units_path(path)`` (``out.csv`` -> ``out.units.csv``: a CSV
    with the columns ``name,unit``, a row per column of the results in their
    order, "" for none), written after the results (an interrupt in between
    leaves the results without their units, never units without results). The
    other formats hold their units (and the variables' descriptions) themselves:
    a .mat in the structs ``units``, ``descriptions`` and ``names`` (the signal's
    name as in the CSV) with a field per signal (its MATLAB-safe name), a
    .parquet in each field's metadata, an .mf4 in each channel.
    Returns ``path``."""
    from artibus.files import signals_held
    from artibus.runner.markers import mark
    path = Path(path)
    with signals_held(written=path):     # a Ctrl-C or SIGTERM now is taken after the write
        mark(f"saving {path}")           # (for the tests: artibus.runner.markers)
        _save(result, path)
    return path


def _save(result, path):
    import csv
    from artibus.files import atomic_path
    from artibus.runner import formats
    units = getattr(result, "units", None) or {}
    with atomic_path(path) as tmp:
        formats.write(result, path, tmp)
    if path.suffix.lower() == ".csv":
        with atomic_path(units_path(path)) as tmp:
            with open(tmp, "w", newline="") as f:
                w = csv.writer(f, quoting=csv.QUOTE_NONNUMERIC)
                w.writerow(["name", "unit"])
                w.writerows([n, units.get(n, "")] for n in result.names)
    return path


def units_path(path):
    """The units' sidecar of a CSV of results: ``out.csv`` -> ``out.units.csv``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.units.csv")


def read_units(path):
    """{name: unit} of a CSV of results (its sidecar, see save)."""
    import csv
    with open(units_path(path), newline="") as f:
        rows = list(csv.reader(f))
    return {n: u for n, u in rows[1:]}


def partial_path(path):
    """Where the results of a run that stopped midway go: ``out.csv`` ->
    ``out.partial.csv`` (every format likewise), never the final name."""
    path = Path(path)
    return path.with_name(f"{path.stem}.partial{path.suffix or '.csv'}")


def save_partial(e, out):
    """After an interrupt: the results up to then (KeyboardInterrupt.result, set by the
    runner) saved as OUT.partial.csv (``partial_path(out)``); the path is remembered on
    the exception (``e.partial``, ``e.partial_time``, or why not: ``e.partial_error``)
    for the command line's message."""
    result = getattr(e, "result", None)
    if result is None or not len(result.rows) or out is None:
        return
    partial = partial_path(out)
    try:
        save(result, partial)
    except (ArtibusError, OSError) as err:
        e.partial_error = str(err)
        return
    e.partial = partial
    e.partial_time = result.time[-1]


def check_results_file(path, what, inputs, results=False):
    """A results file's place checked before the run (artibus.files.check_output),
    and neither ``path`` nor the files written beside it (its units, its partial
    results and theirs) one of the run's ``inputs`` [(path, what it is)]
    (artibus.files.check_not_input: by identity); ``results``: a run's results
    file, its extension one of the formats (artibus.runner.formats.check_format).
    Returns ``path``."""
    from artibus.files import check_not_input, check_output
    path = check_not_input(check_output(path, what), what, inputs)
    if results:                           # (after check_output: a directory is named as one)
        from artibus.runner.formats import check_format
        check_format(path, what)
    for f in (units_path(path), partial_path(path), units_path(partial_path(path))):
        check_not_input(f, what, inputs, beside=path)
    return path
