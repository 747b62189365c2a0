/* fmu_check: a minimal FMI 2.0 importer that loads one FMU's shared object
 * with dlopen and drives it through normal runs and every kind of misuse the
 * standard forbids. Built once per FMU against that FMU's generated variable
 * table (to know its inputs and parameters); run by ctest, under AddressSanitizer
 * and UBSan in the sanitizer build. Any crash, sanitizer finding or unexpected
 * status fails the test.
 *
 * usage: fmu_check <FMU directory (unzipped)>
 *        fmu_check <FMU directory> --run STOP H TOL [NAME=VALUE...]   (no checks: a
 *        co-simulation from the start values and the parameters given, STOP/H steps
 *        of H with tolerance TOL, then every real output printed as "name value";
 *        tests/test_win64.py compares the win64 DLL's, run under Wine, with the
 *        linux64 binary's, tests/test_aarch64.py the aarch64 one's under qemu-user)
 */
#ifdef _WIN32
/* the win64 build (scripts/build_win64.sh), run under Wine: the DLL through LoadLibrary */
#include <windows.h>
#define dlopen(path, flags) ((void *)LoadLibraryA(path))
#define dlsym(so, name) ((void *)GetProcAddress((HMODULE)(so), name))
#define dlclose(so) FreeLibrary((HMODULE)(so))
#define dlerror() "LoadLibrary failed"
#define FMU_BINARY "%s/binaries/win64/%s.dll"
#else
#include <dlfcn.h>
#if defined(__aarch64__)
/* the aarch64 build (scripts/build_aarch64.sh), run under qemu-user (or on an ARM machine) */
#define FMU_BINARY "%s/binaries/aarch64-linux/%s.so"
#else
#define FMU_BINARY "%s/binaries/linux64/%s.so"
#endif
#endif
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2FunctionTypes.h"
#include "vartable.h"

static int failures = 0, checks = 0, errors_logged = 0;
static char last_message[2048];

#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)category;
    va_list ap;
    va_start(ap, message);
    vsnprintf(last_message, sizeof last_message, message, ap);
    va_end(ap);
    if (status >= fmi2Error) errors_logged++;
}

static fmi2CallbackFunctions cb = { logger, calloc, free, NULL, NULL };

#define API(name) static name##TYPE *name
API(fmi2Instantiate); API(fmi2FreeInstance); API(fmi2SetupExperiment);
API(fmi2EnterInitializationMode); API(fmi2ExitInitializationMode); API(fmi2Terminate);
API(fmi2Reset); API(fmi2GetReal); API(fmi2SetReal); API(fmi2SetInteger); API(fmi2DoStep);
API(fmi2GetFMUstate); API(fmi2SetFMUstate); API(fmi2FreeFMUstate);
API(fmi2SerializedFMUstateSize); API(fmi2SerializeFMUstate); API(fmi2DeSerializeFMUstate);
API(fmi2SetDebugLogging); API(fmi2GetRealStatus); API(fmi2SetBoolean); API(fmi2SetString);

static fmi2ValueReference real_vrs[MODEL_NVARS];
static size_t n_real = 0;

static fmi2Component make(const char *uri) {
    return fmi2Instantiate("check", fmi2CoSimulation, MODEL_GUID, uri, &cb, fmi2False, fmi2False);
}

static fmi2Status start(fmi2Component c) {
    fmi2Status s = fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
    if (s == fmi2OK) s = fmi2EnterInitializationMode(c);
    if (s == fmi2OK) s = fmi2ExitInitializationMode(c);
    return s;
}

static int run(fmi2Component c, double t0, int steps, double h, double *out) {
    for (int k = 0; k < steps; k++)
        if (fmi2DoStep(c, t0 + k * h, h, fmi2True) != fmi2OK) return 0;
    return fmi2GetReal(c, real_vrs, n_real, out) == fmi2OK;
}

int main(int argc, char **argv) {
    if (argc != 2 && !(argc >= 6 && strcmp(argv[2], "--run") == 0)) {
        fprintf(stderr, "usage: fmu_check FMUDIR [--run STOP H TOL [NAME=VALUE...]]\n");
        return 2;
    }
    char path[4096], uri[4200];
    snprintf(path, sizeof path, FMU_BINARY, argv[1], MODEL_IDENTIFIER);
    /* file:///dir/resources, or file:///C:/dir/resources for a Windows path */
    snprintf(uri, sizeof uri, "file://%s%s/resources", argv[1][0] == '/' ? "" : "/", argv[1]);
    void *so = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "cannot load %s: %s\n", path, dlerror()); return 1; }
