"""The complementary gain Kc(v) of the damping controller's reference model
(seed 001, 4.1.2) and the Bode plots of its Figs. 4.1-4.3.

The controller's kinematic reference model, small-angle (seed 001, eq. 2.9):

    Lambda' = -(v/l2) Lambda + v a delta*,   l1 = f1 + b1,  l2 = f2 + b2,
    a = 1/l1 + (b11 - b1)/(l1 l2)

so delta* -> Lambda is G_ref(s) = v a / (s + v/l2), DC gain a l2. The thesis
matches its low-frequency gain to the extensive vehicle model's with a
speed-dependent gain, delta* = Kc(v) delta:

    Kc(v) = |G_plant(j w_lo, v)| / |G_ref(j w_lo, v)|      (friction 1)

G_plant (delta[1] -> artAngle[1]) is measured here through the co-simulation
(`artibus.study.bode.frequency_response`) on the bench Scania18m_OpenLoop:
BusDynamics with Scania18m.ssv alone, straight ahead at Bus.vx_start, Fx = 0.
With no drive force the speed falls by the tyres' induced drag, which grows
with the square of the steering amplitude; Kc is steep in v at high speed, so
the amplitude is kept small (AMPLITUDE; the plant is linear there) and the
drift measured and reported (`speed_drift`).
"""
import datetime
import math
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from artibus import runner
from artibus.study.bode import frequency_response
from artibus.bench.parameters import read_parameters

BENCH = "Scania18m_OpenLoop"
INPUT = "Bus.delta[1]"
OUTPUT = "Bus.artAngle[1]"
AMPLITUDE = 0.001          # rad, steering sine: small, so the induced drag slows the bus < 0.02 %
F_LO = 0.01                # Hz, the low frequency of Kc (at 0.02 Hz the plant's gain at 130 km/h is still 0.8 % up)
F_CHECK = 0.005            # Hz, the flatness check: Kc there must agree
PERIODS_LO = 2             # periods fitted at F_LO (F_CHECK: 1, the same run length)
SPEEDS_KMH = (10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 115, 130)   # at most 12: nKc of the controller
BODE_FREQS = tuple(np.geomspace(0.02, 3.0, 20))                     # Hz, Figs. 4.1-4.3


def reference_geometry(ssv="Scania18m"):
    """f1, b1, b11, f2, b2 of seed 001 Table 2.1 from the plant's parameter set
    (f1 = xA[1], b1 = -xA[2], b11 = lHf[1], f2 = lHr[1], b2 = -xA[3]) and
    l1, l2, a of eq. 2.9."""
    p = read_parameters(ssv)
    g = dict(f1=p["xA[1]"], b1=-p["xA[2]"], b11=p["lHf[1]"], f2=p["lHr[1]"], b2=-p["xA[3]"])
    g["l1"] = g["f1"] + g["b1"]
    g["l2"] = g["f2"] + g["b2"]
    g["a"] = 1 / g["l1"] + (g["b11"] - g["b1"]) / (g["l1"] * g["l2"])     # seed 001, eq. 2.9
    return g


def g_ref(f, v, geo, kc=1.0):
    """delta -> Lambda of the reference model at f Hz (array or scalar), speed v
    m/s, with the complementary gain kc: kc v a / (j w + v/l2) (seed 001, eq. 2.9)."""
    w = 2 * np.pi * np.asarray(f, dtype=float)
    return kc * v * geo["a"] / (1j * w + v / geo["l2"])


def settle_time(v, geo):
    """Transient allowed before a fit: ten times the slowest time constant,
    the kinematic one l2/v (the plant's other modes are faster), at least 5 s."""
    return max(5.0, 10 * geo["l2"] / v)


def plant_points(v, freqs, geo, amplitude=AMPLITUDE, periods=4, bench=BENCH):
    """Measured delta[1] -> artAngle[1] at speed v (m/s): one Point per frequency."""
    return frequency_response(bench, INPUT, [OUTPUT], list(freqs), amplitude, periods=periods,
                              settle=settle_time(v, geo), overrides={"Bus.vx_start": v})[OUTPUT]


def speed_drift(v, duration, f, amplitude=AMPLITUDE, bench=BENCH):
    """Relative change of the bus's speed over a run of the given length
    with the steering sine of f Hz (Fx = 0): (v_end - v_start) / v_start."""
    r = runner.run(bench, stop_time=duration, overrides={"Bus.vx_start": v}, record=["Bus.v"],
                   stimuli={INPUT: lambda t: amplitude * math.sin(2 * math.pi * f * t)})
    return r["Bus.v"][-1] / r["Bus.v"][0] - 1


