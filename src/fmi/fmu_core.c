/* The part of the FMI layer that FMI 2.0 and FMI 3.0 share (fmu_core.h): the
 * call-order gate, logging, variables through the generated table (vartable.h),
 * the FMU state, the communication step and the Model Exchange functions. The
 * API functions themselves, with their version's types and allowed states, are
 * in fmi2Functions.c and fmi3Functions.c; each passes its own name (fn) so that
 * every message names the call the importer made.
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_core.h"

const char *const LOG_CATEGORY[LOG_NCATEGORIES] = {
    "logEvents", "logStatusWarning", "logStatusError", "logStatusFatal", "logAll"
};

const char *state_name(InstanceState s) {
    switch (s) {
    case S_INSTANTIATED:  return "instantiated";
    case S_INIT_MODE:     return "initialization mode";
#if FMI_VERSION == 3
    case S_STEP_COMPLETE: return "step mode";
    case S_STEP_FAILED:   return "step mode (the last step discarded)";
#else
    case S_STEP_COMPLETE: return "step complete";
    case S_STEP_FAILED:   return "step failed";
#endif
    case S_TERMINATED:    return "terminated";
    case S_ERROR:         return "error";
    case S_FATAL:         return "fatal";
    case S_EVENT_MODE:    return "event mode";
    case S_CONT_TIME_MODE: return "continuous-time mode";
    }
    return "?";
}

/* ---- logging -------------------------------------------------------------- */

static void vlog(ModelInstance *comp, Status status, LogCategory cat, const char *fmt, va_list ap) {
    if (!comp) return;
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    if (comp->capture) {    /* a scratch instance (params_valid): keep the first error */
        if (status >= Error && !comp->capture[0]) {
            buf[511] = '\0';
            memcpy(comp->capture, buf, strlen(buf) + 1);
        }
        return;
    }
    layer_log(comp, status, cat, buf);
}

void log_event(ModelInstance *comp, const char *fmt, ...) {
    if (!comp || !(comp->logOn[LOG_EVENTS] || comp->logOn[LOG_ALL])) return;
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, OK, LOG_EVENTS, fmt, ap);
    va_end(ap);
}

void log_warning(ModelInstance *comp, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, Warning, LOG_WARNING, fmt, ap);
    va_end(ap);
}

Status log_error(ModelInstance *comp, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog(comp, Error, LOG_ERROR, fmt, ap);
    va_end(ap);
    return Error;
}

/* ---- call-order gate ------------------------------------------------------ */

bool core_allowed(ModelInstance *comp, int mask, const char *fn) {
    if (comp->v.state & mask) return true;
    log_error(comp, "%s: illegal call sequence: not allowed in state '%s'",
              fn, state_name(comp->v.state));
    return false;
}

Status core_leave(ModelInstance *comp, Status status) {
    if (status == Fatal) comp->v.state = S_FATAL;
    else if (status == Error) comp->v.state = S_ERROR;
    return status;
}

#define leave core_leave

static char *fmu_strdup(ModelInstance *comp, const char *s) {
    char *p = layer_calloc(comp, strlen(s) + 1, 1);
    if (p) strcpy(p, s);
    return p;
}

/* file:///path/to/resources or file:/path -> /path/to/resources (percent-decoded);
   isUri = false (FMI 3.0's resourcePath): the path as given */
