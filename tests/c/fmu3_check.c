/* fmu3_check: a minimal FMI 3.0 Co-Simulation importer that drives one FMU's
 * binary through huge steps and the Event Mode calls in legal and illegal
 * orders (issue 41). Built once, run by ctest for every FMI 3.0 FMU (the
 * models' FMI 3.0 builds, the FMI-LS-BUS nodes, CanBus), under AddressSanitizer
 * and UBSan in the sanitizer build. Any crash, sanitizer finding or unexpected
 * status fails the test.
 *
 *   1. huge steps (FMI 3.0, 4.2.1, fmi3DoStep): one doStep(0, h) from the start
 *      values for h from 1e3 s to DBL_MAX returns (its CPU time bounded), OK or
 *      fmi3Error with a message; fmi3Reset recovers and the same run follows;
 *   2. Event Mode (FMI 3.0, 4.2.1 and 5.2: Co-Simulation with eventModeUsed): the
 *      legal sequence (initialization -> Event Mode -> fmi3UpdateDiscreteStates
 *      (twice) -> fmi3EnterStepMode -> fmi3DoStep -> fmi3EnterEventMode -> ...);
 *      each call the state machine does not allow in a state is fmi3Error with a
 *      message;
 *   3. a random call-order fuzzer: seeded random sequences of these calls (steps
 *      from 1e-3 s to DBL_MAX among them; a legal call three times in four, any
 *      call else), each status checked against the standard's state machine kept
 *      here (not the FMU's own table).
 *
 * usage: fmu3_check BINARY MODEL_DESCRIPTION.xml RESOURCE_DIR   (the description FMI 2.0 or 3.0)
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dynload.h"            /* LOAD, SYM: dlopen or LoadLibrary */

#include "fmi3FunctionTypes.h"

static int failures = 0, checks = 0, errors_logged = 0;
static char last_message[2048];

#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env; (void)category;
    snprintf(last_message, sizeof last_message, "%s", message ? message : "");
    if (status >= fmi3Error) errors_logged++;
}

#define API(name) static name##TYPE *name
API(fmi3InstantiateCoSimulation); API(fmi3FreeInstance); API(fmi3EnterInitializationMode);
API(fmi3ExitInitializationMode); API(fmi3EnterEventMode); API(fmi3UpdateDiscreteStates);
API(fmi3EnterStepMode); API(fmi3DoStep); API(fmi3Terminate); API(fmi3Reset);

static char token[512];
static const char *resources;

/* the steps of part 1 and among the fuzzer's: huge ones, and a few between */
static const double HUGE_STEPS[] = { 1e3, 1e6, 1e9, 1e12, 1e15, 1e50, 1e100, 1e200, 1e300, DBL_MAX };
#define N_HUGE (sizeof HUGE_STEPS / sizeof HUGE_STEPS[0])
/* CPU seconds one call may take here (the sanitizers slow the FMU down tenfold;
   the 1 s of the release build is tests/test_dostep_bounded.py's) */
#define CALL_BOUND 10.0

/* the instantiation token from the model description (instantiationToken="...", or an
   FMI 2.0 description's guid="...") */
static int read_token(const char *xml) {
    FILE *f = fopen(xml, "rb");
    if (!f) return 0;
    static char text[1 << 20];
    const size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    /* an FMI 2.0 description (the models' one source, modelDescription/<Name>.xml):
       its guid is the FMI 3.0 build's token */
    const char *key = strstr(text, "instantiationToken=\"") ? "instantiationToken=\"" : "guid=\"";
    const char *p = strstr(text, key);
    if (!p) return 0;
    p += strlen(key);
    const char *e = strchr(p, '"');
    if (!e || (size_t)(e - p) >= sizeof token) return 0;
    memcpy(token, p, (size_t)(e - p));
    token[e - p] = '\0';
    return 1;
}

static fmi3Instance make(int eventModeUsed) {
    return fmi3InstantiateCoSimulation("check3", token, resources, fmi3False, fmi3False,
                                       eventModeUsed ? fmi3True : fmi3False, fmi3False, NULL, 0, NULL,
                                       logger, NULL);
}

