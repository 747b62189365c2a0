/* BusKinematics: the modular kinematic bus model of seed 003 as an FMU.
 * Its variables are declared in modelDescription/BusKinematics.xml. */
#ifndef CONFIG_H
#define CONFIG_H

/* The continuous state is held in the FMI variables themselves: the pose of
 * the distinguished segment (theta[j], x[j], y[j]) and beta[1..N]. Nothing
 * else needs saving. */
typedef struct {
    int unused;
} ModelState;

/* exact directional derivatives (fmu.h): kinematics.c on dual numbers */
#define MODEL_DIRECTIONAL_DERIVATIVE 1

#endif
