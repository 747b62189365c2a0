"""MultiAxle3DOF with ZeroSideslipSteering in the loop (seed 004, Figs. 3-4):
a small co-simulation written here (the controller's delta[i] to the plant's
delta[i] at every communication point), against eq. 4's closed-form steady
states (test_multiaxle_model.py).

Run as a script to draw the step responses of front-axle steering (FWS) and
zero-side-slip steering (ZS) at 5, 10, 20 and 30 m/s (Fig. 3), and their
frequency responses at 20 m/s measured by sine tests through the FMUs (Fig. 4):

    .venv/bin/python tests/test_multiaxle_closed_loop.py [out/]

writes out/MultiAxle_StepSteer.png and .csv (yaw rate, side-slip, lateral
acceleration and roll angle over time) and out/MultiAxle_FrequencyResponse.png
and .csv (gain and phase of w_r/delta_1 and a_y/delta_1).
"""
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from artibus.fmu import Fmu  # noqa: E402
from conftest import fmu_file  # noqa: E402
from test_multiaxle_model import (BUS, fmu_parameters, state_space, steady_state,  # noqa: E402
                                  steer_weights, zero_sideslip_gain)

SPEEDS = [5.0, 10.0, 20.0, 30.0]
RECORD = ["w_r", "beta", "a_y", "phi"]


def cosim(u, mode, veh=BUS, delta1=0.02, stop=30.0, h=0.01, Ts=0.01, driver=None):
    """a front step steer delta1 at t = 0 at constant speed u (or the driver's
    angle driver(t), sampled at the communication points); mode 'FWS' (the
    other axles straight) or 'ZS' (the controller steers them).
    Returns time, {name: array} of the plant's outputs, and the last commands."""
    driver = driver or (lambda t: delta1)
    n = veh["n"]
    plant = Fmu(fmu_file("MultiAxle3DOF"), instance_name="plant")
    ctrl = Fmu(fmu_file("ZeroSideslipSteering"), instance_name="ctrl") if mode == "ZS" else None
    try:
        plant.slave.setupExperiment(startTime=0.0)
        plant.slave.enterInitializationMode()
        plant.set_values(fmu_parameters(veh))
        plant.set_values({"testSteerAmp": 0.0, "rtol": 1e-10, "atol": 1e-12, "u": u})
        cmd_names = [f"delta[{i}]" for i in range(1, n + 1)]
        if ctrl:
            ctrl.slave.setupExperiment(startTime=0.0)
            ctrl.slave.enterInitializationMode()
            ctrl.set_values(fmu_parameters(veh, controller=True))
            ctrl.set_values({"testSteerAmp": 0.0, "testSpeedRate": 0.0, "Ts": Ts,
                             "delta1": driver(0.0), "u": u})
            ctrl.slave.exitInitializationMode()

        def commands(t=0.0):
            return ctrl.get(*cmd_names) if ctrl else [driver(t)] + [0.0] * (n - 1)

        plant.set_values(dict(zip(cmd_names, commands())))
        plant.slave.exitInitializationMode()
        steps = int(round(stop / h))
        t = np.arange(steps + 1) * h
        rec = {k: np.empty(steps + 1) for k in RECORD}
        for k in range(steps + 1):
            for name, x in zip(RECORD, plant.get(*RECORD)):
                rec[name][k] = x
            if k == steps:
                break
            if ctrl:
                ctrl.slave.doStep(k * h, h)
                ctrl.set_values({"delta1": driver((k + 1) * h)})
            plant.slave.doStep(k * h, h)
            plant.set_values(dict(zip(cmd_names, commands((k + 1) * h))))
        return t, rec, commands()
    finally:
        plant.close()
        if ctrl:
            ctrl.close()


@pytest.fixture(scope="module")
def runs():
    return {(u, mode): cosim(u, mode) for u in SPEEDS for mode in ("FWS", "ZS")}


@pytest.mark.parametrize("u", SPEEDS)
def test_zero_sideslip_steering_zeroes_the_steady_side_slip(runs, u):
    """seed 004's claim (Fig. 3a): beta_ss = 0 with ZS at every speed (< 1e-6 rad
    here), while FWS keeps the side-slip of eq. 4's steady state"""
    _, zs, cmd = runs[(u, "ZS")]
    _, fws, _ = runs[(u, "FWS")]
    assert abs(zs["beta"][-1]) < 1e-6
    beta_fws = steady_state(u, BUS, [0.02, 0.0, 0.0])[1]
    assert fws["beta"][-1] == pytest.approx(beta_fws, rel=1e-6)
    assert abs(beta_fws) > 5e-4                         # FWS's side-slip is not zero
    # the loop's steady yaw rate is eq. 4's with delta_i = K_i(u) delta_1
    a, b = steer_weights(BUS)
    K = zero_sideslip_gain(u, BUS)
    ss = steady_state(u, BUS, (a + b * K) * 0.02)
    assert zs["w_r"][-1] == pytest.approx(ss[0], rel=1e-6)
    assert zs["a_y"][-1] == pytest.approx(u * ss[0], rel=1e-6)
    assert cmd[2] == pytest.approx(0.02 * K, rel=1e-9)