#define LOAD(name) name = (name##TYPE *)dlsym(so, #name); if (!name) { printf("missing %s\n", #name); return 1; }
    LOAD(fmi2Instantiate); LOAD(fmi2FreeInstance); LOAD(fmi2SetupExperiment);
    LOAD(fmi2EnterInitializationMode); LOAD(fmi2ExitInitializationMode); LOAD(fmi2Terminate);
    LOAD(fmi2Reset); LOAD(fmi2GetReal); LOAD(fmi2SetReal); LOAD(fmi2SetInteger); LOAD(fmi2DoStep);
    LOAD(fmi2GetFMUstate); LOAD(fmi2SetFMUstate); LOAD(fmi2FreeFMUstate);
    LOAD(fmi2SerializedFMUstateSize); LOAD(fmi2SerializeFMUstate); LOAD(fmi2DeSerializeFMUstate);
    LOAD(fmi2SetDebugLogging); LOAD(fmi2GetRealStatus); LOAD(fmi2SetBoolean); LOAD(fmi2SetString);

    for (size_t i = 0; i < MODEL_NVARS; i++)
        if (VARS[i].type == T_REAL) real_vrs[n_real++] = VARS[i].vr;

    static double a[MODEL_NVARS], b[MODEL_NVARS];
    if (argc >= 6) {
        const double stop = atof(argv[3]), hh = atof(argv[4]), tol = atof(argv[5]);
        const int n = (int)(stop / hh + 0.5);
        fmi2Component r = make(uri);
        for (int i = 6; r && i < argc; i++) {
            const char *eq = strchr(argv[i], '=');
            const VarInfo *v = NULL;
            for (size_t k = 0; eq && k < MODEL_NVARS; k++)
                if (strlen(VARS[k].name) == (size_t)(eq - argv[i]) &&
                    strncmp(VARS[k].name, argv[i], (size_t)(eq - argv[i])) == 0) v = &VARS[k];
            if (!v) { printf("unknown variable: %s\n", argv[i]); return 1; }
            const double d = atof(eq + 1);
            const fmi2Integer in = atoi(eq + 1);
            const fmi2Boolean b = in != 0;
            const fmi2String str = eq + 1;
            fmi2Status st = v->type == T_REAL ? fmi2SetReal(r, &v->vr, 1, &d)
                          : v->type == T_INTEGER ? fmi2SetInteger(r, &v->vr, 1, &in)
                          : v->type == T_BOOLEAN ? fmi2SetBoolean(r, &v->vr, 1, &b)
                          : fmi2SetString(r, &v->vr, 1, &str);
            if (st != fmi2OK) { printf("cannot set %s: %s\n", argv[i], last_message); return 1; }
        }
        if (!r || fmi2SetupExperiment(r, fmi2True, tol, 0, fmi2False, 0) != fmi2OK ||
            fmi2EnterInitializationMode(r) != fmi2OK || fmi2ExitInitializationMode(r) != fmi2OK ||
            !run(r, 0, n, hh, a)) {
            printf("run failed: %s\n", last_message);
            return 1;
        }
        for (size_t i = 0, k = 0; i < MODEL_NVARS; i++)
            if (VARS[i].type == T_REAL && (k++, VARS[i].causality == C_OUTPUT))
                printf("%s %.17g\n", VARS[i].name, a[k - 1]);
        fmi2FreeInstance(r);
        dlclose(so);
        return 0;
    }
    const double h = 0.05;
    const int steps = 100;

    /* 1. wrong GUID, wrong type: NULL, no crash */
    CHECK(fmi2Instantiate("x", fmi2CoSimulation, "{wrong}", uri, &cb, 0, 0) == NULL, "wrong GUID accepted");
#ifndef MODEL_NX
    CHECK(fmi2Instantiate("x", fmi2ModelExchange, MODEL_GUID, uri, &cb, 0, 0) == NULL, "ME accepted");
