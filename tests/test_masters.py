"""Our benches in other SSP masters: each bench's portable pack (artibus pack
--portable: every parameter resolved into one inline set per component) run in
ecos (ecospy), libcosim (libcosimpy) and FMPy's fmpy.ssp.simulate_ssp, each in a
process of its own (tests/masters_run.py), and the bench's KPIs computed by our
own KPI code (the bench's bench.py) from their results, against our runner's on
the same pack with the same base step. Where a master cannot run a bench, or
runs it differently by design (a master that sets no parameters, or starts its
connections from 0 without an initialisation), the test is an xfail with the
master's message or that reason (README: "Other tools").

Runs: the benches' default stop times (Bus36m_Circle 70 s, the longest: a few
seconds in each master)."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from artibus.bench import script
from artibus.bench.portable import pack_portable
from artibus.fmu import Result
from artibus.runner import Simulation

HERE = Path(__file__).resolve().parent
RUN = HERE / "masters_run.py"

#: (bench, variants): the benches of issue 25; Scania18m_LaneChange is the CAN-free lane change
CASES = [
    ("Urbino18_Circle", ()),
    ("MultiAxle_StepSteer", ()),
    ("Scania18m_Damping", ()),
    ("Bus36m_Circle", ("guidedForceMin",)),
    ("Scania18m_LaneChange", ()),
]
MASTERS = ["ecos", "libcosim", "fmpy-ssp"]

#: KPI agreement: relative 2 % of ours (issue 25's bound), or ABS[unit] absolute where ours is near 0
REL = 0.02
#: libcosim steps as our Jacobi does: its KPIs agree to 1e-13 (Urbino18_Circle, Scania18m_Damping)
#: and 7e-5 (Bus36m_Circle, where the plants' integrators see inputs differing in the last digits)
#: relative: held to 0.1 %, a hundredth of the absolute floors
TIGHT = {"libcosim": 1e-3}
ABS = {"m": 0.005, "deg": 0.05, "deg/s": 0.05, "kN": 0.05, "rad": 1e-5, "1/s": 1e-4, "%": 0.05, "kJ": 0.05,
       "-": 0.5, "s": 0.05}

#: (bench, master): why the master's KPIs differ from ours by design, not by a fault of the pack
_ECOS_ORDER = ("ecos steps the components one after the other in the order of their names, each from "
               "the others' latest outputs (neither our Gauss-Seidel, in the connections' feedthrough "
               "order, nor Jacobi): the path agrees, peaks in the closed loop's transients do not")
_FMPY_INPUTS = ("fmpy.ssp.simulate_ssp sets every input connector before each step from the connector's "
                "value, 0 until a connection writes it, connected or not, and exchanges nothing before "
                "the first step")
DIFFERENT = {
    ("MultiAxle_StepSteer", "fmpy-ssp"): _FMPY_INPUTS + ": the unconnected input Steering.delta1, which the "
                                         "bench sets to 0.02 rad (the step steer), is 0 there, so nothing steers",
    ("Bus36m_Circle", "fmpy-ssp"): _FMPY_INPUTS + ": its first step runs with every input at 0 (no drive "
                                   "force, straight wheels) and an input the bench leaves unconnected stays 0 "
                                   "whatever its start value; the hinge forces' peaks are many times ours",
    ("Bus36m_Circle", "ecos"): _ECOS_ORDER,
    ("Scania18m_LaneChange", "ecos"): _ECOS_ORDER,
}


def _id(case):
    bench, variants = case
    return "_".join([bench, *variants])


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    made = {}

    def get(case):
        if case not in made:
            bench, variants = case
            out = tmp_path_factory.mktemp("portable") / f"{_id(case)}.portable.ssp"
            made[case] = pack_portable(bench, variants, out=out)
        return made[case]
    return get


#: how each master steps (tests/masters_run.py; the guide's "Other SSP masters"), as our
#: runner's algorithm and whether every component steps at the base step (one rate) or at
#: its own (multi-rate): libcosim steps every component from the outputs of the step
#: before (Jacobi), each at its osp:StepSizeHint; fmpy.ssp likewise, all at its one step;
#: ecos all at its one step, one component after the other in the order of their names
#: (its SSP loader keeps them in a std::map), each from the others' latest outputs: of our
#: algorithms Jacobi is the nearest (DIFFERENT says where that is not near enough).
STEPPING = {"ecos": ("jacobi", True), "libcosim": ("jacobi", False), "fmpy-ssp": ("jacobi", True)}


def one_rate(pack, step, out):
    """A copy of the pack with every component at the base step (our annotation)."""
    import re
    import zipfile
    with zipfile.ZipFile(pack) as z, zipfile.ZipFile(out, "w") as o:
        for n in z.namelist():
            data = z.read(n)
            if n == "SystemStructure.ssd":
                data = re.sub(rb'stepSize="[^"]*"', f'stepSize="{step!r}"'.encode(), data)
            o.writestr(n, data)
    return out


@pytest.fixture(scope="module")
def ours(packs, tmp_path_factory):
    """Our runner on the portable pack, stepping as ``master`` does (STEPPING; None:
    our default): (result, base step, stop time, KPIs)."""
    done = {}

    def get(case, master=None):
        key = (case, STEPPING.get(master))
        if key not in done:
            pack = packs(case)
            algorithm, single = STEPPING.get(master, ("gauss-seidel", False))
            if single:
                with Simulation(pack) as sim:
                    step = sim.base_step
                pack = one_rate(pack, step, tmp_path_factory.mktemp("one-rate") / pack.name)
            with Simulation(pack, algorithm=algorithm) as sim:
                r = sim.run()
                done[key] = (r, sim.base_step, float(r.time[-1]), script.kpis(case[0], r))
        return done[key]
    return get


def run_master(master, pack, step, stop, names, tmp_path):
    out = tmp_path / f"{master}.json"
    p = subprocess.run([sys.executable, str(RUN), master, str(pack), repr(step), repr(stop), str(out), *names],
                       capture_output=True, text=True, timeout=600)
    if not out.is_file():
        pytest.fail(f"{master} died (exit {p.returncode}): {p.stderr[-2000:]}")
    return json.loads(out.read_text())


def kpi_values(kpis):
    return {k.name: (k.value, k.unit) for k in kpis}


@pytest.mark.parametrize("master", MASTERS)
@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_portable_pack_in_another_master_gives_our_kpis(case, master, packs, ours, tmp_path):
    bench, _ = case
    r, step, stop, our_kpis = ours(case, master)
    names = [n for n in r.names if n != "time"]
    got = run_master(master, packs(case), step, stop, names, tmp_path)
    if not got["ok"]:
        pytest.xfail(f"{master} cannot run {_id(case)}: {got['error']}")
    theirs = Result.from_array(got["names"], np.array(got["rows"], dtype=float))
    assert theirs.time[-1] == pytest.approx(stop, abs=step / 2)
    try:
        their_kpis = kpi_values(script.kpis(bench, theirs))
    except Exception as e:
        if (bench, master) in DIFFERENT:
            pytest.xfail(f"{master}: {DIFFERENT[bench, master]} (KPIs: {e})")
        raise
    off = []
    for name, (value, unit) in kpi_values(our_kpis).items():
        v = their_kpis[name][0]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        rel = TIGHT.get(master, REL)
        tol = max(rel * abs(value), ABS.get(unit, 0.0) * rel / REL)
        if not (math.isfinite(value) == math.isfinite(v) and (not math.isfinite(value) or abs(v - value) <= tol)):
            off.append(f"{name}: ours {value:.6g} {unit}, {master} {v:.6g} (tolerance {tol:.3g})")
    if off and (bench, master) in DIFFERENT:
        pytest.xfail(f"{master}: {DIFFERENT[bench, master]}: " + "; ".join(off))
    assert not off, f"{_id(case)} in {master}: " + "; ".join(off)


#: issue 25's acceptance: Bus36m_Circle guidedForceMin's A4/A6 deviations and hinge-1 force
ACCEPTANCE = ["max deviation of A4 from the A2 trace", "max deviation of A6 from the A2 trace",
              "deviation of A4 on the circle (transients left out)",
              "deviation of A6 on the circle (transients left out)", "max |lateral force| hinge 1"]


def test_ecos_runs_bus36m_circle_guided_force_min_as_our_runner_does(packs, ours, tmp_path):
    """The 36 m bus with seed 000's whole steering system in ecos, from its portable pack (the
    vehicle's Bus36m.ssv and the variant resolved into the one set ecos applies): A4/A6 off the
    A2 trace and the first hinge's force within 2 % of our runner's own run (Gauss-Seidel,
    multi-rate), with the same base step and ecos's own stepping."""
    case = ("Bus36m_Circle", ("guidedForceMin",))
    r, step, stop, our_kpis = ours(case)
    got = run_master("ecos", packs(case), step, stop, [n for n in r.names if n != "time"], tmp_path)
    assert got["ok"], got["error"]
    theirs = kpi_values(script.kpis("Bus36m_Circle",
                                    Result.from_array(got["names"], np.array(got["rows"], dtype=float))))
    mine = kpi_values(our_kpis)
    for name in ACCEPTANCE:
        assert theirs[name][0] == pytest.approx(mine[name][0], rel=REL), name
    # a one-module bus (Bus36m.ssv not applied, as ecos ran the plain pack) would not get there:
    # the variant's A4/A6 stay within 1.0 m of the A2 trace (seed 000, Fig. 9)
    assert theirs["max deviation of A4 from the A2 trace"][0] < 1.0
    assert theirs["max deviation of A6 from the A2 trace"][0] < 1.0
