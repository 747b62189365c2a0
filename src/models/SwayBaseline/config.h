/* SwayBaseline: an ACS5-like condition-based damping baseline (seed 001's
 * description) as an FMU. Variables in modelDescription/SwayBaseline.xml; the
 * algorithm in baseline.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "baseline.h"

/* plain data, saved as FMU state */
typedef struct {
    SbBaseline b;           /* parameters, SSC hold timer, outputs of the last sample */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    unsigned fault;         /* fault bits of the last sample */
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
