/* The Model Exchange facade (issue 38): an ME FMU integrated with CVODE and
 * stepped as a Co-Simulation unit. See me.h for what it does and which sections
 * of FMI 2.0.4 and FMI 3.0 each part follows. */
#define _POSIX_C_SOURCE 200809L
#include "me.h"
#include "me_group.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cv_dense.h"

/* event iterations (newDiscreteStatesNeeded / discreteStatesNeedUpdate) before an error,
 * and events at one instant (an FMU whose time event never moves on) */
#define MAX_EVENT_ITERATIONS 1000
#define MAX_EVENTS_AT_ONE_TIME 1000
/* CVODE's internal steps per call (to one communication point or event) */
#define MAX_NUM_STEPS 100000

typedef struct {
    cv_dense cv;                     /* CVODE on nx states, or one of its own when nx = 0 */
    double *nominal;                 /* nx */
} me_solver;

static int say(ac_me *me, const char *format, ...) {   /* me->message; returns 0 */
    va_list ap;
    va_start(ap, format);
    vsnprintf(me->message, sizeof me->message, format, ap);
    va_end(ap);
    return 0;
}

/* --- the FMU's calls, FMI 2.0 or 3.0 (each version's function of the same meaning) --- */

static fmi2Status set_time(ac_me *me, double t) {
    const ac_me_calls *c = me->calls;
    return me->fmi == 3 ? (fmi2Status)c->fmi3SetTime(me->component, t) : c->fmi2SetTime(me->component, t);
}

static fmi2Status set_states(ac_me *me, const double *x) {
    const ac_me_calls *c = me->calls;
    if (!me->nx)
        return fmi2OK;
    return me->fmi == 3 ? (fmi2Status)c->fmi3SetContinuousStates(me->component, x, me->nx)
                        : c->fmi2SetContinuousStates(me->component, x, me->nx);
}

static fmi2Status get_states(ac_me *me, double *x) {
    const ac_me_calls *c = me->calls;
    if (!me->nx)
        return fmi2OK;
    return me->fmi == 3 ? (fmi2Status)c->fmi3GetContinuousStates(me->component, x, me->nx)
                        : c->fmi2GetContinuousStates(me->component, x, me->nx);
}

static fmi2Status get_derivatives(ac_me *me, double *dx) {
    const ac_me_calls *c = me->calls;
    return me->fmi == 3 ? (fmi2Status)c->fmi3GetContinuousStateDerivatives(me->component, dx, me->nx)
                        : c->fmi2GetDerivatives(me->component, dx, me->nx);
}

static fmi2Status get_indicators(ac_me *me, double *z) {
    const ac_me_calls *c = me->calls;
    return me->fmi == 3 ? (fmi2Status)c->fmi3GetEventIndicators(me->component, z, me->nz)
                        : c->fmi2GetEventIndicators(me->component, z, me->nz);
}

static fmi2Status get_nominals(ac_me *me, double *x) {
    const ac_me_calls *c = me->calls;
    if (!me->nx)
        return fmi2OK;
    return me->fmi == 3 ? (fmi2Status)c->fmi3GetNominalsOfContinuousStates(me->component, x, me->nx)
                        : c->fmi2GetNominalsOfContinuousStates(me->component, x, me->nx);
}

static fmi2Status completed(ac_me *me, int *enter, int *terminate) {
    const ac_me_calls *c = me->calls;
    fmi2Status st;
    if (me->fmi == 3) {
        fmi3Boolean e = fmi3False, t = fmi3False;
        st = (fmi2Status)c->fmi3CompletedIntegratorStep(me->component, fmi3True, &e, &t);
        *enter = e, *terminate = t;
    } else {
        fmi2Boolean e = fmi2False, t = fmi2False;
        st = c->fmi2CompletedIntegratorStep(me->component, fmi2True, &e, &t);
        *enter = e, *terminate = t;
    }
    return st;
}

static fmi2Status enter_event_mode(ac_me *me) {
    const ac_me_calls *c = me->calls;
    return me->fmi == 3 ? (fmi2Status)c->fmi3EnterEventMode(me->component) : c->fmi2EnterEventMode(me->component);
}

