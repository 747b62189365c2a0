/* A Model Exchange group (issue 44): several ME FMUs integrated together in one CVODE, the
 * monolithic reference of a bench (`artibus run BENCH --reference`). See me.h (ac_me_group) for
 * what it does; each member's calls are me.c's (me_group.h). The sections followed:
 *   - the right-hand side: per member fmi2SetTime, fmi2SetContinuousStates, the connected
 *     inputs set (a continuous-time input may be set in Continuous-Time Mode: FMI 2.0.4 3.2.3,
 *     FMI 3.0 3.2.1), fmi2GetDerivatives (FMI 2.0.4 3.2.1, FMI 3.0 3.2.1);
 *   - state events: every member's event indicators are CVODE's root functions (FMI 2.0.4 3.1,
 *     FMI 3.0 3.1.1); time events: the earliest nextEventTime of the members (FMI 2.0.4 3.1,
 *     FMI 3.0 3.1); step events: fmi2CompletedIntegratorStep's enterEventMode (FMI 2.0.4 3.2.2,
 *     FMI 3.0 3.2.1);
 *   - an event is the event iteration of the members whose event it is (FMI 2.0.4 3.2.2, FMI 3.0
 *     2.3.5), then CVODE restarted from every member's states (the others' inputs may have jumped). */
#define _POSIX_C_SOURCE 200809L
#include "me_group.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cv_dense.h"

#define MAX_EVENTS_AT_ONE_TIME 1000
#define MAX_NUM_STEPS 500000

typedef struct {
    cv_dense cv;                     /* CVODE on every member's states (at least 1) */
    size_t n, nz;                    /* states (at least 1), event indicators */
    size_t *x0, *z0;                 /* each member's first state, first indicator (n_members + 1) */
    double *nominal;
    int *roots;                      /* CVodeGetRootInfo */
    int *due;                        /* per member: its event is due */
} group_solver;

static int say(ac_me_group *g, const char *format, ...) {
    va_list ap;
    va_start(ap, format);
    vsnprintf(g->message, sizeof g->message, format, ap);
    va_end(ap);
    return 0;
}

/* a member's call failed: the group's message names the member, its own says the call */
static fmi2Status member_failed(ac_me_group *g, int i, fmi2Status st) {
    g->fail_member = i;
    say(g, "Model Exchange group (the reference), member '%s': %s", g->members[i]->name, g->members[i]->message);
    return st > fmi2Error ? st : fmi2Error;
}

/* every member at (t, y), then the connections inside the group in their order (me.h) */
static fmi2Status evaluate(ac_me_group *g, double t, const double *y) {
    group_solver *s = g->solver;
    fmi2Status st;
    for (int i = 0; i < g->n_members; i++) {
        ac_me *m = g->members[i];
        if ((st = me_fmu_set_time(m, t)) > fmi2Warning)
            return me_fmu_failed(m, "SetTime", st, t), member_failed(g, i, st);
        if ((st = me_fmu_set_states(m, y + s->x0[i])) > fmi2Warning)
            return me_fmu_failed(m, "SetContinuousStates", st, t), member_failed(g, i, st);
    }
    for (int k = 0; k < g->n_links; k++) {
        const ac_me_link *l = &g->links[k];
        double x = 0.0;
        if ((st = me_fmu_get_one(g->members[l->src_member], l->src_vr, &x)) > fmi2Warning)
            return me_fmu_failed(g->members[l->src_member], "GetReal", st, t), member_failed(g, l->src_member, st);
        if ((st = me_fmu_set_one(g->members[l->dst_member], l->dst_vr, l->factor * x + l->offset)) > fmi2Warning)
            return me_fmu_failed(g->members[l->dst_member], "SetReal", st, t), member_failed(g, l->dst_member, st);
    }
    return fmi2OK;
}

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *p) {
    ac_me_group *g = p;
    group_solver *s = g->solver;
    double *dx = N_VGetArrayPointer(ydot);
    fmi2Status st;
    g->rhs_calls++;
    dx[0] = 0.0;
    if (evaluate(g, t, N_VGetArrayPointer(y)) > fmi2Warning)
        return -1;
    for (int i = 0; i < g->n_members; i++) {
        ac_me *m = g->members[i];
        if (m->nx && (st = me_fmu_get_derivatives(m, dx + s->x0[i])) > fmi2Warning)
            return me_fmu_failed(m, "GetDerivatives", st, t), member_failed(g, i, st), -1;
        for (size_t j = s->x0[i]; j < s->x0[i + 1]; j++)
            if (!isfinite(dx[j])) {
                g->fail_member = i;
                say(g, "Model Exchange group (the reference), member '%s': the derivative of its continuous "
                       "state %zu is %g at t = %.17g", m->name, j - s->x0[i] + 1, dx[j], t);
                return 1;
            }
    }
    return 0;
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *z, void *p) {
    ac_me_group *g = p;
    group_solver *s = g->solver;
    fmi2Status st;
    if (evaluate(g, t, N_VGetArrayPointer(y)) > fmi2Warning)
        return -1;
    for (int i = 0; i < g->n_members; i++)
        if ((st = me_fmu_get_indicators(g->members[i], z + s->z0[i])) > fmi2Warning)
            return me_fmu_failed(g->members[i], "GetEventIndicators", st, t), member_failed(g, i, st), -1;
    return 0;
}

