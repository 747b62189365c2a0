"""`artibus bode`: sine tests through the co-simulation of the
MultiAxle_StepSteer bench (plant + zero-side-slip steering) against seed
004's eq. 5 transfer function computed here."""
import math
import subprocess
import sys

import numpy as np
import pytest

from artibus.study.bode import frequency_response
from test_multiaxle_model import BUS, state_space, steer_weights, zero_sideslip_gain

FREQS = [0.1, 0.3, 1.0, 2.0]


def eq5_yaw_rate(u, freqs, h, zs=True):
    """w_r / delta1 from eq. 5: (jw I - A)^-1 B g, g the axle angles per unit
    delta1 (zero-side-slip: 1 and K(u); front-axle steering: 1 and 0). The
    co-simulation holds the plant's inputs over each step: the states see
    sinc(w h / 2) times a half-step delay, which `bode` takes out of its phase."""
    A, B = state_space(u, BUS)
    a, b = steer_weights(BUS)
    g = a + b * zero_sideslip_gain(u, BUS) if zs else np.eye(BUS["n"])[0]
    Bg = B @ np.append(g, 0.0)
    out = []
    for f in freqs:
        w = 2 * math.pi * f
        X = np.linalg.solve(1j * w * np.eye(4) - A, Bg) * np.sinc(w * h / 2 / math.pi)
        out.append(X[0])
    return np.array(out)


@pytest.mark.parametrize("zs", [True, False], ids=["zero side-slip", "front-axle steering"])
def test_bode_matches_eq5(zs):
    overrides = {"Steering.delta1": 0.0}
    if not zs:
        overrides["Vehicle.steerable[3]"] = False
    resp = frequency_response("MultiAxle_StepSteer", "Steering.delta1", ["Vehicle.w_r"], FREQS, 0.01,
                              overrides=overrides)
    ref = eq5_yaw_rate(20.0, FREQS, 0.01, zs)
    for p, H in zip(resp["Vehicle.w_r"], ref):
        assert p.gain == pytest.approx(abs(H), rel=5e-3), p
        assert abs(math.remainder(p.phase - np.angle(H), 2 * math.pi)) < 5e-3, p


def test_bode_cli_writes_csv_and_plot(tmp_path):
    r = subprocess.run([sys.executable, "-m", "artibus", "bode", "MultiAxle_StepSteer", "--input", "Steering.delta1",
                        "--measure", "Vehicle.w_r", "--set", "Steering.delta1=0", "--fmin", "0.2",
                        "--fmax", "1", "--n", "2", "-o", str(tmp_path / "b.csv"), "--plot", str(tmp_path / "b.png")],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert len((tmp_path / "b.csv").read_text().splitlines()) == 3
    assert (tmp_path / "b.png").read_bytes()[:4] == b"\x89PNG"
