/* SteeringECU: the steering ECU of module 2 or 3 (issue 12) as an FMU.
 * Variables in modelDescription/SteeringECU.xml; the algorithm in ecu.c
 * (guidance.c, forcemin.c, can_fallback.c inside). */
#ifndef CONFIG_H
#define CONFIG_H

#ifdef MODEL_LSBUS
#include "lsbus_node.h"
#endif
#include "ecu.h"

/* plain data, saved as FMU state */
typedef struct {
    SteeringEcu e;          /* parameters, lag states, fallback state */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    unsigned fault;         /* fault bits of the last sample (a warning when a bit turns on) */
    unsigned stale;         /* stale mask of the last sample */
    int mode;               /* fallback state of the last sample */
    int direction;          /* driving direction of the last sample (an event when it changes) */
#ifdef MODEL_LSBUS
    LsNode bus;             /* the FMI-LS-BUS build (<Name>_LSBUS): its bus terminal's state */
#endif
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
