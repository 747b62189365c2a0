"""The Windows 64-bit binaries (scripts/build_win64.sh: mingw-w64, SUNDIALS from
Debian's source package, build-win64/win64/<Name>.dll, packed into binaries/win64).

- every DLL's import table names only Windows system DLLs (the C runtime, libgcc,
  libstdc++ and winpthread are linked in) and it exports every FMI 2.0 function
  and nothing else (read with a small PE parser below, no mingw tool needed);
- every FMU archive carries binaries/win64/<Name>.dll, the same bytes as the build's;
- under Wine, the C importer tests/c/fmu_check.c cross-compiled for win64 runs its
  whole check against every DLL without a failure;
- a co-simulation of the default experiment from the start values, run by that
  importer in the win64 DLL under Wine, ends where FMPy's run of the linux64
  binary ends (within the solver tolerance);
- a Windows resource location (file:///Z:/...) and a Windows absolute path reach
  the model as Windows paths (RoadFollowDriver's CSV road under Wine).

Skipped with the reason where the win64 build or Wine is missing (scripts/setup_test.sh
installs both and builds it: ./test.sh runs it).
"""
import os
import re
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from artibus import fmu_dir
from conftest import exclusive

ROOT = Path(__file__).resolve().parents[1]
WIN = Path(os.environ.get("ARTIBUS_WIN64_BUILD", ROOT / "build-win64"))
FMU_DIR = fmu_dir()
NAMES = re.findall(r"^add_fmu\((\w+)\s+(?!LSBUS\b)", (ROOT / "CMakeLists.txt").read_text(), re.M)
#: the FMI 3.0-only FMUs (FMI-LS-BUS, issues 24 and 39: the nodes, their triggered forms, the bus in
#: both forms): build-win64/win64/fmi3/<Name>.dll, in binaries/x86_64-windows of their FMU
LSBUS = re.findall(r"^add_fmu\((\w+)\s+LSBUS\b", (ROOT / "CMakeLists.txt").read_text(), re.M) \
    + ["CanBus", "CanBus_Triggered"]

# the FMI 2.0 functions (both interfaces): the shared layer defines them all
FMI2_FUNCTIONS = set(re.findall(r"FMI2_Export\s+\w+TYPE\s+(fmi2\w+);",
                                (ROOT / "include/fmi2/fmi2Functions.h").read_text()))

FMI3_FUNCTIONS = set(re.findall(r"FMI3_Export\s+\w+TYPE\s+(fmi3\w+);",
                                (ROOT / "include/fmi3/fmi3Functions.h").read_text()))

# what a Windows machine has without installing anything
SYSTEM_DLLS = re.compile(r"^(kernel32|msvcrt|ucrtbase|user32|advapi32|ws2_32|"
                         r"api-ms-win-(crt|core)-[a-z0-9-]+)\.dll$", re.I)


def _dll(name):
    return WIN / "win64" / f"{name}.dll"


def _need_dll(name):
    if not _dll(name).is_file():
        pytest.skip(f"no win64 build ({_dll(name)} missing): run scripts/setup.sh --all-platforms")


def _wine():
    exe = shutil.which("wine64") or shutil.which("wine")
    if not exe and os.access("/usr/lib/wine/wine64", os.X_OK):   # Debian's wine64 package
        exe = "/usr/lib/wine/wine64"
    if not exe:
        pytest.skip("Wine is not installed (apt package wine64; scripts/setup_test.sh installs it)")
    return exe


def _wine_env():
    # build_win64.sh creates this prefix; if it has not, Wine creates it (about 30 s)
    return dict(os.environ, WINEPREFIX=str(WIN / "wineprefix"), WINEDEBUG="-all",
                WINEDLLOVERRIDES="mscoree,mshtml=")


