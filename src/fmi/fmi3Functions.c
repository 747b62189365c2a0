/* The FMI 3.0 API of every artibus FMU: Co-Simulation (with or without Event
 * Mode; the FMU never returns early), and Model Exchange for the models whose
 * model description has <ModelExchange> (MODEL_NX). The same model code as the
 * FMI 2.0 build: the work is done in fmu_core.c, which fmi2Functions.c shares;
 * here are the FMI 3.0 types, callbacks and allowed states (FMI 3.0, 3.2 and
 * 4.2: the state machines of Model Exchange and Co-Simulation).
 *
 * Every API function starts with ENTER(fn, allowed states): a call in a state
 * where the standard does not allow it returns fmi3Error with "illegal call
 * sequence" and the state it was made in; a function that ends in fmi3Error
 * moves the instance to the error state. What this FMU does not provide (the
 * capability flags in its model description say so) answers fmi3Error with a
 * message naming the flag: directional and adjoint derivatives, clocks,
 * configuration mode, output derivatives, intermediate update, Scheduled
 * Execution, and the types it has no variables of (Float32, the 8-, 16- and
 * unsigned integers, Binary). An Enumeration is an Int64 here (FMI 3.0), an
 * Integer an Int32.
 *
 * An FMI-LS-BUS network node (MODEL_LSBUS, src/models/common/lsbus_node.h) also
 * has the Binary and Clock variables of its bus terminal (Rx_Data, Tx_Data,
 * Rx_Clock, Tx_Clock): fmi3Get/SetBinary, fmi3Get/SetClock, fmi3GetIntervalDecimal
 * and fmi3UpdateDiscreteStates hand them to lsbus_node.c; no FMU state there
 * (canGetAndSetFMUState = false).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_core.h"
#ifdef MODEL_LSBUS
#include "lsbus_node.h"     /* an FMI-LS-BUS network node: its Binary and Clock variables */
#endif

/* ---- allowed states per function ------------------------------------------- */
#define M_SetDebugLogging   ANY_BUT_FATAL
#define M_EnterInit         S_INSTANTIATED
#define M_ExitInit          S_INIT_MODE
#define M_EnterEventMode    (S_STEP_COMPLETE | S_CONT_TIME_MODE)
#define M_Terminate         (S_STEP_COMPLETE | S_STEP_FAILED | S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_Reset             ANY_BUT_FATAL
#define M_Get               (S_INIT_MODE | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR | \
                             S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_Set               (S_INSTANTIATED | S_INIT_MODE | S_STEP_COMPLETE | S_EVENT_MODE | \
                             S_CONT_TIME_MODE)
#define M_FMUState          ANY_BUT_FATAL
#define M_DoStep            S_STEP_COMPLETE
#define M_EnterStepMode     S_EVENT_MODE
#define M_UpdateDiscrete    S_EVENT_MODE
#define M_EnterContTime     S_EVENT_MODE
#define M_CompletedStep     S_CONT_TIME_MODE
#define M_SetTime           (S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_SetStates         S_CONT_TIME_MODE
#define M_GetStates         (S_INIT_MODE | S_EVENT_MODE | S_CONT_TIME_MODE | S_TERMINATED | S_ERROR)
#define M_GetNominals       (S_INSTANTIATED | S_EVENT_MODE | S_CONT_TIME_MODE | S_TERMINATED | S_ERROR)
#define M_GetNumber         ANY_BUT_FATAL

/* ---- the layer's callbacks (fmu_core.h) ----------------------------------- */

void layer_log(ModelInstance *comp, Status status, LogCategory cat, const char *text) {
    /* FMI 3.0 (2.3.1): the message is plain text, no format */
    if (comp->logMessage) comp->logMessage(comp->env, (fmi3Status)status, LOG_CATEGORY[cat], text);
}

/* FMI 3.0 has no memory callbacks: the C library's */
void *layer_calloc(ModelInstance *comp, size_t n, size_t size) {
    (void)comp;
    return calloc(n, size);
}

void layer_free(ModelInstance *comp, void *p) {
    (void)comp;
    free(p);
}

