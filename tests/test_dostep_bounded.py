"""Issue 41, class 3: no FMU call that never returns.

Every FMU's doStep returns in bounded time whatever the step: a sampled
controller takes at most MAX_SAMPLES_PER_STEP samples in one step (src/fmi/fmu.h)
and refuses a longer step with fmi2Error/fmi3Error and a message naming the
function, the step and the limit; the plants' integrators give up within their
step limit. The limit's figures here are the documented ones
(docs/developer/fmi-layer.md: 1e5 samples), not read from the code.

Each probe runs in a child process (this file run as a script) so that a
doStep that never returns fails the test at the guard instead of hanging the
suite; the time asserted is the one measured around the call in the child.

`artibus simulate` refuses a step count it cannot take, and stays
interruptible: SIGINT or SIGTERM, sent while it steps, once it has reported a
marker of its step loop (artibus.runner.markers, tests/held_run.py: an event,
not a sleep), ends it within a second with the partial results.
"""
import csv
import json
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from held_run import HeldRun  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
ARTIBUS = [PY, "-m", "artibus"]

#: the FMUs: every model description's FMI 2.0 build (fmus/<Name>.fmu) and FMI 3.0 build
#: (fmus/fmi3/<Name>.fmu), the FMI-LS-BUS nodes and the bus FMI 3.0 only
FMI2 = sorted(p.stem for p in (ROOT / "modelDescription").glob("*.xml"))
FMI3 = sorted(FMI2 + [p.stem for p in (ROOT / "modelDescription/lsbus").glob("*.xml")]
              + [p.stem for p in (ROOT / "modelDescription/fmi3").glob("*.xml")])
#: the steps of the issue: a million seconds (12 s in a 50 Hz controller before), 1e300 s (never returned)
HUGE = (1e6, 1e300)
#: the bound on one call, s
BOUND = 1.0
#: the documented limit of samples one doStep takes (docs/developer/fmi-layer.md)
MAX_SAMPLES = 1e5
#: a guard on a child that never returns: the test fails there instead of hanging
GUARD = 30.0


def fmu_path(name, version):
    """fmus/<Name>.fmu, fmus/fmi3/<Name>.fmu; an LS-BUS node's triggered form (modelDescription/lsbus/
    *_Triggered.xml) in fmus/fmi3/lsbus-triggered/"""
    from artibus import fmu_dir
    if name.endswith("_Triggered"):
        return fmu_dir() / "fmi3" / "lsbus-triggered" / f"{name}.fmu"
    return fmu_dir() / ("fmi3" if version == 3 else "") / f"{name}.fmu"


def probe(path, steps):
    """In a child: for each step h a fresh instance at its start values, one doStep(0, h).
    [{h, status, seconds, log}] (status OK or Error)."""
    try:
        r = subprocess.run([PY, __file__, str(path)] + [repr(h) for h in steps],
                           capture_output=True, text=True, timeout=GUARD)
    except subprocess.TimeoutExpired as e:
        pytest.fail(f"{path}: doStep with a step of {steps} did not return within {GUARD:g} s; "
                    f"the steps that did: {e.stdout}")
    assert r.returncode == 0, f"{path}: the probe failed:\n{r.stdout}\n{r.stderr}"
    return [json.loads(line) for line in r.stdout.splitlines() if line.startswith("{")]


def _probe_main(path, steps):
    """The child: one line of JSON per step."""
    from fmpy.fmi1 import FMICallException
    from artibus.fmu import Fmu
    for h in steps:
        with Fmu(path) as f:
            f.initialize({})
            t0 = time.perf_counter()
            try:
                f.do_step(0.0, h)
                status = "OK"
            except FMICallException:
                status = "Error"
            seconds = time.perf_counter() - t0
            print(json.dumps({"h": h, "status": status, "seconds": seconds, "log": f.log}), flush=True)


def _check(name, results, fn):
    assert len(results) == len(HUGE)
    for r in results:
        assert r["seconds"] < BOUND, f"{name}: doStep(0, {r['h']:g}) took {r['seconds']:.2f} s"
        if r["status"] == "Error":     # refused (a controller) or given up (a plant's integrator): told why
            assert r["log"], f"{name}: doStep(0, {r['h']:g}) failed without a message"
            assert any(fn in m or "CVODE" in m or "ARKODE" in m for m in r["log"]), r["log"]


