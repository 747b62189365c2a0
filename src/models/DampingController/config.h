/* DampingController: seed 001's model-based articulation damping as an FMU.
 * Variables in modelDescription/DampingController.xml; the algorithm in
 * damping.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "damping.h"

/* plain data, saved as FMU state */
typedef struct {
    DcController c;         /* parameters, reference model state, outputs of the last sample */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    unsigned fault;         /* fault bits of the last sample (a message when a bit turns on) */
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