static fmi3Status start(fmi3Instance c) {
    fmi3Status s = fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    return s == fmi3OK ? fmi3ExitInitializationMode(c) : s;
}

static fmi3Status step(fmi3Instance c, double t, double h, double *seconds) {
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    const clock_t c0 = clock();
    const fmi3Status s = fmi3DoStep(c, t, h, fmi3True, &ev, &term, &early, &last);
    if (seconds) *seconds = (double)(clock() - c0) / CLOCKS_PER_SEC;
    return s;
}

static fmi3Status update(fmi3Instance c) {
    fmi3Boolean need, term, nomChanged, valChanged, nextDefined;
    fmi3Float64 next;
    return fmi3UpdateDiscreteStates(c, &need, &term, &nomChanged, &valChanged, &nextDefined, &next);
}

/* a call refused: fmi3Error with a message */
#define REFUSED(call, what) do { errors_logged = 0; \
    CHECK((call) == fmi3Error && errors_logged > 0, "%s accepted (or no message)", what); } while (0)

/* 1. one doStep of each huge step from the start values, in Step Mode and after an event */
static void huge_steps(int eventModeUsed) {
    fmi3Instance c = make(eventModeUsed);
    CHECK(c != NULL, "instantiate (eventModeUsed %d): %s", eventModeUsed, last_message);
    if (!c) return;
    for (size_t i = 0; i < N_HUGE; i++) {
        const double h = HUGE_STEPS[i];
        CHECK(fmi3Reset(c) == fmi3OK && start(c) == fmi3OK, "initialisation: %s", last_message);
        if (eventModeUsed) CHECK(update(c) <= fmi3Warning && fmi3EnterStepMode(c) == fmi3OK,
                                 "event mode at the start: %s", last_message);
        errors_logged = 0;
        double seconds;
        const fmi3Status s = step(c, 0.0, h, &seconds);
        CHECK(s == fmi3OK || s == fmi3Warning || s == fmi3Error, "doStep(0, %g) returned %d", h, s);
        CHECK(s != fmi3Error || errors_logged > 0, "doStep(0, %g) failed without a message", h);
        CHECK(seconds < CALL_BOUND, "doStep(0, %g) took %.2f s", h, seconds);
        /* whatever it answered: reset, and a run of ordinary steps goes on */
        CHECK(fmi3Reset(c) == fmi3OK && start(c) == fmi3OK, "initialisation after doStep(0, %g): %s", h,
              last_message);
        if (eventModeUsed) CHECK(fmi3EnterStepMode(c) == fmi3OK, "EnterStepMode: %s", last_message);
        int ok = 1;
        for (int k = 0; k < 20 && ok; k++) ok = step(c, k * 0.01, 0.01, NULL) <= fmi3Warning;
        CHECK(ok, "steps after doStep(0, %g): %s", h, last_message);
    }
    fmi3FreeInstance(c);
}

