import contextlib
import math
import subprocess
import sys
from pathlib import Path

import pytest

from artibus import fmu_dir
from artibus.fmu import Fmu

# FMPy's default memory callbacks (fmpy.simulate_fmu, an FMU2Slave given no
# callbacks) call libc's calloc/free looked up in libc.so.6, which a preloaded
# ASan never sees: the process's own, as artibus.simulation's (artibus.memory)
import fmpy.fmi2 as _fmi2                     # noqa: E402
from artibus.fmu import memory as _memory         # noqa: E402
_fmi2.defaultCallbacks.allocateMemory = _fmi2.fmi2CallbackAllocateMemoryTYPE(_memory.calloc)
_fmi2.defaultCallbacks.freeMemory = _fmi2.fmi2CallbackFreeMemoryTYPE(_memory.free)

# FMPy's logger proxy (fmpy.logging.addLoggerProxy: a C function that formats the
# FMU's variadic message) keeps ONE global pointer to the Python logger it calls.
# simulate_fmu(logger=f) points it at f's ctypes thunk, local to that call; the
# default callbacks (fmpy.fmi2.defaultCallbacks, every FMU instantiated without
# callbacks of its own) go through the same proxy, so after that call their
# messages jump into the freed thunk: a crash once its memory is reused (seen as
# test_model_exchange's jack-knife test, then any FMU that logs in FMPy). Each
# logger given to the proxy is kept alive, and after every test that gave one the
# proxy points at artibus's dispatcher again (artibus.fmu.claim_logger_proxy: each
# artibus instance's messages into its log, the others printed as FMPy prints them).
import fmpy.logging as _fmpy_logging          # noqa: E402
from artibus.fmu import claim_logger_proxy as restore_fmpy_logger   # noqa: E402
_add_logger_proxy = _fmpy_logging.addLoggerProxy
_proxied = []                                # the callback structs the proxy was given (their thunks)


def _add_logger_proxy_kept(functions):
    _proxied.append(getattr(functions, "_obj", functions))
    _add_logger_proxy(functions)


_fmpy_logging.addLoggerProxy = _add_logger_proxy_kept


@pytest.fixture(autouse=True)
def _fmpy_logger_proxy_restored():
    n = len(_proxied)
    yield
    if len(_proxied) > n:                    # the proxy was given a logger: artibus's dispatcher again
        restore_fmpy_logger()


ROOT = Path(__file__).resolve().parents[1]
#: every FMU the repository declares (one modelDescription/<Name>.xml each)
FMU_NAMES = sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))


def fmu_file(name):
    path = fmu_dir() / f"{name}.fmu"
    assert path.is_file(), f"{path} not built: run the set-up command of the README"
    return path


def need_fmus(*names):
    """skip the test where one of the FMUs ``names`` is not built"""
    for n in names:
        if not (fmu_dir() / f"{n}.fmu").is_file():
            pytest.skip(f"{n}.fmu not built")


@contextlib.contextmanager
def exclusive(lock_file):
    """Held while no other process holds it (an exclusive flock on ``lock_file``, waited for):
    what pytest-xdist's workers must not do side by side (one `pip wheel` of the clone, one
    Wine program on the prefix)."""
    import fcntl
    with open(lock_file, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        yield


def run_artibus(*args):
    """``python -m artibus ARGS...`` as a user runs it: the finished process, its output as text"""
    return subprocess.run([sys.executable, "-m", "artibus", *map(str, args)], capture_output=True, text=True)


def packer_inputs(fmu, tmp_path):
    """A built FMU as src/fmi/package_fmu.py's inputs for packing it again: the FMU
    unpacked as its tree (tmp_path/tree) and its generated variable table (tmp_path/gen,
    the model_vars.c/.h it ships in sources/). Returns (tree, gen)."""
    import shutil
    import zipfile
    tree, gen = tmp_path / "tree", tmp_path / "gen"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tree)
    gen.mkdir()
    for f in ("model_vars.c", "model_vars.h"):
        shutil.copy(tree / "sources" / f, gen / f)
    return tree, gen


