"""A bench's linear model with its controllers in the loop and the stability maps (issue 43:
artibus.linear.bench, artibus.linear.describing, artibus.study.modes, `artibus linearize BENCH`,
`artibus modes`), each checked against the papers' statements, not against numbers the code printed:

- seed 004 (MultiAxle_StepSteer, the 3-axle vehicle with ZeroSideslipSteering): the closed loop's
  steady-state side-slip gain is zero (eq. 3's purpose, Fig. 3(a)); Fig. 4's "phase lag of the yaw
  rate is not influenced in MAS mode" and "phase difference of MAS mode reduces half";
- seed 001 (Scania18m_Damping without its driver): the rear-sway mode at 100 km/h, friction 1, near
  the thesis's ~4.5 rad/s (Fig. 4.2) and its damping with each damping function in the order the
  thesis gives (5.2.4: option 1 worse than options 2 and 3; 5.1.1: the floor always there);
- bad input: a bench without Model Exchange plants, an unknown input, a jack-knifed point."""
import math
from pathlib import Path

import numpy as np
import pytest

from conftest import need_fmus as need, run_artibus as run_cli

ROOT = Path(__file__).resolve().parents[1]
FMUS = ROOT / "fmus"
W = np.geomspace(0.1, 60, 300)          # rad/s: 0.016-9.5 Hz, Fig. 4's range and beyond



# --- seed 004 ----------------------------------------------------------------------------------

@pytest.mark.parametrize("derivatives", ["auto", "fd"])
def test_zero_sideslip_steering_closed_loop_has_zero_steady_side_slip_gain(derivatives):
    """Seed 004, eq. 3: the proportional steering makes the steady side-slip zero at every speed;
    front-wheel steering alone does not (the check can fail). With MultiAxle3DOF's directional
    derivatives ("auto") and by central differences ("fd"): on a model linear in its states and
    inputs these are exact to rounding too (each entry to ~1e-10 relative; the steering's gain
    by central differences of its output, exact for its linear law), so 1e-9 rad/rad holds for
    both (measured: below 1e-15)."""
    need("MultiAxle3DOF", "ZeroSideslipSteering")
    from artibus.study import modes
    for u in (10.0, 20.0, 30.0):
        mas = modes.multiaxle("MAS", u, derivatives=derivatives)
        assert abs(modes.dc_gain(mas, "Steering.delta1", "Vehicle.beta")) < 1e-9, u
    fws = modes.multiaxle("FWS", 20.0, derivatives=derivatives)
    assert abs(modes.dc_gain(fws, "Steering.delta1", "Vehicle.beta")) > 0.1


def _phases(mode, u):
    from artibus.study import modes
    lin = modes.multiaxle(mode, u)
    return (modes.phase_deg(lin, "Steering.delta1", "Vehicle.w_r", W),
            modes.phase_deg(lin, "Steering.delta1", "Vehicle.beta", W))


def test_fig4_yaw_rate_phase_lag_not_influenced_by_mas():
    """Fig. 4(b): the yaw rate's phase lag the same with MAS as with FWS: within 2.5 deg over
    0.1-60 rad/s at every speed 5-30 m/s (it holds at all of them)."""
    need("MultiAxle3DOF", "ZeroSideslipSteering")
    for u in (5.0, 10.0, 20.0, 30.0):
        (yf, _), (ym, _) = _phases("FWS", u), _phases("MAS", u)
        assert np.max(np.abs(yf - ym)) < 2.5, u


def test_fig4_phase_difference_halved_with_mas():
    """Fig. 4(a), read as the phase difference between side-slip and yaw rate (their largest over
    frequency): about 180 deg with FWS, about 90 deg with MAS, the ratio 0.45-0.55 at 15-30 m/s.
    At 10 m/s it does not hold: below about 11 m/s FWS's steady side-slip has the sign of the
    yaw rate and its phase difference is smaller than MAS's."""
    need("MultiAxle3DOF", "ZeroSideslipSteering")
    ratio = {}
    for u in (10.0, 15.0, 20.0, 30.0):
        (yf, bf), (ym, bm) = _phases("FWS", u), _phases("MAS", u)
        ratio[u] = np.max(np.abs(bm - ym)) / np.max(np.abs(bf - yf))
    for u in (15.0, 20.0, 30.0):
        assert 0.45 <= ratio[u] <= 0.55, ratio
    assert ratio[10.0] > 1.0, ratio


