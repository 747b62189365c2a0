"""The 64-bit ARM Linux binaries (scripts/build_aarch64.sh: Debian's gcc-aarch64-linux-gnu,
SUNDIALS from Debian's source package, build-aarch64/aarch64-linux/<Name>.so, packed into
binaries/aarch64-linux), run under qemu-user with the aarch64 C library of Debian's cross
packages (qemu-aarch64 -L /usr/aarch64-linux-gnu):

- every binary is an AArch64 ELF shared object that needs only the C library (libc, libm
  and the dynamic loader: libstdc++ and libgcc are linked in) and exports every FMI 2.0
  function and nothing else (read with the cross binutils' readelf);
- every FMU archive carries binaries/aarch64-linux/<Name>.so, the same bytes as the build's;
- under qemu, the C importer tests/c/fmu_check.c cross-compiled for aarch64 runs its whole
  check against every binary without a failure;
- a co-simulation of the default experiment from the start values, run by that importer
  in the aarch64 binary, ends where the same importer's x86_64 build ends with the linux64
  binary, within the solver tolerance (why a tolerance and what was measured: below).

Skipped with the reason only where the cross tools or qemu-user are not installed; with them
installed a missing aarch64 build fails (scripts/setup.sh installs them and builds it).
"""
import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from artibus import fmu_dir

ROOT = Path(__file__).resolve().parents[1]
ARM = Path(os.environ.get("ARTIBUS_AARCH64_BUILD", ROOT / "build-aarch64"))
NATIVE = Path(os.environ.get("ARTIBUS_BUILD", ROOT / "build"))
FMU_DIR = fmu_dir()
# the FMUs built in FMI 2.0 (add_fmu(<Name> LSBUS ...): an FMI-LS-BUS node, FMI 3.0 only, no fmu_check)
NAMES = re.findall(r"^add_fmu\((\w+)\s+(?!LSBUS\b)", (ROOT / "CMakeLists.txt").read_text(), re.M)
SYSROOT = "/usr/aarch64-linux-gnu"       # Debian's libc6-arm64-cross

FMI2_FUNCTIONS = set(re.findall(r"FMI2_Export\s+\w+TYPE\s+(fmi2\w+);",
                                (ROOT / "include/fmi2/fmi2Functions.h").read_text()))
#: what an aarch64 Linux machine has without installing anything
SYSTEM_LIBS = {"libc.so.6", "libm.so.6", "ld-linux-aarch64.so.1"}


def _tool(name, package):
    exe = shutil.which(name)
    if not exe:
        pytest.skip(f"{name} is not installed (apt package {package}; scripts/setup.sh installs it)")
    return exe


def _readelf():
    return _tool("aarch64-linux-gnu-readelf", "binutils-aarch64-linux-gnu")


def _qemu():
    exe = _tool("qemu-aarch64", "qemu-user")
    if not Path(SYSROOT, "lib", "ld-linux-aarch64.so.1").exists():
        pytest.skip(f"no aarch64 C library in {SYSROOT} (apt package libc6-arm64-cross)")
    return [exe, "-L", SYSROOT]


def _no_build(what):
    """Skipped where the cross tools are absent; where they are installed (scripts/setup.sh
    installs them and builds), a missing build is a failure, not a silent skip."""
    tools = [t for t in ("aarch64-linux-gnu-gcc", "aarch64-linux-gnu-readelf", "qemu-aarch64")
             if not shutil.which(t)]
    msg = f"no aarch64 build ({what} missing): run scripts/build_aarch64.sh"
    if tools:
        pytest.skip(f"{msg}; the cross tools are not installed ({', '.join(tools)})")
    pytest.fail(msg)


def _so(name):
    so = ARM / "aarch64-linux" / f"{name}.so"
    if not so.is_file():
        _no_build(so)
    return so