#endif

    /* 2. normal run, debug logging on */
    fmi2Component c = make(uri);
    CHECK(c != NULL, "instantiate failed");
    CHECK(fmi2SetDebugLogging(c, fmi2True, 0, NULL) == fmi2OK, "SetDebugLogging");
    CHECK(start(c) == fmi2OK, "initialisation failed: %s", last_message);
    CHECK(run(c, 0, steps, h, a), "normal run failed: %s", last_message);
    for (size_t i = 0; i < n_real; i++) CHECK(isfinite(a[i]), "output vr %u not finite", real_vrs[i]);
    CHECK(fmi2Terminate(c) == fmi2OK, "terminate");
    CHECK(fmi2DoStep(c, steps * h, h, fmi2True) == fmi2Error, "doStep after terminate accepted");

    /* 3. reset, then the same run again gives the same result */
    CHECK(fmi2Reset(c) == fmi2OK, "reset from error state");
    CHECK(start(c) == fmi2OK, "initialisation after reset");
    CHECK(run(c, 0, steps, h, b), "run after reset");
    CHECK(memcmp(a, b, n_real * sizeof(double)) == 0, "run after reset differs");

    /* 4. FMU state round trip, in memory and serialized */
    fmi2Reset(c);
    start(c);
    run(c, 0, steps / 2, h, a);
    fmi2FMUstate st = NULL;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "GetFMUstate");
    run(c, steps / 2 * h, steps / 2, h, a);
    CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "SetFMUstate");
    run(c, steps / 2 * h, steps / 2, h, b);
    CHECK(memcmp(a, b, n_real * sizeof(double)) == 0, "restored run differs");
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, st, &size) == fmi2OK && size > 0, "state size");
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK, "serialize");
    fmi2FMUstate st2 = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &st2) == fmi2OK, "deserialize");
    CHECK(fmi2SetFMUstate(c, st2) == fmi2OK, "SetFMUstate deserialized");
    run(c, steps / 2 * h, steps / 2, h, b);
    CHECK(memcmp(a, b, n_real * sizeof(double)) == 0, "deserialized run differs");
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size - 1, &st2) == fmi2Error, "short state accepted");
    free(bytes);
    fmi2Reset(c);
    fmi2FreeFMUstate(c, &st);
    fmi2FreeFMUstate(c, &st2);

    /* 5. call order: each misuse is fmi2Error with a message, then reset recovers */
    fmi2Reset(c);
    errors_logged = 0;
    CHECK(fmi2DoStep(c, 0, h, fmi2True) == fmi2Error, "doStep before initialisation accepted");
    CHECK(errors_logged == 1 && strstr(last_message, "fmi2DoStep"), "no message naming fmi2DoStep: %s", last_message);
    fmi2Reset(c);
    CHECK(fmi2GetReal(c, real_vrs, 1, a) == fmi2Error, "getReal in instantiated accepted");
    fmi2Reset(c);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "exitInit before enterInit accepted");
    fmi2Reset(c);
    start(c);
    CHECK(fmi2DoStep(c, 1.0, h, fmi2True) == fmi2Error, "wrong communication point accepted");
    fmi2Reset(c);
    start(c);
    CHECK(fmi2DoStep(c, 0.0, -h, fmi2True) == fmi2Error, "negative step accepted");
    fmi2Reset(c);
    CHECK(fmi2GetReal(c, NULL, 3, a) == fmi2Error, "NULL vr array accepted");
    fmi2Reset(c);
    start(c);
    fmi2ValueReference bad = 999999;
    double one = 1.0;
    CHECK(fmi2SetReal(c, &bad, 1, &one) == fmi2Error, "unknown value reference accepted");

    /* 6. NaN and Inf on every real input and parameter: fmi2Error naming it */
    for (size_t i = 0; i < MODEL_NVARS; i++) {
        const VarInfo *v = &VARS[i];
        if (v->type != T_REAL || (v->causality != C_INPUT && v->causality != C_PARAMETER)) continue;
        const double bads[2] = { NAN, INFINITY };
        for (int k = 0; k < 2; k++) {
            fmi2Reset(c);
            start(c);
            if (v->causality == C_PARAMETER) { fmi2Reset(c); fmi2SetupExperiment(c, 0, 0, 0, 0, 0); fmi2EnterInitializationMode(c); }
            last_message[0] = 0;
            CHECK(fmi2SetReal(c, &v->vr, 1, &bads[k]) == fmi2Error, "%s = %g accepted", v->name, bads[k]);
            CHECK(strstr(last_message, v->name) != NULL, "message does not name %s: %s", v->name, last_message);
            /* the instance is now in the error state: stepping is refused */
            CHECK(fmi2DoStep(c, 0, h, fmi2True) == fmi2Error, "doStep in error state accepted");
            double t;
            CHECK(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t) == fmi2OK, "GetRealStatus in error state");
        }
    }

    /* 6b. huge steps (issue 41): one doStep(0, h) from the start values returns, in
       bounded CPU time, OK or fmi2Error with a message naming fmi2DoStep or the
       integrator; then reset, and the run of part 2 gives the same result again */
    {
        static const double HUGE_STEPS[] = { 1e3, 1e6, 1e9, 1e12, 1e15, 1e50, 1e100, 1e200, 1e300, DBL_MAX };
        static double ref[MODEL_NVARS];
        fmi2Reset(c);
        CHECK(start(c) == fmi2OK && run(c, 0, steps, h, ref), "reference run: %s", last_message);
        for (size_t i = 0; i < sizeof HUGE_STEPS / sizeof HUGE_STEPS[0]; i++) {
            const double hh = HUGE_STEPS[i];
            fmi2Reset(c);
            CHECK(start(c) == fmi2OK, "initialisation before doStep(0, %g): %s", hh, last_message);
            errors_logged = 0;
            last_message[0] = 0;
            const clock_t c0 = clock();
            const fmi2Status st = fmi2DoStep(c, 0.0, hh, fmi2True);
            const double seconds = (double)(clock() - c0) / CLOCKS_PER_SEC;
            /* 10 s: the sanitizers slow the FMU down tenfold; the 1 s of the release build is
               tests/test_dostep_bounded.py's */
            CHECK(seconds < 10.0, "doStep(0, %g) took %.2f s", hh, seconds);
            CHECK(st == fmi2OK || st == fmi2Warning || st == fmi2Error, "doStep(0, %g) returned %d", hh, st);
            CHECK(st != fmi2Error || (errors_logged > 0 && (strstr(last_message, "fmi2DoStep") ||
                                                            strstr(last_message, "CVODE") ||
                                                            strstr(last_message, "ARKODE"))),
                  "doStep(0, %g) failed without a message naming it: %s", hh, last_message);
            if (st == fmi2Error)
                CHECK(fmi2DoStep(c, 0.0, h, fmi2True) == fmi2Error, "doStep after a refused step accepted");
            fmi2Reset(c);
            CHECK(start(c) == fmi2OK && run(c, 0, steps, h, b), "run after doStep(0, %g): %s", hh, last_message);
            CHECK(memcmp(ref, b, n_real * sizeof(double)) == 0, "run after doStep(0, %g) differs", hh);
        }
    }

    /* 7. free in the error state, and one never initialised */
    fmi2FreeInstance(c);
    fmi2Component d = make(uri);
    fmi2FreeInstance(d);
    fmi2FreeInstance(NULL);

