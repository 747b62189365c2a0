"""Write ssp/logs/Urbino18_test.csv: a SYNTHETIC test log for `artibus replay`
(seed 003, section V), made by a run of our own plant -- not a measurement.

Our BusKinematics FMU with the Urbino 18 Electric's data (ssp/parameters/Urbino18.ssv,
seed 003 Table I: pusher, wagon axle driven, k = 1) is driven through a city
manoeuvre (pull away, a left S into a bus bay and out, a right turn of about
90 deg, slow down) with the true effective steering angle gammaF and wagon-axle
speed v1 as inputs. What a bus's on-board sensors would record of that run is
written at 100 Hz, as seed 003's signals (its sensors: Td ~ 5 ms, DGPS Tp = 1 s):

- alpha_sensor_deg: the steering sensor's angle. The steering column leads the
  effective wheel angle by a backlash of BACKLASH_STEER deg (play: the column
  turns that much before the wheels follow when the direction reverses); the
  column angle in deg is mapped to the sensor angle through the inverse of
  seed 003's Appendix A polynomial (ssp/parameters/Urbino18SteeringMap.ssv),
  then noise N(0, NOISE_ALPHA) and quantisation QUANT_ALPHA deg. The replay
  maps it back with the polynomial.
- v1_tacho_mps: wagon-axle speed, noise N(0, NOISE_V) m/s, quantised QUANT_V.
- beta1_sensor_deg: joint angle through a backlash (play) of BACKLASH_JOINT deg
  in the sensor mounting (seed 003 reports such effects), noise N(0,
  NOISE_BETA), quantised QUANT_BETA deg.
- x1_dgps_m, y1_dgps_m, theta1_dgps_deg: the wagon axle mid-point P1 and the
  wagon's heading from the two roof antennas, at 1 Hz only (empty between),
  noise N(0, NOISE_XY) m and N(0, NOISE_THETA) deg, quantised QUANT_XY m and
  QUANT_THETA deg.

Random numbers: numpy default_rng(SEED). usage: .venv/bin/python scripts/make_test_log.py
"""
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from artibus import fmu_path  # noqa: E402
from artibus.bench.parameters import read_parameters  # noqa: E402
from artibus.fmu import simulate  # noqa: E402

OUT = ROOT / "ssp" / "logs" / "Urbino18_test.csv"
SEED = 2024
DT = 0.01                        # sensor sampling, s
STOP = 70.0
BACKLASH_STEER = 0.4             # deg of effective wheel angle
BACKLASH_JOINT = 0.5             # deg
NOISE_ALPHA, QUANT_ALPHA = 0.05, 0.1      # deg
NOISE_V, QUANT_V = 0.02, 0.01             # m/s
NOISE_BETA, QUANT_BETA = 0.05, 0.1        # deg
NOISE_XY, QUANT_XY = 0.02, 0.001          # m (RTK DGPS class)
NOISE_THETA, QUANT_THETA = 0.2, 0.01      # deg


def smooth(t, t0, t1):
    """0 before t0, 1 after t1, a cosine ramp between."""
    s = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(math.pi * s)


def manoeuvre(t):
    """True effective steering angle gammaF (deg) and wagon-axle speed v1 (m/s)."""
    t = np.asarray(t, dtype=float)
    v = 5.0 * smooth(t, 0, 6) - 2.5 * smooth(t, 30, 34) + 2.0 * smooth(t, 50, 54) - 4.0 * smooth(t, 64, 69)
    g = (12.0 * (smooth(t, 8, 11) - smooth(t, 12, 15))          # left into the bus bay
         - 12.0 * (smooth(t, 16, 19) - smooth(t, 20, 23))       # and out
         - 30.0 * (smooth(t, 34, 37) - smooth(t, 44, 48))       # right turn, about 90 deg
         + 6.0 * (smooth(t, 55, 57) - smooth(t, 59, 62)))       # lane correction
    return g, v


def play(x, width):
    """Backlash (play operator): the output follows x only once x has moved
    width/2 beyond it; it keeps its value inside the gap."""
    y = np.empty_like(x)
    y[0] = x[0]
    h = width / 2
    for i in range(1, len(x)):
        y[i] = min(max(y[i - 1], x[i] - h), x[i] + h)
    return y


def steering_map():
    p = read_parameters(ROOT / "ssp" / "parameters" / "Urbino18SteeringMap.ssv")
    return [float(p[f"c[{i}]"]) for i in range(4)]


