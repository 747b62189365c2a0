"""Stability maps (issue 43): a mode's frequency and damping ratio over speed, with and without a
controller, from the benches' linear models (artibus.linear.bench).

- Seed 001, the Scania 18 m pusher (Scania18m_Damping, the driver left out: steering and drive
  force held, the sway mode of the bus with its hinge damper and damping function): the rear
  section's sway mode (the thesis's ~4.5 rad/s at 100 km/h, Fig. 4.2, 4.5.2) with no damping, the
  3.5 % floor, options 1/2/3 (eqs. 5.3-5.5) and the baseline's passive part (its speed-dependent
  ground level; its sway control SSC switched off). The damper resists motion with a force that
  is zero at zero piston speed and the controller requests damping only against the motion and
  above the floor (5.1.1): at rest their small-signal gain is the damper's regularisation alone,
  the same for every option. The hinge is therefore linearised at an amplitude of articulation
  (the describing function, artibus.linear.describing), ``AMPLITUDE`` by default: a lane change's
  sway (seed 001, 5.2.4) is of this size; the equivalent damping falls as the amplitude grows
  (a friction-like damper), which the page says.
- Seed 004, the 3-axle vehicle (MultiAxle_StepSteer): front-wheel steering (FWS, the tag axle's
  angle ignored) against zero side-slip multi-axle steering (MAS, ZeroSideslipSteering's K(u)),
  the frequency responses from the front angle to side-slip and yaw rate (Fig. 4)."""
import math
from dataclasses import dataclass

import numpy as np

from artibus.linear import bench as lb
from artibus.linear import describing

#: the Scania damping functions compared (the bench's variants; "baseline" with its SSC off)
DAMPINGS = ("none", "floor", "option1", "option2", "option3", "baseline")
#: articulation amplitude of the describing function, rad (2 deg)
AMPLITUDE = math.radians(2.0)
#: the map's speeds, km/h (seed 001's cases: 50, 100, 130 km/h)
SPEEDS = tuple(range(50, 131, 10))
KMH = 1 / 3.6
#: the baseline's passive part: its sway control (SSC) never on (threshold beyond any rate here)
PASSIVE = {"Baseline.LambdaDotSSC": 10.0}


@dataclass
class ModePoint:
    """One mode at one operating point: ``wn`` natural frequency |lambda|, ``wd`` damped
    frequency Im lambda (rad/s), ``zeta`` damping ratio -Re lambda / |lambda|."""
    case: str
    speed_kmh: float
    mu: float
    eigenvalue: complex
    wn: float
    wd: float
    zeta: float


def _point(case, speed_kmh, mu, lam):
    return ModePoint(case, speed_kmh, mu, complex(lam), abs(lam), abs(lam.imag), -lam.real / abs(lam))


def scania_sway(damping, speed_kmh, mu_rear=1.0, amplitude=AMPLITUDE, sets=None, heavy=False):
    """The Scania's sway mode with the damping function ``damping`` (one of DAMPINGS) at
    ``speed_kmh``, the rear axle's friction ``mu_rear`` (the thesis's option case: 0.2), with
    ``heavy`` the heavy rear of Table 5.4 (the bench's variant heavyRear)."""
    v = speed_kmh * KMH
    values = {"Bus.vx_start": v, "Bus.mu[3]": mu_rear, **PASSIVE, **(sets or {})}
    opened = lb.open_bench("Scania18m_Damping", variants=[damping] + (["heavyRear"] if heavy else []),
                           sets=values, exclude=["Driver"])
    try:
        if damping == "none":        # nothing in the hinge: the plant's own mode
            bl = lb.linear_of(opened)
            lam, _ = describing._mode(bl.closed.A, bl.closed.C[_row(bl, "Bus.artAngle[1]")])
        else:
            _, lam, _ = describing.linear_at_amplitude(opened, "Bus.artAngle[1]", amplitude)
    finally:
        opened.close()
    return _point(damping, speed_kmh, mu_rear, lam)


def _row(bl, name):
    return [s.name for s in bl.closed.outputs].index(name)


def scania_map(speeds=SPEEDS, dampings=DAMPINGS, mu_rear=1.0, amplitude=AMPLITUDE):
    """{damping: [ModePoint per speed]}"""
    return {d: [scania_sway(d, s, mu_rear, amplitude) for s in speeds] for d in dampings}


def scania_friction(mus, dampings=("none", "option2", "baseline"), speed_kmh=100.0, heavy=False,
                    amplitude=AMPLITUDE):
    """{damping: [ModePoint per rear friction]} at one speed (``heavy``: the heavy rear)."""
    return {d: [scania_sway(d, speed_kmh, mu, amplitude, heavy=heavy) for mu in mus] for d in dampings}


# --- seed 004 ----------------------------------------------------------------------------------

def multiaxle(mode, speed, sets=None, derivatives="auto"):
    """The closed-loop Linear of MultiAxle_StepSteer at ``speed`` (m/s), ``mode`` "FWS" (the tag
    axle unsteered: the plant ignores its angle) or "MAS" (zero side-slip steering), from the front
    angle Steering.delta1 to the plant's outputs (``derivatives``: as artibus.linear.fmu's)."""
    values = {"Vehicle.u": speed, "Steering.u": speed, "Steering.delta1": 0.0, **(sets or {})}
    if mode == "FWS":
        values["Vehicle.steerable[3]"] = False
    return lb.linearize_bench("MultiAxle_StepSteer", sets=values, inputs=["Steering.delta1"],
                              derivatives=derivatives).closed


def dc_gain(lin, input, output):
    """The steady-state gain -C A^-1 B + D on the dynamic states (the free ones, positions and
    heading, left out: they integrate and feed nothing back)."""
    idx = [k for k, s in enumerate(lin.states) if s.name in lin.dynamic]
    j = [s.name for s in lin.inputs].index(input)
    i = [s.name for s in lin.outputs].index(output)
    A = lin.A[np.ix_(idx, idx)]
    return float(-lin.C[i, idx] @ np.linalg.solve(A, lin.B[idx, j]) + lin.D[i, j])


def phase_deg(lin, input, output, w):
    """The unwrapped phase of the frequency response, deg, the lowest frequency's in (-180, 180]."""
    ph = np.unwrap(np.angle(lin.frequency_response(input, output, w)))
    return np.degrees(ph - 2 * math.pi * round(ph[0] / (2 * math.pi)))
