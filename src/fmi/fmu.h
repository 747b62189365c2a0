/* The shared FMI layer (FMI 2.0 and FMI 3.0, one build per version: FMI_VERSION):
 * the instance every model works on, the logging helpers, and the functions each
 * model supplies. Nothing here depends on the FMI version but the callbacks kept
 * in the instance; a model's code is the same for both (fmi2Functions.c and
 * fmi3Functions.c are thin layers over fmu_core.c).
 *
 * A model folder src/models/<Name>/ holds
 *   config.h  ModelState: the model's own internal states that are not FMI
 *             variables (plain data, no pointers: it is saved as FMU state);
 *   model.c   model_init, model_outputs, model_do_step, model_free.
 * Its variables are declared once, in modelDescription/<Name>.xml; the build
 * generates ModelData (one field per variable) and the table the layer uses
 * for every get/set, range check and start value.
 */
#ifndef ARTIBUS_FMU_H
#define ARTIBUS_FMU_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include "model_vars.h"   /* MODEL_FMI_VERSION: the version the variable table is for */
#ifndef FMI_VERSION
#define FMI_VERSION MODEL_FMI_VERSION
#endif
#if FMI_VERSION != MODEL_FMI_VERSION
#error "FMI_VERSION differs from MODEL_FMI_VERSION: model_vars.h was generated for the other FMI version"
#endif
#if FMI_VERSION == 3
#include "fmi3Functions.h"
#else
#include "fmi2Functions.h"
#endif
#include "vartable.h"
#include "config.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the status every function returns: the values of fmi2Status and fmi3Status
   (OK 0, Warning 1, Discard 2, Error 3, Fatal 4), so a layer casts it */
typedef enum { OK = 0, Warning = 1, Discard = 2, Error = 3, Fatal = 4 } Status;

/* which interface the instance was made for */
typedef enum { IF_CO_SIMULATION, IF_MODEL_EXCHANGE } InterfaceType;

/* instance states of the FMI 2.0 co-simulation state machine (spec 4.2.4); in
   FMI 3.0 S_STEP_COMPLETE is Step Mode, and S_EVENT_MODE serves Model Exchange
   and Co-Simulation with eventModeUsed alike */
typedef enum {
    S_INSTANTIATED   = 1 << 0,
    S_INIT_MODE      = 1 << 1,
    S_STEP_COMPLETE  = 1 << 2,
    S_STEP_FAILED    = 1 << 3,
    S_TERMINATED     = 1 << 4,
    S_ERROR          = 1 << 5,
    S_FATAL          = 1 << 6,
    /* Model Exchange (spec 3.2.3); instantiated, initialization mode,
       terminated, error and fatal are shared with co-simulation */
    S_EVENT_MODE     = 1 << 7,
    S_CONT_TIME_MODE = 1 << 8
} InstanceState;

/* log categories, in the order of <LogCategories> in every model description */
typedef enum {
    LOG_EVENTS = 0, LOG_WARNING, LOG_ERROR, LOG_FATAL, LOG_ALL, LOG_NCATEGORIES
} LogCategory;

typedef struct ModelInstance {
    /* --- plain data: this block is the FMU state (fmi2GetFMUstate) --- */
    struct {
        InstanceState state;
        double time;
        ModelData d;        /* every FMI variable, by name */
        ModelState s;       /* the model's internal states (config.h) */
    } v;

    /* --- everything else: re-created, never saved --- */
    char *instanceName;
    char *resourceDir;      /* file system path of the FMU's resources/, or NULL */
#if FMI_VERSION == 3
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logMessage;
    bool eventModeUsed;     /* fmi3InstantiateCoSimulation's */
#else
    fmi2CallbackFunctions cb;
#endif
    InterfaceType type;     /* co-simulation, or model exchange (models whose
                               model description has <ModelExchange>) */
    bool logOn[LOG_NCATEGORIES];
    double stopTime;        /* +INFINITY unless the experiment (fmi2SetupExperiment,
                               fmi3EnterInitializationMode) defined it */
    double tolerance;       /* 0 unless the experiment defined it */
    bool restart;           /* a variable was set or the state restored: the
                               integrator must restart from v.d at the next step */
    bool forget;            /* that restart must also forget what the integrator
                               learnt before it (its Jacobian, its step size), so
                               it is reproducible bit for bit: set at
                               initialisation and where the FMU state is saved
                               or restored */
    bool dirty;             /* outputs must be recalculated before a get */
    unsigned long generation;   /* counts the changes of values from outside (a set, a
                               restored state, a new mode: core_dirty, which sets dirty);
                               a model's cache of a derived quantity keys on it together
                               with the time and states, which steps change */
    void *solver;           /* model-owned resources (CVODE memory, tables) */
    ModelData *ddSeed;      /* the directional derivatives' seed, zero between calls
                               (made at the first call, fmu_core.c: dd_forward) */
    bool ddOutputs;         /* model_directional_derivative: an output is among the
                               unknowns (else state derivatives only) */
    char *capture;          /* non-NULL on the layer's scratch instance that checks
                               a state's parameters: the first error message goes
                               here (512 bytes), nothing to the importer */
} ModelInstance;