def inverse_map(gamma_deg, c):
    """alpha with c3 a^3 + c2 a^2 + c1 a + c0 = gamma (the polynomial is strictly increasing)."""
    a = (np.asarray(gamma_deg) - c[0]) / c[1]
    for _ in range(30):                      # Newton
        f = ((c[3] * a + c[2]) * a + c[1]) * a + c[0] - gamma_deg
        a = a - f / ((3 * c[3] * a + 2 * c[2]) * a + c[1])
    return a


def main():
    rng = np.random.default_rng(SEED)
    fmu = fmu_path("BusKinematics")
    params = read_parameters("Urbino18", fmu)
    params["testSteerAmp"] = 0.0
    r = simulate(fmu, parameters=params,
                 inputs={"gammaF": lambda t: math.radians(float(manoeuvre(t)[0])),
                         "v": lambda t: float(manoeuvre(t)[1])},
                 stop_time=STOP, step=DT)
    t = r.time
    g_true, v_true = manoeuvre(t)
    c = steering_map()
    column = play(g_true, BACKLASH_STEER)          # what the column sits at: the wheels lag it by the play
    column = 2 * g_true - column                   # the column leads: wheels = play(column)
    alpha = inverse_map(column, c) + rng.normal(0, NOISE_ALPHA, len(t))
    alpha = np.round(alpha / QUANT_ALPHA) * QUANT_ALPHA
    v1 = np.round((v_true + rng.normal(0, NOISE_V, len(t))) / QUANT_V) * QUANT_V
    beta = play(np.degrees(r["beta[1]"]), BACKLASH_JOINT) + rng.normal(0, NOISE_BETA, len(t))
    beta = np.round(beta / QUANT_BETA) * QUANT_BETA
    gps = np.isclose(np.mod(t + 1e-9, 1.0), 0.0, atol=1e-6)
    x1 = np.round((r["x[1]"] + rng.normal(0, NOISE_XY, len(t))) / QUANT_XY) * QUANT_XY
    y1 = np.round((r["y[1]"] + rng.normal(0, NOISE_XY, len(t))) / QUANT_XY) * QUANT_XY
    th1 = np.round((np.degrees(r["theta[1]"]) + rng.normal(0, NOISE_THETA, len(t))) / QUANT_THETA) * QUANT_THETA
    head = [
        "SYNTHETIC test log: made by scripts/make_test_log.py from a run of our own BusKinematics FMU",
        "(ssp/parameters/Urbino18.ssv, seed 003 Table I) on a city manoeuvre; NOT measured on a real bus.",
        "Inputs of that run: true effective steering angle gammaF and wagon-axle speed v1 (see the script).",
        f"alpha_sensor_deg: steering sensor, inverse of seed 003 App. A polynomial "
        f"(ssp/parameters/Urbino18SteeringMap.ssv) of the column angle; steering backlash {BACKLASH_STEER} deg, "
        f"noise sd {NOISE_ALPHA} deg, quantised {QUANT_ALPHA} deg",
        f"v1_tacho_mps: wagon-axle speed, noise sd {NOISE_V} m/s, quantised {QUANT_V} m/s",
        f"beta1_sensor_deg: joint angle, sensor backlash {BACKLASH_JOINT} deg, noise sd {NOISE_BETA} deg, "
        f"quantised {QUANT_BETA} deg",
        f"x1_dgps_m, y1_dgps_m, theta1_dgps_deg: wagon axle P1 and heading at 1 Hz (empty between), "
        f"noise sd {NOISE_XY} m / {NOISE_THETA} deg, quantised {QUANT_XY} m / {QUANT_THETA} deg",
        f"sampling {DT} s, numpy default_rng({SEED})",
    ]
    rows = ["time_s,alpha_sensor_deg,v1_tacho_mps,beta1_sensor_deg,x1_dgps_m,y1_dgps_m,theta1_dgps_deg"]
    for i in range(len(t)):
        g = f"{x1[i]:.3f},{y1[i]:.3f},{th1[i]:.2f}" if gps[i] else ",,"
        rows.append(f"{t[i]:.2f},{alpha[i]:.1f},{v1[i]:.2f},{beta[i]:.1f},{g}")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    part = OUT.with_name(OUT.name + ".part")
    part.write_text("".join(f"# {h}\n" for h in head) + "\n".join(rows) + "\n")
    part.replace(OUT)
    print(f"{OUT}: {len(t)} rows, {int(gps.sum())} DGPS fixes; max |beta1| = "
          f"{np.max(np.abs(np.degrees(r['beta[1]']))):.1f} deg, max |gammaF| = {np.max(np.abs(g_true)):.1f} deg, "
          f"wagon heading change {np.degrees(r['theta[1]'][-1] - r['theta[1]'][0]):.1f} deg")


if __name__ == "__main__":
    main()
