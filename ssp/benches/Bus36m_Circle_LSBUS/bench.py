"""Bus36m_Circle_LSBUS: Bus36m_Circle_CAN with its network as FMI-LS-BUS 1.0 FMUs on the bus
simulation FMU CanBus (issue 24; artibus.runner.lsbus_bench): the circle's KPIs (those of
Bus36m_Circle's variant guidedForceMin)."""
from artibus.bench import script

direct = script.load("Bus36m_Circle")
#: the direct run's counterpart: the variant of Bus36m_Circle with the same controllers
VARIANT = "guidedForceMin"

TEXT = direct.CIRCLE_TEXT + (" The steering network runs as FMI-LS-BUS FMUs (SteeringSensors_LSBUS, "
                             "SteeringECU_LSBUS, SteeringActuator_LSBUS) on the bus simulation FMU CanBus. "
                             "The bench is an SSP 2.0 system structure: the LS-BUS FMUs are components with "
                             "ssc:Binary (the LS-BUS CAN MIME type) and ssc:Clock connectors, each CAN terminal "
                             "its four connections to a terminal of CanBus; artibus's runner reads it "
                             "(artibus.bench.ssp2), the SSP 1.0 masters ecos, libcosim and fmpy.ssp do not, "
                             "and it has no portable pack.")


def kpis(r):
    return direct.variant_kpis(r, VARIANT)


def figures(r, out):
    return direct.circle_figures(r, out, direct.VARIANTS[VARIANT][0], variant=VARIANT)
