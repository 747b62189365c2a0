/* SteeringSensors_LSBUS on its FMI-LS-BUS CAN terminal (src/models/common/lsbus_node.h): the
 * inputs sent every Tx_Clock tick as the DBC's four sensor frames; it receives nothing. */
#include "fmu.h"
#include "lsbus_node.h"
#include "lsbus_units.h"

#define M(x) (1u << BUS36M_##x)

unsigned node_rx_mask(ModelInstance *comp) { (void)comp; return 0u; }

unsigned node_tx_mask(ModelInstance *comp) {
    (void)comp;
    return M(SENSORA1_ANGLE) | M(SENSORG1_ANGLE) | M(SENSORG2_ANGLE) | M(SENSORA6_ANGLE);
}

void node_rx(ModelInstance *comp, int msg, const double *x, unsigned counter) {
    (void)comp; (void)msg; (void)x; (void)counter;
}

void node_tx(ModelInstance *comp, int msg, double *x) {
    switch (msg) {
    case BUS36M_SENSORA1_ANGLE: x[0] = RAD_TO_DEG * D->gamma1; break;
    case BUS36M_SENSORG1_ANGLE: x[0] = RAD_TO_DEG * D->dPsi[1]; break;
    case BUS36M_SENSORG2_ANGLE: x[0] = RAD_TO_DEG * D->dPsi[2]; break;
    case BUS36M_SENSORA6_ANGLE: x[0] = RAD_TO_DEG * D->gammaA6; break;
    default: break;
    }
}

void node_sync(ModelInstance *comp) { (void)comp; }
