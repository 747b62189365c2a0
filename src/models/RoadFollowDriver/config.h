/* RoadFollowDriver: the road-follow driver of seed 001 (ch. 3.2) as an FMU.
 * Its variables are declared in modelDescription/RoadFollowDriver.xml. */
#ifndef CONFIG_H
#define CONFIG_H

#include "driver.h"

/* Saved as FMU state. The road table is not here: it follows from the fixed
 * parameters, is built once at initialisation and lives in comp->solver. */
typedef struct {
    double t0;            /* start time: sample k is at t0 + k Ts [s] */
    long kNext;           /* the next sample to compute */
    DriverMemory mem;     /* the driver's memory between samples */
    DriverOutput out;     /* the outputs of the last sample, held until the next */
    /* the built-in test vehicle (testVehicle = true): rear axle pose and speed
     * at the time of the next sample */
    double xv, yv, psiv, vv;
} ModelState;

/* it samples every Ts (parameter, > 0): a step of more than MAX_SAMPLES_PER_STEP
   samples is refused by the layer (fmu.h) */
#define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)

#endif