static char *resource_path(ModelInstance *comp, const char *uri, bool isUri) {
    if (!uri) return NULL;
    if (!isUri) return fmu_strdup(comp, uri);
    if (strncmp(uri, "file:", 5) != 0) return NULL;
    const char *p = uri + 5;
    if (strncmp(p, "///", 3) == 0) p += 2;
    else if (strncmp(p, "//localhost/", 12) == 0) p += 11;
    char *out = layer_calloc(comp, strlen(p) + 1, 1);
    if (!out) return NULL;
    char *o = out;
    for (; *p; p++) {
        unsigned hex;
        if (*p == '%') {    /* exactly two hex digits, else the location is malformed */
            if (!isxdigit((unsigned char)p[1]) || !isxdigit((unsigned char)p[2]) ||
                sscanf(p + 1, "%2x", &hex) != 1 || hex == 0) {
                layer_free(comp, out);
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

/* ---- life cycle ------------------------------------------------------------- */

Status core_init_instance(ModelInstance *comp, const char *fn, const char *instanceName,
                          const char *token, const char *resourceLocation, bool isUri) {
    comp->instanceName = fmu_strdup(comp, instanceName ? instanceName : "");
    const char *why = NULL;
    if (!instanceName || !*instanceName) why = "instanceName must not be empty";
    else if (!token || strcmp(token, MODEL_GUID) != 0)
        why = FMI_VERSION == 3 ? "instantiationToken does not match the model description"
                               : "GUID does not match the model description";
    if (why || !comp->instanceName) {
        if (why) log_error(comp, "%s: %s (given: '%s', expected '%s')",
                           fn, why, token ? token : "(null)", MODEL_GUID);
        if (comp->instanceName) layer_free(comp, comp->instanceName);
        comp->instanceName = NULL;
        return Error;
    }
    comp->resourceDir = resource_path(comp, resourceLocation, isUri);
    if (isUri && resourceLocation && strncmp(resourceLocation, "file:", 5) == 0 && !comp->resourceDir) {
        log_error(comp, "%s: fmuResourceLocation '%s' has a malformed percent escape "
                        "(%% must be followed by two hex digits, not %%00)", fn, resourceLocation);
        layer_free(comp, comp->instanceName);
        comp->instanceName = NULL;
        return Error;
    }
    comp->v.state = S_INSTANTIATED;
    comp->stopTime = INFINITY;
    vars_set_start_values(&comp->v.d);
    comp->restart = comp->forget = true;
    core_dirty(comp);
    return OK;
}

void core_free_instance(ModelInstance *comp) {
    if (!comp) return;
    model_free(comp);
    if (comp->ddSeed) layer_free(comp, comp->ddSeed);
    if (comp->resourceDir) layer_free(comp, comp->resourceDir);
    if (comp->instanceName) layer_free(comp, comp->instanceName);
    layer_free(comp, comp);
}

Status core_set_debug_logging(ModelInstance *comp, const char *fn, bool on, size_t n,
                              const char *const categories[]) {
    if (n > 0 && !categories)
        return leave(comp, log_error(comp, "%s: argument 'categories' is NULL", fn));
    if (n == 0) {
        for (int i = 0; i < LOG_NCATEGORIES; i++) comp->logOn[i] = on;
        return OK;
    }
    for (size_t i = 0; i < n; i++) {
        int found = -1;
        for (int k = 0; k < LOG_NCATEGORIES; k++)
            if (categories[i] && strcmp(categories[i], LOG_CATEGORY[k]) == 0) found = k;
        if (found < 0)
            return leave(comp, log_error(comp, "%s: unknown log category '%s'", fn,
                                         categories[i] ? categories[i] : "(null)"));
        comp->logOn[found] = on;
    }
    return OK;
}

Status core_setup_experiment(ModelInstance *comp, const char *fn, bool toleranceDefined,
                             double tolerance, double startTime, bool stopTimeDefined, double stopTime) {
    if (!isfinite(startTime))
        return leave(comp, log_error(comp, "%s: startTime = %g is not finite", fn, startTime));
    if (stopTimeDefined && !(stopTime >= startTime))
        return leave(comp, log_error(comp, "%s: stopTime = %g is before startTime = %g",
                                     fn, stopTime, startTime));
    if (toleranceDefined && !(tolerance > 0))
        return leave(comp, log_error(comp, "%s: tolerance = %g must be > 0", fn, tolerance));
    comp->v.time = startTime;
    comp->stopTime = stopTimeDefined ? stopTime : INFINITY;
    comp->tolerance = toleranceDefined ? tolerance : 0.0;
    return OK;
}

static Status check_outputs(ModelInstance *comp, const char *fn);

Status core_exit_init(ModelInstance *comp, const char *fn) {
    Status status = model_init(comp);
    if (status > Warning) return leave(comp, status);
    model_outputs(comp);
    if (check_outputs(comp, fn)) return leave(comp, Error);
    comp->dirty = false;
    comp->restart = comp->forget = true;
    log_event(comp, "initialized at t = %g", comp->v.time);
    return status;
}

Status core_reset(ModelInstance *comp) {
    model_free(comp);
    memset(&comp->v, 0, sizeof comp->v);
    vars_set_start_values(&comp->v.d);
    comp->v.state = S_INSTANTIATED;
    comp->stopTime = INFINITY;
    comp->tolerance = 0.0;
    comp->restart = comp->forget = true;
    core_dirty(comp);
    return OK;
}

/* ---- getting and setting variables ----------------------------------------- */

#if FMI_VERSION == 3
static const char *TYPE_NAME[] = { "Float64", "Int32", "Boolean", "String", "Enumeration (Int64)" };
#else
static const char *TYPE_NAME[] = { "Real", "Integer", "Boolean", "String", "Enumeration" };
#endif

const VarInfo *core_lookup(ModelInstance *comp, const char *fn, VarType type, unsigned vr) {
    const VarInfo *v = vars_find(type, vr);
    if (!v) log_error(comp, "%s: no %s variable has value reference %u", fn, TYPE_NAME[type], vr);
    return v;
}

/* outputs are computed lazily: after a set, before the next get */
Status core_refresh(ModelInstance *comp) {
    if (!comp->dirty) return OK;
    if (comp->v.state == S_INIT_MODE) {
        Status status = model_init(comp);
        if (status > Warning) return status;
    }
    if (comp->v.state & (S_INIT_MODE | S_STEP_COMPLETE | S_EVENT_MODE | S_CONT_TIME_MODE))
        model_outputs(comp);
    comp->dirty = false;
    return OK;
}

void *core_field(ModelInstance *comp, const VarInfo *v) {
    return (char *)&comp->v.d + v->offset;
}

/* may this variable be set now? (FMI 2.0, 2.2.7: causality x variability x state) */
Status core_settable(ModelInstance *comp, const char *fn, const VarInfo *v) {
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
    if (ok) return OK;
    static const char *CAUS[] = { "parameter", "calculatedParameter", "input", "output",
                                  "local", "independent" };
    static const char *VARI[] = { "constant", "fixed", "tunable", "discrete", "continuous" };
    return log_error(comp, "%s: %s '%s' (%s %s) cannot be set in state '%s'", fn,
                     CAUS[v->causality], v->name, VARI[v->variability],
                     CAUS[v->causality], state_name(s));
}

Status core_check_range(ModelInstance *comp, const char *fn, const VarInfo *v, double x) {
    if (!isfinite(x))
        return log_error(comp, "%s: %s = %g is not a finite number", fn, v->name, x);
    if (x < v->min)
        return log_error(comp, "%s: %s = %.15g is below its minimum %.15g", fn, v->name, x, v->min);
    if (x > v->max)
        return log_error(comp, "%s: %s = %.15g is above its maximum %.15g", fn, v->name, x, v->max);
    return OK;
}

void core_dirty(ModelInstance *comp) {
    comp->dirty = true;
    comp->generation++;
}

/* after a value was stored: outputs and the integrator must follow it */
void core_changed(ModelInstance *comp) {
    core_dirty(comp);
    comp->restart = true;
}

Status core_set_string(ModelInstance *comp, const char *fn, const VarInfo *v, const char *value) {
    if (!value || strlen(value) >= ARTIBUS_STRLEN)
        return log_error(comp, "%s: %s: value is NULL or longer than %d bytes", fn, v->name,
                         ARTIBUS_STRLEN - 1);
    char *f = core_field(comp, v);
    if (strcmp(f, value) != 0) {
        strcpy(f, value);
        core_changed(comp);
    }
    return OK;
}

/* ---- FMU state: the plain-data block comp->v, nothing else ------------------
 * A state is validated as a whole before any of it is used (set, deserialize):
 * header, the checksum of a serialized body, the instance state, the time,
 * every variable (finite; parameters and inputs in their declared range) and
 * the model's own ModelState (model_state_valid). Otherwise Error with a
 * message, and the instance's values unchanged. */

typedef struct {
    uint32_t magic;         /* 'ABFS' */
    uint32_t size;          /* sizeof(FmuState) of the build that wrote it */
    char guid[64];
    uint64_t sum;           /* FNV-1a of guid and v, written by the serialization */
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

/* model_check_parameters on the parameters of state s, on a scratch instance
   whose first error message lands in why[512] */
static bool params_valid(ModelInstance *comp, const FmuState *s, char *why) {
    ModelInstance *scratch = layer_calloc(comp, 1, sizeof *scratch);
    if (!scratch) {
        snprintf(why, 512, "out of memory");
        return false;
    }
    scratch->v = s->v;
    scratch->instanceName = comp->instanceName;
    scratch->type = comp->type;
    scratch->stopTime = INFINITY;
    scratch->capture = why;
    why[0] = '\0';
    const Status st = model_check_parameters(scratch);
    layer_free(comp, scratch);
    if (st > Warning && !why[0]) snprintf(why, 512, "its parameters are not consistent");
    return st <= Warning;
}

static Status check_state(ModelInstance *comp, const char *fn, const FmuState *s) {
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
        case T_INTEGER:
        case T_ENUMERATION: {
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
       before any use of it (refresh, exit from initialization mode): not checked */
    char why[512] = "";
    if (st & (S_INSTANTIATED | S_INIT_MODE)) return OK;
    /* the parameters as model_init checks them (the same function), then the
       model's own states */
    if (!params_valid(comp, s, why))
        return log_error(comp, "%s: the state's parameters are not valid: %s", fn, why);
    if (!model_state_valid(&s->v.d, &s->v.s, s->v.time, why, sizeof why))
        return log_error(comp, "%s: the state is not valid: %s", fn, why[0] ? why : "(no reason given)");
    return OK;
}

Status core_get_state(ModelInstance *comp, const char *fn, void **state) {
    if (!state) return leave(comp, log_error(comp, "%s: argument 'FMUState' is NULL", fn));
    if (core_refresh(comp) > Warning) return leave(comp, Error);
    FmuState *s = *state ? (FmuState *)*state : layer_calloc(comp, 1, sizeof(FmuState));
    if (!s) return leave(comp, log_error(comp, "%s: out of memory", fn));
    if (*state && s->magic != FMUSTATE_MAGIC)
        return leave(comp, log_error(comp, "%s: the state to overwrite was not made by this FMU", fn));
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
    return OK;
}

static Status restore(ModelInstance *comp, const char *fn, const FmuState *s) {
    if (check_state(comp, fn, s)) return Error;
    /* the model rebuilds what it derives at initialisation (a fresh instance
       has none of it); if it cannot, the previous values come back */
    __typeof__(comp->v) *old = layer_calloc(comp, 1, sizeof comp->v);
    if (!old) return log_error(comp, "%s: out of memory", fn);
    *old = comp->v;
    comp->v = s->v;
    if (model_restored(comp) > Warning) {
        comp->v = *old;
        layer_free(comp, old);
        comp->restart = comp->forget = true;
        core_dirty(comp);
        return log_error(comp, "%s: the state could not be restored", fn);
    }
    layer_free(comp, old);
    comp->restart = comp->forget = true;
    core_dirty(comp);
    log_event(comp, "%s: state restored at t = %g", fn, comp->v.time);
    return OK;
}

Status core_set_state(ModelInstance *comp, const char *fn, const void *state) {
    return leave(comp, restore(comp, fn, (const FmuState *)state));
}

Status core_free_state(ModelInstance *comp, void **state) {
    if (state && *state) {
        layer_free(comp, *state);
        *state = NULL;
    }
    return OK;
}

Status core_state_size(ModelInstance *comp, const char *fn, const void *state, size_t *size) {
    if (!state || !size) return leave(comp, log_error(comp, "%s: NULL argument", fn));
    *size = sizeof(FmuState);
    return OK;
}

Status core_serialize(ModelInstance *comp, const char *fn, const void *state,
                      unsigned char bytes[], size_t size) {
    if (!state || !bytes || size < sizeof(FmuState))
        return leave(comp, log_error(comp, "%s: need %zu bytes, got %zu",
                                     fn, sizeof(FmuState), bytes ? size : 0));
    const FmuState *s = (const FmuState *)state;
    if (s->magic != FMUSTATE_MAGIC || s->size != sizeof(FmuState))
        return leave(comp, log_error(comp, "%s: the state was not made by this FMU", fn));
    memcpy(bytes, s, sizeof(FmuState));
    const uint64_t sum = state_sum(s);
    memcpy(bytes + offsetof(FmuState, sum), &sum, sizeof sum);
    return OK;
}

Status core_deserialize(ModelInstance *comp, const char *fn, const unsigned char bytes[],
                        size_t size, void **state) {
    if (!bytes || !state || size != sizeof(FmuState))
        return leave(comp, log_error(comp, "%s: expected %zu bytes, got %zu", fn, sizeof(FmuState), size));
    FmuState *tmp = layer_calloc(comp, 1, sizeof(FmuState));
    if (!tmp) return leave(comp, log_error(comp, "%s: out of memory", fn));
    memcpy(tmp, bytes, sizeof(FmuState));
    Status status = OK;
    if (tmp->magic != FMUSTATE_MAGIC || memchr(tmp->guid, '\0', sizeof tmp->guid) == NULL ||
        strcmp(tmp->guid, MODEL_GUID) != 0)
        status = log_error(comp, "%s: the bytes are not a state of this FMU", fn);
    else if (tmp->sum != state_sum(tmp))
        status = log_error(comp, "%s: the state's checksum does not match its body (the bytes "
                                 "were changed after they were serialized)", fn);
    else
        status = check_state(comp, fn, tmp);
    if (status != OK) {
        layer_free(comp, tmp);
        return leave(comp, Error);
    }
    tmp->sum = 0;
    if (*state) {
        FmuState *s = (FmuState *)*state;
        if (s->magic != FMUSTATE_MAGIC) {
            layer_free(comp, tmp);
            return leave(comp, log_error(comp, "%s: the state to overwrite was not made by this FMU", fn));
        }
        *s = *tmp;
        layer_free(comp, tmp);
    } else {
        *state = tmp;
    }
    return OK;
}

/* ---- stepping ---------------------------------------------------------------- */

/* every Real output finite, after model_outputs; else Error naming the
   first one (in the order of VARS) that is not. REAL_OUTPUTS is generated with
   the table: the loop runs over the outputs only, not over every variable. */
static Status check_outputs(ModelInstance *comp, const char *fn) {
    for (const VarInfo *const *out = REAL_OUTPUTS; *out; out++) {
        const VarInfo *v = *out;
        const double x = *(const double *)core_field(comp, v);
        if (!isfinite(x))
            return log_error(comp, "%s: output %s = %g at t = %.17g is not finite (a parameter or "
                                   "input out of its physical range?)", fn, v->name, x, comp->v.time);
    }
    return OK;
}

/* a step of a sampled model (MODEL_SAMPLE_PERIOD in its config.h) that would take
   more than MAX_SAMPLES_PER_STEP samples: Error naming the step and the limit (fmu.h) */
static Status too_many_samples(ModelInstance *comp, const char *fn, double h) {
#ifdef MODEL_SAMPLE_PERIOD
    const double Ts = MODEL_SAMPLE_PERIOD(&comp->v.d);
    if (!(h / Ts <= MAX_SAMPLES_PER_STEP))
        return log_error(comp, "%s: communicationStepSize = %.15g s is %.3g samples of Ts = %g s, more than "
                               "the %g one step may take: take steps of at most %.15g s", fn, h, h / Ts, Ts,
                         MAX_SAMPLES_PER_STEP, MAX_SAMPLES_PER_STEP * Ts);
#else
    (void)comp; (void)fn; (void)h;
#endif
    return OK;
}

Status core_do_step(ModelInstance *comp, const char *fn, double t, double h) {
    const double now = comp->v.time;
    if (!(fabs(t - now) <= 1e-9 * fmax(1.0, fabs(now))))
        return leave(comp, log_error(comp, "%s: expected currentCommunicationPoint = %.17g "
                                           "but was %.17g", fn, now, t));
    if (!(h > 0) || !isfinite(h))
        return leave(comp, log_error(comp, "%s: communicationStepSize = %g must be > 0", fn, h));
    if (now + h > comp->stopTime * (1 + 1e-12) + 1e-12)
        return leave(comp, log_error(comp, "%s: step to t = %.17g goes beyond stopTime = %.17g",
                                     fn, now + h, comp->stopTime));
    if (too_many_samples(comp, fn, h)) return leave(comp, Error);
    Status status = model_do_step(comp, now, h);
    comp->restart = comp->forget = false;
    if (status <= Warning) {
        model_outputs(comp);        /* never a non-finite output with OK */
        comp->dirty = false;
        if (check_outputs(comp, fn)) status = Error;
    } else {
        model_outputs(comp);        /* the state it stopped in, readable in the error state */
        comp->dirty = false;
    }
    if (status == Discard) comp->v.state = S_STEP_FAILED;
    return leave(comp, status);
}

/* ---- Model Exchange ----------------------------------------------------------
 * Only for models whose model description has <ModelExchange> (MODEL_NX from
 * gen_vars.py): the states, derivatives and event indicators come from the
 * model's hooks (fmu.h), the same right-hand side its own integrator uses in
 * co-simulation. */

#ifdef MODEL_NX

/* the caller's array length must be the model description's */
static Status me_size(ModelInstance *comp, const char *fn, const void *p, size_t n,
                      size_t expected, const char *what) {
    if (n != expected)
        return log_error(comp, "%s: %s = %zu, but the model has %zu", fn, what, n, expected);
    if (n > 0 && !p) return log_error(comp, "%s: the array argument is NULL", fn);
    return OK;
}

/* before the derivatives or the event indicators: the model initialised (in Initialization
 * Mode, model_init after a set), but not its outputs. Each model's model_derivatives and
 * model_event_indicators read the states, inputs and parameters only, never an output, and an
 * integrator asks for them after every fmi2SetContinuousStates: refreshing the outputs there
 * (a second evaluation of the equations of motion per right-hand side) is left to the next get
 * of a variable (core_refresh; comp->dirty stays set) */
static Status me_ready(ModelInstance *comp) {
    return comp->v.state == S_INIT_MODE ? core_refresh(comp) : OK;
}

Status core_event_update(ModelInstance *comp, const char *fn, bool *terminate, double *tNext) {
    if (core_refresh(comp) > Warning) return leave(comp, Error);
    *terminate = false;
    *tNext = INFINITY;
    const Status status = model_event_update(comp, terminate, tNext);
    if (status > Warning) return leave(comp, status);
    return status;
}

Status core_set_time(ModelInstance *comp, const char *fn, double time) {
    if (!isfinite(time))
        return leave(comp, log_error(comp, "%s: time = %g is not finite", fn, time));
    if (comp->v.time != time) {
        comp->v.time = time;
        core_dirty(comp);
    }
    return OK;
}

Status core_set_x(ModelInstance *comp, const char *fn, const double x[], size_t nx) {
    if (me_size(comp, fn, x, nx, MODEL_NX, "nx")) return leave(comp, Error);
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(x[i]))
            return leave(comp, log_error(comp, "%s: x[%zu] (%s) = %g is not a finite number",
                                         fn, i, X_NAME[i], x[i]));
    model_set_x(comp, x);
    core_dirty(comp);
    return OK;
}

Status core_derivatives(ModelInstance *comp, const char *fn, double dx[], size_t nx) {
    if (me_size(comp, fn, dx, nx, MODEL_NX, "nx")) return leave(comp, Error);
    if (me_ready(comp) > Warning) return leave(comp, Error);
    if (model_derivatives(comp, dx) > Warning) return leave(comp, Error);
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(dx[i]))
            return leave(comp, log_error(comp, "%s: the derivative of %s is %g at t = %.17g",
                                         fn, X_NAME[i], dx[i], comp->v.time));
    return OK;
}

Status core_event_indicators(ModelInstance *comp, const char *fn, double z[], size_t nz) {
    if (me_size(comp, fn, z, nz, MODEL_NZ, "the number of event indicators")) return leave(comp, Error);
    if (me_ready(comp) > Warning) return leave(comp, Error);
    if (nz > 0) model_event_indicators(comp, z);
    return OK;
}

Status core_get_x(ModelInstance *comp, const char *fn, double x[], size_t nx) {
    if (me_size(comp, fn, x, nx, MODEL_NX, "nx")) return leave(comp, Error);
    if (core_refresh(comp) > Warning) return leave(comp, Error);
    model_get_x(comp, x);
    return OK;
}

Status core_nominals(ModelInstance *comp, const char *fn, double x[], size_t nx) {
    if (me_size(comp, fn, x, nx, MODEL_NX, "nx")) return leave(comp, Error);
    for (size_t i = 0; i < nx; i++) x[i] = X_NOMINAL[i];
    return OK;
}

#endif

/* ---- directional derivatives (fmu.h: MODEL_DIRECTIONAL_DERIVATIVE) ------- */
#ifdef MODEL_DIRECTIONAL_DERIVATIVE

static double *field_of(ModelData *d, const VarInfo *v) {
    return (double *)((char *)d + v->offset);
}

/* a continuous state (Model Exchange: listed in <Derivatives>) */
static bool is_state(const VarInfo *v) {
#ifdef MODEL_NX
    for (int i = 0; i < MODEL_NX; i++)
        if (strcmp(v->name, X_NAME[i]) == 0) return true;
#endif
    (void)v;
    return false;
}

/* FMI 3.0, 2.2.11 (FMI 2.0.4, 2.1.9): the knowns are the continuous states and
   the inputs (Float64 / Real), the unknowns the outputs and state derivatives;
   the value references of both looked up, the VarInfo into ku[] */
static Status dd_variables(ModelInstance *comp, const char *fn, const unsigned unknowns[], size_t nU,
                           const unsigned knowns[], size_t nK, const VarInfo **ku) {
    comp->ddOutputs = false;
    for (size_t j = 0; j < nK; j++) {
        const VarInfo *v = core_lookup(comp, fn, T_REAL, knowns[j]);
        if (!v) return Error;
        if (!(v->causality == C_INPUT || is_state(v)))
            return log_error(comp, "%s: known %s (value reference %u) is neither a continuous state nor "
                                   "a Real input (FMI 3.0, 2.2.11: the knowns a dependency may name)",
                             fn, v->name, knowns[j]);
        ku[j] = v;
    }
    for (size_t i = 0; i < nU; i++) {
        const VarInfo *v = core_lookup(comp, fn, T_REAL, unknowns[i]);
        if (!v) return Error;
        if (!(v->causality == C_OUTPUT || (v->causality == C_LOCAL && v->variability == V_CONTINUOUS)))
            return log_error(comp, "%s: unknown %s (value reference %u) is neither an output nor a state "
                                   "derivative (FMI 3.0, 2.2.11)", fn, v->name, unknowns[i]);
        ku[nK + i] = v;
        if (v->causality == C_OUTPUT) comp->ddOutputs = true;
    }
    return OK;
}

/* one forward pass: tangent of every output and derivative along seed[] on ku[0..nK).
   The seed is the instance's ModelData of zeros (comp->ddSeed, made once: a Jacobian is
   asked for a column at a time) with the seeds written at the knowns and taken out after */
static Status dd_forward(ModelInstance *comp, const char *fn, const VarInfo **ku, size_t nK,
                         const double seed[], ModelData *tangent) {
    for (size_t j = 0; j < nK; j++)
        if (!isfinite(seed[j]))
            return log_error(comp, "%s: the seed of %s is %g", fn, ku[j]->name, seed[j]);
    if (!comp->ddSeed && !(comp->ddSeed = layer_calloc(comp, 1, sizeof(ModelData))))
        return log_error(comp, "%s: out of memory", fn);
    ModelData *sd = comp->ddSeed;
    for (size_t j = 0; j < nK; j++)
        *field_of(sd, ku[j]) += seed[j];      /* a known named twice: the seeds add (J is linear) */
    *tangent = *sd;
    const Status status = model_directional_derivative(comp, sd, tangent);
    for (size_t j = 0; j < nK; j++) *field_of(sd, ku[j]) = 0.0;
    return status;
}

/* ku: the knowns' and unknowns' VarInfo, in `small` (DD_SMALL entries) when they fit
   there, else allocated (freed by dd_release) */
#define DD_SMALL 64
static Status dd_prepare(ModelInstance *comp, const char *fn, const unsigned unknowns[], size_t nU,
                         const unsigned knowns[], size_t nK, const double seed[], const double sensitivity[],
                         const VarInfo **small, const VarInfo ***ku) {
    if ((nK > 0 && (!knowns || !seed)) || (nU > 0 && (!unknowns || !sensitivity)))
        return log_error(comp, "%s: an argument array is NULL", fn);
    if (me_ready(comp) > Warning) return Error;    /* the model initialised; its outputs not needed */
    *ku = nK + nU <= DD_SMALL ? small : layer_calloc(comp, nK + nU + 1, sizeof **ku);
    if (!*ku) return log_error(comp, "%s: out of memory", fn);
    return dd_variables(comp, fn, unknowns, nU, knowns, nK, *ku);
}

static void dd_release(ModelInstance *comp, const VarInfo **small, const VarInfo **ku) {
    if (ku && ku != small) layer_free(comp, (void *)ku);
}

Status core_directional_derivative(ModelInstance *comp, const char *fn, const unsigned unknowns[],
                                   size_t nUnknowns, const unsigned knowns[], size_t nKnowns,
                                   const double seed[], double sensitivity[]) {
    const VarInfo *small[DD_SMALL], **ku = NULL;
    ModelData t;
    Status status = dd_prepare(comp, fn, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity, small, &ku);
    if (status <= Warning) status = dd_forward(comp, fn, ku, nKnowns, seed, &t);
    for (size_t i = 0; status <= Warning && i < nUnknowns; i++)
        sensitivity[i] = *field_of(&t, ku[nKnowns + i]);
    dd_release(comp, small, ku);
    return status > Warning ? leave(comp, status) : status;
}

/* J^T seed, one forward pass per known: cheap here (a few tens of knowns) */
Status core_adjoint_derivative(ModelInstance *comp, const char *fn, const unsigned unknowns[],
                               size_t nUnknowns, const unsigned knowns[], size_t nKnowns,
                               const double seed[], double sensitivity[]) {
    const VarInfo *small[DD_SMALL], **ku = NULL;
    ModelData t;
    /* seed has nUnknowns entries, sensitivity nKnowns (FMI 3.0, 2.2.11) */
    Status status = dd_prepare(comp, fn, unknowns, nUnknowns, knowns, nKnowns, sensitivity, seed, small, &ku);
    for (size_t i = 0; status <= Warning && i < nUnknowns; i++)
        if (!isfinite(seed[i])) status = log_error(comp, "%s: the seed of %s is %g", fn, ku[nKnowns + i]->name, seed[i]);
    for (size_t j = 0; status <= Warning && j < nKnowns; j++) {
        const double one = 1.0;
        status = dd_forward(comp, fn, ku + j, 1, &one, &t);
        double s = 0.0;
        for (size_t i = 0; status <= Warning && i < nUnknowns; i++) s += seed[i] * *field_of(&t, ku[nKnowns + i]);
        sensitivity[j] = s;
    }
    dd_release(comp, small, ku);
    return status > Warning ? leave(comp, status) : status;
}

#endif
