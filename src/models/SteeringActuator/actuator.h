/* The steering actuators of one trailing module (A3+A4 or A5+A6) on the
 * steering CAN (issue 12), plain C99 without FMI types or heap: what runs in
 * the actuators' own controller. Per 10 ms cycle:
 *   1. the command message's alive counter: stale detection and fallback
 *      (can_fallback.c, the same code as the module ECU's): with fresh
 *      commands the target is the received set-point; when the ECU falls
 *      silent the target holds, then ramps to straight (0);
 *   2. the axle follows the target: a first-order lag with time constant Tact
 *      (exact over the cycle: y += (1 - exp(-Ts/Tact)) (target - y); Tact = 0:
 *      none) and a rate limit rateMax (|dy| <= rateMax Ts; 0: none). With
 *      both 0 (the default) the axle angle is the target (pass-through). */
#ifndef STEERING_ACTUATOR_H
#define STEERING_ACTUATOR_H

#include "can_fallback.h"   /* src/models/common, on the include path */

typedef struct {
    double Tact, rateMax;        /* [s], [rad/s]; 0 = none */
    int nStale, nRecover;
    double tHold, rampRate, Ts;
} ActParams;

typedef struct {
    ActParams p;
    double a;                    /* 1 - exp(-Ts/Tact), or 1 */
    CfFallback cf;
    double delta[2];             /* axle angles [rad] */
    double cmdRx[2];             /* set-points of the last new frame [rad] */
    unsigned stale;              /* 1: the command message was stale in the last cycle */
} SteeringAct;

/* 0, or a negative code naming the bad parameter (act_param_name); the axles
 * start at the set-points cmd */
int act_setup(SteeringAct *s, const ActParams *p, const double cmd[2], double alive);
const char *act_param_name(int code);
/* one cycle; the axle angles in s->delta, the fallback state in s->cf.mode */
void act_sample(SteeringAct *s, const double cmd[2], double alive);

#endif
