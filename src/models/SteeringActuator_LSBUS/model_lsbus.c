/* SteeringActuator_LSBUS: SteeringActuator (model.c, actuator.c: unchanged) on its
 * FMI-LS-BUS CAN terminal (src/models/common/lsbus_node.h): it receives its module's command
 * frame (module 1 TractorECU_Cmd, 2 Module2ECU_Cmd, 3 Module3ECU_Cmd) into cmd[1], cmd[2] and
 * alive, as Bus36m_Circle_CAN routes them today, and sends nothing. */
#include "fmu.h"
#include "lsbus_node.h"
#include "lsbus_units.h"

static int command_message(ModelInstance *comp) {
    return D->module == 1 ? BUS36M_TRACTORECU_CMD : D->module == 2 ? BUS36M_MODULE2ECU_CMD : BUS36M_MODULE3ECU_CMD;
}

unsigned node_rx_mask(ModelInstance *comp) { return 1u << command_message(comp); }

unsigned node_tx_mask(ModelInstance *comp) { (void)comp; return 0u; }

void node_rx(ModelInstance *comp, int msg, const double *x, unsigned counter) {
    if (msg != command_message(comp)) return;
    D->cmd[1] = DEG_TO_RAD * x[0];
    D->cmd[2] = DEG_TO_RAD * x[1];
    D->alive = counter;
}

void node_tx(ModelInstance *comp, int msg, double *x) { (void)comp; (void)msg; (void)x; }

void node_sync(ModelInstance *comp) { (void)comp; }
