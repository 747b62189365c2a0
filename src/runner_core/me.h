/* A Model Exchange FMU as a Co-Simulation unit (issue 38): the runner's ME facade.
 *
 * An ME FMU has no doStep: its importer integrates its continuous states
 * (FMI 2.0.4 section 3, FMI 3.0 section 3). The facade does, with SUNDIALS
 * CVODE (BDF, or Adams-Moulton), and offers the FMU to the stepping core and to
 * `artibus simulate` through the calls of a Co-Simulation FMU: its component
 * is an ac_me, its functions artibus_me_* below, of the fmi2/fmi3 types the
 * core calls (core.h's ac_unit: doStep, getReal, setReal, the status
 * functions; ac_settle's exit). Values pass through to the FMU; a step from t
 * to t + h integrates, handling
 *   - time events (nextEventTime: FMI 2.0.4 3.1, FMI 3.0 3.1 "Concepts"),
 *   - state events (event indicators changing sign, CVODE's root finding:
 *     FMI 2.0.4 3.1, FMI 3.0 3.1.1 "Localization of State Events"),
 *   - step events (fmi2/fmi3CompletedIntegratorStep's enterEventMode, when
 *     needsCompletedIntegratorStep: FMI 2.0.4 3.2.2, FMI 3.0 3.2.1),
 * each with the event iteration (fmi2NewDiscreteStates / fmi3UpdateDiscreteStates
 * until no new discrete states are needed: FMI 2.0.4 3.2.2, FMI 3.0 2.3.5 "State: Event Mode") in
 * Event Mode, then Continuous-Time Mode again and CVODE restarted from the
 * FMU's states. A terminateSimulation ends the run as a Co-Simulation FMU ends it
 * (FMI 2.0: fmi2Discard with fmi2Terminated; FMI 3.0: terminateSimulation with
 * lastSuccessfulTime). Inputs set between two steps are held over the step, as a
 * Co-Simulation FMU holds them; CVODE stops at each communication point (its stop
 * time, stop_at_points), so that its history never runs ahead of the inputs; an FMU
 * without inputs may be integrated beyond and interpolated back (as FMPy does).
 *
 * Python (artibus.fmu.me) allocates the ac_me (its layout: gen_layout.py), fills
 * the FMU's functions (ac_me_calls, by name) and the set-up fields, and frees
 * the solver with artibus_me_free. CVODE's own memory is CVODE's (the core's
 * other code uses no heap). */
#ifndef ARTIBUS_RUNNER_ME_H
#define ARTIBUS_RUNNER_ME_H

#include <stddef.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"
#include "lsbus.h"                       /* AC_EXPORT */

/* the FMU's Model Exchange functions, one set per FMI version (the other left NULL) */
typedef struct {
    fmi2SetTimeTYPE *fmi2SetTime;
    fmi2SetContinuousStatesTYPE *fmi2SetContinuousStates;
    fmi2GetContinuousStatesTYPE *fmi2GetContinuousStates;
    fmi2GetDerivativesTYPE *fmi2GetDerivatives;
    fmi2GetEventIndicatorsTYPE *fmi2GetEventIndicators;
    fmi2GetNominalsOfContinuousStatesTYPE *fmi2GetNominalsOfContinuousStates;
    fmi2CompletedIntegratorStepTYPE *fmi2CompletedIntegratorStep;
    fmi2EnterEventModeTYPE *fmi2EnterEventMode;
    fmi2NewDiscreteStatesTYPE *fmi2NewDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE *fmi2EnterContinuousTimeMode;
    fmi2ExitInitializationModeTYPE *fmi2ExitInitializationMode;
    fmi2GetRealTYPE *fmi2GetReal;
    fmi2SetRealTYPE *fmi2SetReal;
    fmi3SetTimeTYPE *fmi3SetTime;
    fmi3SetContinuousStatesTYPE *fmi3SetContinuousStates;
    fmi3GetContinuousStatesTYPE *fmi3GetContinuousStates;
    fmi3GetContinuousStateDerivativesTYPE *fmi3GetContinuousStateDerivatives;
    fmi3GetEventIndicatorsTYPE *fmi3GetEventIndicators;
    fmi3GetNominalsOfContinuousStatesTYPE *fmi3GetNominalsOfContinuousStates;
    fmi3CompletedIntegratorStepTYPE *fmi3CompletedIntegratorStep;
    fmi3EnterEventModeTYPE *fmi3EnterEventMode;
    fmi3UpdateDiscreteStatesTYPE *fmi3UpdateDiscreteStates;
    fmi3EnterContinuousTimeModeTYPE *fmi3EnterContinuousTimeMode;
    fmi3ExitInitializationModeTYPE *fmi3ExitInitializationMode;
    fmi3GetFloat64TYPE *fmi3GetFloat64;
    fmi3SetFloat64TYPE *fmi3SetFloat64;
    fmi3GetNumberOfContinuousStatesTYPE *fmi3GetNumberOfContinuousStates;
    fmi3GetNumberOfEventIndicatorsTYPE *fmi3GetNumberOfEventIndicators;
    /* the Jacobian's columns, where the FMU provides them (jacobian below) */
    fmi2GetDirectionalDerivativeTYPE *fmi2GetDirectionalDerivative;
    fmi3GetDirectionalDerivativeTYPE *fmi3GetDirectionalDerivative;
} ac_me_calls;

