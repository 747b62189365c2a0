"""The complementary gain Kc(v) of the damping controller (seed 001, 4.1.2)
measured on the Scania 18 m plant, and the Bode plots of the thesis's Figs.
4.1-4.3 (steering -> articulation angle, reference model against the plant at
10 and 100 km/h, and at 100 km/h after Kc). Writes into OUT (default out/kc):
Scania18mKc.ssv (the controller's nKc, KcSpeed[i], KcGain[i]), kc_speed.png,
fig4_1_bode_10kmh.png, fig4_2_bode_100kmh.png, fig4_3_bode_100kmh_kc.png,
bode_10kmh.csv, bode_100kmh.csv; prints the table.

usage: .venv/bin/python scripts/kc_table.py [-o OUT] [--ssv PATH]
The committed ssp/parameters/Scania18mKc.ssv is made with
    .venv/bin/python scripts/kc_table.py --ssv ssp/parameters/Scania18mKc.ssv
"""
import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from artibus.study import kc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default="out/kc", help="output directory (default out/kc)")
    ap.add_argument("--ssv", help="where to write the parameter set (default OUT/Scania18mKc.ssv)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    geo = kc.reference_geometry()
    print(f"reference model (seed 001, eq. 2.9): l1 = {geo['l1']:.3f} m, l2 = {geo['l2']:.3f} m, "
          f"a = {geo['a']:.4f} 1/m, kinematic DC gain a l2 = {geo['a'] * geo['l2']:.4f}")
    print(f"plant: bench {kc.BENCH}, steering sine {kc.AMPLITUDE:g} rad on {kc.INPUT}, output {kc.OUTPUT}")

    rows = kc.kc_table()
    t_table = time.perf_counter() - t0
    print(f"\nKc at {kc.F_LO:g} Hz ({kc.PERIODS_LO} periods), flatness check at {kc.F_CHECK:g} Hz:")
    print(f"{'v [km/h]':>8} {'v [m/s]':>8} {'|G_plant|':>10} {'phase [deg]':>11} {'|G_ref|':>8} "
          f"{'Kc':>7} {'Kc(check)':>9} {'diff [%]':>8} {'drift [%]':>9}")
    for r in rows:
        print(f"{r.kmh:8.0f} {r.speed:8.3f} {r.gain:10.5f} {math.degrees(r.phase):11.2f} {r.gain_ref:8.5f} "
              f"{r.kc:7.4f} {r.kc_check:9.4f} {(r.kc_check / r.kc - 1) * 100:8.3f} {r.drift * 100:9.4f}")

    command = " ".join(["scripts/kc_table.py"] + (sys.argv[1:] if argv is None else list(argv)))
    ssv = kc.write_ssv(args.ssv or out / "Scania18mKc.ssv", rows, command, geo=geo)
    kc.plot_kc(out / "kc_speed.png", rows)
    print(f"\n{ssv}\n{out / 'kc_speed.png'}")

    t1 = time.perf_counter()
    kc100 = next(r.kc for r in rows if round(r.kmh) == 100)
    figs = kc.bode_figures(out, kc100, geo)
    for path, _ in figs.images:
        print(out / path)
    t_bode = time.perf_counter() - t1
    print(f"\nrear-sway resonance at 100 km/h: {figs.f_peak:.3f} Hz = {2 * math.pi * figs.f_peak:.2f} rad/s, "
          f"gain {figs.g_peak:.3f} ({20 * math.log10(figs.g_peak / (geo['a'] * geo['l2'])):+.1f} dB against a l2; "
          f"seed 001: about 4.5 rad/s = 0.7 Hz)")
    print(f"10 km/h, up to 10 rad/s: plant gain within {figs.dev10:.2f} dB of the reference model's "
          f"(seed 001: very similar)")
    print(f"\ntime: table {t_table:.1f} s, Bode sweeps and peak {t_bode:.1f} s, "
          f"total {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
