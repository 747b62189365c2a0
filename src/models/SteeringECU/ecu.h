/* The steering ECU of one module of seed 000's 36 m bus (section IV:
 * "three automotive ECUs - one for each vehicle module ... interconnected by
 * CAN ... 10 ms"), issue 12. Plain C99, no FMI types, no heap, no globals:
 * what goes on the ECU.
 *
 * It runs the project's one copy of each algorithm: tg_sample (guidance.c,
 * eqs. 29-42) and fm_sample (forcemin.c, eqs. 43-48), as TrainGuidance and
 * ForceMinimization do, and keeps its own module's two angles.
 *
 * Forwards (DrivingDirection 0) the A1 end leads:
 *   module 1: steers nothing (A1 is the driver's, A2 rigid and driven);
 *   module 2: A4 = the guidance's gamma4; A3 = the force minimisation's gamma3
 *             from gamma1, dPsi1 and that gamma4 (hinge G2 and A6 do not enter
 *             gamma3: passed as 0);
 *   module 3: A6 = the guidance's gamma6; A5 = gamma5 from gamma1, dPsi1,
 *             dPsi2, gamma4 and gamma6. Module 3 computes gamma4 itself (the
 *             guidance of A4 needs only gamma1 and v, so it is bit for bit
 *             module 2's): it does not depend on module 2's ECU being alive.
 * Backwards (DrivingDirection 1) the A6 end leads and every role is mirrored
 * as in TrainGuidance and ForceMinimization (backwards = true): the leading
 * angle is A6's (SensorA6_Angle), the speed of the leading module is -v, the
 * hinges are seen from the leading module through leading_hinges.h (G2 as
 * -dPsi2 first, then G1 as -dPsi1); the guidance's gamma4 goes to A3, its
 * gamma6 to A1, the force minimisation's gamma3 to A4, its gamma5 to A2:
 *   module 3: steers nothing (A6 is the driver's, A5 rigid and driven);
 *   module 2: A3 = gamma4, A4 = gamma3 (needs both hinges: it sits between them);
 *   module 1: A1 = gamma6, A2 = gamma5 (the tractor ECU, with its actuators).
 * When the direction changes, the guidance's lags restart from the steady
 * state of the new leading angle (as TrainGuidance does) and the set-points
 * slew to the new roles' angles at rampRate (as after a fallback), no step.
 *
 * Module 1 is the tractor ECU: it knows the speed from the vehicle network
 * (its input v, signed: negative backwards; it does not watch the
 * TractorECU_State it sends itself) and computes the driving
 * direction it sends (ecu->direction): backwards once v < -vDir, forwards once
 * v > vDir, unchanged in between (hysteresis around standstill). Modules 2
 * and 3 take the direction they receive (TractorECU_State.DrivingDirection).
 *
 * What a module ECU receives on the steering CAN (ssp/can/Bus36m.dbc): the
 * leading steering angle (SensorA1_Angle forwards, SensorA6_Angle backwards),
 * the articulation angles (SensorG1_Angle, SensorG2_Angle), speed and driving
 * direction (TractorECU_State), and each message's alive counter.
 *
 * Fallback (can_fallback.h): a message the module uses in the current
 * direction stale for nStale cycles, or a driving direction other than 0 or 1
 * (J1939's error, not available), puts its set-points into hold, then a ramp
 * to straight. The algorithm keeps running on the last good inputs (its
 * outputs `calc`). */
#ifndef STEERING_ECU_H
#define STEERING_ECU_H

/* by name alone: the build puts the folders of src/models/TrainGuidance,
 * ForceMinimization and common on the include path, the source FMU has them all
 * in sources/ */
#include "guidance.h"
#include "forcemin.h"
#include "can_fallback.h"
#include "leading_hinges.h"

/* the messages an ECU watches, in this order (bits of the stale mask) */
enum { ECU_MSG_A1 = 0, ECU_MSG_G1 = 1, ECU_MSG_G2 = 2, ECU_MSG_STATE = 3, ECU_MSG_A6 = 4, ECU_NMSG = 5 };

#define ECU_FAULT_DIRECTION 32u   /* driving direction neither forwards (0) nor backwards (1): fallback */

typedef struct {
    int module;                   /* 1, 2 or 3 */
    TgParams tg;                  /* the guidance (Ts is the ECU's cycle) */
    FmParams fm;                  /* the force minimisation */
    int nStale, nRecover;         /* fallback (can_fallback.h) */
    double tHold, rampRate;
    double vDir;                  /* module 1: speed beyond which the direction is decided [m/s] */
} EcuParams;

typedef struct {
    double gamma1;                /* steered angle of A1 [rad] */
    double gammaA6;               /* steered angle of A6 [rad] (the leading angle backwards) */
    double v;                     /* speed of module 1, negative backwards [m/s] */
    double dPsi1, dPsi2;          /* articulation angles of G1, G2 [rad] */
    double direction;             /* DrivingDirection received: 0 forwards, 1 backwards, 2 error, 3 n/a */
    double alive[ECU_NMSG];       /* alive counters of the messages, ECU_MSG_* order */
} EcuInputs;

typedef struct {
    int module;
    double vDir;
    unsigned used;                /* the messages this module's algorithm uses in the current direction */
    int direction;                /* the direction it steers for (module 1: computes and sends it) */
    int backwards;                /* the roles of the guidance's lags now (1: A6 end leads) */
    TgGuidance g;
    FmSteering f;
    CfFallback cf;
    double calc[2];               /* the algorithm's angles: [0] front axle A1/A3/A5, [1] rear axle A2/A4/A6 [rad] */
    unsigned stale;               /* stale mask of the last cycle (messages the module uses) */
    unsigned fault;               /* TG_FAULT_* | FM_FAULT_* | ECU_FAULT_DIRECTION of the last cycle */
} SteeringEcu;

/* 0, or a negative code naming the bad parameter (ecu_param_name). The lags
 * start in the steady state of the leading angle, the outputs from in. */
int ecu_setup(SteeringEcu *e, const EcuParams *p, const EcuInputs *in);
const char *ecu_param_name(int code);

/* One 10 ms cycle; the set-points in e->cf.out[0] (front axle of the module),
 * e->cf.out[1] (rear axle), the fallback state in e->cf.mode, the direction in
 * e->direction. Returns e->fault. */
unsigned ecu_sample(SteeringEcu *e, const EcuInputs *in);

#endif