typedef struct {
    /* set up by Python before artibus_me_exit_initialization */
    void *component;                /* the FMU's fmi2Component / fmi3Instance */
    int fmi;                        /* 2 or 3 */
    const ac_me_calls *calls;
    int adams;                      /* 1: Adams-Moulton, 0: BDF */
    double rtol;                    /* relative tolerance; absolute: rtol * each state's nominal */
    int completed_step;             /* needsCompletedIntegratorStep */
    int jacobian;                   /* 1: CVODE's Jacobian from the FMU's directional derivatives
                                     * (providesDirectionalDerivative(s): FMI 2.0.4 3.2.2 / FMI 3.0
                                     * 2.2.11), the value references below; 0: CVODE's difference quotients */
    const unsigned int *x_vrs;      /* nx: the continuous states' value references, in the FMU's order */
    const unsigned int *dx_vrs;     /* nx: their derivatives' */
    int stop_at_points;             /* 1: CVODE stops at each communication point (inputs may change
                                     * there); 0: it may step beyond and interpolate back (no inputs) */
    double time;                    /* the FMU's time: the start time, then where it is */
    size_t nx, nz;                  /* states, event indicators (FMI 3.0: asked after the initialisation) */
    /* state and counts */
    int terminated;                 /* terminateSimulation was asked */
    double last_successful_time;
    int inputs_set;                 /* inputs set since the last step (held over the next) */
    int next_event_defined;
    double next_event_time;
    long steps;                     /* CVODE's internal steps */
    long rhs_calls;
    long time_events, state_events, step_events;
    long restarts;                  /* CVODE re-initialised (events, changed inputs) */
    char message[512];              /* why the last call failed */
    void *solver;                   /* me.c's CVODE state, NULL before the initialisation's end */
    void *group;                    /* its ac_me_group (the monolithic reference), or NULL: then its
                                     * step integrates the group (me_group.c), not the FMU alone */
    char name[128];                 /* the component's name in the group's messages */
} ac_me;

/* fmi2/fmi3ExitInitializationMode of the FMU, the event iteration at the
 * initialisation's end (FMI 2.0.4 3.2.2 / FMI 3.0 2.3.5 "State: Event Mode": Event Mode after it),
 * Continuous-Time Mode, and CVODE set up on its states (ac_settle's exit). */
AC_EXPORT fmi2Status artibus_me_exit_initialization(fmi2Component me);

/* discrete inputs set at me->time (FMI 3.0 3.2.1: a discrete input is set in Event Mode only,
 * not in Continuous-Time Mode; FMI 2.0.4 3.2.3 likewise): begin enters Event Mode, the caller
 * sets them, end runs the event iteration, Continuous-Time Mode, CVODE restarted */
