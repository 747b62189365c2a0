/* SteeringECU_LSBUS: SteeringECU (model.c, ecu.c: unchanged) on its FMI-LS-BUS CAN terminal
 * (src/models/common/lsbus_node.h). What goes in and out of the frames, as the bench
 * Bus36m_Circle_CAN routes it today (ssp/benches/Bus36m_Circle_CAN, Route):
 *   received: SensorA1_Angle -> gamma1, aliveA1; SensorG1_Angle -> dPsi[1], aliveG1;
 *             SensorG2_Angle -> dPsi[2], aliveG2; SensorA6_Angle -> gammaA6, aliveA6;
 *             TractorECU_State -> direction, v, aliveState (modules 2 and 3: module 1 sends it);
 *   sent:     module 1 TractorECU_State (DrivingDirection = drivingDirection, VehicleSpeed =
 *             vVehicle) and TractorECU_Cmd (SteerCmdA1, A2 = gammaFront, gammaRear);
 *             module 2 Module2ECU_Cmd (A3, A4), module 3 Module3ECU_Cmd (A5, A6).
 * Module 1's v is vVehicle (the vehicle network's speed), copied before each sample. */
#include "fmu.h"
#include "lsbus_node.h"
#include "lsbus_units.h"

#define M(x) (1u << BUS36M_##x)

unsigned node_rx_mask(ModelInstance *comp) {
    const unsigned sensors = M(SENSORA1_ANGLE) | M(SENSORG1_ANGLE) | M(SENSORG2_ANGLE) | M(SENSORA6_ANGLE);
    return D->module == 1 ? sensors : sensors | M(TRACTORECU_STATE);
}

unsigned node_tx_mask(ModelInstance *comp) {
    return D->module == 1 ? M(TRACTORECU_STATE) | M(TRACTORECU_CMD) :
           D->module == 2 ? M(MODULE2ECU_CMD) : M(MODULE3ECU_CMD);
}

void node_rx(ModelInstance *comp, int msg, const double *x, unsigned counter) {
    switch (msg) {
    case BUS36M_SENSORA1_ANGLE: D->gamma1 = DEG_TO_RAD * x[0]; D->aliveA1 = counter; break;
    case BUS36M_SENSORG1_ANGLE: D->dPsi[1] = DEG_TO_RAD * x[0]; D->aliveG1 = counter; break;
    case BUS36M_SENSORG2_ANGLE: D->dPsi[2] = DEG_TO_RAD * x[0]; D->aliveG2 = counter; break;
    case BUS36M_SENSORA6_ANGLE: D->gammaA6 = DEG_TO_RAD * x[0]; D->aliveA6 = counter; break;
    case BUS36M_TRACTORECU_STATE:
        D->direction = x[BUS36M_TRACTORECU_STATE_DRIVINGDIRECTION];
        D->v = KMH_TO_MS * x[BUS36M_TRACTORECU_STATE_VEHICLESPEED];
        D->aliveState = counter;
        break;
    default: break;
    }
}

void node_tx(ModelInstance *comp, int msg, double *x) {
    if (msg == BUS36M_TRACTORECU_STATE) {
        x[BUS36M_TRACTORECU_STATE_DRIVINGDIRECTION] = D->drivingDirection;
        x[BUS36M_TRACTORECU_STATE_VEHICLESPEED] = MS_TO_KMH * D->vVehicle;
    } else {        /* the module's command frame: front axle, rear axle */
        x[0] = RAD_TO_DEG * D->gammaFront;
        x[1] = RAD_TO_DEG * D->gammaRear;
    }
}

void node_sync(ModelInstance *comp) {
    if (D->module == 1) D->v = D->vVehicle;
}
