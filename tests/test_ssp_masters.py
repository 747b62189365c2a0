"""Other people's SSPs against other masters (issue 40): a two-FMU loop whose outputs declare no
dependencies, run by our runner and by FMPy's fmpy.ssp.simulate_ssp on the same file; a file of
OMSimulator 3.x (version="2.0" on SSP 1.0 content) made a portable pack.

The loop's FMUs are our BusKinematics and RoadFollowDriver with their ModelStructure's
dependencies removed (tests/test_foreign_ssp.without_dependencies), as many exporters write
them: each output is then assumed to depend on every input (FMI 2.0 2.2.8), so Bus -> Driver ->
Bus is a loop Gauss-Seidel must break."""
import re
import shutil
import zipfile

import numpy as np
import pytest

from artibus.base import fmu_dir
from artibus.runner import Simulation

from test_foreign_ssp import CORPUS, OUT_B, corpus, packed, reference_fmu, without_dependencies

#: a step whose multiples are exact in binary: FMPy adds the step to its time (t += h) where our
#: runner takes k * h, so both hand the FMUs the same communication points
H = 1 / 128


def driver_loop(tmp_path):
    """tests/ssp_corpus/loop_driver_bus packed with the two FMUs, their dependencies removed."""
    folder = tmp_path / "loop_driver_bus"
    shutil.copytree(CORPUS / "loop_driver_bus", folder)
    (folder / "resources").mkdir(exist_ok=True)
    for name in ("BusKinematics", "RoadFollowDriver"):
        without_dependencies(fmu_dir() / f"{name}.fmu", folder / "resources" / f"{name}.fmu")
    return packed(folder)


@pytest.fixture(scope="module")
def loop_runs(tmp_path_factory):
    """(the pack, FMPy's simulate_ssp result, {algorithm: our Result}) over the file's 20 s."""
    from fmpy.ssp.simulation import simulate_ssp
    ssp = driver_loop(tmp_path_factory.mktemp("loop"))
    theirs = simulate_ssp(str(ssp), stop_time=20.0, step_size=H)
    ours = {}
    for algorithm in ("jacobi", "gauss-seidel"):
        with Simulation(ssp, step=H, algorithm=algorithm, single_rate=True) as sim:
            ours[algorithm] = sim.run()
    return ssp, theirs, ours


SIGNALS = ["Bus.x[0]", "Bus.y[0]", "Bus.theta[0]", "Driver.delta"]


def fmpy_at_step_ends(theirs, n):
    """{signal: values after steps 1..n}: simulate_ssp's row i holds the values after the step
    from its time t_i (fmpy/ssp/simulation.py: do_step, then the row), i.e. at t_(i+1)."""
    return {s: np.asarray(theirs[s][:n], dtype=float) for s in SIGNALS}


def test_loop_without_dependencies_under_jacobi_equals_fmpy_simulate_ssp(loop_runs):
    """--algorithm jacobi is how simulate_ssp steps (every component from the connectors' values,
    then every connection copied: fmpy/ssp/simulation.py's loop), and the file (no bindings, the
    loop's connected outputs 0 at t = 0: the bus at the origin on the road's straight start,
    the driver's steering 0) leaves FMPy's connectors starting at 0 no different from our
    initialisation. Bit for bit while the inputs stay constant (until the driver first steers:
    the lane change's start), then within 1e-3 m and 2e-3 rad: FMPy sets every input before
    every step, our runner only a changed one, and BusKinematics restarts its ARKODE integrator
    on every set (src/fmi/fmu_core.c, core_changed), so the integrators' step histories part
    (measured: 1.6e-4 m on Bus.y[0], 4.1e-4 rad on Driver.delta over 20 s)."""
    _, theirs, ours = loop_runs
    r = ours["jacobi"]
    n = len(r.time) - 1
    assert len(theirs) >= n and r.time[-1] == pytest.approx(20.0)
    fm = fmpy_at_step_ends(theirs, n)
    first = int(np.argmax(fm["Driver.delta"] != 0.0))
    assert first > 100 and np.max(np.abs(fm["Bus.y[0]"])) > 3.0     # the lane change: the loop does steer
    for s in SIGNALS:
        np.testing.assert_array_equal(r[s][1:first + 2], fm[s][:first + 1], err_msg=s)
    np.testing.assert_allclose(r["Bus.y[0]"][1:], fm["Bus.y[0]"], rtol=0, atol=1e-3)
    np.testing.assert_allclose(r["Bus.theta[0]"][1:], fm["Bus.theta[0]"], rtol=0, atol=2e-3)
    np.testing.assert_allclose(r["Driver.delta"][1:], fm["Driver.delta"], rtol=0, atol=2e-3)


