"""Bus36m_Slalom: the steered 36 m bus, slalom through 6 cones 30 m apart at
40 km/h. Its KPIs (a function of the result alone), figures and text
(artibus.benches)."""
from artibus.report import Kpi
from artibus.report.benchkit import ROAD_TEST_TEXT, road_test_figures, road_test_kpis, slalom_road_module
from artibus.study import kpi

TEXT = ROAD_TEST_TEXT
sl = slalom_road_module()


def _t_after(r):
    x1 = r["Bus.xAxle[1]"]
    return float(r.time[x1 > sl.end_of_slalom()][0]) if (x1 > sl.end_of_slalom()).any() else r.time[-1]


def kpis(r):
    x1 = r["Bus.xAxle[1]"]
    inside = (x1 >= sl.cones()[0]) & (x1 <= sl.cones()[-1])
    in6 = (r["Bus.xAxle[6]"] >= sl.cones()[0]) & (r["Bus.xAxle[6]"] <= sl.cones()[-1])
    amp1 = kpi.peak(r["Bus.yAxle[1]"][inside]) if inside.any() else float("nan")
    amp6 = kpi.peak(r["Bus.yAxle[6]"][in6]) if in6.any() else float("nan")
    extra = [
        Kpi("A1: max |lateral offset| between the cones", amp1, "m", f"road: {sl.AMPLITUDE:g}", ""),
        Kpi("A6: max |lateral offset| between the cones", amp6, "m"),
        Kpi("rearward amplification A6 / A1", amp6 / amp1, "-"),
    ]
    return road_test_kpis(r, _t_after(r), "slalom", extra)


def figures(r, out):
    from artibus import ROOT
    from artibus.bench import roads
    road = roads.read_csv(ROOT / "ssp" / "roads" / "Bus36m_Slalom.csv")
    return road_test_figures(r, out, f"Steered 36 m bus, slalom: {sl.CONES} cones {sl.SPACING:g} m apart "
                             f"(path +-{sl.AMPLITUDE:g} m) at 40 km/h", (road[0], road[1]), _t_after(r), "slalom",
                             cones=sl.cones())