@pytest.mark.parametrize("name", FMI2)
def test_fmi2_dostep_with_a_huge_step_returns_within_a_second(name):
    _check(name, probe(fmu_path(name, 2), HUGE), "fmi2DoStep")


@pytest.mark.parametrize("name", FMI3)
def test_fmi3_dostep_with_a_huge_step_returns_within_a_second(name):
    _check(name, probe(fmu_path(name, 3), HUGE), "DoStep")


@pytest.mark.parametrize("version", (2, 3))
def test_a_step_of_the_documented_limit_is_taken_one_beyond_it_refused(version):
    """DampingController samples at Ts = 0.02 s (its start value, modelDescription): a step of
    1e5 samples (2000 s) is taken, one of 1e5 + 1 samples refused with a message naming the
    function, the step and the limit."""
    ts = 0.02
    ok, beyond = probe(fmu_path("DampingController", version), (MAX_SAMPLES * ts, (MAX_SAMPLES + 1) * ts))
    assert ok["status"] == "OK" and ok["seconds"] < BOUND, ok
    assert beyond["status"] == "Error", beyond
    message = " ".join(beyond["log"])
    assert f"fmi{version}DoStep" in message and "2000.02" in message and "100000" in message, message


def _simulate(tmp_path, *args):
    return subprocess.run(ARTIBUS + ["simulate", "DampingController", "-o", str(tmp_path / "r.csv"), *args],
                          capture_output=True, text=True, timeout=GUARD, cwd=tmp_path)


def test_simulate_with_a_huge_step_is_a_clear_error(tmp_path):
    """the issue's reproducer: refused by the FMU at its first step, an error naming the call and the
    step, no traceback (it hung before, deaf to SIGINT and SIGTERM)"""
    r = _simulate(tmp_path, "--stop-time", "1e300", "--step", "1e299")
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert "artibus: error:" in r.stderr and "fmi2DoStep" in r.stderr and "1e+299" in r.stderr, r.stderr


@pytest.mark.parametrize("stop, step", [("1e300", "1e-300"), ("1e300", "1")])
def test_simulate_refuses_a_step_count_it_cannot_take(tmp_path, stop, step):
    """(stop - start) / step = 1e600 or 1e300 steps: refused before it starts, naming the count"""
    r = _simulate(tmp_path, "--stop-time", stop, "--step", step)
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert "artibus: error:" in r.stderr and "steps" in r.stderr, r.stderr
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_simulate_is_interrupted_within_a_second_with_its_partial_results(tmp_path, sig):
    """a long run (5e6 steps) signalled while it steps, once it has reported its first
    marker (t = 100 s, artibus.runner.markers; not held there): it ends within a second,
    128 + the signal, every row up to then in r.partial.csv"""
    out = tmp_path / "r.csv"
    with HeldRun(["simulate", "DampingController", "-o", out, "--stop-time", "1e5", "--step", "0.02"],
                 cwd=tmp_path, hold=False) as run:
        assert run.wait_for(lambda line: line.startswith("t=")) == "t=100.0"
        t0 = time.monotonic()
        run.signal(sig)
        run.proc.wait(timeout=GUARD)
        took = time.monotonic() - t0
        err = run.finish()
    assert run.proc.returncode == 128 + sig.value, err
    assert took < BOUND, f"{took:.2f} s from {sig.name} to the exit"
    partial = tmp_path / "r.partial.csv"
    assert f"stopped by {sig.name}; partial results up to t = " in err and str(partial) in err, err
    with open(partial, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0][0] == "time" and len(rows) >= 5002
    times = [float(r[0]) for r in rows[1:]]      # every step from 0 s up to the signal, none lost
    assert times[0] == 0.0 and all(math.isclose(b - a, 0.02, abs_tol=1e-9) for a, b in zip(times, times[1:]))


if __name__ == "__main__":
    _probe_main(sys.argv[1], [float(x) for x in sys.argv[2:]])