@dataclass
class KcRow:
    speed: float          # m/s
    gain: float           # |G_plant| at F_LO
    phase: float          # rad, of G_plant at F_LO
    gain_ref: float       # |G_ref| at F_LO
    kc: float             # gain / gain_ref
    kc_check: float       # the same at F_CHECK
    drift: float          # relative speed change over the F_LO run

    @property
    def kmh(self):
        return self.speed * 3.6


def kc_table(speeds_kmh=SPEEDS_KMH, f_lo=F_LO, f_check=F_CHECK, amplitude=AMPLITUDE, geo=None,
             bench=BENCH):
    """Kc at each speed (km/h) from a sine of f_lo (PERIODS_LO periods fitted)
    and, as the flatness check, of f_check (one period; the same length when
    f_check = f_lo / 2)."""
    geo = geo or reference_geometry()
    rows = []
    for kmh in speeds_kmh:
        v = kmh / 3.6
        p = plant_points(v, [f_lo], geo, amplitude, PERIODS_LO, bench)[0]
        q = plant_points(v, [f_check], geo, amplitude, 1, bench)[0]
        g_lo, g_ck = abs(g_ref(f_lo, v, geo)), abs(g_ref(f_check, v, geo))
        drift = speed_drift(v, settle_time(v, geo) + PERIODS_LO / f_lo, f_lo, amplitude, bench)
        rows.append(KcRow(v, p.gain, p.phase, g_lo, p.gain / g_lo, q.gain / g_ck, drift))
    return rows