static fmi2Status enter_continuous_time_mode(ac_me *me) {
    const ac_me_calls *c = me->calls;
    return me->fmi == 3 ? (fmi2Status)c->fmi3EnterContinuousTimeMode(me->component)
                        : c->fmi2EnterContinuousTimeMode(me->component);
}

/* one fmi2NewDiscreteStates / fmi3UpdateDiscreteStates: *need, *terminate; the next time event kept */
static fmi2Status update(ac_me *me, int *need, int *terminate) {
    const ac_me_calls *c = me->calls;
    fmi2Status st;
    if (me->fmi == 3) {
        fmi3Boolean n = fmi3False, t = fmi3False, nominals = fmi3False, values = fmi3False, defined = fmi3False;
        fmi3Float64 next = 0.0;
        st = (fmi2Status)c->fmi3UpdateDiscreteStates(me->component, &n, &t, &nominals, &values, &defined, &next);
        *need = n, *terminate = t;
        me->next_event_defined = defined, me->next_event_time = next;
    } else {
        fmi2EventInfo e = {fmi2False, fmi2False, fmi2False, fmi2False, fmi2False, 0.0};
        st = c->fmi2NewDiscreteStates(me->component, &e);
        *need = e.newDiscreteStatesNeeded, *terminate = e.terminateSimulation;
        me->next_event_defined = e.nextEventTimeDefined, me->next_event_time = e.nextEventTime;
    }
    return st;
}

static const char *status_name(fmi2Status st) {
    static const char *names[] = {"OK", "Warning", "Discard", "Error", "Fatal", "Pending"};
    return (int)st >= 0 && (int)st < 6 ? names[st] : "?";
}

/* a failed FMU call: the message names it and the time; returns its status */
static fmi2Status call_failed(ac_me *me, const char *name, fmi2Status st, double t) {
    say(me, "fmi%d%s returned %s at t = %.17g", me->fmi, name, status_name(st), t);
    return st;
}

/* --- CVODE ------------------------------------------------------------------------- */

/* the right-hand side: the FMU at (t, y), its derivatives (FMI 2.0.4 3.2.1 / FMI 3.0 3.2.1:
 * fmi2SetTime, fmi2SetContinuousStates, fmi2GetDerivatives). A failed call stops CVODE
 * (-1); a derivative that is no finite number is a recoverable failure (1: CVODE tries a
 * smaller step, then fails with CV_REPTD_RHSFUNC_ERR / CV_FIRST_RHSFUNC_ERR), named. */
static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *p) {
    ac_me *me = p;
    double *dx = N_VGetArrayPointer(ydot);
    fmi2Status st;
    me->rhs_calls++;
    if (!me->nx) {
        dx[0] = 0.0;
        return 0;
    }
    if ((st = set_time(me, t)) > fmi2Warning)
        return call_failed(me, "SetTime", st, t), -1;
    if ((st = set_states(me, N_VGetArrayPointer(y))) > fmi2Warning)
        return call_failed(me, "SetContinuousStates", st, t), -1;
    if ((st = get_derivatives(me, dx)) > fmi2Warning)
        return call_failed(me, me->fmi == 3 ? "GetContinuousStateDerivatives" : "GetDerivatives", st, t), -1;
    for (size_t i = 0; i < me->nx; i++)
        if (!isfinite(dx[i])) {
            say(me, "the derivative of continuous state %zu is %g at t = %.17g (fmi%d%s)", i + 1, dx[i], t,
                me->fmi, me->fmi == 3 ? "GetContinuousStateDerivatives" : "GetDerivatives");
            return 1;
        }
    return 0;
}

/* CVODE's Jacobian df/dy at (t, y) from the FMU's directional derivatives (me->jacobian): column
 * j the derivatives' sensitivity to state j with the seed 1 (FMI 2.0.4 3.2.2
 * fmi2GetDirectionalDerivative, FMI 3.0 2.2.11 fmi3GetDirectionalDerivative: knowns the states,
 * unknowns the state derivatives, in Continuous-Time Mode), exact where the FMU's are, one call a
 * column instead of CVODE's difference quotient of a right-hand side a column */