@pytest.mark.parametrize("name", NAMES)
def test_needs_only_the_c_library_and_exports_fmi2(name):
    readelf, so = _readelf(), _so(name)
    header = subprocess.run([readelf, "-h", str(so)], capture_output=True, text=True, check=True).stdout
    assert re.search(r"Machine:\s+AArch64", header) and re.search(r"Type:\s+DYN", header), header
    dyn = subprocess.run([readelf, "-d", str(so)], capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dyn))
    assert needed and needed <= SYSTEM_LIBS, needed
    syms = subprocess.run([readelf, "--dyn-syms", "-W", str(so)], capture_output=True, text=True,
                          check=True).stdout
    # defined (section index not UND), global, default visibility: what dlsym can find
    exported = {f[7] for f in (line.split() for line in syms.splitlines())
                if len(f) >= 8 and f[4] in ("GLOBAL", "WEAK") and f[5] == "DEFAULT" and f[6] != "UND"}
    assert FMI2_FUNCTIONS <= exported, sorted(FMI2_FUNCTIONS - exported)
    assert exported <= FMI2_FUNCTIONS, sorted(exported - FMI2_FUNCTIONS)


@pytest.mark.parametrize("name", NAMES)
def test_fmu_carries_the_aarch64_binary(name):
    so = _so(name)
    fmu = FMU_DIR / f"{name}.fmu"
    if not fmu.is_file():
        pytest.skip(f"{fmu} not built")
    with zipfile.ZipFile(fmu) as z:
        assert f"binaries/aarch64-linux/{name}.so" in z.namelist()
        packed = z.read(f"binaries/aarch64-linux/{name}.so")
    assert packed == so.read_bytes(), "the FMU's aarch64 binary is not the aarch64 build's"


def _importer(name):
    exe = ARM / f"fmu_check_{name}"
    tree = ARM / "fmu" / name
    if not exe.is_file() or not (tree / "binaries" / "aarch64-linux" / f"{name}.so").is_file():
        _no_build(exe)
    return exe, tree


@pytest.mark.parametrize("name", NAMES)
def test_c_importer_under_qemu(name):
    qemu = _qemu()
    exe, tree = _importer(name)
    p = subprocess.run([*qemu, str(exe), str(tree)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-2000:]
    assert re.search(r"^\d+ passed, 0 failed$", p.stdout, re.M), p.stdout[-3000:]


def _outputs(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                       env={k: v for k, v in os.environ.items() if k != "LD_PRELOAD"})
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    return {k: float(v) for k, v in (line.split() for line in p.stdout.splitlines())}


@pytest.mark.parametrize("name", NAMES)
def test_aarch64_cosimulation_equals_x86_64(name):
    qemu = _qemu()
    exe, tree = _importer(name)
    native_exe, native_tree = NATIVE / f"fmu_check_{name}", NATIVE / "fmu" / name
    if not native_exe.is_file() or not (native_tree / "binaries" / "linux64").is_dir():
        pytest.skip(f"no x86_64 build of {name} in {NATIVE}")
    md = read_model_description(str(native_tree / "modelDescription.xml"))
    ex = md.defaultExperiment
    h = float(ex.stepSize)
    stop = min(float(ex.stopTime), 200 * h)    # at most 200 steps of the default experiment
    tol = float(ex.tolerance) if ex.tolerance else 1e-6
    run = ["--run", repr(stop), repr(h), repr(tol)]
    arm = _outputs([*qemu, str(exe), str(tree), *run])
    x86 = _outputs([str(native_exe), str(native_tree), *run])
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    assert outputs and sorted(arm) == sorted(x86) == sorted(outputs)
    for n in outputs:
        # The same C code and the same importer; only the instruction set differs. Both
        # builds round every product and sum alone (-ffp-contract=off for aarch64, where GCC
        # would otherwise fuse a*b+c into one fmadd; x86-64's baseline has no FMA), so what
        # may still differ are the C library's functions (sin, cos, exp, atan2, pow: glibc's
        # aarch64 code and its x86_64 FMA variants are accurate to within an ulp, not
        # correctly rounded, so a last bit may differ), and a plant's adaptive solver carries
        # such a bit on within its own tolerance: hence the solver's relative tolerance of
        # the variable's size. Measured: all 243 outputs of the 13 FMUs bit for bit equal,
        # on these 200 steps and on the whole default experiments; built with contraction,
        # 5 of the 41 outputs of the six controllers differed in the last bit (1.6e-16).
        scale = max(abs(x86[n]), 1e-3)
        assert abs(arm[n] - x86[n]) <= tol * scale, (n, arm[n], x86[n])
