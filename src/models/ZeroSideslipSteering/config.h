/* ZeroSideslipSteering: seed 004's zero-side-slip proportional multi-axle
 * steering as a discrete FMU. Its variables are declared in
 * modelDescription/ZeroSideslipSteering.xml. */
#ifndef CONFIG_H
#define CONFIG_H

#include "zero_sideslip.h"

/* Saved as FMU state: plain data, nothing on the heap. */
typedef struct {
    double t0;                          /* start time: sample k is at t0 + k Ts [s] */
    long kNext;                         /* the next sample to compute */
    ZsGains gains;                      /* from the fixed parameters, at initialisation */
    ZsMemory mem;                       /* the law's memory between samples */
    double delta[ZS_MAX_AXLES + 1];     /* outputs of the last sample, held until the next */
    double K[ZS_MAX_AXLES + 1];
    unsigned flags;                     /* zs_step flags of the last sample */
    unsigned warned;                    /* flags already warned about in this episode */
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