#define D (&comp->v.d)      /* the variables, in a model's functions */

/* ---- supplied by each model (model.c) ---------------------------------- */

/* Check the parameters and set the initial state in v.d / v.s from them.
 * Called in initialization mode whenever an output is read, and at
 * fmi2ExitInitializationMode. Must be cheap and idempotent. */
Status model_init(ModelInstance *comp);

/* The invariants on the parameters that model_init enforces beyond their
 * declared ranges (a far look-ahead point beyond the near one, a speed table
 * that increases, a mass matrix that is positive definite, ...). Reads v.d
 * only; on a violation logs why (log_error, naming the variables and values)
 * and returns Error. model_init calls it first; the layer (fmu_core.c) calls it on
 * every state restored after initialisation (on a scratch copy, its message
 * becomes the restore's), so that no state holds parameters model_init would
 * have refused: one function, so the two cannot drift apart. */
Status model_check_parameters(ModelInstance *comp);

/* Compute all outputs from the state and the current inputs. */
void model_outputs(ModelInstance *comp);

/* Advance from v.time = t by h; on success set v.time = t + h. On failure log
 * why, leave v.d at the last good state and v.time at its time. */
Status model_do_step(ModelInstance *comp, double t, double h);

/* Release comp->solver (fmi2Reset, fmi2FreeInstance). */
void model_free(ModelInstance *comp);

/* A state about to be restored (fmi2SetFMUstate, fmi2DeSerializeFMUstate).
 * The layer has checked the time, the instance state and every variable in d
 * (finite; parameters and inputs within their declared min/max); the model
 * checks its ModelState as a whole against d: every count and index in range,
 * every double finite, sample counters consistent with time. On failure it
 * writes why into why[n] and returns false. Must not touch anything else. */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n);

/* After a state was restored (v is the restored one, validated): rebuild what
 * the model derives at initialisation in comp->solver (a road, the integrator
 * of another size), so that a state restores into a fresh instance too. On
 * Error (logged) the layer puts the previous v back. */
Status model_restored(ModelInstance *comp);

/* in model_state_valid: return STATE_INVALID("nAxles = %d", ...) */
#define STATE_INVALID(...) (snprintf(why, n, __VA_ARGS__), false)

/* all n doubles finite */
static inline bool finite_all(const double *x, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) return false;
    return true;
}

/* a discrete controller's next sample k (at t0 + k Ts) in a restored state
 * lies within a sample period or so of the time the state was taken at: so a
 * step takes at most h / Ts + 2 samples (a corrupted counter would loop) */
static inline bool sample_index_ok(double t0, long long k, double Ts, double time) {
    if (!isfinite(t0) || !(Ts > 0) || k < 0 || k > (1LL << 52) || t0 > time + 1e-9 * Ts ||
        !(fabs(t0) + fabs(time) < 1e11 * Ts))     /* else t + Ts would round to t */
        return false;
    const double tk = t0 + (double)k * Ts;
    return tk >= time - 1.5 * Ts && tk <= time + 2.5 * Ts;
}

/* ---- Model Exchange: supplied by the models whose model description has
 * <ModelExchange> (the plants); MODEL_NX states and MODEL_NZ event
 * indicators, in the order of <Derivatives> (model_vars.h lists it). The
 * derivatives are the right-hand side the model's own integrator uses in
 * model_do_step; model_outputs also sets the derivative variables. --------- */

