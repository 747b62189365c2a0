/* Times N calls of fmi2DoStep or fmi3DoStep of one FMU binary, in C (no Python between
 * the calls): benchmarks/fmi3_dostep.py compiles and runs it.
 *
 * usage: dostep_timer 2|3 BINARY TOKEN RESOURCE_URI_OR_PATH STEP N
 * prints the nanoseconds of the N steps (CLOCK_MONOTONIC), after initialisation at the
 * start values, as N / BLOCK times the fastest block of BLOCK consecutive steps: a block
 * in which the process was descheduled or interrupted does not count (on a busy machine
 * the plain total of N steps varies by 15-35 %, the fastest block by a few %). */
#define BLOCK 1000
#include <stdlib.h>

#include "fmi3Functions.h"
#include "fmi_timer.h"

static void log_fmi3(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    (void)e; (void)c;
    if (s > fmi3Warning) fprintf(stderr, "%s\n", m);
}

int main(int argc, char **argv) {
    if (argc != 7) { fprintf(stderr, "usage: dostep_timer 2|3 BINARY TOKEN RESOURCES STEP N\n"); return 2; }
    const int v = atoi(argv[1]);
    const double h = atof(argv[5]);
    const long n = atol(argv[6]);
    void *lib = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    double best = 1e300;                    /* the fastest block's nanoseconds */
    if (n < BLOCK || n % BLOCK) { fprintf(stderr, "N must be a multiple of %d\n", BLOCK); return 2; }
    if (v == 2) {
        SYM(fmi2InstantiateTYPE *, fmi2Instantiate)
        SYM(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        SYM(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        SYM(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        SYM(fmi2DoStepTYPE *, fmi2DoStep)
        SYM(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        const fmi2CallbackFunctions cb = { log_fmi2, calloc, free, NULL, NULL };
        fmi2Component c = fmi2Instantiate("t", fmi2CoSimulation, argv[3], argv[4], &cb, fmi2False, fmi2False);
        if (!c || fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0) > fmi2Warning ||
            fmi2EnterInitializationMode(c) > fmi2Warning || fmi2ExitInitializationMode(c) > fmi2Warning)
            return 1;
        for (long k = 0; k < n; k += BLOCK) {
            const double b0 = now_ns();
            for (long j = k; j < k + BLOCK; j++)
                if (fmi2DoStep(c, j * h, h, fmi2True) > fmi2Warning) return 1;
            const double b1 = now_ns();
            if (b1 - b0 < best) best = b1 - b0;
        }
        fmi2FreeInstance(c);
    } else {
        SYM(fmi3InstantiateCoSimulationTYPE *, fmi3InstantiateCoSimulation)
        SYM(fmi3EnterInitializationModeTYPE *, fmi3EnterInitializationMode)
        SYM(fmi3ExitInitializationModeTYPE *, fmi3ExitInitializationMode)
        SYM(fmi3DoStepTYPE *, fmi3DoStep)
        SYM(fmi3FreeInstanceTYPE *, fmi3FreeInstance)
        fmi3Instance c = fmi3InstantiateCoSimulation("t", argv[3], argv[4], fmi3False, fmi3False, fmi3False,
                                                     fmi3False, NULL, 0, NULL, log_fmi3, NULL);
        if (!c || fmi3EnterInitializationMode(c, fmi3False, 0, 0, fmi3False, 0) > fmi3Warning ||
            fmi3ExitInitializationMode(c) > fmi3Warning)
            return 1;
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        for (long k = 0; k < n; k += BLOCK) {
            const double b0 = now_ns();
            for (long j = k; j < k + BLOCK; j++)
                if (fmi3DoStep(c, j * h, h, fmi3True, &ev, &term, &early, &last) > fmi3Warning) return 1;
            const double b1 = now_ns();
            if (b1 - b0 < best) best = b1 - b0;
        }
        fmi3FreeInstance(c);
    }
    printf("%.0f\n", best * (double)(n / BLOCK));
    return 0;
}
