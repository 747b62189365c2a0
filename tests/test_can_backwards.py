"""The driving direction on the steering CAN (issue 12): seed 000's 36 m bus
driven backwards (the A6 end leads) with one SteeringECU per module, the
tractor ECU (module 1) deciding the direction from the wheel speed's sign and
steering A1 and A2 through its actuators, against the direct bench
Bus36m_Circle_Backwards (TrainGuidance and ForceMinimization with
backwards = true); a direction change seen by every ECU within one cycle."""

import cantools
import numpy as np
import pytest

from artibus.bench import ssp
from artibus.runner import run
from artibus.study import kpi
from can_bound import DBC, assert_within_bound, kpi_bound

DIRECT, CAN_BENCH = "Bus36m_Circle_Backwards", "Bus36m_Circle_CAN_Backwards"
COUNTER = "AliveCounter"
ECUS = ["ECU1", "ECU2", "ECU3"]
FALLBACK = [f"{c}.fallback" for c in ECUS + ["Act1", "Act2", "Act3"]]
#: each routed output and input of the CAN bench and its counterpart in the direct bench
#: (one TrainGuidance and one ForceMinimization for the whole bus, set-points into the plant).
#: [] : not used backwards (A1's angle, the direction, module 3's set-points: A5 is commanded
#: straight, exactly 0 in every resolution; A6 is the driver's)
DIRECT_OF = {
    "ECU1.gammaFront": ["Guidance.gamma6"], "ECU1.gammaRear": ["ForceMin.gamma5"],
    "ECU2.gammaFront": ["Guidance.gamma4"], "ECU2.gammaRear": ["ForceMin.gamma3"],
    "ECU1.gammaA6": ["Guidance.gamma1", "ForceMin.gamma1"], "ECU2.gammaA6": [], "ECU3.gammaA6": [],
    "ECU1.v": [], "ECU2.v": ["Guidance.v"], "ECU3.v": [],
    "ECU1.dPsi[1]": ["ForceMin.dPsi[1]"], "ECU2.dPsi[1]": [], "ECU3.dPsi[1]": [],
    "ECU1.dPsi[2]": ["ForceMin.dPsi[2]"], "ECU2.dPsi[2]": [], "ECU3.dPsi[2]": [],
    "Act1.cmd[1]": ["Bus.delta[1]"], "Act1.cmd[2]": ["Bus.delta[2]"],
    "Act2.cmd[1]": ["Bus.delta[3]"], "Act2.cmd[2]": ["Bus.delta[4]"],
}
#: the direct bench's source of each routed sender output
SOURCE_OF = {"ECU1.gammaFront": "Guidance.gamma6", "ECU1.gammaRear": "ForceMin.gamma5",
             "ECU2.gammaFront": "Guidance.gamma4", "ECU2.gammaRear": "ForceMin.gamma3"}
#: signals that carry nothing the backwards run depends on, or an exact integer
UNUSED = {("SensorA1_Angle", "RoadWheelAngleA1"), ("TractorECU_State", "DrivingDirection"),
          ("Module3ECU_Cmd", "SteerCmdA5"), ("Module3ECU_Cmd", "SteerCmdA6")}
KPI_RECORD = ([f"Bus.{n}[{a}]" for n in ("xAxle", "yAxle") for a in range(1, 7)]
              + [f"Bus.{n}[{k}]" for n in ("artAngle", "FjointX", "FjointY") for k in (1, 2)] + ["Driver.s"])


def routes():
    """{(message, signal): (source "C.v", [receiver "C.v", ...])} as the bench declares them."""
    out = {}
    for c in ssp.read(ssp.ssp_path(CAN_BENCH)).connections:
        if c.can:
            src, ends = out.setdefault((c.can["message"], c.can["signal"]), (".".join(c.start), []))
            assert src == ".".join(c.start)
            ends.append(".".join(c.end))
    return out


def kpis(r):
    """Bus36m_Circle_Backwards' paper KPIs: A3 and A1 from the A5 trace, the
    leading hinge G2's lateral force (in module 3's frame)."""
    ax = {a: (r[f"Bus.xAxle[{a}]"], r[f"Bus.yAxle[{a}]"]) for a in (1, 3, 5)}
    a2 = r["Bus.artAngle[2]"]
    G2 = np.sin(a2) * r["Bus.FjointX[2]"] + np.cos(a2) * r["Bus.FjointY[2]"]
    return np.array([kpi.trace_deviation(*ax[5], *ax[3]), kpi.trace_deviation(*ax[5], *ax[1]), kpi.peak(G2)])


