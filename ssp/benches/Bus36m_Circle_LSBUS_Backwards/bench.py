"""Bus36m_Circle_LSBUS_Backwards: Bus36m_Circle_CAN_Backwards with its network as FMI-LS-BUS 1.0
FMUs on the bus simulation FMU CanBus (issue 24; artibus.runner.lsbus_bench): the KPIs of
Bus36m_Circle_Backwards."""
from artibus.bench import script

direct = script.load("Bus36m_Circle_Backwards")

TEXT = direct.TEXT + (" The steering network runs as FMI-LS-BUS FMUs (SteeringSensors_LSBUS, SteeringECU_LSBUS, "
                      "SteeringActuator_LSBUS) on the bus simulation FMU CanBus.")


def kpis(r):
    return direct.kpis(r)


def figures(r, out):
    return direct.figures(r, out)
