"""Scania18m_OpenLoop: the Scania 18 m alone, open loop, for frequency
responses (artibus.kc). The KPIs of one run (a function of the result alone);
the report is a study: seed 001's Figs. 4.1-4.3 by sine tests (the bench's own
run, straight ahead, is not what it is for) (artibus.benches)."""
from artibus import report
from artibus.report import Kpi
from artibus.report.benchkit import DEG
from artibus.study import kc, kpi


def kpis(r):
    return [Kpi("max |articulation angle|", kpi.peak(r["Bus.artAngle[1]"]) * DEG, "deg"),
            Kpi("speed at the end of the run", float(r["Bus.vx[1]"][-1]) * 3.6, "km/h")]


def figures(r, out):
    report.signals(out / "signals.png", r.time, [
        ("articulation [deg]", {"hinge": r["Bus.artAngle[1]"] * DEG}),
        ("speed [km/h]", {"vx[1]": r["Bus.vx[1]"] * 3.6})], title="Scania18m_OpenLoop, this run")
    return [("signals.png", "Articulation angle and speed of this run.")]


def study(r, out):
    return kc.report(r, out)