def _wine_run(args):
    """the importer under Wine with its output captured. Wine now and then loses a console
    program's whole stdout (exit 0, nothing printed; seen in a CI run of 2026-12-04 with two
    test workers starting Wine side by side), or the program's connection to the wineserver
    ("wine client error: ... Connection reset by peer", when the wineserver of the run before
    shuts down): then the run is made again, a second later, twice at most. What the run
    prints is still asserted in full. A run killed by a signal with nothing printed (returncode
    -3, SIGQUIT: its wineserver went away under it) is made again too: the program never ran
    to say anything, and an FMU that crashes under Wine exits with a Windows status instead.
    So is a run that ends with status 1 and nothing on stdout or stderr (a CI run of 2026-12-07,
    SteeringActuator): tests/c/fmu_check.c prints on every way out, its usage, a load failure,
    a missing function, its count of checks, so a run that printed nothing at all lost its
    output to Wine or never started. A failure of the program's own is made again and fails
    again: three runs, and what the last one prints is asserted."""
    import time
    for _ in range(3):
        with _one_wine_program():
            p = subprocess.run(args, capture_output=True, text=True, env=_wine_env(), timeout=300)
        silent = not p.stdout.strip() and not p.stderr.strip()
        lost = ((p.returncode == 0 and not p.stdout.strip()) or "wine client error" in p.stderr
                or silent)
        if not lost:              # (a "wine client error": the wineserver went away under it)
            return p
        time.sleep(1.0)           # the wineserver of the run before shuts down; a new one starts
    return p


def _one_wine_program():
    """One Wine program at a time on the prefix, whichever pytest-xdist worker runs it (an
    exclusive lock on build-win64/wineprefix.lock): Wine's hiccups seen in CI (a program's output
    lost, its wineserver gone under it) came with two workers starting Wine side by side. (pytest
    9.2 with pytest-xdist 3.8 does not keep an xdist_group on one worker under --dist loadgroup:
    tried.) A program takes 0.2 s once the server runs."""
    WIN.mkdir(parents=True, exist_ok=True)
    return exclusive(WIN / "wineprefix.lock")


@pytest.fixture(scope="module", autouse=True)
def wineserver():
    """One Wine server and its service processes for the module's runs, started by a
    first program whose output goes nowhere (the services inherit it: started by a
    test's run they would hold its output pipe open for seconds after it ends); a
    program then takes 0.2 s, not 6 s. The server stays 10 s after its last program
    and then ends by itself: it is not killed at the module's end, since it serves
    the prefix, and with pytest-xdist another worker may still be running this
    module's other tests on it (a kill ended such a run with SIGQUIT under load,
    2026-12-07)."""
    server = shutil.which("wineserver") or "/usr/lib/wine/wineserver64"
    wine = shutil.which("wine64") or shutil.which("wine") or "/usr/lib/wine/wine64"
    exes = sorted(WIN.glob("fmu_check_*.exe")) if WIN.is_dir() else []
    if not (os.access(server, os.X_OK) and os.access(wine, os.X_OK) and exes):
        yield
        return
    quiet = dict(stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                 stderr=subprocess.DEVNULL, env=_wine_env(), check=False)
    with _one_wine_program():
        subprocess.run([server, "-p10"], **quiet)
        subprocess.run([wine, str(exes[0])], timeout=300, **quiet)   # prints its usage
    yield


def pe_tables(path):
    """(imported DLL names, exported names) of a PE32+ file."""
    b = Path(path).read_bytes()
    pe = struct.unpack_from("<I", b, 0x3C)[0]
    assert b[pe:pe + 4] == b"PE\0\0", "not a PE file"
    machine, nsec, _, _, _, opt_size, _ = struct.unpack_from("<HHIIIHH", b, pe + 4)
    opt = pe + 24
    assert machine == 0x8664 and struct.unpack_from("<H", b, opt)[0] == 0x20B, "not PE32+ x86-64"
    dirs = opt + 112                                   # data directories of a PE32+ header
    exp_rva, _ = struct.unpack_from("<II", b, dirs)
    imp_rva, _ = struct.unpack_from("<II", b, dirs + 8)
    sections = [struct.unpack_from("<IIII", b, opt + opt_size + 40 * i + 8) for i in range(nsec)]

    def off(rva):
        for vsize, vaddr, rsize, raw in sections:
            if vaddr <= rva < vaddr + max(vsize, rsize):
                return rva - vaddr + raw
        raise ValueError(f"RVA {rva:#x} in no section")

    def cstr(rva):
        o = off(rva)
        return b[o:b.index(b"\0", o)].decode()

    imports = []
    if imp_rva:
        o = off(imp_rva)
        while True:
            desc = struct.unpack_from("<IIIII", b, o)
            if not any(desc):
                break
            imports.append(cstr(desc[3]))
            o += 20
    exports = []
    if exp_rva:
        o = off(exp_rva)
        n_names, _, names_rva = struct.unpack_from("<III", b, o + 24)
        exports = [cstr(struct.unpack_from("<I", b, off(names_rva) + 4 * i)[0])
                   for i in range(n_names)]
    return imports, exports


