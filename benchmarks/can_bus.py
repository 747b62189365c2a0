"""Benchmark (prints, not a test) of the CAN path (artibus.can, issue 12).

1. Real-time factor of Bus36m_Circle_CAN (70 s, six frames every 10 ms on
   python-can's virtual bus) against the same bench with direct connections,
   Bus36m_Circle's variant guidedForceMin, and the wall time spent in the network's
   ticks; without a log and with a .blf log. Runs alternate; best and median
   of REPEAT runs are printed (this machine is shared).
2. The CAN path's cost per frame, its parts timed alone on the bench's
   network: cantools encode (strict) with counter and CRC, the frame's bit
   count (stuffing; cached by content), VirtualBus send + receive, the checks
   and cantools decode into the receivers' inputs.

usage: .venv/bin/python benchmarks/can_bus.py (not can.py: the name would shadow python-can)
"""
import statistics
import tempfile
import time
from pathlib import Path

import can as pycan

from artibus import can as artcan, runner
from artibus.bench import ssp

REPEAT = 3


def timed_run(bench, log=None, variant=None):
    overrides = ssp.variant_overrides(bench, [variant]) if variant else None
    with runner.Simulation(bench, can_log=log, overrides=overrides) as sim:
        in_ticks = [0.0]
        if sim.can is not None:
            tick = sim.can.tick

            def timed(k, t):
                w = time.perf_counter()
                tick(k, t)
                in_ticks[0] += time.perf_counter() - w
            sim.can.tick = timed
        r = sim.run()
        frames = sim.can.frames if sim.can is not None else 0
        return r.time[-1] - r.time[0], sim.wall, in_ticks[0], frames


def main():
    rows = {"direct": [], "CAN": [], "CAN + .blf": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(REPEAT):
            rows["direct"].append(timed_run("Bus36m_Circle", variant="guidedForceMin"))
            rows["CAN"].append(timed_run("Bus36m_Circle_CAN"))
            rows["CAN + .blf"].append(timed_run("Bus36m_Circle_CAN", Path(tmp) / f"r{i}.blf"))
    print(f"1. real-time factor, best / median of {REPEAT} runs (70 s simulated)")
    best_direct = min(w for _, w, _, _ in rows["direct"])
    for name, rs in rows.items():
        span = rs[0][0]
        walls = [w for _, w, _, _ in rs]
        ticks = [c for _, _, c, _ in rs]
        frames = rs[0][3]
        extra = (f"; in the network's ticks {min(ticks):.2f} s, {1e6 * min(ticks) / frames:.0f} us per frame"
                 if frames else "")
        print(f"   {name:12s} {span / min(walls):7.1f} x / {span / statistics.median(walls):7.1f} x real time "
              f"(wall {min(walls):.2f} s, {min(walls) / best_direct:.1f} x the direct bench){extra}")

    print("2. cost per frame of the CAN path's parts (the bench's network after a run, best of 5 x 2000)")
    with runner.Simulation("Bus36m_Circle_CAN") as sim:
        sim.run(stop_time=20.0)
        net = sim.can
        m = next(x for x in net.messages if x.msg.name == "Module2ECU_Cmd")
        data = net._encode(m, 20.0)
        msg = pycan.Message(arbitration_id=m.msg.frame_id, is_extended_id=False, data=data, timestamp=20.0)

        def best(f, n=2000):
            ts = []
            for _ in range(5):
                w = time.perf_counter()
                for _ in range(n):
                    f()
                ts.append((time.perf_counter() - w) / n)
            return min(ts)

        def deliver():
            m.last_counter = None
            net._deliver(m, data)

        def send_recv():
            net.bus.send(msg)
            net.bus.recv(timeout=0.0)

        parts = [
            ("encode (cantools, strict) + counter + CRC", lambda: net._encode(m, 20.0)),
            ("E2E CRC alone (table)", lambda: artcan.e2e_crc(data, m.data_id)),
            ("bit count, cached", lambda: artcan.frame_bits(m.msg.frame_id, data)),
            ("bit count, not cached", lambda: artcan.frame_bits.__wrapped__(m.msg.frame_id, data)),
            ("VirtualBus send + recv", send_recv),
            ("checks + decode (cantools) into the inputs", deliver),
        ]
        for name, f in parts:
            print(f"   {name:45s} {1e6 * best(f):7.1f} us")


if __name__ == "__main__":
    main()