static int jac(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *p, N_Vector t1, N_Vector t2, N_Vector t3) {
    (void)fy, (void)t1, (void)t2, (void)t3;
    ac_me *me = p;
    const ac_me_calls *c = me->calls;
    fmi2Status st;
    if ((st = set_time(me, t)) > fmi2Warning)
        return call_failed(me, "SetTime", st, t), -1;
    if ((st = set_states(me, N_VGetArrayPointer(y))) > fmi2Warning)
        return call_failed(me, "SetContinuousStates", st, t), -1;
    const double seed = 1.0;
    for (size_t j = 0; j < me->nx; j++) {
        double *col = SUNDenseMatrix_Column(J, (sunindextype)j);
        st = me->fmi == 3
            ? (fmi2Status)c->fmi3GetDirectionalDerivative(me->component, me->dx_vrs, me->nx, &me->x_vrs[j], 1,
                                                          &seed, 1, col, me->nx)
            : c->fmi2GetDirectionalDerivative(me->component, me->dx_vrs, me->nx, &me->x_vrs[j], 1, &seed, col);
        if (st > fmi2Warning)
            return call_failed(me, "GetDirectionalDerivative", st, t), -1;
        for (size_t i = 0; i < me->nx; i++)
            if (!isfinite(col[i]))
                return say(me, "the Jacobian's entry (%zu, %zu) is %g at t = %.17g (fmi%dGetDirectionalDerivative)",
                           i + 1, j + 1, col[i], t, me->fmi), 1;
    }
    return 0;
}

/* the event indicators at (t, y): CVODE's root functions (FMI 2.0.4 3.1: a state event
 * where an indicator changes sign) */
static int roots(sunrealtype t, N_Vector y, sunrealtype *g, void *p) {
    ac_me *me = p;
    fmi2Status st;
    if ((st = set_time(me, t)) > fmi2Warning)
        return call_failed(me, "SetTime", st, t), -1;
    if ((st = set_states(me, N_VGetArrayPointer(y))) > fmi2Warning)
        return call_failed(me, "SetContinuousStates", st, t), -1;
    if ((st = get_indicators(me, g)) > fmi2Warning)
        return call_failed(me, "GetEventIndicators", st, t), -1;
    return 0;
}

/* the absolute tolerances: rtol * |nominal| of each state (as FMPy's CVodeSolver takes them) */
static fmi2Status tolerances(ac_me *me, me_solver *s) {
    fmi2Status st = get_nominals(me, s->nominal);
    if (st > fmi2Warning)
        return call_failed(me, "GetNominalsOfContinuousStates", st, me->time);
    cv_dense_abstol(&s->cv, s->nominal, me->nx, me->rtol);
    return fmi2OK;
}

/* CVODE from the FMU's states at me->time after an event (FMI 2.0.4 3.2.2: the states may
 * have been changed by the event iteration, valuesOfContinuousStatesChanged; CVODE's history
 * is of the old equations either way) */
static fmi2Status restart(ac_me *me) {
    me_solver *s = me->solver;
    fmi2Status st = get_states(me, N_VGetArrayPointer(s->cv.y));
    if (st > fmi2Warning)
        return call_failed(me, "GetContinuousStates", st, me->time);
    if ((st = tolerances(me, s)) > fmi2Warning)
        return st;
    if (!cv_dense_restart(&s->cv, me->time, me->rtol))
        return say(me, "CVODE could not restart at t = %.17g", me->time), fmi2Error;
    me->restarts++;
    return fmi2OK;
}

static void solver_free(me_solver *s) {
    if (!s)
        return;
    cv_dense_free(&s->cv);
    free(s->nominal);
    free(s);
}

/* CVODE (BDF or Adams, dense Newton) on the FMU's states at me->time, its root
 * functions the event indicators */
