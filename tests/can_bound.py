"""How far a bench with the steering on CAN may differ from its direct bench
(the same controllers and plant wired without a bus): the bound on the KPIs
that tests/test_can.py (forwards) and tests/test_can_backwards.py (backwards)
derive from the DBC.

The CAN path changes each routed input by at most half a step of its signal's
resolution (the DBC's scale) plus one cycle of delay, T times the input's
largest rate on the direct run. The KPIs' sensitivity to each signal's error
comes from a direct run with that error added to the signal's receivers'
counterparts as a constant bias (runner stimuli); the bound is twice the sum
over the signals (a bias stands for an error that varies in time)."""
import math

import cantools
import numpy as np

from artibus import ROOT

DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
T = 0.01                                    # the network's tick (seed 000: 10 ms)
TO_SI = {"deg": math.pi / 180, "km/h": 1 / 3.6, "": 1.0}   # the DBC's units to the FMUs' (rad, m/s)


def kpi_bound(direct, kpis, run_direct, signals, record):
    """The bound on |kpis(CAN run) - kpis(direct)|, an array like kpis' result.

    direct: the direct bench's result, recording each signal's source;
    kpis(result) -> array of the KPIs; run_direct(record=, stimuli=) runs the
    direct bench; signals: [(message, signal, source, targets)] with source
    the direct bench's name of what the signal carries and targets the names
    there of its receivers' counterparts; record: what the KPIs need."""
    db = cantools.database.load_file(str(DBC))
    k0 = kpis(direct)
    bound = np.zeros(len(k0))
    h = direct.time[1] - direct.time[0]
    for msg, sig, src, targets in signals:
        s = db.get_message_by_name(msg).get_signal_by_name(sig)
        u = direct[src]
        e = s.scale * TO_SI[s.unit] / 2 + T * np.max(np.abs(np.diff(u))) / h
        r = run_direct(record=record, stimuli={x: (lambda t, e=e: e) for x in targets})
        bound += np.abs(kpis(r) - k0)
    return 2 * bound


def assert_within_bound(r, direct, kpis, bound, axles, fallback):
    """The CAN run r against the direct run: its KPIs within bound of the
    direct run's; the paths themselves, of the two axles whose deviations the
    first two KPIs measure, within the bound of their KPI; the paper's figures
    still hold (seed 000, Figs. 9, 10: deviations < 1.0 m, hinge force < 4 kN)
    with the whole circle driven (25 m straight, then R = 17.5 m); no receiver
    leaves normal operation (each of fallback 0 throughout)."""
    k0, k = kpis(direct), kpis(r)
    assert np.all(np.abs(k - k0) <= bound), (k, k0, bound)
    for a, b in zip(axles, bound[:2]):
        dist = np.hypot(r[f"Bus.xAxle[{a}]"] - direct[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"] - direct[f"Bus.yAxle[{a}]"])
        assert np.max(dist) <= b, (a, np.max(dist), b)
    assert k[0] < 1.0 and k[1] < 1.0 and k[2] < 4e3
    assert r["Driver.s"][-1] > 25 + 2 * math.pi * 17.5
    for x in fallback:
        assert np.all(r[x] == 0), x