def test_yaw_rate_and_lateral_acceleration_gains(runs):
    """Fig. 3b/c's observations, as numbers from eq. 4's steady states: with ZS
    the yaw-rate gain changes little above 10 m/s (FWS's grows with u), and the
    steady lateral acceleration at 20 and 30 m/s is well below FWS's"""
    zs = {u: runs[(u, "ZS")][1]["w_r"][-1] / 0.02 for u in SPEEDS}
    fws = {u: runs[(u, "FWS")][1]["w_r"][-1] / 0.02 for u in SPEEDS}
    for u in SPEEDS:
        assert fws[u] == pytest.approx(steady_state(u, BUS, [1.0, 0, 0])[0], rel=1e-6)
    assert max(zs[u] for u in (10, 20, 30)) / min(zs[u] for u in (10, 20, 30)) < 1.25
    assert fws[30.0] / fws[10.0] > 3.0
    for u in (20.0, 30.0):
        assert runs[(u, "ZS")][1]["a_y"][-1] < 0.6 * runs[(u, "FWS")][1]["a_y"][-1]


def test_closed_loop_transient_is_stable_and_bounded(runs):
    for (u, mode), (t, rec, _) in runs.items():
        for name in RECORD:
            assert np.all(np.isfinite(rec[name])), (u, mode, name)
        tail = rec["w_r"][t > 20.0]
        assert np.ptp(tail) < 1e-6 * abs(tail[-1]), (u, mode)


# ---- frequency response: sine tests through the FMUs (seed 004, Fig. 4) --------

def frequency_response(u, mode, freqs, h=0.01, amp=0.01, settle=12.0):
    """gain and phase of w_r/delta_1 and a_y/delta_1 by sine tests: the loop
    driven with delta_1 = amp sin(2 pi f t), the sine fitted by least squares
    over whole periods after the transient has died away"""
    H = {"w_r": [], "a_y": []}
    for f in freqs:
        w = 2 * np.pi * f
        periods = max(2, int(np.ceil(2.0 * f)))
        t_fit = periods / f
        stop = settle + t_fit
        stop = np.ceil(stop / h) * h
        t, rec, _ = cosim(u, mode, h=h, stop=stop, driver=lambda t: amp * np.sin(w * t))
        sel = t > stop - t_fit - 1e-9
        sel[np.nonzero(sel)[0][0]] = False          # exactly `periods` periods of samples
        X = np.column_stack([np.ones(sel.sum()), np.cos(w * t[sel]), np.sin(w * t[sel])])
        for name in H:
            c, a, b = np.linalg.lstsq(X, rec[name][sel], rcond=None)[0]
            H[name].append((b + 1j * a) / amp)
    return {k: np.array(v) for k, v in H.items()}


def frequency_response_eq5(u, mode, freqs, h=0.01, veh=BUS):
    """eq. 5's transfer functions with what the co-simulation adds: with ZS the
    controller's one-step delay (e^{-j w h}); the plant's inputs held over each
    communication step, which the states see as sinc(w h/2) e^{-j w h/2} (the
    fundamental of the staircase) while a_y's direct feedthrough u B[1] U reads
    the value held at the sample itself"""
    A, B = state_space(u, veh)
    a, b = steer_weights(veh)
    g = a + b * zero_sideslip_gain(u, veh) if mode == "ZS" else np.eye(veh["n"])[0]
    Bg = B @ np.append(g, 0.0)
    out = {"w_r": [], "a_y": []}
    for f in freqs:
        jw = 2j * np.pi * f
        wh = 2 * np.pi * f * h
        delay = np.exp(-1j * wh) if mode == "ZS" else 1.0
        hold = np.sinc(wh / 2 / np.pi) * np.exp(-0.5j * wh) * delay
        X = np.linalg.solve(jw * np.eye(4) - A, Bg) * hold
        out["w_r"].append(X[0])
        # a_y = u (w_r + beta') with beta' = A[1] X + B[1] U (eq. 5)
        out["a_y"].append(u * (X[0] + A[1] @ X + Bg[1] * delay))
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("mode", ["FWS", "ZS"])
def test_frequency_response_by_sine_tests_matches_eq5(mode):
    freqs = [0.2, 0.5, 1.0, 2.0]
    meas = frequency_response(20.0, mode, freqs)
    ref = frequency_response_eq5(20.0, mode, freqs)
    for name in ("w_r", "a_y"):
        assert np.allclose(np.abs(meas[name]), np.abs(ref[name]), rtol=2e-3), name
        assert np.allclose(np.angle(meas[name]), np.angle(ref[name]), atol=3e-3), name