static fmi2Status solver_new(ac_me *me) {
    me_solver *s = calloc(1, sizeof *s);
    if (!s)
        return say(me, "out of memory"), fmi2Fatal;
    me->solver = s;
    s->nominal = calloc(me->nx ? me->nx : 1, sizeof(double));
    if (!s->nominal || !cv_dense_create(&s->cv, me->nx, me->adams, me->message, sizeof me->message))
        return say(me, "out of memory"), fmi2Fatal;
    fmi2Status st = get_states(me, N_VGetArrayPointer(s->cv.y));
    if (st > fmi2Warning)
        return call_failed(me, "GetContinuousStates", st, me->time);
    if ((st = tolerances(me, s)) > fmi2Warning)
        return st;
    if (!cv_dense_init(&s->cv, rhs, me->time, me, me->rtol, MAX_NUM_STEPS)
        || (me->jacobian && me->nx && CVodeSetJacFn(s->cv.mem, jac) != CV_SUCCESS)
        || (me->nz && CVodeRootInit(s->cv.mem, (int)me->nz, roots) != CV_SUCCESS))
        return say(me, "CVODE could not be set up for %zu states and %zu event indicators (rtol %g)",
                   me->nx, me->nz, me->rtol), fmi2Error;
    if (me->nz)
        CVodeSetNoInactiveRootWarn(s->cv.mem);
    return fmi2OK;
}

/* --- events ------------------------------------------------------------------------ */

/* the event iteration in Event Mode (FMI 2.0.4 3.2.2, FMI 3.0 2.3.5 "State: Event Mode"): new discrete states
 * until none are needed; *terminate when the FMU asks to end the simulation */
static fmi2Status iterate(ac_me *me, int *terminate) {
    int need = 1;
    *terminate = 0;
    for (int i = 0; i < MAX_EVENT_ITERATIONS && need && !*terminate; i++) {
        const fmi2Status st = update(me, &need, terminate);
        if (st > fmi2Warning)
            return call_failed(me, me->fmi == 3 ? "UpdateDiscreteStates" : "NewDiscreteStates", st, me->time);
    }
    if (need && !*terminate)
        return say(me, "the event iteration at t = %.17g did not end in %d iterations", me->time,
                   MAX_EVENT_ITERATIONS), fmi2Error;
    return fmi2OK;
}

/* the FMU ends the simulation at me->time: as a Co-Simulation FMU says it (me.h) */
static fmi2Status ended(ac_me *me) {
    me->terminated = 1;
    me->last_successful_time = me->time;
    say(me, "the FMU asked to terminate the simulation at t = %.17g", me->time);
    return fmi2Discard;
}

/* the end of an event at me->time, the FMU in Event Mode: the iteration, Continuous-Time Mode,
 * CVODE restarted */
static fmi2Status end_event(ac_me *me) {
    int terminate;
    fmi2Status st;
    if ((st = iterate(me, &terminate)) > fmi2Warning)
        return st;
    if (terminate)
        return ended(me);
    if ((st = enter_continuous_time_mode(me)) > fmi2Warning)
        return call_failed(me, "EnterContinuousTimeMode", st, me->time);
    return restart(me);
}

/* an event at me->time: Event Mode, then end_event */
static fmi2Status handle_event(ac_me *me) {
    const fmi2Status st = enter_event_mode(me);
    if (st > fmi2Warning)
        return call_failed(me, "EnterEventMode", st, me->time);
    return end_event(me);
}

/* Discrete inputs changed at a communication point (me.h): in Continuous-Time Mode only the
 * continuous-time inputs u_c may be set (FMI 3.0 3.2.1, "State: Continuous-Time Mode", its table;
 * FMI 2.0.4 3.2.3, the table of calls: there fmi2SetReal only "for a variable with causality =
 * input and variability = continuous", no fmi2SetInteger/Boolean/String), a discrete one u_d in
 * Event Mode: begin enters it, the caller sets them, end ends the event. */
AC_EXPORT fmi2Status artibus_me_begin_input_event(fmi2Component p) {
    ac_me *me = p;
    me->message[0] = 0;
    if (!me->solver)
        return say(me, "an input event at t = %.17g came before the initialisation's end", me->time), fmi2Error;
    if (me->terminated)
        return fmi2Discard;
    const fmi2Status st = enter_event_mode(me);
    return st > fmi2Warning ? call_failed(me, "EnterEventMode", st, me->time) : fmi2OK;
}