def test_pe_parser_reads_a_known_dll():
    # the parser itself, on a DLL whose tables are known: Wine's kernel32 imports ntdll
    # and exports CreateFileW (it is a PE file in Debian's wine64 package)
    k32 = Path("/usr/lib/x86_64-linux-gnu/wine/x86_64-windows/kernel32.dll")
    if not k32.is_file():
        pytest.skip("Wine's kernel32.dll is not installed")
    imports, exports = pe_tables(k32)
    assert any(i.lower() == "ntdll.dll" for i in imports)
    assert "CreateFileW" in exports and "GetProcAddress" in exports


@pytest.mark.parametrize("name", NAMES)
def test_imports_only_windows_system_dlls(name):
    _need_dll(name)
    imports, exports = pe_tables(_dll(name))
    assert imports, "no import table"
    assert all(SYSTEM_DLLS.match(i) for i in imports), imports
    assert not any(re.match(r"lib(stdc\+\+|gcc_s|winpthread)", i, re.I) for i in imports)
    assert FMI2_FUNCTIONS <= set(exports), sorted(FMI2_FUNCTIONS - set(exports))
    assert set(exports) <= FMI2_FUNCTIONS, sorted(set(exports) - FMI2_FUNCTIONS)


@pytest.mark.parametrize("name", NAMES)
def test_fmu_carries_the_win64_binary(name):
    _need_dll(name)
    fmu = FMU_DIR / f"{name}.fmu"
    if not fmu.is_file():
        pytest.skip(f"{fmu} not built")
    with zipfile.ZipFile(fmu) as z:
        assert f"binaries/win64/{name}.dll" in z.namelist()
        packed = z.read(f"binaries/win64/{name}.dll")
    assert packed == _dll(name).read_bytes(), "the FMU's DLL is not the win64 build's"


@pytest.mark.parametrize("name", LSBUS)
def test_fmi3_only_fmu_carries_its_win64_binary(name):
    """an FMI-LS-BUS FMU (FMI 3.0 only): its DLL imports only Windows system DLLs, exports every
    FMI 3.0 function and nothing else, and is the one in its FMU's binaries/x86_64-windows (FMI 3.0,
    2.5.1.1)"""
    dll = WIN / "win64" / "fmi3" / f"{name}.dll"
    if not dll.is_file():
        pytest.skip(f"no win64 build ({dll} missing): run scripts/setup.sh --all-platforms")
    imports, exports = pe_tables(dll)
    assert imports and all(SYSTEM_DLLS.match(i) for i in imports), imports
    assert set(exports) == FMI3_FUNCTIONS, sorted(set(exports) ^ FMI3_FUNCTIONS)
    fmu = FMU_DIR / "fmi3" / f"{name}.fmu"
    if name.endswith("_Triggered"):
        fmu = FMU_DIR / "fmi3" / "lsbus-triggered" / f"{name}.fmu"
    if not fmu.is_file():
        pytest.skip(f"{fmu} not built")
    with zipfile.ZipFile(fmu) as z:
        packed = z.read(f"binaries/x86_64-windows/{name}.dll")
    assert packed == dll.read_bytes(), "the FMU's DLL is not the win64 build's"


def _importer(name):
    exe = WIN / f"fmu_check_{name}.exe"
    tree = WIN / "fmu" / name
    if not exe.is_file() or not (tree / "binaries" / "win64" / f"{name}.dll").is_file():
        pytest.skip(f"no win64 build of {name} (run scripts/build_win64.sh)")
    return exe, tree


@pytest.mark.parametrize("name", NAMES)
def test_c_importer_under_wine(name):
    wine = _wine()
    exe, tree = _importer(name)
    p = _wine_run([wine, str(exe), str(tree)])
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-2000:]
    assert re.search(r"^\d+ passed, 0 failed$", p.stdout, re.M), p.stdout[-3000:]


