/* TrainGuidance: seed 000, Task 1, as an FMU. Variables in
 * modelDescription/TrainGuidance.xml; the algorithm in guidance.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "guidance.h"

/* plain data, saved as FMU state */
typedef struct {
    TgGuidance g;           /* parameters, constants, lag states */
    TgPath pm;              /* mode = pathMemory: pose, stored trace of A2 (fixed ring buffer) */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    unsigned fault;         /* fault bits of the last sample (a warning when a bit turns on) */
    int backwards;          /* driving direction of the last sample */
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