/* the continuous states into x[MODEL_NX] */
void model_get_x(ModelInstance *comp, double x[]);
/* set the continuous states from x[MODEL_NX] (finite, checked by the layer) */
void model_set_x(ModelInstance *comp, const double x[]);
/* dx/dt at v.time from the states and the inputs; Error (logged) where
   the right-hand side is not defined there */
Status model_derivatives(ModelInstance *comp, double dx[]);
/* the event indicators z[MODEL_NZ] (a state event where one changes sign) */
void model_event_indicators(ModelInstance *comp, double z[]);
/* at an event (fmi2NewDiscreteStates): *terminate = true to stop the
   simulation there (logged why); *tNext the next time event, INFINITY if none */
Status model_event_update(ModelInstance *comp, bool *terminate, double *tNext);

/* ---- Directional derivatives: supplied by the models whose config.h says
 *     #define MODEL_DIRECTIONAL_DERIVATIVE 1
 * (their model description says providesDirectionalDerivative(s)="true"); the
 * others refuse fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative
 * with Error and a message.
 *
 * The knowns are the continuous states and the Real inputs, the unknowns the
 * outputs and the state derivatives (FMI 2.0.4, 2.1.9 and 3.2.2; FMI 3.0,
 * 2.2.11: v_unknown = g(v_known, v_rest), the sensitivity J seed). The layer
 * writes the seed into `seed`, a ModelData that is zero but at the knowns'
 * fields, and `tangent` starts as a copy of it. The model sets, at the
 * current state, inputs and time (v), every output and derivative field of
 * `tangent` (the outputs' fields may be left when comp->ddOutputs is false: no
 * output is among the unknowns) to the derivative of that variable along the seed: forward-mode
 * differentiation of the same equations model_outputs evaluates. Error
 * (logged) where the equations are not defined there. */
#ifdef MODEL_DIRECTIONAL_DERIVATIVE
Status model_directional_derivative(ModelInstance *comp, const ModelData *seed, ModelData *tangent);
#endif

/* The built-in test stimulus of a model run alone (`fmpy simulate`): one
 * sine period amp sin(2 pi t / period), an S-curve on a steering input, then
 * nothing. Parameters testSteerAmp / testSteerPeriod; off (amp = 0) by default. */
static inline double test_sine(double amp, double period, double t) {
    return (amp != 0.0 && t < period) ? amp * sin(2 * M_PI * t / period) : 0.0;
}

/* The most samples one communication step may take (issue 41): a discrete
 * controller takes every sample instant of a step, so the work of one doStep
 * grows with h / Ts. A model that samples names its sample period in its
 * config.h,
 *     #define MODEL_SAMPLE_PERIOD(d) ((d)->Ts)     (d: the ModelData, checked Ts > 0)
 * and the layer (core_do_step) refuses a step of more than this many samples
 * with Error and a message naming the function, the step and the limit, before
 * the model sees it: a doStep returns in bounded time whatever the step (1e5
 * samples: 1 ms to 0.2 s in these controllers, release build), and the importer
 * splits a longer span into steps. The steps of any bench (one sample or a few)
 * are far below. */
#define MAX_SAMPLES_PER_STEP 1e5

/* A discrete controller (an ECU) samples at t0 + k Ts; a communication step
 * [t, t + h) takes every sample instant in it, from the inputs held over the
 * step. True while sample k falls in the step, its instant in *tk:
 *     for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) ...      */
static inline int sample_due(double t0, long long k, double Ts, double t, double h, double *tk) {
    *tk = t0 + (double)k * Ts;
    return *tk < t + h - 1e-9 * Ts;
}

/* ---- logging (messages name the variable and the value) ----------------- */

/* logEvents: only when debug logging of that category is on */
void log_event(ModelInstance *comp, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* warnings and errors always reach the logger */
void log_warning(ModelInstance *comp, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* returns Error, so that `return log_error(comp, ...)` reads naturally */
Status log_error(ModelInstance *comp, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

#ifdef __cplusplus
}
#endif

#endif
