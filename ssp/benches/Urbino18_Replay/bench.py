"""Urbino18_Replay: seed 003's replay of a recorded drive (section V, Figs.
9-11) in the main job: the bench's own run stands still (its inputs come
from a log), so the report is a study that replays the shipped log
ssp/logs/Urbino18_test.csv into this bench (artibus.can.replay, as
`artibus replay ssp/logs/Urbino18_test.csv --bench Urbino18_Replay`) and
shows model against measured, with the RMS error of each signal."""
from artibus import ROOT
from artibus.report import Kpi

LOG = ROOT / "ssp" / "logs" / "Urbino18_test.csv"

TEXT = ("The shipped log is SYNTHETIC (scripts/make_test_log.py: a run of our own BusKinematics with sensor "
        "noise, quantisation and backlash), not a measurement: the errors show what the replay recovers, not "
        "how the model compares with a real Urbino 18.")


def kpis(r):
    """The bench's own run (no log: its inputs stay at 0): nothing to grade."""
    moved = abs(r["Bus.x[0]"][-1] - r["Bus.x[0]"][0]) + abs(r["Bus.y[0]"][-1] - r["Bus.y[0]"][0])
    return [Kpi("distance moved by the rear axle P0 without a log", float(moved), "m")]


def figures(r, out):
    return []


def study(r, out):
    """The shipped log replayed into this bench: model against measured, RMS per signal (the page's KPIs);
    the page shows the replay's run (its span, animation, results.csv), not the bench's own standing still."""
    from artibus.can import replay
    rep = replay.replay(LOG, "Urbino18_Replay", record=["Bus.x[0]", "Bus.y[0]", "Bus.theta[0]"])
    kpis, images, notes = replay.page_parts(rep, out, f"{LOG.name} replayed into Urbino18_Replay")
    return kpis, images, [f"The shipped recorded drive {LOG.relative_to(ROOT)} replayed. " + TEXT] + notes, rep.result
