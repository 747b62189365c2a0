"""The stability maps' page (issue 43, artibus.study.modes): the Scania 18 m bus's sway mode over
speed with each damping function (damping ratio against speed, root locus, the table of natural
frequency, damped frequency and damping ratio) and seed 004's FWS against zero side-slip MAS
(frequency responses, root locus); `artibus modes -o DIR` writes it."""
import html
import math
from pathlib import Path

import numpy as np

from artibus import files
from artibus.report.plots import plt, save_figure
from artibus.study import modes

LABELS = {"none": "no damping", "floor": "3.5 % floor only", "option1": "option 1 (angle error)",
          "option2": "option 2 (rate error)", "option3": "option 3 (both)",
          "baseline": "baseline, passive part (ground level)"}


def damping_vs_speed(path, maps, title):
    """zeta and the damped frequency against speed, a line per case ({case: [ModePoint]})."""
    fig, (a, b) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for case, pts in maps.items():
        s = [p.speed_kmh for p in pts]
        a.plot(s, [p.zeta for p in pts], "o-", label=LABELS.get(case, case))
        b.plot(s, [p.wd for p in pts], "o-")
    a.set_ylabel("damping ratio zeta [-]")
    b.set_ylabel("damped frequency wd [rad/s]")
    b.set_xlabel("speed [km/h]")
    a.legend(fontsize=8)
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
    a.set_title(title, fontsize=10)
    return save_figure(fig, path, dpi=110)