/* y from every member's states, the absolute tolerances from their nominals */
static fmi2Status gather(ac_me_group *g) {
    group_solver *s = g->solver;
    double *y = N_VGetArrayPointer(s->cv.y);
    fmi2Status st;
    N_VConst(0.0, s->cv.y);
    for (int i = 0; i < g->n_members; i++) {
        ac_me *m = g->members[i];
        if ((st = me_fmu_get_states(m, y + s->x0[i])) > fmi2Warning)
            return me_fmu_failed(m, "GetContinuousStates", st, g->time), member_failed(g, i, st);
        if ((st = me_fmu_get_nominals(m, s->nominal + s->x0[i])) > fmi2Warning)
            return me_fmu_failed(m, "GetNominalsOfContinuousStates", st, g->time), member_failed(g, i, st);
    }
    cv_dense_abstol(&s->cv, s->nominal, s->x0[g->n_members], g->rtol);
    return fmi2OK;
}

static void solver_free(group_solver *s) {
    if (!s)
        return;
    cv_dense_free(&s->cv);
    free(s->x0), free(s->z0), free(s->nominal), free(s->roots), free(s->due);
    free(s);
}

/* the members' sizes: each one's first state and indicator in the group's vectors */
static int layout(ac_me_group *g, group_solver *s) {
    if (g->n_members < 1)
        return 0;
    const size_t n = (size_t)g->n_members;
    s->x0 = calloc(n + 1, sizeof(size_t));
    s->z0 = calloc(n + 1, sizeof(size_t));
    s->due = calloc(n, sizeof(int));
    if (!s->x0 || !s->z0 || !s->due)
        return 0;
    for (size_t i = 0; i < n; i++) {
        s->x0[i + 1] = s->x0[i] + g->members[i]->nx;
        s->z0[i + 1] = s->z0[i] + g->members[i]->nz;
    }
    s->n = s->x0[n] ? s->x0[n] : 1;
    s->nz = s->z0[n];
    s->nominal = calloc(s->n, sizeof(double));
    s->roots = calloc(s->nz ? s->nz : 1, sizeof(int));
    return s->nominal && s->roots;
}

/* CVODE (BDF or Adams, dense Newton) on every member's states at g->time (each member past its
 * own initialisation: the facade's exit), the event indicators its root functions */