def test_bench_linearize_cli_matches_the_plant_with_the_steering_gains(tmp_path):
    """`artibus linearize MultiAxle_StepSteer`: the closed loop's input Steering.delta1 acts on the
    plant as delta[1] + K3 delta[3] with K3 the steering's own output ratio at the point (read from
    the controller FMU alone here): B_cl = B[:, delta1] + K3 B[:, delta3]."""
    need("MultiAxle3DOF", "ZeroSideslipSteering")
    from scipy.io import loadmat

    from artibus.fmu.instance import Fmu
    from artibus.linear import linearize
    mat = tmp_path / "cl.mat"
    r = run_cli("linearize", "MultiAxle_StepSteer", "--inputs", "Steering.delta1", "-o", mat)
    assert r.returncode == 0, r.stderr
    assert "Steering: Co-Simulation, sampled every 0.01 s" in r.stdout and "continuous equivalent" in r.stdout
    with Fmu(FMUS / "ZeroSideslipSteering.fmu", instance_name="k") as f:
        f.initialize({"u": 20.0, "delta1": 0.02})
        f.do_step(0.0, 0.01)
        d1, d3 = f.get("delta[1]", "delta[3]")
    plant = linearize(FMUS / "MultiAxle3DOF.fmu", parameters=_vehicle(), inputs=["delta[1]", "delta[3]"])
    expected = plant.B[:, 0] + (d3 / d1) * plant.B[:, 1]
    assert np.allclose(loadmat(mat)["B"][:, 0], expected, rtol=1e-6, atol=1e-9)


def _vehicle():
    from artibus.bench import ssp
    return dict(ssp.read(ssp.ssp_path("MultiAxle_StepSteer")).components["Vehicle"].parameters)


# --- seed 001 ----------------------------------------------------------------------------------

def test_scania_sway_damping_order_at_100_kmh(tmp_path):
    """Seed 001 at 100 km/h, friction 1: the sway mode's damped frequency within 10 % of the
    thesis's ~4.5 rad/s (Fig. 4.2, no damping); its damping ratio rises from no damping to the
    3.5 % floor (5.1.1) and to option 1, and options 2 and 3 each above option 1 (5.2.4: "Option 1
    seems to be working worse than the other two"; between 2 and 3 the thesis gives no order of
    damping, only option 2's slightly smaller initial overshoot: not asserted). The page with its
    plots is written (artibus.report.modes)."""
    need("BusDynamics", "ArticulationDamper", "DampingController", "SwayBaseline")
    from artibus.report import modes as page
    where, smap = page.write(tmp_path / "modes", speeds=[100.0], mas_speed=20.0, mus=None)
    z = {d: pts[0].zeta for d, pts in smap.items()}
    assert abs(smap["none"][0].wd - 4.5) / 4.5 < 0.10
    assert z["none"] < z["floor"] < z["option1"] < min(z["option2"], z["option3"]), z
    assert z["none"] < z["baseline"], z
    for p in smap["option2"]:                       # natural and damped frequency are not the same
        assert p.wd < p.wn and p.wd == pytest.approx(p.wn * math.sqrt(1 - p.zeta ** 2), rel=1e-9)
    html = where.read_text()
    for png in ("scania_damping.png", "scania_locus.png", "multiaxle_bode.png", "multiaxle_locus.png"):
        assert (where.parent / png).stat().st_size > 1000 and png in html


# --- bad input ---------------------------------------------------------------------------------

def test_a_bench_without_model_exchange_plants_says_so(tmp_path):
    need("ZeroSideslipSteering")
    d = tmp_path / "only"
    (d / "resources").mkdir(parents=True)
    (d / "resources" / "ZeroSideslipSteering.fmu").write_bytes((FMUS / "ZeroSideslipSteering.fmu").read_bytes())
    (d / "SystemStructure.ssd").write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
        'version="1.0" name="OnlySteering"><ssd:System name="OnlySteering"><ssd:Elements>'
        '<ssd:Component name="Steering" source="resources/ZeroSideslipSteering.fmu" '
        'type="application/x-fmu-sharedlibrary"/></ssd:Elements></ssd:System></ssd:SystemStructureDescription>\n')
    r = run_cli("linearize", d / "SystemStructure.ssd")
    err = r.stderr.strip()
    assert r.returncode != 0 and "Traceback" not in err and len(err.splitlines()) == 1, err
    for w in ("SystemStructure.ssd", "OnlySteering", "no Model Exchange plant", "Steering (Co-Simulation only)"):
        assert w in err, err


@pytest.mark.parametrize("args, words", [
    (["MultiAxle_StepSteer", "--inputs", "Steering.delt1"], ["'Steering.delt1'", "no input", "Steering.delta1"]),
    (["Scania18m_Damping", "--exclude", "Driver", "--set", "Bus.psi_start[2]=2.0"],
     ["Scania18m_Damping.ssp", "Bus", "jack-knifed", "artAngle[1]"]),
    (["Scania18m_Damping", "--exclude", "Drver"], ["--exclude Drver", "'Driver'"]),
    (["Scania18m_Damping", "--exclude", "Driver", "--amplitude", "Bus.artAngl[1]=0.03"],
     ["'Bus.artAngl[1]'", "Bus.artAngle[1]"]),
])
def test_bench_bad_input_is_one_line(args, words):
    need("MultiAxle3DOF", "BusDynamics")
    r = run_cli("linearize", *args)
    err = r.stderr.strip()
    assert r.returncode != 0 and "Traceback" not in err and len(err.splitlines()) == 1, err
    for w in words:
        assert w in err, err