def root_locus(path, maps, title):
    """Each case's eigenvalue over speed in the complex plane, the lowest speed marked."""
    fig, ax = plt.subplots(figsize=(7, 5))
    for case, pts in maps.items():
        lam = np.array([p.eigenvalue for p in pts])
        line, = ax.plot(lam.real, lam.imag, "o-", ms=3, label=LABELS.get(case, case))
        ax.annotate(f"{pts[0].speed_kmh:g}", (lam[0].real, lam[0].imag), fontsize=7, color=line.get_color())
        ax.annotate(f"{pts[-1].speed_kmh:g} km/h", (lam[-1].real, lam[-1].imag), fontsize=7,
                    color=line.get_color())
    lim = max(abs(p.eigenvalue) for pts in maps.values() for p in pts) * 1.1
    for z in (0.1, 0.2, 0.3, 0.5):                      # lines of constant damping ratio
        ang = math.acos(z)
        ax.plot([0, -lim * math.cos(ang)], [0, lim * math.sin(ang)], "k:", lw=0.6)
        ax.annotate(f"zeta {z:g}", (-lim * math.cos(ang), lim * math.sin(ang)), fontsize=7)
    ax.set_xlabel("Re lambda [1/s]")
    ax.set_ylabel("Im lambda [rad/s]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=10)
    return save_figure(fig, path, dpi=110)


def friction_plot(path, standard, heavy, speed_kmh):
    """zeta against the rear axle's friction, each damping function, the standard rear solid and
    the heavy rear (Table 5.4) dashed."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for maps, style, what in ((standard, "o-", "standard rear"), (heavy, "s--", "heavy rear")):
        for k, (case, pts) in enumerate(maps.items()):
            ax.plot([p.mu for p in pts], [p.zeta for p in pts], style, color=f"C{k}",
                    label=f"{LABELS.get(case, case)}, {what}")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("rear axle friction mu[3] [-]")
    ax.set_ylabel("damping ratio zeta [-]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(f"Scania 18 m sway mode at {speed_kmh:g} km/h over rear friction (zeta < 0: unstable)", fontsize=10)
    return save_figure(fig, path, dpi=110)


def multiaxle_bode(path, speed, w=None):
    """Side-slip and yaw rate per front angle, FWS against MAS, at ``speed`` m/s (seed 004, Fig. 4)."""
    w = np.geomspace(0.1, 60, 300) if w is None else w
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    for mode in ("FWS", "MAS"):
        lin = modes.multiaxle(mode, speed)
        for k, out in enumerate(("Vehicle.beta", "Vehicle.w_r")):
            g = lin.frequency_response("Steering.delta1", out, w)
            axes[0, k].loglog(w, np.abs(g), label=mode)
            axes[1, k].semilogx(w, modes.phase_deg(lin, "Steering.delta1", out, w), label=mode)
            axes[0, k].set_title(f"{out.split('.')[1]} / delta1 at {speed:g} m/s", fontsize=10)
    for ax in axes.flat:
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend()
    axes[1, 0].set_ylabel("phase [deg]")
    axes[0, 0].set_ylabel("gain")
    for ax in axes[1]:
        ax.set_xlabel("w [rad/s]")
    return save_figure(fig, path, dpi=110)


def multiaxle_map(speeds):
    """{"FWS": [ModePoint], "MAS": [...]}: the least damped oscillatory mode of each (MAS's gains
    act through the plant's input: A_cl = A, the same modes, which the map shows)."""
    out = {}
    for mode in ("FWS", "MAS"):
        pts = []
        for u in speeds:
            osc = [m for m in modes.multiaxle(mode, u).modes() if m.kind == "oscillatory"]
            m = min(osc, key=lambda m: m.zeta) if osc else None
            lam = m.eigenvalue if m else complex(0, 0)
            pts.append(modes.ModePoint(mode, u * 3.6, 1.0, lam, abs(lam), abs(lam.imag),
                                       -lam.real / abs(lam) if abs(lam) else 0.0))
        out[mode] = pts
    return out


def table_html(maps):
    """wn (natural), wd (damped), zeta per speed and case, and the damping each adds over "none"."""
    cases = list(maps)
    base = maps.get("none")
    head = "".join(f"<th colspan=4>{html.escape(LABELS.get(c, c))}</th>" for c in cases)
    sub = "".join("<th>wn</th><th>wd</th><th>zeta</th><th>+zeta</th>" for _ in cases)
    rows = []
    for k, p0 in enumerate(maps[cases[0]]):
        cells = []
        for c in cases:
            p = maps[c][k]
            add = f"{p.zeta - base[k].zeta:+.3f}" if base else ""
            cells.append(f"<td class=n>{p.wn:.3f}</td><td class=n>{p.wd:.3f}</td>"
                         f"<td class=n>{p.zeta:.3f}</td><td class=n>{add}</td>")
        rows.append(f"<tr><td>{p0.speed_kmh:g}</td>{''.join(cells)}</tr>")
    return (f"<table><tr><th rowspan=2>km/h</th>{head}</tr><tr>{sub}</tr>{''.join(rows)}</table>")


def text_table(maps):
    """The same as lines of text (`artibus modes` prints them)."""
    lines = ["wn natural frequency |lambda|, wd damped frequency Im lambda (rad/s), zeta damping ratio "
             "-Re/|lambda|, +zeta the damping added over no damping"]
    base = maps.get("none")
    for c, pts in maps.items():
        lines.append(f"{LABELS.get(c, c)}:")
        for k, p in enumerate(pts):
            add = f"  +zeta {p.zeta - base[k].zeta:+.3f}" if base and c != "none" else ""
            lines.append(f"  {p.speed_kmh:5.0f} km/h  wn {p.wn:6.3f}  wd {p.wd:6.3f}  zeta {p.zeta:6.3f}{add}")
    return lines


#: the friction map's rear friction values (seed 001's option case has 0.2)
MUS = (0.2, 0.4, 0.6, 0.8, 1.0)


def write(out_dir, speeds=modes.SPEEDS, mu_rear=1.0, amplitude=modes.AMPLITUDE, mas_speed=20.0, mus=MUS):
    """The page out_dir/index.html with its PNGs (``mus``: the friction map's values at 100 km/h,
    standard and heavy rear; None leaves it out); returns (the page, the Scania map)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    smap = modes.scania_map(speeds, mu_rear=mu_rear, amplitude=amplitude)
    t = f"Scania 18 m sway mode, rear friction {mu_rear:g}, hinge at {math.degrees(amplitude):g} deg amplitude"
    damping_vs_speed(out / "scania_damping.png", smap, t)
    root_locus(out / "scania_locus.png", smap, t)
    if mus:
        friction_plot(out / "scania_friction.png", modes.scania_friction(mus, amplitude=amplitude),
                      modes.scania_friction(mus, heavy=True, amplitude=amplitude), 100.0)
    mspeeds = [s / 3.6 for s in speeds]
    mmap = multiaxle_map(mspeeds)
    root_locus(out / "multiaxle_locus.png", mmap, "seed 004, 3-axle vehicle: least damped mode, FWS and MAS")
    multiaxle_bode(out / "multiaxle_bode.png", mas_speed)
    body = _page(smap, mu_rear, amplitude, mas_speed, bool(mus))
    page = out / "index.html"
    with files.atomic_write(page) as f:
        f.write(body)
    return page, smap


def _page(smap, mu_rear, amplitude, mas_speed, friction):
    figs = [("scania_damping.png", "Sway mode's damping ratio and damped frequency over speed, each damping function"),
            ("scania_locus.png", "Root locus of the sway mode over speed (dotted: constant damping ratio)")]
    if friction:
        figs.append(("scania_friction.png", "Sway mode's damping ratio at 100 km/h over the rear axle's friction, "
                     "standard and heavy rear (Table 5.4): on a slippery rear axle a hinge damped stiffly makes the "
                     "bus nearly one rigid, oversteering body, whose mode is unstable at this speed (zeta < 0)"))
    figs += [("multiaxle_bode.png", f"Seed 004 (Fig. 4): side-slip and yaw rate per front angle, FWS and MAS, "
              f"{mas_speed:g} m/s"),
             ("multiaxle_locus.png", "Seed 004: least damped mode over speed, FWS and MAS")]
    imgs = "".join(f'<figure><img src="{n}" alt="{html.escape(c)}"><figcaption>{html.escape(c)}</figcaption></figure>'
                   for n, c in figs)
    return f"""<!doctype html><html><head><meta charset="utf-8"><title>Modes and stability maps</title>
<style>body{{font-family:sans-serif;max-width:70em;margin:auto}} td.n{{text-align:right}}
table{{border-collapse:collapse;font-size:85%}} td,th{{border:1px solid #ccc;padding:2px 5px}}
img{{max-width:100%}}</style>
</head><body><h1>Modes and stability maps (issue 43)</h1>
<p>Scania18m_Damping linearised with the driver left out (steering and drive force held), rear friction
{mu_rear:g}: BusDynamics by its Jacobian, the damper and damping functions by their first harmonic at
{math.degrees(amplitude):g} deg of articulation in the sway mode (describing function: at rest their gain is the
damper's regularisation alone, the same for every option; the equivalent damping falls as the amplitude
grows). wn natural frequency |lambda|, wd damped frequency Im lambda, both rad/s; zeta damping ratio;
+zeta the damping the function adds over none.</p>
{table_html(smap)}
<p>Seed 004's statements (Fig. 4) checked on MultiAxle_StepSteer's linear closed loop: the yaw rate's phase
lag is the same with MAS as with FWS (within 2.5 deg, 5-30 m/s); the phase difference between side-slip
and yaw rate (its largest over frequency) is halved with MAS (ratio 0.45-0.55 from 15 m/s up; below the
speed at which FWS's steady side-slip changes sign, about 11 m/s, it is not); MAS's steady side-slip gain
is zero.</p>
{imgs}</body></html>
"""