/* 2. Event Mode in the standard's order, then each call out of it */
static void event_mode(void) {
    fmi3Instance c = make(1);
    CHECK(c != NULL, "instantiate with Event Mode: %s", last_message);
    if (!c) return;
    REFUSED(fmi3EnterEventMode(c), "EnterEventMode when instantiated");
    fmi3Reset(c);
    REFUSED(fmi3EnterStepMode(c), "EnterStepMode when instantiated");
    fmi3Reset(c);
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "EnterInit");
    REFUSED(update(c), "UpdateDiscreteStates in Initialization Mode");
    fmi3Reset(c);
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    REFUSED(fmi3EnterStepMode(c), "EnterStepMode in Initialization Mode");
    fmi3Reset(c);
    /* legal: ExitInit goes to Event Mode (eventModeUsed), updates, steps, events */
    CHECK(start(c) == fmi3OK, "initialisation: %s", last_message);
    double t = 0.0;
    int ok = 1;
    for (int k = 0; k < 10 && ok; k++) {
        ok = update(c) <= fmi3Warning && update(c) <= fmi3Warning && fmi3EnterStepMode(c) == fmi3OK
          && step(c, t, 0.01, NULL) <= fmi3Warning && fmi3EnterEventMode(c) == fmi3OK;
        t += 0.01;
    }
    CHECK(ok, "the legal Event Mode sequence failed at t = %g: %s", t, last_message);
    REFUSED(step(c, t, 0.01, NULL), "DoStep in Event Mode");
    fmi3Reset(c);
    start(c);
    REFUSED(fmi3EnterEventMode(c), "EnterEventMode in Event Mode");
    fmi3Reset(c);
    start(c);
    fmi3EnterStepMode(c);
    REFUSED(fmi3EnterStepMode(c), "EnterStepMode in Step Mode");
    fmi3Reset(c);
    start(c);
    fmi3EnterStepMode(c);
    REFUSED(update(c), "UpdateDiscreteStates in Step Mode");
    fmi3Reset(c);
    start(c);
    CHECK(fmi3Terminate(c) == fmi3OK, "Terminate in Event Mode: %s", last_message);
    REFUSED(fmi3EnterStepMode(c), "EnterStepMode when terminated");
    fmi3Reset(c);
    start(c);
    fmi3Terminate(c);
    REFUSED(update(c), "UpdateDiscreteStates when terminated");
    fmi3FreeInstance(c);
    /* without Event Mode, fmi3EnterEventMode is an error */
    c = make(0);
    start(c);
    REFUSED(fmi3EnterEventMode(c), "EnterEventMode with eventModeUsed = false");
    fmi3FreeInstance(c);
}

/* 3. the fuzzer: the standard's Co-Simulation state machine (FMI 3.0, 4.2.1) */
typedef enum { INSTANTIATED, INIT_MODE, EVENT_MODE, STEP_MODE, TERMINATED, ERROR } RefState;
typedef enum { C_ENTER_INIT, C_EXIT_INIT, C_ENTER_EVENT, C_UPDATE, C_ENTER_STEP, C_STEP, C_HUGE_STEP,
               C_TERMINATE, C_RESET, N_CALLS } Call;
static const char *CALL_NAME[] = { "EnterInitializationMode", "ExitInitializationMode", "EnterEventMode",
                                   "UpdateDiscreteStates", "EnterStepMode", "DoStep", "DoStep (huge)",
                                   "Terminate", "Reset" };

/* 1 legal, 0 illegal, -1 either (what the standard leaves open here) */
static int legal(RefState s, Call call, int eventModeUsed) {
    switch (call) {
    case C_ENTER_INIT:  return s == INSTANTIATED;
    case C_EXIT_INIT:   return s == INIT_MODE;
    case C_ENTER_EVENT: return s == STEP_MODE && eventModeUsed;
    case C_UPDATE:      return s == EVENT_MODE;
    case C_ENTER_STEP:  return s == EVENT_MODE;
    case C_STEP:
    case C_HUGE_STEP:   return s == STEP_MODE;
    case C_TERMINATE:   return s == EVENT_MODE || s == STEP_MODE ? 1 : s == INIT_MODE ? -1 : 0;
    default:            return 1;   /* Reset: in every state */
    }
}

static unsigned long long rng_state;
static long fuzz_refused, fuzz_huge_taken;     /* for the summary: calls answered fmi3Error, huge steps taken */
static unsigned rnd(unsigned n) {
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (unsigned)(rng_state >> 33) % n;
}

/* the next call: one the state machine allows in state s three times in four (so that the
   walk reaches Step and Event Mode and stays there a while), else any */
static Call pick(RefState s, int eventModeUsed) {
    if (rnd(4) == 0) return (Call)rnd(N_CALLS);
    Call allowed[N_CALLS];
    unsigned n = 0;
    for (int k = 0; k < N_CALLS; k++)
        if (legal(s, (Call)k, eventModeUsed) == 1 && !(k == C_RESET && s != ERROR && s != TERMINATED))
            allowed[n++] = (Call)k;
    return n ? allowed[rnd(n)] : C_RESET;
}