AC_EXPORT fmi2Status artibus_me_end_input_event(fmi2Component p) {
    ac_me *me = p;
    me->time_events++;                        /* (an event at a time the importer knew: the input table's) */
    if (me->group)                            /* the group's CVODE restarts at its next step */
        ((ac_me_group *)me->group)->inputs_set = 1;
    return end_event(me);
}

AC_EXPORT fmi2Status artibus_me_exit_initialization(fmi2Component p) {
    ac_me *me = p;
    const ac_me_calls *c = me->calls;
    int terminate;
    me->message[0] = 0;
    fmi2Status st = me->fmi == 3 ? (fmi2Status)c->fmi3ExitInitializationMode(me->component)
                                 : c->fmi2ExitInitializationMode(me->component);
    if (st > fmi2Warning)
        return call_failed(me, "ExitInitializationMode", st, me->time);
    if ((st = iterate(me, &terminate)) > fmi2Warning)
        return st;
    if (terminate)
        return say(me, "the FMU asked to terminate the simulation in its initial event iteration "
                       "(t = %.17g)", me->time), fmi2Error;
    if ((st = enter_continuous_time_mode(me)) > fmi2Warning)
        return call_failed(me, "EnterContinuousTimeMode", st, me->time);
    if (me->fmi == 3) {                       /* the sizes after the structural parameters (FMI 3.0 3.2.1) */
        size_t nx = me->nx, nz = me->nz;
        if (c->fmi3GetNumberOfContinuousStates && c->fmi3GetNumberOfContinuousStates(me->component, &nx) <= fmi3Warning)
            me->nx = nx;
        if (c->fmi3GetNumberOfEventIndicators && c->fmi3GetNumberOfEventIndicators(me->component, &nz) <= fmi3Warning)
            me->nz = nz;
    }
    solver_free(me->solver);
    me->solver = NULL;
    me->inputs_set = 0;
    return solver_new(me);
}

/* --- the step ---------------------------------------------------------------------- */

/* CVODE from me->time to tout, its stop time (no step beyond the communication point or the
 * time event: the inputs may change there, the equations at the event; an FMU without inputs,
 * stop_at_points 0: beyond a communication point and back, as FMPy does); the FMU then at the
 * time reached (tret) and its states, and its step completed (FMI 2.0.4 3.2.2:
 * fmi2CompletedIntegratorStep). *event: a state or step event at tret. */
static fmi2Status integrate(ac_me *me, double tout, int time_event, int *event) {
    me_solver *s = me->solver;
    sunrealtype tret = me->time;
    long before = 0, after = 0;
    *event = 0;
    CVodeSetStopTime(s->cv.mem, time_event || me->stop_at_points ? tout : INFINITY);
    CVodeGetNumSteps(s->cv.mem, &before);
    me->message[0] = 0;
    const int flag = CVode(s->cv.mem, tout, s->cv.y, &tret, CV_NORMAL);
    CVodeGetNumSteps(s->cv.mem, &after);
    me->steps += after - before;
    if (flag < 0) {
        char why[sizeof me->message];
        snprintf(why, sizeof why, "%s", me->message[0] ? me->message : "no message");
        char *name = CVodeGetReturnFlagName(flag);
        say(me, "CVODE failed (%s) at t = %.17g, integrating to t = %.17g: %s", name ? name : "?", (double)tret,
            tout, why);
        free(name);
        me->last_successful_time = me->time;
        return fmi2Error;
    }
    fmi2Status st;
    if ((st = set_time(me, tret)) > fmi2Warning)
        return call_failed(me, "SetTime", st, tret);
    me->time = tret;
    if ((st = set_states(me, N_VGetArrayPointer(s->cv.y))) > fmi2Warning)
        return call_failed(me, "SetContinuousStates", st, tret);
    if (flag == CV_ROOT_RETURN) {
        me->state_events++;
        *event = 1;
    }
    if (me->completed_step) {                /* once per return of CVode (as FMPy calls it), not after
                                              * each of its internal steps (CV_NORMAL) */
        int enter = 0, terminate = 0;
        if ((st = completed(me, &enter, &terminate)) > fmi2Warning)
            return call_failed(me, "CompletedIntegratorStep", st, tret);
        if (terminate)
            return ended(me);
        if (enter && !*event)
            me->step_events++;
        *event |= enter;
    }
    return fmi2OK;
}