#define leave(comp, s) ((fmi3Status)core_leave((comp), (s)))
#define ST(s) ((fmi3Status)(s))

#define ENTER(fn, mask)                                             \
    ModelInstance *comp = (ModelInstance *)instance;               \
    if (!comp) return fmi3Error;                                   \
    if (!core_allowed(comp, (mask), fn)) return leave(comp, Error)

#define REQUIRE_ARRAY(fn, p, n)                                                \
    if ((n) > 0 && !(p))                                                       \
        return leave(comp, log_error(comp, "%s: argument '%s' is NULL", fn, #p))

/* ---- inquiry ---------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn,
                               size_t nCategories, const fmi3String categories[]) {
    ENTER("fmi3SetDebugLogging", M_SetDebugLogging);
    return ST(core_set_debug_logging(comp, "fmi3SetDebugLogging", loggingOn, nCategories, categories));
}

/* ---- life cycle ------------------------------------------------------------- */

static ModelInstance *instantiate(const char *fn, InterfaceType type, fmi3String instanceName,
                                  fmi3String token, fmi3String resourcePath, fmi3Boolean loggingOn,
                                  fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage) {
    ModelInstance *comp = calloc(1, sizeof(ModelInstance));
    if (!comp) return NULL;
    comp->env = env;
    comp->logMessage = logMessage;
    comp->type = type;
    if (core_init_instance(comp, fn, instanceName, token, resourcePath, false) != OK) {
        free(comp);
        return NULL;
    }
    for (int i = 0; i < LOG_NCATEGORIES; i++) comp->logOn[i] = loggingOn;
    return comp;
}

/* a message before there is an instance */
static void log_refusal(fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage, const char *text) {
    if (logMessage) logMessage(env, fmi3Error, "logStatusError", text);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)visible;
#ifdef MODEL_NX
    return instantiate("fmi3InstantiateModelExchange", IF_MODEL_EXCHANGE, instanceName, instantiationToken,
                       resourcePath, loggingOn, instanceEnvironment, logMessage);
#else
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)loggingOn;
    log_refusal(instanceEnvironment, logMessage, "fmi3InstantiateModelExchange: this FMU has no Model "
                "Exchange interface (a sampled controller: co-simulation only)");
    return NULL;
#endif
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)visible; (void)requiredIntermediateVariables; (void)intermediateUpdate;
    /* earlyReturnAllowed: accepted; the FMU never returns early
       (mightReturnEarlyFromDoStep = false): it handles its events inside the step */
    (void)earlyReturnAllowed;
    if (nRequiredIntermediateVariables > 0) {
        log_refusal(instanceEnvironment, logMessage, "fmi3InstantiateCoSimulation: this FMU provides no "
                    "intermediate update (providesIntermediateUpdate = false): "
                    "nRequiredIntermediateVariables must be 0");
        return NULL;
    }
    ModelInstance *comp = instantiate("fmi3InstantiateCoSimulation", IF_CO_SIMULATION, instanceName,
                                      instantiationToken, resourcePath, loggingOn, instanceEnvironment,
                                      logMessage);
    if (comp) comp->eventModeUsed = eventModeUsed;
    return comp;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    log_refusal(instanceEnvironment, logMessage, "fmi3InstantiateScheduledExecution: this FMU has no "
                "Scheduled Execution interface (Co-Simulation and Model Exchange only)");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    core_free_instance((ModelInstance *)instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    ENTER("fmi3EnterInitializationMode", M_EnterInit);
    const Status status = core_setup_experiment(comp, "fmi3EnterInitializationMode", toleranceDefined,
                                                tolerance, startTime, stopTimeDefined, stopTime);
    if (status > Warning) return ST(status);
    comp->v.state = S_INIT_MODE;
    core_dirty(comp);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    ENTER("fmi3ExitInitializationMode", M_ExitInit);
    const Status status = core_exit_init(comp, "fmi3ExitInitializationMode");
    if (status > Warning) return ST(status);
    comp->v.state = comp->type == IF_MODEL_EXCHANGE || comp->eventModeUsed ? S_EVENT_MODE : S_STEP_COMPLETE;
#ifdef MODEL_LSBUS
    lsnode_enter_event_mode(comp);  /* the first event: t = startTime */
#endif
    return ST(status);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER("fmi3EnterEventMode", M_EnterEventMode);
    if (comp->type == IF_CO_SIMULATION && !comp->eventModeUsed)
        return leave(comp, log_error(comp, "fmi3EnterEventMode: the instance was made with "
                                           "eventModeUsed = false"));
    if (comp->type == IF_MODEL_EXCHANGE && comp->v.state != S_CONT_TIME_MODE)
        return leave(comp, log_error(comp, "fmi3EnterEventMode: illegal call sequence: not allowed in "
                                           "state '%s'", state_name(comp->v.state)));
    comp->v.state = S_EVENT_MODE;
#ifdef MODEL_LSBUS
    lsnode_enter_event_mode(comp);
#endif
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ENTER("fmi3Terminate", M_Terminate);
    comp->v.state = S_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    ENTER("fmi3Reset", M_Reset);
    return ST(core_reset(comp));
}