@pytest.fixture
def open_fmu():
    """open_fmu(name) -> artibus.simulation.Fmu, freed after the test."""
    opened = []

    def make(name):
        f = Fmu(fmu_file(name))
        opened.append(f)
        return f

    yield make
    for f in opened:
        f.close()


def init(fmu, **values):
    """setupExperiment + initialization mode with the given values set."""
    fmu.initialize(values)


DEG = math.pi / 180


# --- markers: which tests the sanitizer pass runs, which are slow --------------
# `sanitize`: what the sanitizers add to the suite. test.sh runs these a second
# time with every FMU (and the C stepping core) from the AddressSanitizer +
# UBSan build (ARTIBUS_SANITIZER_PASS=1 deselects everything else): the FMUs'
# C code under the fuzzers and the state, call-order, misuse and hardening
# tests, the C core on the small benches. Left out there: the checks of the
# release binaries themselves (their imports and exports), the second importer,
# and the whole-bench bit-for-bit runs (the same FMU code as above, ten times
# slower under the sanitizers).
SANITIZE_FILES = {
    "test_fmu_state.py", "test_fmu_standard.py", "test_hardening.py", "test_model_exchange.py",
    "test_runner_core.py", "test_can_core.py", "test_runner_types.py", "test_fmi3.py",
    "test_state_fuzzer.py", "test_canbus.py", "test_lsbus_node.py", "test_can_codec_c.py",
    "test_lsbus_examples.py", "test_lsbus_core.py", "test_directional_derivatives.py",
}
SANITIZE_SKIP = ("binary_depends_only_on_system_libraries", "only_fmi_symbols_exported", "fmi_sim",
                 "bench_bit_for_bit")
# `slow`: the end-to-end runs (whole benches, sweeps, reports, other processes).
# ./test.sh runs them (it is the whole suite); `./test.sh -m "not slow"` is the quick loop.
SLOW_FILES = {
    "test_benches.py", "test_benches_roads.py", "test_bus36m_equilibrium.py", "test_can.py",
    "test_can_backwards.py", "test_can_faults.py", "test_circle_variants.py", "test_damping_benches.py",
    "test_replay_can.py", "test_reports.py", "test_runner_safety.py", "test_simulate_partial.py", "test_single_rate.py",
    "test_masters.py",
    "test_steering_controllers_benches.py", "test_sweep.py", "test_grading.py",
}
SLOW_TESTS = ("bus36m_hinge_forces_on_a_circle", "fmi3_win64")


def pytest_configure(config):
    config.addinivalue_line("markers", "sanitize: also run in the sanitizer pass of test.sh")
    config.addinivalue_line("markers", "slow: an end-to-end run (a bench, a sweep, a report, a subprocess)")


def pytest_collection_modifyitems(config, items):
    import os
    for item in items:
        fname = item.path.name
        if fname in SANITIZE_FILES and not any(s in item.name for s in SANITIZE_SKIP):
            item.add_marker(pytest.mark.sanitize)
        if fname in SLOW_FILES or any(s in item.name for s in SLOW_TESTS):
            item.add_marker(pytest.mark.slow)
    if os.environ.get("ARTIBUS_SANITIZER_PASS"):
        kept = [i for i in items if i.get_closest_marker("sanitize")]
        dropped = [i for i in items if not i.get_closest_marker("sanitize")]
        if dropped:
            config.hook.pytest_deselected(items=dropped)
        items[:] = kept


def fmu3(name):
    """fmus/fmi3/<name>.fmu, the FMI 3.0 build (the LS-BUS FMUs have no other); skipped if not built."""
    path = fmu_dir() / "fmi3" / f"{name}.fmu"
    if not path.is_file():
        pytest.skip(f"{path} not built")
    return path


@pytest.fixture(scope="module")
def db():
    """ssp/can/Bus36m.dbc as cantools reads it (strict), for the CAN frames' expected bytes."""
    import cantools
    return cantools.database.load_file(str(ROOT / "ssp" / "can" / "Bus36m.dbc"), strict=True)
