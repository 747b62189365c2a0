"""Bus36m_LaneChange: the steered 36 m bus, lane change 3.5 m over 40 m at
50 km/h. Its KPIs (a function of the result alone), figures and text
(artibus.benches)."""
from artibus.report import Kpi
from artibus.report.benchkit import ROAD_TEST_TEXT, lane_change_road, road_test_figures, road_test_kpis
from artibus.study import kpi

LENGTH, OFFSET, LANE, WIDTH = 40.0, 3.5, 3.5, 2.55
TEXT = ROAD_TEST_TEXT


def _t_after(r):
    done = r["Driver.s"] > 25 + LENGTH
    return float(r.time[done][0]) if done.any() else r.time[-1]


def kpis(r):
    e = kpi.peak(r["Driver.eLat"])
    allowed = (LANE - WIDTH) / 2
    extra = [
        Kpi("front axle A1: max |lateral error| against what the lane allows", e, "m",
            f"< (lane 3.5 m - body 2.55 m) / 2 = {allowed:.3f}", "ours: the lane's geometry (seed 000 gives none)",
            e < allowed, bound=allowed, explain="The bound is the lane's geometry, not a paper's figure. The error depends on "
                                 "the road-follow driver's look-ahead (Driver.tNear, tFar) and steering-rate "
                                 "limit at 50 km/h; a longer look-ahead or a longer lane change would lower it."),
        Kpi("A4 overshoot beyond the 3.5 m offset", kpi.overshoot(r["Bus.yAxle[4]"], OFFSET), "m"),
        Kpi("A6 overshoot beyond the 3.5 m offset", kpi.overshoot(r["Bus.yAxle[6]"], OFFSET), "m"),
    ]
    return road_test_kpis(r, _t_after(r), "lane change", extra)


def figures(r, out):
    return road_test_figures(r, out, "Steered 36 m bus, lane change 3.5 m / 40 m at 50 km/h",
                             lane_change_road(LENGTH, OFFSET, after=250), _t_after(r), "lane change",
                             bounds=[(4, y, "the lane allows +-0.475 m (lane 3.5 m, body 2.55 m; ours)")
                                     for y in ((LANE - WIDTH) / 2, -(LANE - WIDTH) / 2)])
