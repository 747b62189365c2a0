/* MultiAxle3DOF: the linear 3-DOF multi-axle vehicle of seed 004 as an FMU.
 * Its variables are declared in modelDescription/MultiAxle3DOF.xml. */
#ifndef CONFIG_H
#define CONFIG_H

/* The continuous state lives in the FMI variables (w_r, v, p, phi, psi, x, y).
 * Saved besides: whether the low-speed warning was given in this episode. */
typedef struct {
    int warnedSpeed;
} ModelState;

/* exact directional derivatives (fmu.h): lateral3dof.c on dual numbers */
#define MODEL_DIRECTIONAL_DERIVATIVE 1

#endif