/* from me->time to t + h, the events met on the way handled (me.h) */
static fmi2Status step(ac_me *me, double t, double h) {
    const double tend = t + h;
    const double eps = 1e-9 * fabs(h) + 4.0 * DBL_EPSILON * fabs(tend);   /* "at" a time */
    fmi2Status st;
    int at_once = 0;
    double at = me->time;
    if (!me->solver)
        return say(me, "the step at t = %.17g came before the initialisation's end", t), fmi2Error;
    if (me->terminated)
        return fmi2Discard;
    /* Inputs set since the last step (me->inputs_set) are held over this one, as a
     * Co-Simulation FMU holds them: CVODE never stepped beyond t (its stop time, integrate;
     * stop_at_points), so its history is of the inputs before t only, and the jump of the derivatives at t is
     * taken by its error control (a step too long for it is rejected and cut), without a
     * restart at order 1 each time a bench's driver samples: at rtol 1e-6 our plants' KPIs
     * then stay within 0.4 % of their CS builds' (tests/test_me_facade.py) */
    if (me->inputs_set && !me->stop_at_points && (st = restart(me)) > fmi2Warning)
        return st;                           /* (CVODE may have stepped beyond t with the old inputs) */
    me->inputs_set = 0;
    while (tend - me->time > eps) {
        at_once = me->time == at ? at_once + 1 : 0;
        at = me->time;
        if (at_once > MAX_EVENTS_AT_ONE_TIME)
            return say(me, "more than %d events at t = %.17g", MAX_EVENTS_AT_ONE_TIME, me->time), fmi2Error;
        if (me->next_event_defined && me->next_event_time <= me->time + eps) {   /* a time event due now */
            me->time_events++;
            if ((st = handle_event(me)) != fmi2OK)
                return st;
            continue;
        }
        const int time_event = me->next_event_defined && me->next_event_time <= tend + eps;
        const double tout = time_event ? me->next_event_time : tend;
        int event;
        if ((st = integrate(me, tout, time_event, &event)) != fmi2OK)
            return st;
        if (time_event && !event && me->time >= tout) {
            me->time_events++;
            event = 1;
        }
        if (event && (st = handle_event(me)) != fmi2OK)
            return st;
    }
    return fmi2OK;
}

AC_EXPORT fmi2Status artibus_me_do_step(fmi2Component p, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    ac_me *me = p;
    return me->group ? artibus_me_group_step(me->group, t, h) : step(me, t, h);
}

AC_EXPORT fmi3Status artibus_me3_do_step(fmi3Instance p, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                                         fmi3Boolean *event, fmi3Boolean *terminate, fmi3Boolean *early,
                                         fmi3Float64 *last) {
    (void)no_prior;
    ac_me *me = p;
    const fmi2Status st = me->group ? artibus_me_group_step(me->group, t, h) : step(me, t, h);
    *event = fmi3False;
    *early = fmi3False;
    *terminate = me->terminated ? fmi3True : fmi3False;
    *last = me->time;
    /* FMI 3.0 4.2.1: an FMU that ends the simulation says so with terminateSimulation */
    return st == fmi2Discard && me->terminated ? fmi3OK : (fmi3Status)st;
}

AC_EXPORT fmi2Status artibus_me_get_real(fmi2Component p, const fmi2ValueReference vr[], size_t n,
                                         fmi2Real value[]) {
    ac_me *me = p;
    return me->calls->fmi2GetReal(me->component, vr, n, value);
}

AC_EXPORT fmi2Status artibus_me_set_real(fmi2Component p, const fmi2ValueReference vr[], size_t n,
                                         const fmi2Real value[]) {
    ac_me *me = p;
    const fmi2Status st = me->calls->fmi2SetReal(me->component, vr, n, value);
    me->inputs_set |= n > 0;
    return st;
}