/* ---- getting and setting variables -------------------------------------------
 * A scalar variable has one value: nValues must equal nValueReferences. */

#define SIZES(FN)                                                                 \
    REQUIRE_ARRAY(FN, valueReferences, nValueReferences);                         \
    REQUIRE_ARRAY(FN, values, nValues);                                           \
    if (nValues != nValueReferences)                                              \
        return leave(comp, log_error(comp, "%s: nValues = %zu, but the %zu variables are scalars: "  \
                                           "nValues must be nValueReferences", FN, nValues,          \
                                     nValueReferences))

#define GETTER(FN, T, TYPE, READ)                                                 \
    fmi3Status FN(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                  size_t nValueReferences, T values[], size_t nValues) {          \
        ENTER(#FN, M_Get);                                                        \
        SIZES(#FN);                                                               \
        if (core_refresh(comp) > Warning) return leave(comp, Error);              \
        for (size_t i = 0; i < nValueReferences; i++) {                           \
            const VarInfo *v = core_lookup(comp, #FN, TYPE, valueReferences[i]);  \
            if (!v) return leave(comp, Error);                                    \
            READ;                                                                 \
        }                                                                         \
        return fmi3OK;                                                            \
    }

/* the Float64 variables FMI 3.0 adds to the table: time and the event indicators */
static bool get_extra_float64(ModelInstance *comp, fmi3ValueReference vr, double *value) {
    if (vr == MODEL_VR_TIME) {
        *value = comp->v.time;
        return true;
    }
#if defined(MODEL_NX) && defined(MODEL_VR_Z0)
    if (vr >= MODEL_VR_Z0 && vr < MODEL_VR_Z0 + MODEL_NZ) {
        double z[MODEL_NZ];
        model_event_indicators(comp, z);
        *value = z[vr - MODEL_VR_Z0];
        return true;
    }
#endif
    return false;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    ENTER("fmi3GetFloat64", M_Get);
    SIZES("fmi3GetFloat64");
    if (core_refresh(comp) > Warning) return leave(comp, Error);
    for (size_t i = 0; i < nValueReferences; i++) {
        if (get_extra_float64(comp, valueReferences[i], &values[i])) continue;
        const VarInfo *v = core_lookup(comp, "fmi3GetFloat64", T_REAL, valueReferences[i]);
        if (!v) return leave(comp, Error);
        values[i] = *(double *)core_field(comp, v);
    }
    return fmi3OK;
}

GETTER(fmi3GetInt32, fmi3Int32, T_INTEGER, values[i] = *(int *)core_field(comp, v))
GETTER(fmi3GetInt64, fmi3Int64, T_ENUMERATION, values[i] = *(int *)core_field(comp, v))
GETTER(fmi3GetBoolean, fmi3Boolean, T_BOOLEAN, values[i] = *(int *)core_field(comp, v) != 0)
GETTER(fmi3GetString, fmi3String, T_STRING, values[i] = (const char *)core_field(comp, v))

#define SETTER(FN, T, TYPE, CHECK, DIFFERS, WRITE)                                \
    fmi3Status FN(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                  size_t nValueReferences, const T values[], size_t nValues) {    \
        ENTER(#FN, M_Set);                                                        \
        SIZES(#FN);                                                               \
        for (size_t i = 0; i < nValueReferences; i++) {                           \
            const VarInfo *v = core_lookup(comp, #FN, TYPE, valueReferences[i]);  \
            if (!v || core_settable(comp, #FN, v)) return leave(comp, Error);     \
            CHECK;                                                                \
            if (DIFFERS) { WRITE; core_changed(comp); }                           \
        }                                                                         \
        return fmi3OK;                                                            \
    }

SETTER(fmi3SetFloat64, fmi3Float64, T_REAL,
       if (core_check_range(comp, "fmi3SetFloat64", v, values[i])) return leave(comp, Error),
       *(double *)core_field(comp, v) != values[i],
       *(double *)core_field(comp, v) = values[i])
SETTER(fmi3SetInt32, fmi3Int32, T_INTEGER,
       if (core_check_range(comp, "fmi3SetInt32", v, (double)values[i])) return leave(comp, Error),
       *(int *)core_field(comp, v) != values[i],
       *(int *)core_field(comp, v) = values[i])
/* an Enumeration: its declared min/max (within its items) bound it, so the
   value fits the int it is kept in */
SETTER(fmi3SetInt64, fmi3Int64, T_ENUMERATION,
       if (core_check_range(comp, "fmi3SetInt64", v, (double)values[i]) ||
           values[i] < INT32_MIN || values[i] > INT32_MAX)
           return leave(comp, log_error(comp, "fmi3SetInt64: %s = %lld is out of its range", v->name,
                                        (long long)values[i])),
       *(int *)core_field(comp, v) != (int)values[i],
       *(int *)core_field(comp, v) = (int)values[i])
SETTER(fmi3SetBoolean, fmi3Boolean, T_BOOLEAN,
       (void)0,
       *(int *)core_field(comp, v) != (values[i] ? 1 : 0),
       *(int *)core_field(comp, v) = values[i] ? 1 : 0)
SETTER(fmi3SetString, fmi3String, T_STRING,
       if (core_set_string(comp, "fmi3SetString", v, values[i])) return leave(comp, Error),
       false, (void)0)

/* the types this FMU has no variables of: a call with variables is an error
   naming the first value reference */
static fmi3Status no_such_type(fmi3Instance instance, const char *fn, const char *type, int mask,
                               const fmi3ValueReference vr[], size_t nvr) {
    ENTER(fn, mask);
    if (nvr == 0) return fmi3OK;
    return leave(comp, log_error(comp, "%s: no %s variable has value reference %u (this FMU has no %s "
                                       "variables)", fn, type, vr ? vr[0] : 0u, type));
}

#define NO_TYPE(GET, SET, T, NAME)                                                \
    fmi3Status GET(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                   size_t nValueReferences, T values[], size_t nValues) {         \
        (void)values; (void)nValues;                                              \
        return no_such_type(instance, #GET, NAME, M_Get, valueReferences, nValueReferences); \
    }                                                                             \
    fmi3Status SET(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                   size_t nValueReferences, const T values[], size_t nValues) {   \
        (void)values; (void)nValues;                                              \
        return no_such_type(instance, #SET, NAME, M_Set, valueReferences, nValueReferences); \
    }

NO_TYPE(fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, "Float32")
NO_TYPE(fmi3GetInt8, fmi3SetInt8, fmi3Int8, "Int8")
NO_TYPE(fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, "UInt8")
NO_TYPE(fmi3GetInt16, fmi3SetInt16, fmi3Int16, "Int16")
NO_TYPE(fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, "UInt16")
NO_TYPE(fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, "UInt32")
NO_TYPE(fmi3GetUInt64, fmi3SetUInt64, fmi3UInt64, "UInt64")

#ifdef MODEL_LSBUS

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    ENTER("fmi3GetBinary", M_Get);
    SIZES("fmi3GetBinary");
    REQUIRE_ARRAY("fmi3GetBinary", valueSizes, nValues);
    for (size_t i = 0; i < nValueReferences; i++)
        if (lsnode_get_binary(comp, valueReferences[i], &valueSizes[i], &values[i])) return leave(comp, Error);
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues) {
    ENTER("fmi3SetBinary", M_Set);
    SIZES("fmi3SetBinary");
    REQUIRE_ARRAY("fmi3SetBinary", valueSizes, nValues);
    for (size_t i = 0; i < nValueReferences; i++)
        if (lsnode_set_binary(comp, valueReferences[i], valueSizes[i], values[i])) return leave(comp, Error);
    return fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    ENTER("fmi3GetClock", M_Get);
    REQUIRE_ARRAY("fmi3GetClock", valueReferences, nValueReferences);
    REQUIRE_ARRAY("fmi3GetClock", values, nValueReferences);
    for (size_t i = 0; i < nValueReferences; i++) {
        bool active = false;
        if (lsnode_get_clock(comp, valueReferences[i], &active)) return leave(comp, Error);
        values[i] = active;
    }
    return fmi3OK;
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    ModelInstance *node = (ModelInstance *)instance;   /* in Step Mode, ...: named with node, clock and time */
    if (node && !(node->v.state & (S_EVENT_MODE | S_ERROR | S_FATAL)) && nValueReferences > 0 && valueReferences)
        return leave(node, lsnode_clock_outside_event_mode(node, valueReferences[0]));
    ENTER("fmi3SetClock", S_EVENT_MODE);     /* FMI 3.0, 2.2.9: clocks are set in Event Mode only */
    REQUIRE_ARRAY("fmi3SetClock", valueReferences, nValueReferences);
    REQUIRE_ARRAY("fmi3SetClock", values, nValueReferences);
    for (size_t i = 0; i < nValueReferences; i++)
        if (lsnode_set_clock(comp, valueReferences[i], values[i] != fmi3ClockInactive)) return leave(comp, Error);
    return fmi3OK;
}

#else

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes; (void)values; (void)nValues;
    return no_such_type(instance, "fmi3GetBinary", "Binary", M_Get, valueReferences, nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues) {
    (void)valueSizes; (void)values; (void)nValues;
    return no_such_type(instance, "fmi3SetBinary", "Binary", M_Set, valueReferences, nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    (void)values;
    return no_such_type(instance, "fmi3GetClock", "Clock", M_Get, valueReferences, nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    (void)values;
    return no_such_type(instance, "fmi3SetClock", "Clock", M_Set, valueReferences, nValueReferences);
}

#endif

/* ---- what this FMU does not provide ------------------------------------------ */

static fmi3Status not_provided(fmi3Instance instance, const char *fn, const char *why) {
    ENTER(fn, ANY_BUT_FATAL);
    return leave(comp, log_error(comp, "%s: not provided by this FMU (%s)", fn, why));
}

#define NOT_PROVIDED(fn, why) not_provided(instance, fn, why)

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference; (void)nDependencies;
    return NOT_PROVIDED("fmi3GetNumberOfVariableDependencies", "providesPerElementDependencies = false; "
                        "the dependencies are in <ModelStructure>");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    (void)dependent; (void)elementIndicesOfDependent; (void)independents;
    (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
    return NOT_PROVIDED("fmi3GetVariableDependencies", "providesPerElementDependencies = false; "
                        "the dependencies are in <ModelStructure>");
}

/* ---- directional and adjoint derivatives (FMI 3.0, 2.2.11): sensitivity =
 * J seed resp. J^T seed, the knowns continuous states and inputs, the unknowns
 * outputs and state derivatives; allowed in Initialization, Event,
 * Continuous-Time and Step Mode and when Terminated (2.3.3, 2.3.5, 2.3.8, 3.2,
 * 4.2). Every variable is a scalar, so nSeed and nSensitivity are counts of
 * variables. Models without the hook (fmu.h: MODEL_DIRECTIONAL_DERIVATIVE)
 * refuse both (providesDirectionalDerivatives = false). */
#define M_Derivatives (S_INIT_MODE | S_EVENT_MODE | S_CONT_TIME_MODE | S_STEP_COMPLETE | S_TERMINATED)

#ifdef MODEL_DIRECTIONAL_DERIVATIVE
static fmi3Status derivative(fmi3Instance instance, const char *fn, bool adjoint,
                             const fmi3ValueReference unknowns[], size_t nUnknowns,
                             const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                             size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    ENTER(fn, M_Derivatives);
    const size_t nIn = adjoint ? nUnknowns : nKnowns, nOut = adjoint ? nKnowns : nUnknowns;
    if (nSeed != nIn || nSensitivity != nOut)
        return leave(comp, log_error(comp, "%s: nSeed = %zu and nSensitivity = %zu must be %zu and %zu "
                                           "(every variable of this FMU is a scalar)",
                                     fn, nSeed, nSensitivity, nIn, nOut));
    return ST((adjoint ? core_adjoint_derivative : core_directional_derivative)(
        comp, fn, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity));
}
#endif

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity) {
#ifdef MODEL_DIRECTIONAL_DERIVATIVE
    return derivative(instance, "fmi3GetDirectionalDerivative", false, unknowns, nUnknowns, knowns, nKnowns,
                      seed, nSeed, sensitivity, nSensitivity);
#else
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return NOT_PROVIDED("fmi3GetDirectionalDerivative", "providesDirectionalDerivatives = false");
#endif
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                    size_t nSensitivity) {
#ifdef MODEL_DIRECTIONAL_DERIVATIVE
    return derivative(instance, "fmi3GetAdjointDerivative", true, unknowns, nUnknowns, knowns, nKnowns,
                      seed, nSeed, sensitivity, nSensitivity);
#else
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return NOT_PROVIDED("fmi3GetAdjointDerivative", "providesAdjointDerivatives = false");
#endif
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return NOT_PROVIDED("fmi3EnterConfigurationMode", "the FMU has no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return NOT_PROVIDED("fmi3ExitConfigurationMode", "the FMU has no structural parameters");
}

#define NO_CLOCKS "the FMU has no clocks"

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
#ifdef MODEL_LSBUS
    ENTER("fmi3GetIntervalDecimal", M_Get);
    REQUIRE_ARRAY("fmi3GetIntervalDecimal", valueReferences, nValueReferences);
    REQUIRE_ARRAY("fmi3GetIntervalDecimal", intervals, nValueReferences);
    REQUIRE_ARRAY("fmi3GetIntervalDecimal", qualifiers, nValueReferences);
    for (size_t i = 0; i < nValueReferences; i++) {
        if (lsnode_interval(comp, valueReferences[i], &intervals[i])) return leave(comp, Error);
        qualifiers[i] = fmi3IntervalUnchanged;   /* a constant clock: its interval never changes */
    }
    return fmi3OK;
#else
    (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers;
    return NOT_PROVIDED("fmi3GetIntervalDecimal", NO_CLOCKS);
#endif
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers;
    return NOT_PROVIDED("fmi3GetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return NOT_PROVIDED("fmi3GetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return NOT_PROVIDED("fmi3GetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals;
    return NOT_PROVIDED("fmi3SetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return NOT_PROVIDED("fmi3SetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return NOT_PROVIDED("fmi3SetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return NOT_PROVIDED("fmi3SetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference; (void)activationTime;
    return NOT_PROVIDED("fmi3ActivateModelPartition", "no Scheduled Execution interface");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)orders; (void)values; (void)nValues;
    return NOT_PROVIDED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder = 0");
}

/* ---- FMU state (fmu_core.c: validated as a whole before any of it is used) -- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER("fmi3GetFMUState", M_FMUState);
#ifdef MODEL_LSBUS
    (void)FMUState;
    return leave(comp, log_error(comp, "fmi3GetFMUState: not provided by this FMU (canGetAndSetFMUState = "
                                       "false: a network node's bus state is not saved)"));
#else
    return ST(core_get_state(comp, "fmi3GetFMUState", FMUState));
#endif
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    ENTER("fmi3SetFMUState", M_FMUState);
#ifdef MODEL_LSBUS
    (void)FMUState;
    return leave(comp, log_error(comp, "fmi3SetFMUState: not provided by this FMU (canGetAndSetFMUState = "
                                       "false: a network node's bus state is not saved)"));
#else
    return ST(core_set_state(comp, "fmi3SetFMUState", FMUState));
#endif
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER("fmi3FreeFMUState", M_FMUState);
    return ST(core_free_state(comp, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    ENTER("fmi3SerializedFMUStateSize", M_FMUState);
    return ST(core_state_size(comp, "fmi3SerializedFMUStateSize", FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    ENTER("fmi3SerializeFMUState", M_FMUState);
    return ST(core_serialize(comp, "fmi3SerializeFMUState", FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    ENTER("fmi3DeserializeFMUState", M_FMUState);
#ifdef MODEL_LSBUS
    (void)serializedState; (void)size; (void)FMUState;
    return leave(comp, log_error(comp, "fmi3DeserializeFMUState: not provided by this FMU "
                                       "(canSerializeFMUState = false)"));
#endif
    return ST(core_deserialize(comp, "fmi3DeserializeFMUState", serializedState, size, FMUState));
}

/* ---- Event Mode (Model Exchange; Co-Simulation with eventModeUsed) ---------- */

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    ENTER("fmi3EvaluateDiscreteStates", M_UpdateDiscrete);
    /* no clocked partitions: the discrete states are updated by
       fmi3UpdateDiscreteStates (and in Co-Simulation inside the step) */
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    ENTER("fmi3UpdateDiscreteStates", M_UpdateDiscrete);
    if (!discreteStatesNeedUpdate || !terminateSimulation || !nominalsOfContinuousStatesChanged ||
        !valuesOfContinuousStatesChanged || !nextEventTimeDefined || !nextEventTime)
        return leave(comp, log_error(comp, "fmi3UpdateDiscreteStates: NULL argument"));
    bool terminate = false;
    double tNext = INFINITY;
    Status status = OK;
#ifdef MODEL_LSBUS
    /* a network node: the operations received (Rx_Clock) and those to send (Tx_Clock) */
    if (core_refresh(comp) > Warning) return leave(comp, Error);
    status = (Status)lsnode_update(comp, &tNext);   /* a triggered Tx_Clock's next tick */
    if (status > Warning) return leave(comp, status);
#endif
#ifdef MODEL_NX
    /* Co-Simulation handles its events inside the step: nothing to update here */
    if (comp->type == IF_MODEL_EXCHANGE) {
        status = core_event_update(comp, "fmi3UpdateDiscreteStates", &terminate, &tNext);
        if (status > Warning) return ST(status);
    }
#endif
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = terminate;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = isfinite(tNext);
    *nextEventTime = isfinite(tNext) ? tNext : 0.0;
    return ST(status);
}

/* ---- Co-Simulation ------------------------------------------------------------- */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER("fmi3EnterStepMode", M_EnterStepMode);
    if (comp->type != IF_CO_SIMULATION)
        return leave(comp, log_error(comp, "fmi3EnterStepMode: a Co-Simulation function, but the instance "
                                           "was instantiated for Model Exchange"));
    comp->v.state = S_STEP_COMPLETE;
#ifdef MODEL_LSBUS
    lsnode_leave_event_mode(comp);  /* the clocks of this event are over */
#endif
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi3DoStep", M_DoStep);
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return leave(comp, log_error(comp, "fmi3DoStep: NULL argument"));
#ifdef MODEL_LSBUS
    lsnode_step(comp);              /* the bus's operations of the last event are done */
    if (communicationStepSize == 0.0 && fabs(currentCommunicationPoint - comp->v.time) <= 1e-9)
        /* FMI 3.0.2, 4.2 wants communicationStepSize > 0; fmu-manipulation-toolbox 2.0's
           container steps 0 to serve a countdown clock due now (the bus's interval 0): a
           network node takes it as no step at all, with a warning (lsbus_node.h) */
        return ST(lsnode_zero_step(comp, eventHandlingNeeded, terminateSimulation, earlyReturn,
                                   lastSuccessfulTime));
#endif
    const Status status = core_do_step(comp, "fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    /* the FMU handles its events (a sample, an end stop) inside the step */
    *eventHandlingNeeded = fmi3False;
#ifdef MODEL_LSBUS
    /* a triggered Tx_Clock's tick reached: fmi-ls-bus 1.0, 4____network_abstraction.adoc,
       "Triggered Tx Clocks" (at the step's end, never by an early return) */
    *eventHandlingNeeded = status <= Warning && lsnode_event_needed(comp);
#endif
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = comp->v.time;
    return ST(status);
}

/* ---- Model Exchange ------------------------------------------------------------- */

#ifdef MODEL_NX

#define ME_ENTER(fn, mask)                                                          \
    ENTER(fn, mask);                                                                \
    if (comp->type != IF_MODEL_EXCHANGE)                                            \
        return leave(comp, log_error(comp, "%s: a Model Exchange function, but the "  \
                                           "instance was instantiated for Co-Simulation", fn))

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    ME_ENTER("fmi3EnterContinuousTimeMode", M_EnterContTime);
    comp->v.state = S_CONT_TIME_MODE;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ME_ENTER("fmi3CompletedIntegratorStep", M_CompletedStep);
    if (!enterEventMode || !terminateSimulation)
        return leave(comp, log_error(comp, "fmi3CompletedIntegratorStep: NULL argument"));
    *enterEventMode = fmi3False;            /* no step events: every event is a state or time event */
    *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    ME_ENTER("fmi3SetTime", M_SetTime);
    return ST(core_set_time(comp, "fmi3SetTime", time));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    ME_ENTER("fmi3SetContinuousStates", M_SetStates);
    return ST(core_set_x(comp, "fmi3SetContinuousStates", continuousStates, nContinuousStates));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    ME_ENTER("fmi3GetContinuousStateDerivatives", M_GetStates);
    return ST(core_derivatives(comp, "fmi3GetContinuousStateDerivatives", derivatives, nContinuousStates));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    ME_ENTER("fmi3GetEventIndicators", M_GetStates);
    return ST(core_event_indicators(comp, "fmi3GetEventIndicators", eventIndicators, nEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    ME_ENTER("fmi3GetContinuousStates", M_GetStates);
    return ST(core_get_x(comp, "fmi3GetContinuousStates", continuousStates, nContinuousStates));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    ME_ENTER("fmi3GetNominalsOfContinuousStates", M_GetNominals);
    return ST(core_nominals(comp, "fmi3GetNominalsOfContinuousStates", nominals, nContinuousStates));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    ME_ENTER("fmi3GetNumberOfEventIndicators", M_GetNumber);
    if (!nEventIndicators)
        return leave(comp, log_error(comp, "fmi3GetNumberOfEventIndicators: NULL argument"));
    *nEventIndicators = MODEL_NZ;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    ME_ENTER("fmi3GetNumberOfContinuousStates", M_GetNumber);
    if (!nContinuousStates)
        return leave(comp, log_error(comp, "fmi3GetNumberOfContinuousStates: NULL argument"));
    *nContinuousStates = MODEL_NX;
    return fmi3OK;
}

#else   /* a co-simulation-only FMU: every Model Exchange function is an error */

#define NOT_ME(fn) not_provided(instance, fn, "no Model Exchange interface: a sampled controller, " \
                                "co-simulation only")

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return NOT_ME("fmi3EnterContinuousTimeMode");
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return NOT_ME("fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return NOT_ME("fmi3SetTime");
}
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    return NOT_ME("fmi3SetContinuousStates");
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives; (void)nContinuousStates;
    return NOT_ME("fmi3GetContinuousStateDerivatives");
}
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    (void)eventIndicators; (void)nEventIndicators;
    return NOT_ME("fmi3GetEventIndicators");
}
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    return NOT_ME("fmi3GetContinuousStates");
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    (void)nominals; (void)nContinuousStates;
    return NOT_ME("fmi3GetNominalsOfContinuousStates");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    (void)nEventIndicators;
    return NOT_ME("fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    (void)nContinuousStates;
    return NOT_ME("fmi3GetNumberOfContinuousStates");
}

#endif
