/* SteeringActuator: the steering actuators of one trailing module (issue 12)
 * as an FMU. Variables in modelDescription/SteeringActuator.xml; the
 * algorithm in actuator.c (can_fallback.c inside). */
#ifndef CONFIG_H
#define CONFIG_H

#ifdef MODEL_LSBUS
#include "lsbus_node.h"
#endif
#include "actuator.h"

/* plain data, saved as FMU state */
typedef struct {
    SteeringAct a;          /* parameters, fallback state, axle angles */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    int mode;               /* fallback state of the last sample */
#ifdef MODEL_LSBUS
    LsNode bus;             /* the FMI-LS-BUS build (<Name>_LSBUS): its bus terminal's state */
#endif
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