#ifdef MODEL_NX
    /* 8. Model Exchange (a plant): initialise, explicit Euler steps through the ME
       calls, the states and derivatives finite, misuse refused */
    {
#define ME_LOAD(name) name##TYPE *name = (name##TYPE *)dlsym(so, #name); \
        if (!name) { printf("missing %s\n", #name); return 1; }
        ME_LOAD(fmi2EnterEventMode); ME_LOAD(fmi2NewDiscreteStates); ME_LOAD(fmi2EnterContinuousTimeMode);
        ME_LOAD(fmi2CompletedIntegratorStep); ME_LOAD(fmi2SetTime); ME_LOAD(fmi2SetContinuousStates);
        ME_LOAD(fmi2GetDerivatives); ME_LOAD(fmi2GetEventIndicators); ME_LOAD(fmi2GetContinuousStates);
        ME_LOAD(fmi2GetNominalsOfContinuousStates);
        fmi2Component m = fmi2Instantiate("me", fmi2ModelExchange, MODEL_GUID, uri, &cb, 0, 0);
        CHECK(m != NULL, "ME instantiate failed: %s", last_message);
        double x[MODEL_NX], dx[MODEL_NX], nom[MODEL_NX], z[MODEL_NZ + 1];
        CHECK(fmi2GetNominalsOfContinuousStates(m, nom, MODEL_NX) == fmi2OK, "ME nominals");
        CHECK(fmi2EnterEventMode(m) == fmi2Error, "ME EnterEventMode before initialisation accepted");
        fmi2FreeInstance(m);
        m = fmi2Instantiate("me", fmi2ModelExchange, MODEL_GUID, uri, &cb, 0, 0);
        CHECK(start(m) == fmi2OK, "ME initialisation: %s", last_message);
        fmi2EventInfo info;
        CHECK(fmi2NewDiscreteStates(m, &info) == fmi2OK && !info.terminateSimulation, "ME event update: %s",
              last_message);
        CHECK(fmi2DoStep(m, 0, h, fmi2True) == fmi2Error, "doStep on an ME instance accepted");
        fmi2Reset(m);
        CHECK(start(m) == fmi2OK, "ME initialisation after reset: %s", last_message);
        fmi2NewDiscreteStates(m, &info);
        CHECK(fmi2EnterContinuousTimeMode(m) == fmi2OK, "ME EnterContinuousTimeMode");
        CHECK(fmi2GetContinuousStates(m, x, MODEL_NX + 1) == fmi2Error, "ME wrong nx accepted");
        fmi2Reset(m);
        start(m);
        fmi2NewDiscreteStates(m, &info);
        fmi2EnterContinuousTimeMode(m);
        const double dt = 1e-3;
        int ok = 1;
        for (int k = 1; k <= 100 && ok; k++) {
            fmi2Boolean enter, term;
            ok = fmi2GetContinuousStates(m, x, MODEL_NX) == fmi2OK
              && fmi2GetDerivatives(m, dx, MODEL_NX) == fmi2OK
              && fmi2GetEventIndicators(m, z, MODEL_NZ) == fmi2OK;
            for (int i = 0; i < MODEL_NX; i++) { ok = ok && isfinite(dx[i]); x[i] += dt * dx[i]; }
            ok = ok && fmi2SetTime(m, k * dt) == fmi2OK
                    && fmi2SetContinuousStates(m, x, MODEL_NX) == fmi2OK
                    && fmi2CompletedIntegratorStep(m, fmi2True, &enter, &term) == fmi2OK;
        }
        CHECK(ok, "ME Euler steps: %s", last_message);
        CHECK(fmi2GetReal(m, real_vrs, n_real, a) == fmi2OK, "ME outputs");
        for (size_t i = 0; i < n_real; i++) CHECK(isfinite(a[i]), "ME output vr %u not finite", real_vrs[i]);
        /* FMU state in continuous-time mode: save, go on, restore, go on again: the same */
        fmi2FMUstate ms = NULL;
        double xa[MODEL_NX], xb[MODEL_NX];
        CHECK(fmi2GetFMUstate(m, &ms) == fmi2OK, "ME GetFMUstate: %s", last_message);
        for (int pass = 0; pass < 2; pass++) {
            double *xe = pass ? xb : xa;
            ok = fmi2GetContinuousStates(m, xe, MODEL_NX) == fmi2OK;
            for (int k = 1; k <= 10 && ok; k++) {
                ok = fmi2GetDerivatives(m, dx, MODEL_NX) == fmi2OK;
                for (int i = 0; i < MODEL_NX; i++) xe[i] += dt * dx[i];
                ok = ok && fmi2SetTime(m, 0.1 + k * dt) == fmi2OK
                        && fmi2SetContinuousStates(m, xe, MODEL_NX) == fmi2OK;
            }
            CHECK(ok, "ME steps after the state was %s: %s", pass ? "restored" : "saved", last_message);
            if (!pass) CHECK(fmi2SetFMUstate(m, ms) == fmi2OK, "ME SetFMUstate: %s", last_message);
        }
        CHECK(memcmp(xa, xb, sizeof xa) == 0, "ME run after SetFMUstate differs");
        fmi2FreeFMUstate(m, &ms);
        x[0] = NAN;
        last_message[0] = 0;
        CHECK(fmi2SetContinuousStates(m, x, MODEL_NX) == fmi2Error, "ME NaN state accepted");
        CHECK(strstr(last_message, X_NAME[0]) != NULL, "message does not name %s: %s", X_NAME[0], last_message);
        fmi2Reset(m);
        start(m);
        CHECK(fmi2SetContinuousStates(m, x, MODEL_NX) == fmi2Error, "ME SetContinuousStates in event mode accepted");
        fmi2FreeInstance(m);
        /* a co-simulation instance refuses the ME calls */
        fmi2Component cs = make(uri);
        start(cs);
        CHECK(fmi2GetDerivatives(cs, dx, MODEL_NX) == fmi2Error, "GetDerivatives on a CS instance accepted");
        fmi2FreeInstance(cs);
    }
#endif

    dlclose(so);
    printf("%d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