def test_fig4_observations_from_eq5():
    """seed 004 Fig. 4's observations, checked on eq. 5 at 20 m/s (the sine
    tests above tie the FMUs to it): (b) the yaw rate's phase lag is hardly
    changed by ZS (within 5 deg up to 2 Hz); (a) the lateral acceleration's
    largest phase lag below 0.5 Hz is less than half of FWS's"""
    f = np.geomspace(0.05, 2.0, 40)
    fws = frequency_response_eq5(20.0, "FWS", f, h=0.0)
    zs = frequency_response_eq5(20.0, "ZS", f, h=0.0)
    assert np.max(np.abs(np.angle(zs["w_r"] / fws["w_r"]))) < np.radians(5.0)
    low = f <= 0.5
    lag_fws = np.max(-np.angle(fws["a_y"][low]))
    lag_zs = np.max(-np.angle(zs["a_y"][low]))
    assert lag_fws > np.radians(30.0) and lag_zs < 0.5 * lag_fws


def test_the_figure_script_writes_its_png(tmp_path):
    plot(tmp_path, speeds=[10.0], stop=3.0, freqs=[0.5, 1.0])
    assert (tmp_path / "MultiAxle_StepSteer.png").stat().st_size > 10000
    assert (tmp_path / "MultiAxle_FrequencyResponse.png").stat().st_size > 10000
    data = np.loadtxt(tmp_path / "MultiAxle_StepSteer.csv", delimiter=",", skiprows=1)
    assert data.shape[1] == 1 + 2 * len(RECORD)


def plot(out_dir, speeds=SPEEDS, stop=8.0, delta1=0.02, freqs=None, u_freq=20.0):
    """seed 004 Figs. 3 and 4: step responses and frequency responses, FWS vs ZS"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    labels = {"w_r": "yaw rate w_r [rad/s]", "beta": "side-slip beta [rad]",
              "a_y": "lateral acceleration a_y [m/s2]", "phi": "roll angle phi [rad]"}
    fig, axes = plt.subplots(len(RECORD), 1, figsize=(8, 11), sharex=True)
    columns, header = [], ["time"]
    for j, u in enumerate(speeds):
        for mode, style in (("FWS", "--"), ("ZS", "-")):
            t, rec, _ = cosim(u, mode, delta1=delta1, stop=stop)
            if not columns:
                columns.append(t)
            for ax, name in zip(axes, RECORD):
                ax.plot(t, rec[name], style, color=f"C{j}", label=f"{mode} {u:g} m/s")
                columns.append(rec[name])
                header.append(f"{name}_{mode}_{u:g}")
    for ax, name in zip(axes, RECORD):
        ax.set_ylabel(labels[name])
        ax.grid(True, alpha=0.3)
    axes[0].legend(ncol=2, fontsize=8)
    axes[0].set_title(f"front step steer delta_1 = {delta1} rad: front-axle steering (FWS, dashed) vs "
                      f"zero-side-slip steering (ZS, solid)\nMultiAxle3DOF + ZeroSideslipSteering, "
                      f"15 m three-axle bus (estimated data), seed 004 Fig. 3", fontsize=9)
    axes[-1].set_xlabel("time after the step [s]")
    fig.tight_layout()
    fig.savefig(out_dir / "MultiAxle_StepSteer.png", dpi=110)
    plt.close(fig)
    np.savetxt(out_dir / "MultiAxle_StepSteer.csv", np.column_stack(columns), delimiter=",",
               header=",".join(header), comments="", fmt="%.10g")

    freqs = np.array(freqs if freqs is not None else np.geomspace(0.05, 3.0, 14))
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    columns, header = [freqs], ["f_Hz"]
    for mode, style in (("FWS", "o--"), ("ZS", "s-")):
        H = frequency_response(u_freq, mode, freqs)
        for j, name in enumerate(("w_r", "a_y")):
            axes[0, j].loglog(freqs, np.abs(H[name]), style, label=mode)
            axes[1, j].semilogx(freqs, np.degrees(np.angle(H[name])), style, label=mode)
            columns += [np.abs(H[name]), np.angle(H[name])]
            header += [f"gain_{name}_{mode}", f"phase_{name}_{mode}_rad"]
    axes[0, 0].set_ylabel("gain w_r/delta_1 [1/s]")
    axes[0, 1].set_ylabel("gain a_y/delta_1 [m/s2/rad]")
    for j in range(2):
        axes[1, j].set_ylabel("phase [deg]")
        axes[1, j].set_xlabel("frequency [Hz]")
        for i in range(2):
            axes[i, j].grid(True, which="both", alpha=0.3)
    axes[0, 0].legend()
    fig.suptitle(f"frequency response at {u_freq:g} m/s by sine tests through the FMUs "
                 f"(seed 004 Fig. 4): FWS vs ZS, 15 m three-axle bus (estimated data)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out_dir / "MultiAxle_FrequencyResponse.png", dpi=110)
    plt.close(fig)
    np.savetxt(out_dir / "MultiAxle_FrequencyResponse.csv", np.column_stack(columns), delimiter=",",
               header=",".join(header), comments="", fmt="%.10g")


if __name__ == "__main__":
    plot(sys.argv[1] if len(sys.argv) > 1 else "out")
