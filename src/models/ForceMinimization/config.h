/* ForceMinimization: seed 000, Task 2, as an FMU. Variables in
 * modelDescription/ForceMinimization.xml; the algorithm in forcemin.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "forcemin.h"

/* plain data, saved as FMU state */
typedef struct {
    FmSteering f;           /* parameters and the outputs of the last sample */
    double t0;              /* start time: sample k is at t0 + k Ts */
    long long k;            /* index of the next sample */
    unsigned fault;         /* fault bits of the last sample */
    double gamma4, gamma6;  /* the gamma4, gamma6 inputs held at the last sample (law = likeGuided) */
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

/* the values of the parameter law (modelDescription/ForceMinimization.xml) */
enum { LAW_STRAIGHT = 0, LAW_FORCE_MINIMIZATION = 1, LAW_LIKE_GUIDED = 2 };

#endif
