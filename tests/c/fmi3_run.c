/* A minimal FMI 3.0 Co-Simulation importer for tests/test_fmi3.py: loads an FMU's
 * binary (dlopen, or LoadLibrary in its win64 build under Wine), instantiates it,
 * initialises it at its start values, takes N steps of size H and prints each Float64
 * given as VR=NAME as "NAME %.17g". Any status above fmi3Warning: the message on stderr,
 * exit 1.
 *
 * usage: fmi3_run BINARY TOKEN RESOURCE_PATH H N VR=NAME... */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynload.h"            /* LOAD, SYM: dlopen or LoadLibrary */

#include "fmi3Functions.h"

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    if (status > fmi3Warning) fprintf(stderr, "[%s] %s\n", category, message);
}

#define GET(T, name) T *name = (T *)SYM(lib, #name); \
    if (!name) { fprintf(stderr, "no %s\n", #name); return 1; }

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: fmi3_run BINARY TOKEN RESOURCE_PATH H N VR=NAME...\n");
        return 2;
    }
    void *lib = LOAD(argv[1]);
    if (!lib) { fprintf(stderr, "cannot load %s\n", argv[1]); return 1; }
    GET(fmi3InstantiateCoSimulationTYPE, fmi3InstantiateCoSimulation)
    GET(fmi3EnterInitializationModeTYPE, fmi3EnterInitializationMode)
    GET(fmi3ExitInitializationModeTYPE, fmi3ExitInitializationMode)
    GET(fmi3DoStepTYPE, fmi3DoStep)
    GET(fmi3GetFloat64TYPE, fmi3GetFloat64)
    GET(fmi3TerminateTYPE, fmi3Terminate)
    GET(fmi3FreeInstanceTYPE, fmi3FreeInstance)
    const double h = atof(argv[4]);
    const long n = atol(argv[5]);
    fmi3Instance c = fmi3InstantiateCoSimulation("run", argv[2], argv[3], fmi3False, fmi3False, fmi3False,
                                                 fmi3False, NULL, 0, NULL, logger, NULL);
    if (!c) { fprintf(stderr, "instantiation failed\n"); return 1; }
    if (fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) > fmi3Warning ||
        fmi3ExitInitializationMode(c) > fmi3Warning)
        return 1;
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    for (long k = 0; k < n; k++)
        if (fmi3DoStep(c, k * h, h, fmi3True, &ev, &term, &early, &last) > fmi3Warning) return 1;
    for (int i = 6; i < argc; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq) return 2;
        const fmi3ValueReference vr = (fmi3ValueReference)strtoul(argv[i], NULL, 10);
        fmi3Float64 x;
        if (fmi3GetFloat64(c, &vr, 1, &x, 1) > fmi3Warning) return 1;
        printf("%s %.17g\n", eq + 1, x);
    }
    fmi3Terminate(c);
    fmi3FreeInstance(c);
    return 0;
}
