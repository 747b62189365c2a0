/* The FMI 2.0 API of every artibus FMU: Co-Simulation, and Model Exchange for
 * the models whose model description has <ModelExchange> (MODEL_NX).
 *
 * Every API function starts with ENTER(fn, allowed states): a call in a state
 * where the standard does not allow it returns fmi2Error with "illegal call
 * sequence" and the state it was made in. A function that ends in fmi2Error
 * moves the instance to the error state (FMI 2.0, 2.1.3: then only getters,
 * fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance are allowed).
 * The work is done in fmu_core.c, which fmi3Functions.c shares; here are the
 * FMI 2.0 types, callbacks and allowed states.
 */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "fmu_core.h"

/* ---- allowed states per function (FMI 2.0, table in 4.2.4) --------------- */
#define M_SetDebugLogging   ANY_BUT_FATAL
#define M_SetupExperiment   S_INSTANTIATED
#define M_EnterInit         S_INSTANTIATED
#define M_ExitInit          S_INIT_MODE
#define M_Terminate         (S_STEP_COMPLETE | S_STEP_FAILED | S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_Reset             ANY_BUT_FATAL
#define M_Get               (S_INIT_MODE | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR | \
                             S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_Set               (S_INSTANTIATED | S_INIT_MODE | S_STEP_COMPLETE | S_EVENT_MODE | \
                             S_CONT_TIME_MODE)
#define M_FMUstate          ANY_BUT_FATAL
#define M_DoStep            S_STEP_COMPLETE
#define M_Status            (S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR)

/* ---- the layer's callbacks (fmu_core.h) ----------------------------------- */

void layer_log(ModelInstance *comp, Status status, LogCategory cat, const char *text) {
    if (!comp->cb.logger) return;
    /* the message is a printf format (FMI 2.0, 2.1.5) in which '#' starts a
       value-reference escape: pass the text with '%' and '#' doubled, no arguments */
    char out[2048];
    size_t o = 0;
    for (const char *p = text; *p && o < sizeof out - 2; p++) {
        if (*p == '#' || *p == '%') out[o++] = *p;
        out[o++] = *p;
    }
    out[o] = '\0';
    comp->cb.logger(comp->cb.componentEnvironment, comp->instanceName ? comp->instanceName : "",
                    (fmi2Status)status, LOG_CATEGORY[cat], out);
}

void *layer_calloc(ModelInstance *comp, size_t n, size_t size) {
    return comp->cb.allocateMemory(n, size);
}

void layer_free(ModelInstance *comp, void *p) {
    comp->cb.freeMemory(p);
}

#define leave(comp, s) ((fmi2Status)core_leave((comp), (s)))
#define ST(s) ((fmi2Status)(s))

#define ENTER(fn, mask)                                             \
    ModelInstance *comp = (ModelInstance *)c;                      \
    if (!comp) return fmi2Error;                                   \
    if (!core_allowed(comp, (mask), fn)) return leave(comp, Error)

#define REQUIRE_ARRAY(fn, p)                                                   \
    if (n > 0 && !(p))                                                         \
        return leave(comp, log_error(comp, "%s: argument '%s' is NULL", fn, #p))

/* ---- inquiry ---------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                               size_t n, const fmi2String categories[]) {
    ENTER("fmi2SetDebugLogging", M_SetDebugLogging);
    return ST(core_set_debug_logging(comp, "fmi2SetDebugLogging", loggingOn != fmi2False, n, categories));
}

/* ---- life cycle ------------------------------------------------------------- */

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                              fmi2String guid, fmi2String resourceLocation,
                              const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    ModelInstance *comp = functions->allocateMemory(1, sizeof(ModelInstance));
    if (!comp) return NULL;
    comp->cb = *functions;
    comp->type = fmuType == fmi2ModelExchange ? IF_MODEL_EXCHANGE : IF_CO_SIMULATION;
    const char *why = NULL;
#ifdef MODEL_NX
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange)
        why = "fmuType must be fmi2CoSimulation or fmi2ModelExchange";
#else
    if (fmuType != fmi2CoSimulation) why = "this FMU supports co-simulation only (fmuType must be fmi2CoSimulation)";
#endif
    if (why) {
        comp->instanceName = (char *)(instanceName ? instanceName : "");
        log_error(comp, "fmi2Instantiate: %s", why);
        functions->freeMemory(comp);
        return NULL;
    }
    if (core_init_instance(comp, "fmi2Instantiate", instanceName, guid, resourceLocation, true) != OK) {
        functions->freeMemory(comp);
        return NULL;
    }
    for (int i = 0; i < LOG_NCATEGORIES; i++) comp->logOn[i] = loggingOn;
    return comp;
}