static fmi2Status solver_new(ac_me_group *g) {
    group_solver *s = calloc(1, sizeof *s);
    fmi2Status st;
    if (!s)
        return say(g, "out of memory"), fmi2Fatal;
    g->solver = s;
    g->fail_member = -1;
    for (int i = 0; i < g->n_members; i++)
        if (!g->members[i]->solver)
            return say(g, "member '%s' stepped before its initialisation's end", g->members[i]->name), fmi2Error;
    g->time = g->members[0]->time;
    if (!layout(g, s) || !cv_dense_create(&s->cv, s->n, g->adams, g->message, sizeof g->message))
        return say(g, "out of memory"), fmi2Fatal;
    if ((st = gather(g)) > fmi2Warning)
        return st;
    if (!cv_dense_init(&s->cv, rhs, g->time, g, g->rtol, MAX_NUM_STEPS)
        || (s->nz && CVodeRootInit(s->cv.mem, (int)s->nz, roots) != CV_SUCCESS))
        return say(g, "CVODE could not be set up for the group's %zu states and %zu event indicators (rtol %g)",
                   s->n, s->nz, g->rtol), fmi2Error;
    if (s->nz)
        CVodeSetNoInactiveRootWarn(s->cv.mem);
    return evaluate(g, g->time, N_VGetArrayPointer(s->cv.y));
}

/* CVODE from every member's states at g->time (after an event or a changed discrete input) */
static fmi2Status restart(ac_me_group *g) {
    group_solver *s = g->solver;
    fmi2Status st;
    if ((st = gather(g)) > fmi2Warning)
        return st;
    if (!cv_dense_restart(&s->cv, g->time, g->rtol))
        return say(g, "CVODE could not restart the group at t = %.17g", g->time), fmi2Error;
    g->restarts++;
    return evaluate(g, g->time, N_VGetArrayPointer(s->cv.y));
}

/* the group ends the simulation at g->time: every member says so as a Co-Simulation FMU would */
static fmi2Status ended(ac_me_group *g, int i) {
    g->terminated = 1;
    g->last_successful_time = g->time;
    say(g, "member '%s' asked to terminate the simulation at t = %.17g", g->members[i]->name, g->time);
    for (int j = 0; j < g->n_members; j++)
        g->members[j]->terminated = 1, g->members[j]->last_successful_time = g->time;
    return fmi2Discard;
}

/* the events due (s->due) at g->time: each such member's event iteration, then CVODE restarted */
static fmi2Status events(ac_me_group *g) {
    group_solver *s = g->solver;
    fmi2Status st;
    for (int i = 0; i < g->n_members; i++) {
        int terminate = 0;
        if (!s->due[i])
            continue;
        s->due[i] = 0;
        if ((st = me_fmu_event(g->members[i], &terminate)) > fmi2Warning)
            return member_failed(g, i, st);
        if (terminate)
            return ended(g, i);
    }
    return restart(g);
}

/* the earliest time event of the members (INFINITY: none) */
static double next_time_event(const ac_me_group *g) {
    double next = INFINITY;
    for (int i = 0; i < g->n_members; i++)
        if (g->members[i]->next_event_defined && g->members[i]->next_event_time < next)
            next = g->members[i]->next_event_time;
    return next;
}

/* the members whose time event is due at or before t: marked; returns how many */
static int due_time_events(ac_me_group *g, double t) {
    group_solver *s = g->solver;
    int n = 0;
    for (int i = 0; i < g->n_members; i++)
        if (g->members[i]->next_event_defined && g->members[i]->next_event_time <= t)
            s->due[i] = 1, n++;
    return n;
}

/* CVODE from g->time to tout (its stop time: the inputs may change there); the members at the
 * time reached, their steps completed; the members with a state or step event marked */
