"""Bus36m_Circle_LSBUS: Bus36m_Circle_CAN with its network as FMI-LS-BUS 1.0 FMUs on the bus
simulation FMU CanBus (issue 24; artibus.runner.lsbus_bench): the circle's KPIs (those of
Bus36m_Circle's variant guidedForceMin)."""
from artibus.bench import script

direct = script.load("Bus36m_Circle")
#: the direct run's counterpart: the variant of Bus36m_Circle with the same controllers
VARIANT = "guidedForceMin"

TEXT = direct.CIRCLE_TEXT + (" The steering network runs as FMI-LS-BUS FMUs (SteeringSensors_LSBUS, "
                             "SteeringECU_LSBUS, SteeringActuator_LSBUS) on the bus simulation FMU CanBus.")


def kpis(r):
    return direct.variant_kpis(r, VARIANT)


def figures(r, out):
    return direct.circle_figures(r, out, direct.VARIANTS[VARIANT][0], variant=VARIANT)
