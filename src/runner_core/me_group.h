/* The calls of one member FMU that the Model Exchange group (me_group.c) makes, each version's
 * function of the same meaning (me.c's, hidden in the library: not part of its interface). A
 * failed call's message is in me->message (me.c's call_failed). */
#ifndef ARTIBUS_RUNNER_ME_GROUP_H
#define ARTIBUS_RUNNER_ME_GROUP_H

#include "me.h"

fmi2Status me_fmu_set_time(ac_me *me, double t);
fmi2Status me_fmu_set_states(ac_me *me, const double *x);
fmi2Status me_fmu_get_states(ac_me *me, double *x);
fmi2Status me_fmu_get_derivatives(ac_me *me, double *dx);
fmi2Status me_fmu_get_indicators(ac_me *me, double *z);
fmi2Status me_fmu_get_nominals(ac_me *me, double *x);
fmi2Status me_fmu_completed(ac_me *me, int *enter, int *terminate);
fmi2Status me_fmu_failed(ac_me *me, const char *name, fmi2Status st, double t);
fmi2Status me_fmu_event(ac_me *me, int *terminate);
fmi2Status me_fmu_get_one(ac_me *me, fmi2ValueReference vr, double *x);
fmi2Status me_fmu_set_one(ac_me *me, fmi2ValueReference vr, double x);

#endif