AC_EXPORT fmi2Status artibus_me_begin_input_event(fmi2Component me);
AC_EXPORT fmi2Status artibus_me_end_input_event(fmi2Component me);
/* a Co-Simulation step of the ME FMU: integrate from me->time to t + h */
AC_EXPORT fmi2Status artibus_me_do_step(fmi2Component me, fmi2Real t, fmi2Real h, fmi2Boolean no_prior);
AC_EXPORT fmi3Status artibus_me3_do_step(fmi3Instance me, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                                         fmi3Boolean *event, fmi3Boolean *terminate, fmi3Boolean *early,
                                         fmi3Float64 *last);
/* the FMU's own get/set of Real (Float64) values; a set marks the inputs changed */
AC_EXPORT fmi2Status artibus_me_get_real(fmi2Component me, const fmi2ValueReference vr[], size_t n,
                                         fmi2Real value[]);
AC_EXPORT fmi2Status artibus_me_set_real(fmi2Component me, const fmi2ValueReference vr[], size_t n,
                                         const fmi2Real value[]);
AC_EXPORT fmi3Status artibus_me3_get_float64(fmi3Instance me, const fmi3ValueReference vr[], size_t n,
                                             fmi3Float64 value[], size_t nv);
AC_EXPORT fmi3Status artibus_me3_set_float64(fmi3Instance me, const fmi3ValueReference vr[], size_t n,
                                             const fmi3Float64 value[], size_t nv);
/* FMI 2.0's status functions (FMI 2.0.4 4.2.3): fmi2Terminated, fmi2LastSuccessfulTime */
AC_EXPORT fmi2Status artibus_me_get_boolean_status(fmi2Component me, const fmi2StatusKind s, fmi2Boolean *value);
AC_EXPORT fmi2Status artibus_me_get_real_status(fmi2Component me, const fmi2StatusKind s, fmi2Real *value);
/* CVODE freed (the FMU is the caller's to free) */
AC_EXPORT void artibus_me_free(ac_me *me);

/* --- a Model Exchange group: the monolithic reference (issue 44, me_group.c) ------------------
 *
 * Several ME FMUs of a bench (its plants, the damper) integrated together in one CVODE: their
 * states concatenated, their event indicators concatenated, and each member's continuous input
 * that another member's output feeds set inside every evaluation of the right-hand side and of
 * the root functions (ac_me_link: the bench's connection with its linear transformation or unit
 * factor), in an order Python computes from the members' direct feedthrough (an algebraic loop
 * is refused there). Each member stays a unit of the stepping core with its own inputs from
 * outside the group and its own outputs; its step (artibus_me_do_step with me->group set)
 * integrates the whole group to t + h the first time it is asked for that interval, the other
 * members' steps find it done. The plan writes every member's inputs before the first member's
 * step (artibus.runner.plan). Time, state and step events of any member are handled for the
 * group: each member whose event it is does its event iteration (FMI 2.0.4 3.2.2, FMI 3.0
 * 2.3.5), then CVODE restarts from all members' states. */
typedef struct {
    int src_member, dst_member;     /* indices into ac_me_group.members */
    fmi2ValueReference src_vr, dst_vr;
    double factor, offset;          /* dst = factor * src + offset */
} ac_me_link;

typedef struct {
    int n_members;
    ac_me **members;                /* each set up as for the facade alone, its group set to this */
    int n_links;
    const ac_me_link *links;        /* in evaluation order: a link after those its source depends on */
    int adams;
    double rtol;                    /* relative tolerance; absolute: rtol * each state's nominal */
    double time;
    int inputs_set;                 /* a member's discrete input changed (its input event): restart */
    int terminated;
    double last_successful_time;
    long steps, rhs_calls, time_events, state_events, step_events, restarts;
    int fail_member;                /* the member whose call failed, -1: none (CVODE's own failure) */
    char message[512];
    void *solver;                   /* me_group.c's CVODE state, set up at the group's first step */
} ac_me_group;

/* the group's step from its time to t + h (a member's step delegates here) */
AC_EXPORT fmi2Status artibus_me_group_step(ac_me_group *g, double t, double h);
AC_EXPORT void artibus_me_group_free(ac_me_group *g);

#endif