static fmi2Status integrate(ac_me_group *g, double tout, int *event) {
    group_solver *s = g->solver;
    sunrealtype tret = g->time;
    long before = 0, after = 0;
    fmi2Status st;
    *event = 0;
    CVodeSetStopTime(s->cv.mem, tout);
    CVodeGetNumSteps(s->cv.mem, &before);
    g->message[0] = 0;
    const int flag = CVode(s->cv.mem, tout, s->cv.y, &tret, CV_NORMAL);
    CVodeGetNumSteps(s->cv.mem, &after);
    g->steps += after - before;
    if (flag < 0) {
        char why[sizeof g->message];
        snprintf(why, sizeof why, "%s", g->message[0] ? g->message : "no message");
        char *name = CVodeGetReturnFlagName(flag);
        say(g, "CVODE failed (%s) at t = %.17g, integrating the group to t = %.17g: %s", name ? name : "?",
            (double)tret, tout, why);
        free(name);
        g->last_successful_time = g->time;
        return fmi2Error;
    }
    g->time = tret;
    if ((st = evaluate(g, tret, N_VGetArrayPointer(s->cv.y))) > fmi2Warning)
        return st;
    if (flag == CV_ROOT_RETURN) {
        CVodeGetRootInfo(s->cv.mem, s->roots);
        for (int i = 0; i < g->n_members; i++)
            for (size_t j = s->z0[i]; j < s->z0[i + 1]; j++)
                if (s->roots[j])
                    s->due[i] = 1;
        g->state_events++;
        *event = 1;
    }
    for (int i = 0; i < g->n_members; i++) {
        ac_me *m = g->members[i];
        int enter = 0, terminate = 0;
        m->time = tret;
        if (!m->completed_step)
            continue;
        if ((st = me_fmu_completed(m, &enter, &terminate)) > fmi2Warning)
            return me_fmu_failed(m, "CompletedIntegratorStep", st, tret), member_failed(g, i, st);
        if (terminate)
            return ended(g, i);
        if (enter && !s->due[i])
            g->step_events++;
        s->due[i] |= enter;
        *event |= enter;
    }
    return fmi2OK;
}

/* the group's copy of its message into every member's (the core names the unit whose step it was) */
static fmi2Status told(ac_me_group *g, fmi2Status st) {
    if (st != fmi2OK)
        for (int i = 0; i < g->n_members; i++)
            snprintf(g->members[i]->message, sizeof g->members[i]->message, "%s", g->message);
    return st;
}

static fmi2Status group_step(ac_me_group *g, double t, double h) {
    const double tend = t + h;
    const double eps = 1e-9 * fabs(h) + 4.0 * DBL_EPSILON * fabs(tend);
    fmi2Status st;
    int at_once = 0;
    double at = g->time;
    if (!g->solver && (st = solver_new(g)) > fmi2Warning)
        return st;
    if (g->terminated)
        return fmi2Discard;
    if (tend - g->time <= eps)               /* done: an earlier member's step of this interval */
        return fmi2OK;
    if (g->inputs_set && (st = restart(g)) > fmi2Warning)
        return st;
    g->inputs_set = 0;
    while (tend - g->time > eps) {
        at_once = g->time == at ? at_once + 1 : 0;
        at = g->time;
        if (at_once > MAX_EVENTS_AT_ONE_TIME)
            return say(g, "more than %d events at t = %.17g", MAX_EVENTS_AT_ONE_TIME, g->time), fmi2Error;
        const double next = next_time_event(g);
        if (next <= g->time + eps) {         /* a time event due now */
            g->time_events += due_time_events(g, g->time + eps) > 0;
            if ((st = events(g)) != fmi2OK)
                return st;
            continue;
        }
        const int time_event = next <= tend + eps;
        const double tout = time_event ? next : tend;
        int event;
        if ((st = integrate(g, tout, &event)) != fmi2OK)
            return st;
        if (time_event && g->time >= tout && due_time_events(g, tout + eps)) {
            g->time_events++;
            event = 1;
        }
        if (event && (st = events(g)) != fmi2OK)
            return st;
    }
    return fmi2OK;
}

AC_EXPORT fmi2Status artibus_me_group_step(ac_me_group *g, double t, double h) {
    return told(g, group_step(g, t, h));
}

AC_EXPORT void artibus_me_group_free(ac_me_group *g) {
    solver_free(g->solver);
    g->solver = NULL;
}