@pytest.mark.parametrize("name", NAMES)
def test_win64_cosimulation_equals_linux64(name):
    wine = _wine()
    exe, tree = _importer(name)
    fmu = FMU_DIR / f"{name}.fmu"
    if not fmu.is_file():
        pytest.skip(f"{fmu} not built")
    md = read_model_description(str(fmu))
    ex = md.defaultExperiment
    h = float(ex.stepSize)
    stop = min(float(ex.stopTime), 200 * h)    # at most 200 steps of the default experiment
    tol = float(ex.tolerance) if ex.tolerance else 1e-6
    p = _wine_run([wine, str(exe), str(tree), "--run", repr(stop), repr(h), repr(tol)])
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    win = {k: float(v) for k, v in (line.split() for line in p.stdout.splitlines())}
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    assert outputs and sorted(win) == sorted(outputs)

    res = simulate_fmu(str(fmu), stop_time=stop, output_interval=h, relative_tolerance=tol,
                       output=outputs, set_stop_time=False)
    assert np.isclose(res["time"][-1], stop)
    lin = {n: float(res[n][-1]) for n in outputs}
    for n in outputs:
        assert np.isfinite(win[n]), n
        # the same C code, another compiler and C library (mingw-w64's, Microsoft's
        # msvcrt under Wine): equal within the solver's relative tolerance of the
        # variable's size (measured: within 2e-14 absolute, most outputs bit-equal)
        scale = max(abs(lin[n]), np.max(np.abs(res[n])), 1e-3)
        assert abs(win[n] - lin[n]) <= tol * scale, (n, win[n], lin[n])


def test_win64_csv_road_from_the_resources(tmp_path):
    """A Windows resource location (file:///Z:/dir/resources, the importer given a drive
    path) reaches the model as Z:/dir/resources: RoadFollowDriver's CSV road named
    relative to its resources/ is read under Wine, so is one named by a Windows absolute
    path, and the driver, placed on the slalom beside the road, steers as the linux64
    binary does with the same file by its path."""
    wine = _wine()
    exe, tree = _importer("RoadFollowDriver")
    fmu = FMU_DIR / "RoadFollowDriver.fmu"
    if not fmu.is_file():
        pytest.skip(f"{fmu} not built")
    csv = ROOT / "ssp" / "roads" / "Bus36m_Slalom.csv"
    win_tree = tmp_path / "RoadFollowDriver"
    shutil.copytree(tree, win_tree)
    shutil.copy(csv, win_tree / "resources" / "slalom.csv")
    drive_path = "Z:" + str(win_tree).replace("/", "\\")
    # on the slalom's first bend (x = 50 m, the road at y = 1.3 m), 0.5 m to its left,
    # heading 0.1 rad, at 10 m/s
    place = {"x": 50.0, "y": 1.8, "psi": 0.1, "v": 10.0}
    stop, h, tol = 1.0, 0.01, 1e-6

    def win_run(road_file):
        args = [f"{k}={v!r}" for k, v in place.items()] + ["road=0", f"roadFile={road_file}"]
        return _wine_run([wine, str(exe), drive_path, "--run", repr(stop), repr(h), repr(tol)] + args)

    p = win_run("slalom.csv")
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    win = {k: float(v) for k, v in (line.split() for line in p.stdout.splitlines())}
    assert win, "the Wine run printed no outputs, three times"
    # the road is really read: a file that is not there is refused
    missing = win_run("no_such_road.csv")
    assert missing.returncode != 0 and "run failed" in missing.stdout
    # a Windows absolute path (drive letter, backslashes) is taken as it is
    p = win_run("Z:" + str(csv).replace("/", "\\"))
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    assert {k: float(v) for k, v in (line.split() for line in p.stdout.splitlines())} == win

    res = simulate_fmu(str(fmu), stop_time=stop, output_interval=h, relative_tolerance=tol,
                       start_values=dict(place, road=0, roadFile=str(csv)),
                       output=list(win), set_stop_time=False)
    assert abs(win["delta"]) > 1e-3, win          # it steers back towards the road
    assert win["eLat"] > 0.1, win                 # left of the road (a 0.5 m offset)
    for n, value in win.items():
        assert abs(value - res[n][-1]) <= tol * max(abs(res[n][-1]), 1e-3), (n, value, res[n][-1])
