"""Bus36m_Circle_LSBUS_Backwards: Bus36m_Circle_CAN_Backwards with its network as FMI-LS-BUS 1.0
FMUs on the bus simulation FMU CanBus (issue 24; artibus.runner.lsbus_bench): the KPIs of
Bus36m_Circle_Backwards."""
from artibus import report
from artibus.bench import script
from artibus.report.benchkit import circle_road, outlines

direct = script.load("Bus36m_Circle_Backwards")

TEXT = direct.TEXT + (" The steering network runs as FMI-LS-BUS FMUs (SteeringSensors_LSBUS, SteeringECU_LSBUS, "
                      "SteeringActuator_LSBUS) on the bus simulation FMU CanBus. The bench is an SSP 2.0 system "
                      "structure: the LS-BUS FMUs are components with ssc:Binary (the LS-BUS CAN MIME type) and "
                      "ssc:Clock connectors, each CAN terminal its four connections to a terminal of CanBus; "
                      "artibus's runner reads it (artibus.bench.ssp2), the SSP 1.0 masters ecos, libcosim and "
                      "fmpy.ssp do not, and it has no portable pack.")


def kpis(r):
    return direct.kpis(r)


def figures(r, out):
    """the path (the direct bench's other figures plot its Guidance component's signals, which
    run inside the LS-BUS ECUs here)"""
    ax = {a: (r[f"Bus.xAxle[{a}]"][::5], r[f"Bus.yAxle[{a}]"][::5]) for a in range(1, 7)}
    report.birds_eye(out / "path.png", {f"A{a}": ax[a] for a in range(1, 7)}, outlines=outlines(r, 3),
                     road=circle_road(), every=300,
                     title="36 m bus driven backwards on FMI-LS-BUS (A6 end leads), 3 m/s")
    return [("path.png", "Bird's-eye view: road (grey, followed by the outermost leading point), "
                         "body outlines every 3 s, axle traces.")]