/* one random sequence of calls on a fresh instance; returns the calls made */
static int fuzz_run(int eventModeUsed, int ncalls) {
    fmi3Instance c = make(eventModeUsed);
    CHECK(c != NULL, "instantiate: %s", last_message);
    if (!c) return 0;
    RefState s = INSTANTIATED;
    double t = 0.0;
    for (int i = 0; i < ncalls; i++) {
        const Call call = pick(s, eventModeUsed);
        const int want = legal(s, call, eventModeUsed);
        const double h = call == C_HUGE_STEP ? HUGE_STEPS[rnd(N_HUGE)] : 1e-3 * (1 + rnd(50));
        errors_logged = 0;
        double seconds = 0.0;
        fmi3Status st;
        switch (call) {
        case C_ENTER_INIT:  st = fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0); break;
        case C_EXIT_INIT:   st = fmi3ExitInitializationMode(c); break;
        case C_ENTER_EVENT: st = fmi3EnterEventMode(c); break;
        case C_UPDATE:      st = update(c); break;
        case C_ENTER_STEP:  st = fmi3EnterStepMode(c); break;
        case C_TERMINATE:   st = fmi3Terminate(c); break;
        case C_RESET:       st = fmi3Reset(c); break;
        default:            st = step(c, t, h, &seconds); break;
        }
        CHECK(st <= fmi3Error, "call %d, %s: status %d (fatal?)", i, CALL_NAME[call], st);
        CHECK(st != fmi3Error || errors_logged > 0, "call %d, %s: fmi3Error without a message", i, CALL_NAME[call]);
        CHECK(seconds < CALL_BOUND, "call %d, DoStep(%g, %g) took %.2f s", i, t, h, seconds);
        if (want == 0)
            CHECK(st == fmi3Error, "call %d: %s accepted in state %d", i, CALL_NAME[call], s);
        /* legal and ordinary: must succeed (a huge step may be refused, as may a step from
           a time where a plant's integrator cannot go on) */
        if (want == 1 && call != C_HUGE_STEP && !(call == C_STEP && t > 1e6))
            CHECK(st <= fmi3Warning, "call %d: %s refused in state %d: %s", i, CALL_NAME[call], s, last_message);
        if (call == C_HUGE_STEP && st <= fmi3Warning) fuzz_huge_taken++;
        if (st == fmi3Error) {
            fuzz_refused++;
            s = ERROR;
            continue;
        }
        switch (call) {
        case C_ENTER_INIT:  s = INIT_MODE; break;
        case C_EXIT_INIT:   s = eventModeUsed ? EVENT_MODE : STEP_MODE; break;
        case C_ENTER_EVENT: s = EVENT_MODE; break;
        case C_ENTER_STEP:  s = STEP_MODE; break;
        case C_TERMINATE:   s = TERMINATED; break;
        case C_RESET:       s = INSTANTIATED; t = 0.0; break;
        case C_STEP:
        case C_HUGE_STEP:   t += h; break;
        default:            break;
        }
    }
    fmi3FreeInstance(c);
    return ncalls;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: fmu3_check BINARY MODEL_DESCRIPTION.xml RESOURCE_DIR\n");
        return 2;
    }
    if (!read_token(argv[2])) { fprintf(stderr, "no instantiationToken in %s\n", argv[2]); return 1; }
    resources = argv[3];
    void *lib = LOAD(argv[1]);
    if (!lib) { fprintf(stderr, "cannot load %s\n", argv[1]); return 1; }
#define GET(name) name = (name##TYPE *)SYM(lib, #name); if (!name) { printf("missing %s\n", #name); return 1; }
    GET(fmi3InstantiateCoSimulation); GET(fmi3FreeInstance); GET(fmi3EnterInitializationMode);
    GET(fmi3ExitInitializationMode); GET(fmi3EnterEventMode); GET(fmi3UpdateDiscreteStates);
    GET(fmi3EnterStepMode); GET(fmi3DoStep); GET(fmi3Terminate); GET(fmi3Reset);

    huge_steps(0);
    huge_steps(1);
    event_mode();
    long calls = 0;
    rng_state = 41;
    for (int run = 0; run < 40; run++) calls += fuzz_run(run % 2, 200);

    printf("%d passed, %d failed (%zu huge steps twice; %ld fuzzed calls, %ld of them answered fmi3Error, "
           "%ld huge steps taken)\n", checks - failures, failures, N_HUGE, calls, fuzz_refused, fuzz_huge_taken);
    return failures ? 1 : 0;
}