def test_loop_without_dependencies_under_gauss_seidel_breaks_one_connection_near_fmpy(loop_runs):
    """The default Gauss-Seidel breaks the loop at one connection (named by `artibus check` as in
    the run's warning: its file and line) and runs; simulate_ssp knows no Gauss-Seidel (it steps
    every component before it copies a connection), so our driver sees the bus one step sooner
    than there: the path agrees within 1e-3 m (measured 1.9e-4 m on Bus.y[0]), the steering
    within 0.01 rad (6.1e-3 rad)."""
    from artibus.bench.check import check_bench
    ssp, theirs, ours = loop_runs
    lines = []
    assert check_bench(str(ssp), lines.append) == 0
    line = next(k for k, s in enumerate(zipfile.ZipFile(ssp).read("SystemStructure.ssd").decode().splitlines(), 1)
                if 'startElement="Driver"' in s)
    assert re.search(rf"broken at .*SystemStructure\.ssd:{line}: Connection Driver\.delta -> Bus\.gammaF, one step "
                     r"of delay", "\n".join(lines)), lines
    r = ours["gauss-seidel"]
    fm = fmpy_at_step_ends(theirs, len(r.time) - 1)
    np.testing.assert_allclose(r["Bus.y[0]"][1:], fm["Bus.y[0]"], rtol=0, atol=1e-3)
    np.testing.assert_allclose(r["Driver.delta"][1:], fm["Driver.delta"], rtol=0, atol=0.01)
    assert np.max(np.abs(r["Driver.delta"][1:] - ours["jacobi"]["Driver.delta"][1:])) > 1e-4   # not Jacobi's run


def test_portable_pack_of_an_omsimulator3_file_is_ssp1(tmp_path):
    """A version="2.0" .ssd of SSP 1.0 content (OMSimulator 3.x) is read as SSP 1.0 (Bench.read_as),
    so `pack --portable` packs it as such (it refused it as "an SSP 2.0 system structure"): the
    pack says version="1.0" and runs with the file's stated result (B's output 1.5)."""
    from artibus.bench.portable import pack_portable
    folder = corpus("omsimulator3_version", tmp_path, {"resources/Feedthrough.fmu": reference_fmu("Feedthrough")})
    out = pack_portable(packed(folder), out=tmp_path / "model.portable.ssp")
    ssd = zipfile.ZipFile(out).read("SystemStructure.ssd").decode()
    assert re.search(r'<ssd:SystemStructureDescription[^>]*\sversion="1\.0"', ssd), ssd[:600]
    with Simulation(out, step=0.5) as sim:
        r = sim.run()
        assert (sim.bench.version, sim.bench.read_as) == ("1.0", "1.0")
    np.testing.assert_array_equal(r[OUT_B], 1.5)


def test_portable_pack_runs_without_warnings_and_osp_step_hints_are_read(tmp_path, capfd):
    """Our runner reads a portable pack's own annotations: no "annotation type the runner does not
    read" for its com.opensimulationplatform ones (there were five on every run), and a component's
    osp:StepSizeHint (libcosim's annotation, SSP 1.0 allows any) is its step where our
    org.artibus.simulation annotation gives none: the Driver hinted at 0.04 s steps 4 base steps."""
    from artibus.bench.portable import pack_portable
    pack = pack_portable("Urbino18_Circle", out=tmp_path / "u.portable.ssp")
    capfd.readouterr()
    with Simulation(pack) as sim:
        assert {u.path: u.ratio for u in sim.units} == {"Bus": 1, "Driver": 2}
    assert "annotation type" not in capfd.readouterr().err
    ssd = zipfile.ZipFile(pack).read("SystemStructure.ssd").decode()
    ssd = re.sub(r'<ssc:Annotation type="org\.artibus\.simulation">.*?</ssc:Annotation>', "", ssd, flags=re.S)
    ssd = ssd.replace('<osp:StepSizeHint value="0.02"/>', '<osp:StepSizeHint value="0.04"/>')
    assert "org.artibus.simulation" not in ssd and ssd.count('StepSizeHint value="0.04"') == 1
    hinted = tmp_path / "hinted.ssp"
    with zipfile.ZipFile(pack) as z, zipfile.ZipFile(hinted, "w") as o:
        for n in z.namelist():
            o.writestr(n, ssd if n == "SystemStructure.ssd" else z.read(n))
    with Simulation(hinted) as sim:
        assert {u.path: u.ratio for u in sim.units} == {"Bus": 1, "Driver": 4}


def test_initialisation_holds_the_broken_connection_of_a_gain_2_loop(tmp_path):
    """The connection Gauss-Seidel breaks carries one value at the initialisation as at every step
    (its source's output before the exchange), not iterated to a fixed point: a loop of gain 2 in
    each FMU, started off its fixed point, initialises (it did not: "initialisation did not settle
    in 50 iterations") and runs with the file's stated result."""
    folder = tmp_path / "loop_gain2"
    shutil.copytree(CORPUS / "loop_gain2", folder)
    (folder / "resources").mkdir()
    without_dependencies(fmu_dir() / "TypesTest.fmu", folder / "resources" / "TypesTest.fmu")
    with Simulation(packed(folder), step=0.1) as sim:
        r = sim.run()
    k = np.arange(6)
    np.testing.assert_allclose(r.time, 0.1 * k, atol=1e-12)
    np.testing.assert_array_equal(r["A.real_out"], 4.0 ** (k + 1))
    np.testing.assert_array_equal(r["B.real_out"], 2 * 4.0 ** (k + 1))