def write_ssv(path, rows, command, f_lo=F_LO, f_check=F_CHECK, amplitude=AMPLITUDE, geo=None):
    """The SSP parameter set of the DampingController's table: nKc, KcSpeed[i]
    (m/s), KcGain[i]; a comment says how it was made."""
    geo = geo or reference_geometry()
    if not 1 <= len(rows) <= 12:
        raise ValueError(f"{len(rows)} speeds: the controller's table holds 1..12 (nKc)")
    flat = max(abs(r.kc_check / r.kc - 1) for r in rows) * 100
    drift = max(abs(r.drift) for r in rows) * 100
    how = [
        f"made by: {command}",
        f"date: {datetime.date.today().isoformat()}",
        "what: the complementary gain of the damping controller's reference model (seed 001, 4.1.2),",
        f"  Kc(v) = |G_plant(j w, v)| / |G_ref(j w, v)| of steering -> articulation angle at f = {f_lo:g} Hz;",
        f"  G_ref = v a / (j w + v/l2) (seed 001, eq. 2.9; l1 = {geo['l1']:.3f} m, l2 = {geo['l2']:.3f} m,",
        f"  a = {geo['a']:.4f} 1/m, a l2 = {geo['a'] * geo['l2']:.4f});",
        f"  G_plant measured through the co-simulation of the bench {BENCH} (BusDynamics with",
        "  Scania18m.ssv, friction 1, Fx = 0, straight ahead at Bus.vx_start): a steering sine of",
        f"  {amplitude:g} rad added to Bus.delta[1], gain fitted over {PERIODS_LO} periods of Bus.artAngle[1]",
        f"flatness: Kc at {f_check:g} Hz differs from Kc at {f_lo:g} Hz by at most {flat:.2f} %",
        f"speed drift over a run (no drive force): at most {drift:.3f} %",
    ]
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<!-- GENERATED, do not edit: the source is src/artibus/study/kc.py (scripts/kc_table.py); how it was",
        "     made (command, frequency, amplitude, date) is in the annotation at the end.",
        "     The DampingController's table of the complementary gain Kc(v) (seed 001, 4.1.2). -->",
        '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"',
        '                  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"',
        '                  version="1.0" name="Scania18mKc">',
        "  <ssv:Parameters>",
        f'    <ssv:Parameter name="nKc"><ssv:Integer value="{len(rows)}"/></ssv:Parameter>',
    ]
    for i, r in enumerate(rows, 1):
        lines.append(f'    <ssv:Parameter name="KcSpeed[{i}]"><ssv:Real value="{r.speed:.6f}" unit="m/s"/>'
                     f'</ssv:Parameter>  <!-- {r.kmh:g} km/h -->')
    for i, r in enumerate(rows, 1):
        lines.append(f'    <ssv:Parameter name="KcGain[{i}]"><ssv:Real value="{r.kc:.5f}"/></ssv:Parameter>'
                     f'  <!-- {r.kmh:g} km/h: |G_plant| {r.gain:.5f}, |G_ref| {r.gain_ref:.5f} -->')
    lines += ["  </ssv:Parameters>", "  <ssv:Annotations>",
              '    <ssc:Annotation type="org.artibus.source">',
              '      <Source xmlns="urn:artibus">']
    lines += [f"        {escape(t)}" for t in how]
    lines += ["      </Source>", "    </ssc:Annotation>", "  </ssv:Annotations>", "</ssv:ParameterSet>", ""]
    from artibus.files import write_text
    write_text(path, "\n".join(lines))
    return Path(path)


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_kc(path, rows, f_lo=F_LO, f_check=F_CHECK):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    kmh = [r.kmh for r in rows]
    ax.plot(kmh, [r.kc for r in rows], "o-", label=f"Kc at {f_lo:g} Hz (the table)")
    ax.plot(kmh, [r.kc_check for r in rows], "x", ms=8, label=f"Kc at {f_check:g} Hz (flatness check)")
    ax.set_xlabel("speed v [km/h]")
    ax.set_ylabel("Kc [-]")
    ax.set_ylim(0, 1.05)
    ax.set_title("Complementary gain Kc(v) = |G_plant| / |G_ref|, steering -> articulation angle\n"
                 "Scania 18 m, friction 1 (seed 001, 4.1.2)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    sec = ax.secondary_xaxis("top", functions=(lambda x: x / 3.6, lambda x: x * 3.6))
    sec.set_xlabel("speed v [m/s]")
    fig.tight_layout()
    from artibus.report import save_figure
    save_figure(fig, path, dpi=110)


def plot_bode(path, v, points, geo, kc=1.0, title="", marks=None):
    """delta -> Lambda: the reference model (closed form, times kc) as a line,
    the plant as measured points (artibus.study.bode.plot, the reference through its
    ``reference`` argument)."""
    from artibus.study import bode
    f = np.array([p.frequency for p in points])
    fr = np.geomspace(f.min(), f.max(), 300)
    ref_label = "reference model, eq. 2.9" + (f", times Kc = {kc:.3f}" if kc != 1.0 else "")
    return bode.plot(path, {OUTPUT: {"extensive model (BusDynamics), measured": points}}, title,
                     units={OUTPUT: "rad"}, input_unit="rad",
                     reference={OUTPUT: (ref_label, fr, g_ref(fr, v, geo, kc))}, marks=marks)


def sway_peak(v, points, geo, amplitude=AMPLITUDE, n=9):
    """The rear-sway resonance: around the largest measured gain, n more points
    between its neighbours and a parabola through the top three (log f, dB).
    Returns (frequency Hz, gain, the new points)."""
    k = int(np.argmax([p.gain for p in points]))
    lo, hi = points[max(k - 1, 0)].frequency, points[min(k + 1, len(points) - 1)].frequency
    fine = plant_points(v, np.geomspace(lo, hi, n + 2)[1:-1], geo, amplitude)
    j = int(np.clip(np.argmax([p.gain for p in fine]), 1, n - 2))
    x = np.log([p.frequency for p in fine[j - 1:j + 2]])
    y = 20 * np.log10([p.gain for p in fine[j - 1:j + 2]])
    c2, c1, c0 = np.polyfit(x, y, 2)
    xm = -c1 / (2 * c2)
    return math.exp(xm), 10 ** (np.polyval([c2, c1, c0], xm) / 20), fine


def write_bode_csv(path, v, points, geo, kc_value):
    from artibus.files import atomic_write
    with atomic_write(path) as f:
        f.write("frequency [Hz],plant gain [rad/rad],plant phase [deg],reference gain [rad/rad],"
                "reference phase [deg],reference gain times Kc [rad/rad]\n")
        ph = np.degrees(np.unwrap([p.phase for p in points]))
        for p, q in zip(points, ph):
            G = g_ref(p.frequency, v, geo)
            f.write(f"{p.frequency:.6g},{p.gain:.6g},{q:.4f},{abs(G):.6g},{math.degrees(np.angle(G)):.4f},"
                    f"{kc_value * abs(G):.6g}\n")


@dataclass
class BodeFigures:
    images: list        # [(file name in out, caption)]
    f_peak: float       # rear-sway resonance at 100 km/h, Hz
    g_peak: float       # its gain, rad/rad
    dev10: float        # 10 km/h: largest |plant - reference| gain up to 10 rad/s, dB


def bode_figures(out, kc100, geo=None):
    """The thesis's Figs. 4.1-4.3 into ``out``: steering -> articulation angle,
    the reference model against the plant at 10 and 100 km/h, and at 100 km/h
    with the complementary gain kc100; CSVs beside them."""
    out = Path(out)
    geo = geo or reference_geometry()
    sweeps = {kmh: plant_points(kmh / 3.6, BODE_FREQS, geo) for kmh in (10, 100)}
    f_pk, g_pk, fine = sway_peak(100 / 3.6, sweeps[100], geo)    # its points join the 100 km/h curve
    sweeps[100] = sorted(sweeps[100] + fine, key=lambda p: p.frequency)
    for kmh in (10, 100):
        write_bode_csv(out / f"bode_{kmh}kmh.csv", kmh / 3.6, sweeps[kmh], geo, kc100 if kmh == 100 else 1.0)
    figs = [("fig4_1_bode_10kmh.png", 10, 1.0, "Fig. 4.1: steering -> articulation angle at 10 km/h"),
            ("fig4_2_bode_100kmh.png", 100, 1.0, "Fig. 4.2: steering -> articulation angle at 100 km/h"),
            ("fig4_3_bode_100kmh_kc.png", 100, kc100,
             "Fig. 4.3: at 100 km/h, the reference model with the complementary gain Kc")]
    for name, kmh, k, title in figs:
        marks = ([(4.5 / (2 * math.pi), "paper: rear-sway peak about 4.5 rad/s (seed 001, Fig. 4.2)")] if kmh == 100
                 else [(10 / (2 * math.pi), "paper: very similar up to 10 rad/s (seed 001, Fig. 4.1)")])
        plot_bode(out / name, kmh / 3.6, sweeps[kmh], geo, k, f"{title}\nScania 18 m, friction 1 (seed 001, 4.1.2)",
                  marks)
    band = [p for p in sweeps[10] if 2 * math.pi * p.frequency <= 10.0]
    dev = max(abs(20 * math.log10(p.gain / abs(g_ref(p.frequency, 10 / 3.6, geo)))) for p in band)
    return BodeFigures([(name, title) for name, _, _, title in figs], f_pk, g_pk, dev)


def report(r, out):
    """The Scania18m_OpenLoop bench's report: seed 001's Figs. 4.1-4.3 (the
    bench's own run, straight ahead, is not what it is for)."""
    from artibus.report import Kpi
    geo = reference_geometry()
    ssv = read_parameters("Scania18mKc")
    speeds = [ssv[f"KcSpeed[{i}]"] for i in range(1, ssv["nKc"] + 1)]
    gains = [ssv[f"KcGain[{i}]"] for i in range(1, ssv["nKc"] + 1)]
    kc100 = float(np.interp(100 / 3.6, speeds, gains))
    figs = bode_figures(out, kc100, geo)
    kpis = [Kpi("rear-sway resonance at 100 km/h, friction 1", 2 * math.pi * figs.f_peak, "rad/s",
                "about 4.5 (0.7 Hz; read as 4.0-5.0)", "seed 001, 4.1.2, Fig. 4.2", abs(2 * math.pi * figs.f_peak - 4.5) < 0.5,
                bound=(4.0, 5.0),
                explain="The rear-sway resonance depends on the rear section's yaw inertia and the front "
                        "stiffnesses, which the thesis does not give (estimated in Scania18m.ssv), and on the "
                        "tyre model (linear, as the thesis's)."),
            Kpi("10 km/h: plant against reference model gain, up to 10 rad/s (largest difference)", figs.dev10,
                "dB", "very similar up to 10 rad/s (read as within 1 dB)", "seed 001, Fig. 4.1", figs.dev10 < 1.0,
                bound=1.0,
                explain="At 10 km/h the plant should behave kinematically; a difference depends on the tyre "
                        "stiffnesses (the slip at low speed) and on the sine test's amplitude and settling."),
            Kpi("complementary gain Kc at 100 km/h (Scania18mKc.ssv)", kc100, "-", "not given", "seed 001, 4.1.2",
                calibrated=True)]
    notes = ("Kc(v) matches the reference model's low-frequency gain to the plant's (scripts/kc_table.py "
             "writes the table; Scania18mKc.ssv). Sine tests through the co-simulation, amplitude "
             f"{AMPLITUDE:g} rad.")
    return kpis, figs.images, notes