void fmi2FreeInstance(fmi2Component c) {
    core_free_instance((ModelInstance *)c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    ENTER("fmi2SetupExperiment", M_SetupExperiment);
    return ST(core_setup_experiment(comp, "fmi2SetupExperiment", toleranceDefined, tolerance,
                                    startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ENTER("fmi2EnterInitializationMode", M_EnterInit);
    comp->v.state = S_INIT_MODE;
    core_dirty(comp);
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    ENTER("fmi2ExitInitializationMode", M_ExitInit);
    const Status status = core_exit_init(comp, "fmi2ExitInitializationMode");
    if (status > Warning) return ST(status);
    comp->v.state = comp->type == IF_MODEL_EXCHANGE ? S_EVENT_MODE : S_STEP_COMPLETE;
    return ST(status);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ENTER("fmi2Terminate", M_Terminate);
    comp->v.state = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    ENTER("fmi2Reset", M_Reset);
    return ST(core_reset(comp));
}

/* ---- getting and setting variables ----------------------------------------- */

#define GETTER(FN, T, TYPE, READ)                                                 \
    fmi2Status FN(fmi2Component c, const fmi2ValueReference vr[], size_t n, T value[]) { \
        ENTER(#FN, M_Get);                                                        \
        REQUIRE_ARRAY(#FN, vr);                                                   \
        REQUIRE_ARRAY(#FN, value);                                                \
        if (core_refresh(comp) > Warning) return leave(comp, Error);              \
        for (size_t i = 0; i < n; i++) {                                          \
            const VarInfo *v = core_lookup(comp, #FN, TYPE, vr[i]);               \
            if (!v) return leave(comp, Error);                                    \
            READ;                                                                 \
        }                                                                         \
        return fmi2OK;                                                            \
    }

GETTER(fmi2GetReal, fmi2Real, T_REAL, value[i] = *(double *)core_field(comp, v))
GETTER(fmi2GetInteger, fmi2Integer, T_INTEGER, value[i] = *(int *)core_field(comp, v))
GETTER(fmi2GetBoolean, fmi2Boolean, T_BOOLEAN, value[i] = *(int *)core_field(comp, v) ? fmi2True : fmi2False)
GETTER(fmi2GetString, fmi2String, T_STRING, value[i] = (const char *)core_field(comp, v))

#define SETTER(FN, T, TYPE, CHECK, DIFFERS, WRITE)                                \
    fmi2Status FN(fmi2Component c, const fmi2ValueReference vr[], size_t n, const T value[]) { \
        ENTER(#FN, M_Set);                                                        \
        REQUIRE_ARRAY(#FN, vr);                                                   \
        REQUIRE_ARRAY(#FN, value);                                                \
        for (size_t i = 0; i < n; i++) {                                          \
            const VarInfo *v = core_lookup(comp, #FN, TYPE, vr[i]);               \
            if (!v || core_settable(comp, #FN, v)) return leave(comp, Error);     \
            CHECK;                                                                \
            if (DIFFERS) { WRITE; core_changed(comp); }                           \
        }                                                                         \
        return fmi2OK;                                                            \
    }

SETTER(fmi2SetReal, fmi2Real, T_REAL,
       if (core_check_range(comp, "fmi2SetReal", v, value[i])) return leave(comp, Error),
       *(double *)core_field(comp, v) != value[i],
       *(double *)core_field(comp, v) = value[i])
SETTER(fmi2SetInteger, fmi2Integer, T_INTEGER,
       if (core_check_range(comp, "fmi2SetInteger", v, (double)value[i])) return leave(comp, Error),
       *(int *)core_field(comp, v) != value[i],
       *(int *)core_field(comp, v) = value[i])
SETTER(fmi2SetBoolean, fmi2Boolean, T_BOOLEAN,
       (void)0,
       *(int *)core_field(comp, v) != (value[i] ? 1 : 0),
       *(int *)core_field(comp, v) = value[i] ? 1 : 0)
SETTER(fmi2SetString, fmi2String, T_STRING,
       if (core_set_string(comp, "fmi2SetString", v, value[i])) return leave(comp, Error),
       false, (void)0)

/* ---- FMU state (fmu_core.c: validated as a whole before any of it is used) -- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER("fmi2GetFMUstate", M_FMUstate);
    return ST(core_get_state(comp, "fmi2GetFMUstate", state));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    ENTER("fmi2SetFMUstate", M_FMUstate);
    return ST(core_set_state(comp, "fmi2SetFMUstate", state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER("fmi2FreeFMUstate", M_FMUstate);
    return ST(core_free_state(comp, state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    ENTER("fmi2SerializedFMUstateSize", M_FMUstate);
    return ST(core_state_size(comp, "fmi2SerializedFMUstateSize", state, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    ENTER("fmi2SerializeFMUstate", M_FMUstate);
    return ST(core_serialize(comp, "fmi2SerializeFMUstate", state, (unsigned char *)bytes, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    ENTER("fmi2DeSerializeFMUstate", M_FMUstate);
    return ST(core_deserialize(comp, "fmi2DeSerializeFMUstate", (const unsigned char *)bytes, size, state));
}

/* ---- directional derivatives (FMI 2.0.4, 2.1.9): dvUnknown = J dvKnown, the
 * knowns states and inputs, the unknowns outputs and state derivatives; allowed
 * where getters are (4.2.4 and 3.2.3 tables). Models without the hook (fmu.h:
 * MODEL_DIRECTIONAL_DERIVATIVE) say providesDirectionalDerivative = false. */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[],
                                        size_t nUnknown, const fmi2ValueReference vKnown[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    ENTER("fmi2GetDirectionalDerivative", M_Get);
#ifdef MODEL_DIRECTIONAL_DERIVATIVE
    return ST(core_directional_derivative(comp, "fmi2GetDirectionalDerivative", vUnknown, nUnknown,
                                          vKnown, nKnown, dvKnown, dvUnknown));
#else
    (void)vUnknown; (void)nUnknown; (void)vKnown; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return leave(comp, log_error(comp, "fmi2GetDirectionalDerivative: not provided by this FMU "
                                       "(providesDirectionalDerivative = false)"));
#endif
}

/* ---- not provided (capability flags are false in the model description) --- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    ENTER("fmi2SetRealInputDerivatives", M_Set);
    return leave(comp, log_error(comp, "fmi2SetRealInputDerivatives: inputs are held constant over a "
                                       "step (canInterpolateInputs = false)"));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    ENTER("fmi2GetRealOutputDerivatives", M_Get);
    return leave(comp, log_error(comp, "fmi2GetRealOutputDerivatives: not provided "
                                       "(maxOutputDerivativeOrder = 0)"));
}

/* ---- stepping ---------------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi2DoStep", M_DoStep);
    return ST(core_do_step(comp, "fmi2DoStep", t, h));
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    ENTER("fmi2CancelStep", M_Status);
    return leave(comp, log_error(comp, "fmi2CancelStep: fmi2DoStep is synchronous; there is no step to cancel"));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    ENTER("fmi2GetStatus", M_Status);
    return leave(comp, log_error(comp, "fmi2GetStatus: only asynchronous steps have a status; "
                                       "fmi2DoStep here is synchronous"));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    ENTER("fmi2GetRealStatus", M_Status);
    if (s != fmi2LastSuccessfulTime || !value)
        return leave(comp, log_error(comp, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is provided"));
    *value = comp->v.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    ENTER("fmi2GetIntegerStatus", M_Status);
    return leave(comp, log_error(comp, "fmi2GetIntegerStatus: no integer status is provided"));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    ENTER("fmi2GetBooleanStatus", M_Status);
    if (s != fmi2Terminated || !value)
        return leave(comp, log_error(comp, "fmi2GetBooleanStatus: only fmi2Terminated is provided"));
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    ENTER("fmi2GetStringStatus", M_Status);
    return leave(comp, log_error(comp, "fmi2GetStringStatus: no string status is provided"));
}

/* ---- Model Exchange (FMI 2.0, chapter 3) -------------------------------------
 * Only for models whose model description has <ModelExchange> (MODEL_NX from
 * gen_vars.py): the plants. The states, derivatives and event indicators come
 * from the model's hooks (fmu.h), the same right-hand side its own integrator
 * uses in co-simulation. A co-simulation-only FMU answers each with fmi2Error. */

#define M_EnterEventMode    (S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_NewDiscrete       S_EVENT_MODE
#define M_EnterContTime     S_EVENT_MODE
#define M_CompletedStep     S_CONT_TIME_MODE
#define M_SetTime           (S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_SetStates         S_CONT_TIME_MODE
#define M_GetStates         (S_INIT_MODE | S_EVENT_MODE | S_CONT_TIME_MODE | S_TERMINATED | S_ERROR)
#define M_GetNominals       (S_INSTANTIATED | S_EVENT_MODE | S_CONT_TIME_MODE | S_TERMINATED | S_ERROR)

#ifdef MODEL_NX

#define ME_ENTER(fn, mask)                                                          \
    ENTER(fn, mask);                                                                \
    if (comp->type != IF_MODEL_EXCHANGE)                                            \
        return leave(comp, log_error(comp, "%s: a Model Exchange function, but the "  \
                                           "instance was instantiated for co-simulation", fn))

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    ME_ENTER("fmi2EnterEventMode", M_EnterEventMode);
    comp->v.state = S_EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    ME_ENTER("fmi2NewDiscreteStates", M_NewDiscrete);
    if (!info) return leave(comp, log_error(comp, "fmi2NewDiscreteStates: argument 'fmi2eventInfo' is NULL"));
    bool terminate;
    double tNext;
    const Status status = core_event_update(comp, "fmi2NewDiscreteStates", &terminate, &tNext);
    if (status > Warning) return ST(status);
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = terminate ? fmi2True : fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = isfinite(tNext) ? fmi2True : fmi2False;
    info->nextEventTime = isfinite(tNext) ? tNext : 0.0;
    return ST(status);
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    ME_ENTER("fmi2EnterContinuousTimeMode", M_EnterContTime);
    comp->v.state = S_CONT_TIME_MODE;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ME_ENTER("fmi2CompletedIntegratorStep", M_CompletedStep);
    if (!enterEventMode || !terminateSimulation)
        return leave(comp, log_error(comp, "fmi2CompletedIntegratorStep: NULL argument"));
    *enterEventMode = fmi2False;            /* no step events: every event is a state or time event */
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    ME_ENTER("fmi2SetTime", M_SetTime);
    return ST(core_set_time(comp, "fmi2SetTime", time));
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    ME_ENTER("fmi2SetContinuousStates", M_SetStates);
    return ST(core_set_x(comp, "fmi2SetContinuousStates", x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    ME_ENTER("fmi2GetDerivatives", M_GetStates);
    return ST(core_derivatives(comp, "fmi2GetDerivatives", dx, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t ni) {
    ME_ENTER("fmi2GetEventIndicators", M_GetStates);
    return ST(core_event_indicators(comp, "fmi2GetEventIndicators", z, ni));
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    ME_ENTER("fmi2GetContinuousStates", M_GetStates);
    return ST(core_get_x(comp, "fmi2GetContinuousStates", x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    ME_ENTER("fmi2GetNominalsOfContinuousStates", M_GetNominals);
    return ST(core_nominals(comp, "fmi2GetNominalsOfContinuousStates", x_nominal, nx));
}

#else   /* a co-simulation-only FMU */

/* every Model Exchange function of a co-simulation-only FMU: fmi2Error, and the
 * log names the function fn */
static fmi2Status not_me(fmi2Component c, const char *fn) {
    ENTER(fn, ANY_BUT_FATAL);
    return leave(comp, log_error(comp, "%s: this FMU has no Model Exchange interface "
                                       "(a sampled controller: co-simulation only)", fn));
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { return not_me(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)info;
    return not_me(c, "fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return not_me(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return not_me(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    return not_me(c, "fmi2SetTime");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x; (void)nx;
    return not_me(c, "fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    (void)dx; (void)nx;
    return not_me(c, "fmi2GetDerivatives");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t ni) {
    (void)z; (void)ni;
    return not_me(c, "fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x; (void)nx;
    return not_me(c, "fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal; (void)nx;
    return not_me(c, "fmi2GetNominalsOfContinuousStates");
}

#endif
