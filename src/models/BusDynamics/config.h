/* BusDynamics: the kinetic single-track multibody model of seed 000 as an FMU.
 * Its variables are declared in modelDescription/BusDynamics.xml. */
#ifndef CONFIG_H
#define CONFIG_H

/* The continuous state: minimal coordinates z = (x, y, psi_1 .. psi_n) of
 * seed 000, eq. 1 ((x, y) the centre of mass of module 1) and their rates.
 * Sized for 4 modules (DYN_MAX_Q in dynamics.h). */
typedef struct {
    double z[6];
    double zd[6];
} ModelState;

/* exact directional derivatives (fmu.h): dynamics.cpp on dual numbers */
#define MODEL_DIRECTIONAL_DERIVATIVE 1

#endif
