"""Plots people can read: the bus's path seen from above, and signals over time."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_path(result, n_segments, path, title, lengths=None, every=5.0):
    """Bird's-eye view: the path of every axle mid-point, with the chain of
    segments drawn every ``every`` seconds (axle, joint, next axle)."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.5),
                                  gridspec_kw={"width_ratios": [1.4, 1]})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i in range(n_segments + 1):
        label = "tractor rear axle P0" if i == 0 else f"wagon {i} axle P{i}"
        ax.plot(result[f"x[{i}]"], result[f"y[{i}]"], color=colours[i], lw=1.5, label=label)
    t = result.time
    for tk in np.arange(t[0], t[-1] + 1e-9, every):
        k = int(np.argmin(abs(t - tk)))
        xs = [result[f"x[{i}]"][k] for i in range(n_segments + 1)]
        ys = [result[f"y[{i}]"][k] for i in range(n_segments + 1)]
        ax.plot(xs, ys, "k-", lw=0.8, alpha=0.5)
        ax.plot(xs, ys, "ko", ms=2.5, alpha=0.6)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    for i in range(1, n_segments + 1):
        ax2.plot(t, np.degrees(result[f"beta[{i}]"]), color=colours[i], label=f"joint angle beta[{i}]")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("angle [deg]")
    ax2.grid(True, alpha=0.3)
    ax2.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
