/* The steering ECU of one trailing module of seed 000's 36 m bus (section IV:
 * "three automotive ECUs - one for each vehicle module ... interconnected by
 * CAN ... 10 ms"), issue 12: module 2's ECU steers A3 (force minimisation,
 * Task 2) and A4 (train-like guidance, Task 1), module 3's ECU A5 and A6.
 * Plain C99, no FMI types, no heap, no globals: what goes on the ECU.
 *
 * It runs the project's one copy of each algorithm: tg_sample (guidance.c,
 * eqs. 29-42) and fm_sample (forcemin.c, eqs. 43-48), as TrainGuidance and
 * ForceMinimization do, and keeps its own module's two angles:
 *   module 2: A4 = the guidance's gamma4; A3 = the force minimisation's gamma3
 *             from gamma1, dPsi1 and that gamma4 (hinge G2 and A6 do not enter
 *             gamma3: passed as 0);
 *   module 3: A6 = the guidance's gamma6; A5 = gamma5 from gamma1, dPsi1,
 *             dPsi2, gamma4 and gamma6. Module 3 computes gamma4 itself (the
 *             guidance of A4 needs only gamma1 and v, so it is bit for bit
 *             module 2's): it does not depend on module 2's ECU being alive.
 * What a module ECU receives on the steering CAN (ssp/can/Bus36m.dbc): the
 * front steering angle (SensorA1_Angle), the articulation angles
 * (SensorG1_Angle; module 3 also SensorG2_Angle), speed and driving
 * direction (TractorECU_State), and each message's alive counter.
 *
 * Fallback (can_fallback.h): a used message stale for nStale cycles, or a
 * driving direction other than forwards (this ECU implements the forward
 * roles only), puts its set-points into hold, then a ramp to straight. The
 * algorithm keeps running on the last good inputs (its outputs `calc`). */
#ifndef STEERING_ECU_H
#define STEERING_ECU_H

#include "../TrainGuidance/guidance.h"
#include "../ForceMinimization/forcemin.h"
#include "../common/can_fallback.h"

/* the messages an ECU watches, in this order (bits of the stale mask) */
enum { ECU_MSG_A1 = 0, ECU_MSG_G1 = 1, ECU_MSG_G2 = 2, ECU_MSG_STATE = 3, ECU_NMSG = 4 };

#define ECU_FAULT_DIRECTION 32u   /* driving direction not forwards (0): fallback */

typedef struct {
    int module;                   /* 2 or 3 */
    TgParams tg;                  /* the guidance (Ts is the ECU's cycle) */
    FmParams fm;                  /* the force minimisation */
    int nStale, nRecover;         /* fallback (can_fallback.h) */
    double tHold, rampRate;
} EcuParams;

typedef struct {
    double gamma1;                /* front steering angle [rad] */
    double v;                     /* speed of module 1 [m/s] */
    double dPsi1, dPsi2;          /* articulation angles of G1, G2 [rad] */
    double direction;             /* DrivingDirection: 0 forwards, 1 backwards, 2 error, 3 n/a */
    double alive[ECU_NMSG];       /* alive counters of the messages, ECU_MSG_* order */
} EcuInputs;

typedef struct {
    int module;
    unsigned used;                /* the messages this module's algorithm uses */
    TgGuidance g;
    FmSteering f;
    CfFallback cf;
    double calc[2];               /* the algorithm's angles: [0] A3/A5, [1] A4/A6 [rad] */
    unsigned stale;               /* stale mask of the last cycle (messages the module uses) */
    unsigned fault;               /* TG_FAULT_* | FM_FAULT_* | ECU_FAULT_DIRECTION of the last cycle */
} SteeringEcu;

/* 0, or a negative code naming the bad parameter (ecu_param_name). The lags
 * start in the steady state of in->gamma1, the outputs from in. */
int ecu_setup(SteeringEcu *e, const EcuParams *p, const EcuInputs *in);
const char *ecu_param_name(int code);

/* One 10 ms cycle; the set-points in e->cf.out[0] (A3/A5), e->cf.out[1]
 * (A4/A6), the fallback state in e->cf.mode. Returns e->fault. */
unsigned ecu_sample(SteeringEcu *e, const EcuInputs *in);

#endif