@pytest.fixture(scope="module")
def direct():
    sources = [SOURCE_OF.get(s, s) for s, _ in routes().values()]
    rec = [s for s in sources if not s.startswith(("ECU", "Act"))]
    return run(DIRECT, record=list(dict.fromkeys(KPI_RECORD + rec + list(SOURCE_OF.values()))))


@pytest.fixture(scope="module")
def backwards():
    return run(CAN_BENCH, record=KPI_RECORD + FALLBACK + [f"{c}.drivingDirection" for c in ECUS])


def test_bench_routes_what_a_module_ecu_can_know():
    """Each ECU gets only its own module's sensors and what the bus carries:
    the A6 angle, the hinges and TractorECU_State over CAN; the tractor ECU's
    speed directly (the vehicle network), and it sends the direction."""
    r = routes()
    assert r[("TractorECU_State", "DrivingDirection")] == ("ECU1.drivingDirection", ["ECU2.direction", "ECU3.direction"])
    assert set(r[("SensorA6_Angle", "RoadWheelAngleA6")][1]) == {"ECU1.gammaA6", "ECU2.gammaA6", "ECU3.gammaA6"}
    assert r[("TractorECU_Cmd", "SteerCmdA1")] == ("ECU1.gammaFront", ["Act1.cmd[1]"])
    db = cantools.database.load_file(str(DBC))
    for (msg, sig), (src, ends) in r.items():
        m = db.get_message_by_name(msg)
        for e in ends:         # every receiver is a node the DBC names as one
            node = {"ECU1": "TractorECU", "ECU2": "Module2ECU", "ECU3": "Module3ECU", "Act1": "SteerActuatorM1",
                    "Act2": "SteerActuatorM2", "Act3": "SteerActuatorM3"}[e.split(".")[0]]
            assert node in m.get_signal_by_name(sig).receivers, (msg, sig, e)


def test_backwards_on_can_reproduces_the_direct_kpis_within_a_derived_bound(direct, backwards):
    """The bound derived from the DBC as forwards (tests/can_bound.py): each
    routed signal's error as a constant bias on its receivers' counterparts
    in the direct bench. Signals the backwards run does not depend on (A1's
    angle: no ECU uses it backwards; module 3's set-points: exactly 0; the
    direction: a constant integer) add nothing. No receiver leaves normal
    operation, every ECU steers backwards throughout, and the paper's < 1.0 m
    and < 4 kN hold."""
    signals = [(msg, sig, SOURCE_OF.get(src, src), [d for x in ends for d in DIRECT_OF[x]])
               for (msg, sig), (src, ends) in routes().items() if sig != COUNTER and (msg, sig) not in UNUSED]
    for msg, sig, _, targets in signals:
        assert targets, (msg, sig)
    assert len(signals) == 8               # A6, G1, G2, speed, A1..A4's set-points
    bound = kpi_bound(direct, kpis, lambda **kw: run(DIRECT, **kw), signals, KPI_RECORD)
    assert_within_bound(backwards, direct, kpis, bound, (3, 1), FALLBACK)    # A3, A1: the deviation KPIs'
    for c in ECUS:
        assert np.all(backwards[f"{c}.drivingDirection"] == 1), c


def test_a_direction_change_reaches_every_ecu_within_one_cycle():
    """The bus rolls forwards at 1.5 m/s and the driver (wired for backwards)
    reverses it: the tractor ECU turns to backwards in the first cycle its
    speed input is below -vDir (1 m/s in this bench), modules 2 and 3 in the
    next one (TractorECU_State sent at the next tick). Before, every ECU steers
    forwards; no receiver falls back."""
    rec = ["Bus.vx[3]"] + FALLBACK + [f"{c}.drivingDirection" for c in ECUS]
    r = run(CAN_BENCH, overrides={"Bus.vx_start": 1.5}, record=rec, stop_time=8.0)
    d = {c: r[f"{c}.drivingDirection"] for c in ECUS}
    for c in ECUS:
        assert d[c][0] == 0 and d[c][-1] == 1 and np.all(np.diff(d[c]) >= 0), c
    k1 = int(np.argmax(d["ECU1"] == 1))
    # ECU1 samples its input at the start of each step: the direction is 1 from the first
    # sample whose speed is below -1 m/s (the recorded output follows the step's sample)
    kv = int(np.argmax(r["Bus.vx[3]"] < -1.0))
    assert k1 - kv in (0, 1), (k1, kv)
    for c in ("ECU2", "ECU3"):
        kc = int(np.argmax(d[c] == 1))
        assert 0 < kc - k1 <= 1, (c, kc - k1)
    for x in FALLBACK:
        assert np.all(r[x] == 0), x
