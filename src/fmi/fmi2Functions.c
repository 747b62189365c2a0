/* The FMI 2.0 Co-Simulation API, shared by every artibus FMU.
 *
 * Every API function starts with ENTER(fn, allowed states): a call in a state
 * where the standard does not allow it returns fmi2Error with "illegal call
 * sequence" and the state it was made in. A function that ends in fmi2Error
 * moves the instance to the error state (FMI 2.0, 2.1.3: then only getters,
 * fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance are allowed).
 * Variables are read and written through the generated table (vartable.h).
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu.h"

/* ---- allowed states per function (FMI 2.0, table in 4.2.4) --------------- */
#define ANY_BUT_FATAL (S_INSTANTIATED | S_INIT_MODE | S_STEP_COMPLETE | S_STEP_FAILED | \
                       S_TERMINATED | S_ERROR | S_EVENT_MODE | S_CONT_TIME_MODE)
#define M_SetDebugLogging   ANY_BUT_FATAL
#define M_FreeInstance      (ANY_BUT_FATAL | S_FATAL)
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

static const char *const CATEGORY[LOG_NCATEGORIES] = {
    "logEvents", "logStatusWarning", "logStatusError", "logStatusFatal", "logAll"
};

static const char *state_name(InstanceState s) {
    switch (s) {
    case S_INSTANTIATED:  return "instantiated";
    case S_INIT_MODE:     return "initialization mode";
    case S_STEP_COMPLETE: return "step complete";
    case S_STEP_FAILED:   return "step failed";
    case S_TERMINATED:    return "terminated";
    case S_ERROR:         return "error";
    case S_FATAL:         return "fatal";
    case S_EVENT_MODE:    return "event mode";
    case S_CONT_TIME_MODE: return "continuous-time mode";
    }
    return "?";
}

/* ---- logging -------------------------------------------------------------- */

static void vlog(ModelInstance *comp, fmi2Status status, LogCategory cat,
                 const char *fmt, va_list ap) {
    if (!comp || !comp->cb.logger) return;
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    /* the message is a printf format (FMI 2.0, 2.1.5) in which '#' starts a
       value-reference escape: pass the text with '%' and '#' doubled, no arguments */
    char out[2 * sizeof buf];
    size_t o = 0;
    for (const char *p = buf; *p && o < sizeof out - 2; p++) {
        if (*p == '#' || *p == '%') out[o++] = *p;
        out[o++] = *p;
    }
    out[o] = '\0';
    comp->cb.logger(comp->cb.componentEnvironment, comp->instanceName, status,
                    CATEGORY[cat], out);
}

void log_event(ModelInstance *comp, const char *fmt, ...) {
    if (!comp || !(comp->logOn[LOG_EVENTS] || comp->logOn[LOG_ALL])) return;
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, fmi2OK, LOG_EVENTS, fmt, ap);
    va_end(ap);
}

void log_warning(ModelInstance *comp, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, fmi2Warning, LOG_WARNING, fmt, ap);
    va_end(ap);
}

fmi2Status log_error(ModelInstance *comp, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, fmi2Error, LOG_ERROR, fmt, ap);
    va_end(ap);
    return fmi2Error;
}

/* ---- call-order gate ------------------------------------------------------ */

static bool allowed(ModelInstance *comp, int mask, const char *fn) {
    if (comp->v.state & mask) return true;
    log_error(comp, "%s: illegal call sequence: not allowed in state '%s'",
              fn, state_name(comp->v.state));
    return false;
}

/* the status a function returns; an error moves the instance to S_ERROR */
static fmi2Status leave(ModelInstance *comp, fmi2Status status) {
    if (status == fmi2Fatal) comp->v.state = S_FATAL;
    else if (status == fmi2Error) comp->v.state = S_ERROR;
    return status;
}

#define ENTER(fn, mask)                                             \
    ModelInstance *comp = (ModelInstance *)c;                      \
    if (!comp) return fmi2Error;                                   \
    if (!allowed(comp, (mask), fn)) return leave(comp, fmi2Error)

