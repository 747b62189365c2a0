/* ArticulationDamper: seed 001's two-cylinder articulation damper (1.3.1,
 * App. B) as an FMU. Variables in modelDescription/ArticulationDamper.xml;
 * the algorithm in damper.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "damper.h"

/* plain data, saved as FMU state */
typedef struct {
    DamperParams par;   /* from the fixed parameters, at initialisation */
    double pValve;      /* valve pressure: the state of the lag tauP (tauP = 0: pSet) [Pa] */
    double Ediss;       /* energy dissipated since initialisation [J] */
    int warned;         /* a cylinder length was limited at DAMPER_L_MIN (warned once) */
} ModelState;

/* exact directional derivatives (fmu.h): damper.c on dual numbers */
#define MODEL_DIRECTIONAL_DERIVATIVE 1

#endif