AC_EXPORT fmi3Status artibus_me3_get_float64(fmi3Instance p, const fmi3ValueReference vr[], size_t n,
                                             fmi3Float64 value[], size_t nv) {
    ac_me *me = p;
    return me->calls->fmi3GetFloat64(me->component, vr, n, value, nv);
}

AC_EXPORT fmi3Status artibus_me3_set_float64(fmi3Instance p, const fmi3ValueReference vr[], size_t n,
                                             const fmi3Float64 value[], size_t nv) {
    ac_me *me = p;
    const fmi3Status st = me->calls->fmi3SetFloat64(me->component, vr, n, value, nv);
    me->inputs_set |= n > 0;
    return st;
}

AC_EXPORT fmi2Status artibus_me_get_boolean_status(fmi2Component p, const fmi2StatusKind s, fmi2Boolean *value) {
    ac_me *me = p;
    if (s != fmi2Terminated)
        return fmi2Discard;
    *value = me->terminated ? fmi2True : fmi2False;
    return fmi2OK;
}

AC_EXPORT fmi2Status artibus_me_get_real_status(fmi2Component p, const fmi2StatusKind s, fmi2Real *value) {
    ac_me *me = p;
    if (s != fmi2LastSuccessfulTime)
        return fmi2Discard;
    *value = me->terminated ? me->last_successful_time : me->time;
    return fmi2OK;
}

AC_EXPORT void artibus_me_free(ac_me *me) {
    solver_free(me->solver);
    me->solver = NULL;
}

/* --- the FMU's calls for the group (me_group.h; hidden in the library) ----------------------- */

fmi2Status me_fmu_set_time(ac_me *me, double t) { return set_time(me, t); }
fmi2Status me_fmu_set_states(ac_me *me, const double *x) { return set_states(me, x); }
fmi2Status me_fmu_get_states(ac_me *me, double *x) { return get_states(me, x); }
fmi2Status me_fmu_get_derivatives(ac_me *me, double *dx) { return get_derivatives(me, dx); }
fmi2Status me_fmu_get_indicators(ac_me *me, double *z) { return me->nz ? get_indicators(me, z) : fmi2OK; }
fmi2Status me_fmu_get_nominals(ac_me *me, double *x) { return get_nominals(me, x); }
fmi2Status me_fmu_completed(ac_me *me, int *enter, int *terminate) { return completed(me, enter, terminate); }
fmi2Status me_fmu_failed(ac_me *me, const char *name, fmi2Status st, double t) {
    return call_failed(me, name, st, t);
}

/* an event of the member at me->time: Event Mode, the event iteration, Continuous-Time Mode
 * (FMI 2.0.4 3.2.2, FMI 3.0 2.3.5); the group restarts CVODE itself. *terminate: it asked to end */
fmi2Status me_fmu_event(ac_me *me, int *terminate) {
    fmi2Status st = enter_event_mode(me);
    *terminate = 0;
    if (st > fmi2Warning)
        return call_failed(me, "EnterEventMode", st, me->time);
    if ((st = iterate(me, terminate)) > fmi2Warning || *terminate)
        return st;
    if ((st = enter_continuous_time_mode(me)) > fmi2Warning)
        return call_failed(me, "EnterContinuousTimeMode", st, me->time);
    return fmi2OK;
}

/* one Float64 value of the member: get (its output) and set (its input) */
fmi2Status me_fmu_get_one(ac_me *me, fmi2ValueReference vr, double *x) {
    return me->fmi == 3 ? (fmi2Status)me->calls->fmi3GetFloat64(me->component, &vr, 1, x, 1)
                        : me->calls->fmi2GetReal(me->component, &vr, 1, x);
}

fmi2Status me_fmu_set_one(ac_me *me, fmi2ValueReference vr, double x) {
    return me->fmi == 3 ? (fmi2Status)me->calls->fmi3SetFloat64(me->component, &vr, 1, &x, 1)
                        : me->calls->fmi2SetReal(me->component, &vr, 1, &x);
}