#define REQUIRE_ARRAY(fn, p)                                                   \
    if (n > 0 && !(p))                                                         \
        return leave(comp, log_error(comp, "%s: argument '%s' is NULL", fn, #p))

/* ---- memory through the importer's callbacks ------------------------------ */

static void *fmu_calloc(ModelInstance *comp, size_t n, size_t size) {
    return comp->cb.allocateMemory(n, size);
}

static char *fmu_strdup(ModelInstance *comp, const char *s) {
    char *p = fmu_calloc(comp, strlen(s) + 1, 1);
    if (p) strcpy(p, s);
    return p;
}

/* file:///path/to/resources or file:/path -> /path/to/resources (percent-decoded) */
static char *resource_path(ModelInstance *comp, const char *uri) {
    if (!uri || strncmp(uri, "file:", 5) != 0) return NULL;
    const char *p = uri + 5;
    if (strncmp(p, "///", 3) == 0) p += 2;
    else if (strncmp(p, "//localhost/", 12) == 0) p += 11;
    char *out = fmu_calloc(comp, strlen(p) + 1, 1);
    if (!out) return NULL;
    char *o = out;
    for (; *p; p++) {
        unsigned hex;
        if (*p == '%') {    /* exactly two hex digits, else the location is malformed */
            if (!isxdigit((unsigned char)p[1]) || !isxdigit((unsigned char)p[2]) ||
                sscanf(p + 1, "%2x", &hex) != 1 || hex == 0) {
                comp->cb.freeMemory(out);
                return NULL;
            }
            *o++ = (char)hex;
            p += 2;
        }
        else *o++ = *p;
    }
#ifdef _WIN32
    /* file:///C:/dir -> C:/dir */
    if (out[0] == '/' && out[1] && out[2] == ':') memmove(out, out + 1, strlen(out));
#endif
    return out;
}

/* ---- inquiry ---------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                               size_t n, const fmi2String categories[]) {
    ENTER("fmi2SetDebugLogging", M_SetDebugLogging);
    REQUIRE_ARRAY("fmi2SetDebugLogging", categories);
    if (n == 0) {
        for (int i = 0; i < LOG_NCATEGORIES; i++) comp->logOn[i] = loggingOn;
        return fmi2OK;
    }
    for (size_t i = 0; i < n; i++) {
        int found = -1;
        for (int k = 0; k < LOG_NCATEGORIES; k++)
            if (categories[i] && strcmp(categories[i], CATEGORY[k]) == 0) found = k;
        if (found < 0)
            return leave(comp, log_error(comp, "fmi2SetDebugLogging: unknown log category '%s'",
                                         categories[i] ? categories[i] : "(null)"));
        comp->logOn[found] = loggingOn;
    }
    return fmi2OK;
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
    comp->type = fmuType;
    comp->instanceName = fmu_strdup(comp, instanceName ? instanceName : "");
    const char *why = NULL;
    if (!instanceName || !*instanceName) why = "instanceName must not be empty";
#ifdef MODEL_NX
    else if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange)
        why = "fmuType must be fmi2CoSimulation or fmi2ModelExchange";
#else
    else if (fmuType != fmi2CoSimulation) why = "this FMU supports co-simulation only (fmuType must be fmi2CoSimulation)";
#endif
    else if (!guid || strcmp(guid, MODEL_GUID) != 0) why = "GUID does not match the model description";
    if (why || !comp->instanceName) {
        if (why) log_error(comp, "fmi2Instantiate: %s (GUID given: '%s', expected '%s')",
                           why, guid ? guid : "(null)", MODEL_GUID);
        if (comp->instanceName) functions->freeMemory(comp->instanceName);
        functions->freeMemory(comp);
        return NULL;
    }
    comp->resourceDir = resource_path(comp, resourceLocation);
    if (resourceLocation && strncmp(resourceLocation, "file:", 5) == 0 && !comp->resourceDir) {
        log_error(comp, "fmi2Instantiate: fmuResourceLocation '%s' has a malformed percent escape "
                        "(%% must be followed by two hex digits, not %%00)", resourceLocation);
        functions->freeMemory(comp->instanceName);
        functions->freeMemory(comp);
        return NULL;
    }
    for (int i = 0; i < LOG_NCATEGORIES; i++) comp->logOn[i] = loggingOn;
    comp->v.state = S_INSTANTIATED;
    comp->stopTime = INFINITY;
    vars_set_start_values(&comp->v.d);
    comp->restart = comp->forget = comp->dirty = true;
    return comp;
}

void fmi2FreeInstance(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!comp) return;
    model_free(comp);
    if (comp->resourceDir) comp->cb.freeMemory(comp->resourceDir);
    comp->cb.freeMemory(comp->instanceName);
    comp->cb.freeMemory(comp);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    ENTER("fmi2SetupExperiment", M_SetupExperiment);
    if (!isfinite(startTime))
        return leave(comp, log_error(comp, "fmi2SetupExperiment: startTime = %g is not finite", startTime));
    if (stopTimeDefined && !(stopTime >= startTime))
        return leave(comp, log_error(comp, "fmi2SetupExperiment: stopTime = %g is before startTime = %g",
                                     stopTime, startTime));
    if (toleranceDefined && !(tolerance > 0))
        return leave(comp, log_error(comp, "fmi2SetupExperiment: tolerance = %g must be > 0", tolerance));
    comp->v.time = startTime;
    comp->stopTime = stopTimeDefined ? stopTime : INFINITY;
    comp->tolerance = toleranceDefined ? tolerance : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ENTER("fmi2EnterInitializationMode", M_EnterInit);
    comp->v.state = S_INIT_MODE;
    comp->dirty = true;
    return fmi2OK;
}

static fmi2Status check_outputs(ModelInstance *comp, const char *fn);

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    ENTER("fmi2ExitInitializationMode", M_ExitInit);
    fmi2Status status = model_init(comp);
    if (status > fmi2Warning) return leave(comp, status);
    model_outputs(comp);
    if (check_outputs(comp, "fmi2ExitInitializationMode")) return leave(comp, fmi2Error);
    comp->dirty = false;
    comp->restart = comp->forget = true;
    comp->v.state = comp->type == fmi2ModelExchange ? S_EVENT_MODE : S_STEP_COMPLETE;
    log_event(comp, "initialized at t = %g", comp->v.time);
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ENTER("fmi2Terminate", M_Terminate);
    comp->v.state = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    ENTER("fmi2Reset", M_Reset);
    model_free(comp);
    memset(&comp->v, 0, sizeof comp->v);
    vars_set_start_values(&comp->v.d);
    comp->v.state = S_INSTANTIATED;
    comp->stopTime = INFINITY;
    comp->tolerance = 0.0;
    comp->restart = comp->forget = comp->dirty = true;
    return fmi2OK;
}

/* ---- getting and setting variables ----------------------------------------- */

static const char *TYPE_NAME[] = { "Real", "Integer", "Boolean", "String" };

static fmi2Status lookup(ModelInstance *comp, const char *fn, VarType type,
                         fmi2ValueReference vr, const VarInfo **out) {
    *out = vars_find(type, vr);
    if (!*out)
        return log_error(comp, "%s: no %s variable has value reference %u",
                         fn, TYPE_NAME[type], vr);
    return fmi2OK;
}

/* outputs are computed lazily: after a set, before the next get */
static fmi2Status refresh(ModelInstance *comp) {
    if (!comp->dirty) return fmi2OK;
    if (comp->v.state == S_INIT_MODE) {
        fmi2Status status = model_init(comp);
        if (status > fmi2Warning) return status;
    }
    if (comp->v.state & (S_INIT_MODE | S_STEP_COMPLETE | S_EVENT_MODE | S_CONT_TIME_MODE))
        model_outputs(comp);
    comp->dirty = false;
    return fmi2OK;
}

static void *field(ModelInstance *comp, const VarInfo *v) {
    return (char *)&comp->v.d + v->offset;
}

#define GETTER(FN, T, TYPE, READ)                                                 \
    fmi2Status FN(fmi2Component c, const fmi2ValueReference vr[], size_t n, T value[]) { \
        ENTER(#FN, M_Get);                                                        \
        REQUIRE_ARRAY(#FN, vr);                                                   \
        REQUIRE_ARRAY(#FN, value);                                                \
        if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);           \
        for (size_t i = 0; i < n; i++) {                                          \
            const VarInfo *v;                                                     \
            if (lookup(comp, #FN, TYPE, vr[i], &v)) return leave(comp, fmi2Error);\
            READ;                                                                 \
        }                                                                         \
        return fmi2OK;                                                            \
    }

GETTER(fmi2GetReal, fmi2Real, T_REAL, value[i] = *(double *)field(comp, v))
GETTER(fmi2GetInteger, fmi2Integer, T_INTEGER, value[i] = *(int *)field(comp, v))
GETTER(fmi2GetBoolean, fmi2Boolean, T_BOOLEAN, value[i] = *(int *)field(comp, v) ? fmi2True : fmi2False)
GETTER(fmi2GetString, fmi2String, T_STRING, value[i] = (const char *)field(comp, v))

/* may this variable be set now? (FMI 2.0, 2.2.7: causality x variability x state) */
static fmi2Status settable(ModelInstance *comp, const char *fn, const VarInfo *v) {
    const InstanceState s = comp->v.state;
    bool ok;
    switch (v->causality) {
    case C_INPUT:
        ok = true;
        break;
    case C_PARAMETER:
        ok = v->variability == V_TUNABLE ? !(s & S_CONT_TIME_MODE)   /* ME: in event mode */
           : v->variability == V_FIXED ? (s & (S_INSTANTIATED | S_INIT_MODE)) != 0
           : false;
        break;
    default:
        ok = false;
    }
    if (ok) return fmi2OK;
    static const char *CAUS[] = { "parameter", "calculatedParameter", "input", "output",
                                  "local", "independent" };
    static const char *VARI[] = { "constant", "fixed", "tunable", "discrete", "continuous" };
    return log_error(comp, "%s: %s '%s' (%s %s) cannot be set in state '%s'", fn,
                     CAUS[v->causality], v->name, VARI[v->variability],
                     CAUS[v->causality], state_name(s));
}

static fmi2Status check_range(ModelInstance *comp, const char *fn, const VarInfo *v, double x) {
    if (!isfinite(x))
        return log_error(comp, "%s: %s = %g is not a finite number", fn, v->name, x);
    if (x < v->min)
        return log_error(comp, "%s: %s = %.15g is below its minimum %.15g", fn, v->name, x, v->min);
    if (x > v->max)
        return log_error(comp, "%s: %s = %.15g is above its maximum %.15g", fn, v->name, x, v->max);
    return fmi2OK;
}

/* after a value was stored: outputs and the integrator must follow it */
static void changed(ModelInstance *comp) {
    comp->dirty = true;
    comp->restart = true;
}

#define SETTER(FN, T, TYPE, CHECK, DIFFERS, WRITE)                                \
    fmi2Status FN(fmi2Component c, const fmi2ValueReference vr[], size_t n, const T value[]) { \
        ENTER(#FN, M_Set);                                                        \
        REQUIRE_ARRAY(#FN, vr);                                                   \
        REQUIRE_ARRAY(#FN, value);                                                \
        for (size_t i = 0; i < n; i++) {                                          \
            const VarInfo *v;                                                     \
            if (lookup(comp, #FN, TYPE, vr[i], &v) || settable(comp, #FN, v))     \
                return leave(comp, fmi2Error);                                    \
            CHECK;                                                                \
            if (DIFFERS) { WRITE; changed(comp); }                                \
        }                                                                         \
        return fmi2OK;                                                            \
    }

SETTER(fmi2SetReal, fmi2Real, T_REAL,
       if (check_range(comp, "fmi2SetReal", v, value[i])) return leave(comp, fmi2Error),
       *(double *)field(comp, v) != value[i],
       *(double *)field(comp, v) = value[i])
SETTER(fmi2SetInteger, fmi2Integer, T_INTEGER,
       if (check_range(comp, "fmi2SetInteger", v, (double)value[i])) return leave(comp, fmi2Error),
       *(int *)field(comp, v) != value[i],
       *(int *)field(comp, v) = value[i])
SETTER(fmi2SetBoolean, fmi2Boolean, T_BOOLEAN,
       (void)0,
       *(int *)field(comp, v) != (value[i] ? 1 : 0),
       *(int *)field(comp, v) = value[i] ? 1 : 0)
SETTER(fmi2SetString, fmi2String, T_STRING,
       if (!value[i] || strlen(value[i]) >= ARTIBUS_STRLEN)
           return leave(comp, log_error(comp, "fmi2SetString: %s: value is NULL or longer than %d bytes",
                                        v->name, ARTIBUS_STRLEN - 1)),
       strcmp((char *)field(comp, v), value[i]) != 0,
       strcpy((char *)field(comp, v), value[i]))

/* ---- FMU state: the plain-data block comp->v, nothing else ------------------
 * A state is validated as a whole before any of it is used (fmi2SetFMUstate,
 * fmi2DeSerializeFMUstate): header, the checksum of a serialized body, the
 * instance state, the time, every variable (finite; parameters and inputs in
 * their declared range) and the model's own ModelState (model_state_valid).
 * Otherwise fmi2Error with a message, and the instance's values unchanged. */

typedef struct {
    uint32_t magic;         /* 'ABFS' */
    uint32_t size;          /* sizeof(FmuState) of the build that wrote it */
    char guid[64];
    uint64_t sum;           /* FNV-1a of guid and v, written by fmi2SerializeFMUstate */
    __typeof__(((ModelInstance *)0)->v) v;
} FmuState;

#define FMUSTATE_MAGIC 0x41424653u

static uint64_t fnv1a(uint64_t h, const void *p, size_t n) {
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) { h ^= b[i]; h *= 1099511628211ull; }
    return h;
}

/* the checksum of a serialized state: FNV-1a over its GUID field and body */
static uint64_t state_sum(const FmuState *s) {
    return fnv1a(fnv1a(1469598103934665603ull, s->guid, sizeof s->guid), &s->v, sizeof s->v);
}

/* the first error message of model_check_parameters on a scratch instance,
   '%%' and '##' (doubled by vlog) single again */
static void capture_error(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                          fmi2String category, fmi2String message, ...) {
    (void)name; (void)category;
    char *why = env;
    if (status < fmi2Error || !why || why[0] || !message) return;
    size_t o = 0;
    for (const char *p = message; *p && o < 511; p++) {
        if ((*p == '%' || *p == '#') && p[1] == *p) p++;
        why[o++] = *p;
    }
    why[o] = '\0';
}

/* model_check_parameters on the parameters of state v, its message in why[512] */
static bool params_valid(ModelInstance *comp, const FmuState *s, char *why) {
    ModelInstance *scratch = fmu_calloc(comp, 1, sizeof *scratch);
    if (!scratch) {
        snprintf(why, 512, "out of memory");
        return false;
    }
    scratch->v = s->v;
    scratch->cb = comp->cb;
    scratch->cb.logger = capture_error;
    scratch->cb.componentEnvironment = why;
    scratch->instanceName = comp->instanceName;
    scratch->type = comp->type;
    scratch->stopTime = INFINITY;
    why[0] = '\0';
    const fmi2Status st = model_check_parameters(scratch);
    comp->cb.freeMemory(scratch);
    if (st > fmi2Warning && !why[0]) snprintf(why, 512, "its parameters are not consistent");
    return st <= fmi2Warning;
}

static fmi2Status check_state(ModelInstance *comp, const char *fn, const FmuState *s) {
    if (!s || s->magic != FMUSTATE_MAGIC || s->size != sizeof(FmuState) ||
        memchr(s->guid, '\0', sizeof s->guid) == NULL || strcmp(s->guid, MODEL_GUID) != 0)
        return log_error(comp, "%s: the state was not made by this FMU (GUID %s)", fn, MODEL_GUID);
    const unsigned st = (unsigned)s->v.state;
    if (!(st & (unsigned)ANY_BUT_FATAL) || (st & (st - 1)) || (st & ~(unsigned)ANY_BUT_FATAL))
        return log_error(comp, "%s: the state's instance state %u is not a legal one", fn, st);
    if (!isfinite(s->v.time))
        return log_error(comp, "%s: the state's time %g is not finite", fn, s->v.time);
    for (size_t i = 0; i < MODEL_NVARS; i++) {
        const VarInfo *v = &VARS[i];
        const char *p = (const char *)&s->v.d + v->offset;
        const bool ranged = v->causality == C_PARAMETER || v->causality == C_INPUT;
        double x;
        switch (v->type) {
        case T_REAL:
            memcpy(&x, p, sizeof x);
            if (!isfinite(x))
                return log_error(comp, "%s: the state's %s = %g is not finite", fn, v->name, x);
            break;
        case T_INTEGER: {
            int k;
            memcpy(&k, p, sizeof k);
            x = k;
            break;
        }
        case T_BOOLEAN: {
            int k;
            memcpy(&k, p, sizeof k);
            if (k != 0 && k != 1)
                return log_error(comp, "%s: the state's Boolean %s = %d is neither 0 nor 1", fn, v->name, k);
            continue;
        }
        default:
            if (!memchr(p, '\0', ARTIBUS_STRLEN))
                return log_error(comp, "%s: the state's String %s is not terminated", fn, v->name);
            continue;
        }
        if (ranged && !(x >= v->min && x <= v->max))
            return log_error(comp, "%s: the state's %s = %.15g is outside its range [%g, %g]",
                             fn, v->name, x, v->min, v->max);
    }
    /* before initialisation model_init sets the ModelState from the variables
       before any use of it (refresh, fmi2ExitInitializationMode): not checked */
    char why[512] = "";
    if (st & (S_INSTANTIATED | S_INIT_MODE)) return fmi2OK;
    /* the parameters as model_init checks them (the same function), then the
       model's own states */
    if (!params_valid(comp, s, why))
        return log_error(comp, "%s: the state's parameters are not valid: %s", fn, why);
    if (!model_state_valid(&s->v.d, &s->v.s, s->v.time, why, sizeof why))
        return log_error(comp, "%s: the state is not valid: %s", fn, why[0] ? why : "(no reason given)");
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER("fmi2GetFMUstate", M_FMUstate);
    if (!state) return leave(comp, log_error(comp, "fmi2GetFMUstate: argument 'FMUstate' is NULL"));
    if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);
    FmuState *s = *state ? (FmuState *)*state : fmu_calloc(comp, 1, sizeof(FmuState));
    if (!s) return leave(comp, log_error(comp, "fmi2GetFMUstate: out of memory"));
    if (*state && s->magic != FMUSTATE_MAGIC)
        return leave(comp, log_error(comp, "fmi2GetFMUstate: the state to overwrite was not made by this FMU"));
    s->magic = FMUSTATE_MAGIC;
    s->size = sizeof(FmuState);
    memset(s->guid, 0, sizeof s->guid);
    snprintf(s->guid, sizeof s->guid, "%s", MODEL_GUID);
    s->sum = 0;
    s->v = comp->v;
    *state = s;
    /* the integrator restarts here, exactly as it will after a restore: so a
       run continued from this point and one restored to it are identical */
    comp->restart = comp->forget = true;
    return fmi2OK;
}

static fmi2Status restore(ModelInstance *comp, const char *fn, const FmuState *s) {
    if (check_state(comp, fn, s)) return fmi2Error;
    /* the model rebuilds what it derives at initialisation (a fresh instance
       has none of it); if it cannot, the previous values come back */
    __typeof__(comp->v) *old = fmu_calloc(comp, 1, sizeof comp->v);
    if (!old) return log_error(comp, "%s: out of memory", fn);
    *old = comp->v;
    comp->v = s->v;
    if (model_restored(comp) > fmi2Warning) {
        comp->v = *old;
        comp->cb.freeMemory(old);
        comp->dirty = comp->restart = comp->forget = true;
        return log_error(comp, "%s: the state could not be restored", fn);
    }
    comp->cb.freeMemory(old);
    comp->restart = comp->forget = true;
    comp->dirty = true;
    log_event(comp, "%s: state restored at t = %g", fn, comp->v.time);
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    ENTER("fmi2SetFMUstate", M_FMUstate);
    return leave(comp, restore(comp, "fmi2SetFMUstate", (const FmuState *)state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER("fmi2FreeFMUstate", M_FMUstate);
    if (state && *state) {
        comp->cb.freeMemory(*state);
        *state = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    ENTER("fmi2SerializedFMUstateSize", M_FMUstate);
    if (!state || !size)
        return leave(comp, log_error(comp, "fmi2SerializedFMUstateSize: NULL argument"));
    *size = sizeof(FmuState);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    ENTER("fmi2SerializeFMUstate", M_FMUstate);
    if (!state || !bytes || size < sizeof(FmuState))
        return leave(comp, log_error(comp, "fmi2SerializeFMUstate: need %zu bytes, got %zu",
                                     sizeof(FmuState), bytes ? size : 0));
    const FmuState *s = (const FmuState *)state;
    if (s->magic != FMUSTATE_MAGIC || s->size != sizeof(FmuState))
        return leave(comp, log_error(comp, "fmi2SerializeFMUstate: the state was not made by this FMU"));
    memcpy(bytes, s, sizeof(FmuState));
    const uint64_t sum = state_sum(s);
    memcpy(bytes + offsetof(FmuState, sum), &sum, sizeof sum);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    ENTER("fmi2DeSerializeFMUstate", M_FMUstate);
    if (!bytes || !state || size != sizeof(FmuState))
        return leave(comp, log_error(comp, "fmi2DeSerializeFMUstate: expected %zu bytes, got %zu",
                                     sizeof(FmuState), size));
    FmuState *tmp = fmu_calloc(comp, 1, sizeof(FmuState));
    if (!tmp) return leave(comp, log_error(comp, "fmi2DeSerializeFMUstate: out of memory"));
    memcpy(tmp, bytes, sizeof(FmuState));
    fmi2Status status = fmi2OK;
    if (tmp->magic != FMUSTATE_MAGIC || memchr(tmp->guid, '\0', sizeof tmp->guid) == NULL ||
        strcmp(tmp->guid, MODEL_GUID) != 0)
        status = log_error(comp, "fmi2DeSerializeFMUstate: the bytes are not a state of this FMU");
    else if (tmp->sum != state_sum(tmp))
        status = log_error(comp, "fmi2DeSerializeFMUstate: the state's checksum does not match its "
                                 "body (the bytes were changed after fmi2SerializeFMUstate)");
    else
        status = check_state(comp, "fmi2DeSerializeFMUstate", tmp);
    if (status != fmi2OK) {
        comp->cb.freeMemory(tmp);
        return leave(comp, fmi2Error);
    }
    tmp->sum = 0;
    if (*state) {
        FmuState *s = (FmuState *)*state;
        if (s->magic != FMUSTATE_MAGIC) {
            comp->cb.freeMemory(tmp);
            return leave(comp, log_error(comp, "fmi2DeSerializeFMUstate: the state to overwrite was "
                                               "not made by this FMU"));
        }
        *s = *tmp;
        comp->cb.freeMemory(tmp);
    } else {
        *state = tmp;
    }
    return fmi2OK;
}

/* ---- not provided (capability flags are false in the model description) --- */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[],
                                        size_t nUnknown, const fmi2ValueReference vKnown[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown; (void)nUnknown; (void)vKnown; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    ENTER("fmi2GetDirectionalDerivative", M_Get);
    return leave(comp, log_error(comp, "fmi2GetDirectionalDerivative: not provided by this FMU "
                                       "(providesDirectionalDerivative = false)"));
}

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

/* every Real output finite, after model_outputs; else fmi2Error naming the
   first one (in the order of VARS) that is not. REAL_OUTPUTS is generated with
   the table: the loop runs over the outputs only, not over every variable. */
static fmi2Status check_outputs(ModelInstance *comp, const char *fn) {
    for (const VarInfo *const *out = REAL_OUTPUTS; *out; out++) {
        const VarInfo *v = *out;
        const double x = *(const double *)field(comp, v);
        if (!isfinite(x))
            return log_error(comp, "%s: output %s = %g at t = %.17g is not finite (a parameter or "
                                   "input out of its physical range?)", fn, v->name, x, comp->v.time);
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi2DoStep", M_DoStep);
    const double now = comp->v.time;
    if (!(fabs(t - now) <= 1e-9 * fmax(1.0, fabs(now))))
        return leave(comp, log_error(comp, "fmi2DoStep: expected currentCommunicationPoint = %.17g "
                                           "but was %.17g", now, t));
    if (!(h > 0) || !isfinite(h))
        return leave(comp, log_error(comp, "fmi2DoStep: communicationStepSize = %g must be > 0", h));
    if (now + h > comp->stopTime * (1 + 1e-12) + 1e-12)
        return leave(comp, log_error(comp, "fmi2DoStep: step to t = %.17g goes beyond stopTime = %.17g",
                                     now + h, comp->stopTime));
    fmi2Status status = model_do_step(comp, now, h);
    comp->restart = comp->forget = false;
    if (status <= fmi2Warning) {
        model_outputs(comp);        /* never a non-finite output with fmi2OK */
        comp->dirty = false;
        if (check_outputs(comp, "fmi2DoStep")) status = fmi2Error;
    } else {
        model_outputs(comp);        /* the state it stopped in, readable in the error state */
        comp->dirty = false;
    }
    if (status == fmi2Discard) comp->v.state = S_STEP_FAILED;
    return leave(comp, status);
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
    if (comp->type != fmi2ModelExchange)                                            \
        return leave(comp, log_error(comp, "%s: a Model Exchange function, but the "  \
                                           "instance was instantiated for co-simulation", fn))

/* the caller's array length must be the model description's */
static fmi2Status me_size(ModelInstance *comp, const char *fn, const void *p, size_t n,
                          size_t expected, const char *what) {
    if (n != expected)
        return log_error(comp, "%s: %s = %zu, but the model has %zu", fn, what, n, expected);
    if (n > 0 && !p) return log_error(comp, "%s: the array argument is NULL", fn);
    return fmi2OK;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    ME_ENTER("fmi2EnterEventMode", M_EnterEventMode);
    comp->v.state = S_EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    ME_ENTER("fmi2NewDiscreteStates", M_NewDiscrete);
    if (!info) return leave(comp, log_error(comp, "fmi2NewDiscreteStates: argument 'fmi2eventInfo' is NULL"));
    if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);
    bool terminate = false;
    double tNext = INFINITY;
    const fmi2Status status = model_event_update(comp, &terminate, &tNext);
    if (status > fmi2Warning) return leave(comp, status);
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = terminate ? fmi2True : fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = isfinite(tNext) ? fmi2True : fmi2False;
    info->nextEventTime = isfinite(tNext) ? tNext : 0.0;
    return status;
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
    if (!isfinite(time))
        return leave(comp, log_error(comp, "fmi2SetTime: time = %g is not finite", time));
    if (comp->v.time != time) {
        comp->v.time = time;
        comp->dirty = true;
    }
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    ME_ENTER("fmi2SetContinuousStates", M_SetStates);
    if (me_size(comp, "fmi2SetContinuousStates", x, nx, MODEL_NX, "nx")) return leave(comp, fmi2Error);
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(x[i]))
            return leave(comp, log_error(comp, "fmi2SetContinuousStates: x[%zu] (%s) = %g is not a "
                                               "finite number", i, X_NAME[i], x[i]));
    model_set_x(comp, x);
    comp->dirty = true;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    ME_ENTER("fmi2GetDerivatives", M_GetStates);
    if (me_size(comp, "fmi2GetDerivatives", dx, nx, MODEL_NX, "nx")) return leave(comp, fmi2Error);
    if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);
    if (model_derivatives(comp, dx) > fmi2Warning) return leave(comp, fmi2Error);
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(dx[i]))
            return leave(comp, log_error(comp, "fmi2GetDerivatives: the derivative of %s is %g at "
                                               "t = %.17g", X_NAME[i], dx[i], comp->v.time));
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t ni) {
    ME_ENTER("fmi2GetEventIndicators", M_GetStates);
    if (me_size(comp, "fmi2GetEventIndicators", z, ni, MODEL_NZ, "ni")) return leave(comp, fmi2Error);
    if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);
    if (ni > 0) model_event_indicators(comp, z);
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    ME_ENTER("fmi2GetContinuousStates", M_GetStates);
    if (me_size(comp, "fmi2GetContinuousStates", x, nx, MODEL_NX, "nx")) return leave(comp, fmi2Error);
    if (refresh(comp) > fmi2Warning) return leave(comp, fmi2Error);
    model_get_x(comp, x);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    ME_ENTER("fmi2GetNominalsOfContinuousStates", M_GetNominals);
    if (me_size(comp, "fmi2GetNominalsOfContinuousStates", x_nominal, nx, MODEL_NX, "nx"))
        return leave(comp, fmi2Error);
    for (size_t i = 0; i < nx; i++) x_nominal[i] = X_NOMINAL[i];
    return fmi2OK;
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
