/* Times CVODE's two ways to a Jacobian d(der x)/dx of one FMI 2.0 Model Exchange FMU, in C (no
 * Python between the calls): benchmarks/bus_dynamics_jacobian.py compiles and runs it.
 *   difference quotients: per state, fmi2SetContinuousStates and fmi2GetDerivatives (what
 *     CVODE's dense difference-quotient Jacobian asks of the FMU: a right-hand side a column);
 *   directional derivatives: fmi2SetContinuousStates once, then per state one
 *     fmi2GetDirectionalDerivative with the unit seed (artibus' ME facade, me.c: jac).
 * Each Jacobian at a state moved a little from the last (a new point, as in an integration).
 *
 * usage: jacobian_timer BINARY GUID RESOURCE_URI N X_VRS DX_VRS
 *   X_VRS, DX_VRS: the states' and the derivatives' value references, comma-separated
 * prints the nanoseconds of one Jacobian each way: the fastest block of BLOCK Jacobians / BLOCK
 * (a block in which the process was descheduled does not count). */
#define BLOCK 200
#define MAX_X 64
#include <stdlib.h>

#include "fmi_timer.h"

static size_t parse_vrs(const char *text, fmi2ValueReference *vrs) {
    size_t n = 0;
    for (char *end; *text && n < MAX_X; text = *end ? end + 1 : end) vrs[n++] = (fmi2ValueReference)strtoul(text, &end, 10);
    return n;
}

int main(int argc, char **argv) {
    if (argc != 7) { fprintf(stderr, "usage: jacobian_timer BINARY GUID RESOURCES N X_VRS DX_VRS\n"); return 2; }
    const long n = atol(argv[4]);
    fmi2ValueReference xv[MAX_X], dv[MAX_X];
    const size_t nx = parse_vrs(argv[5], xv);
    if (n < BLOCK || n % BLOCK || nx == 0 || parse_vrs(argv[6], dv) != nx) {
        fprintf(stderr, "N a multiple of %d, as many states as derivatives\n", BLOCK);
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    SYM(fmi2InstantiateTYPE *, fmi2Instantiate)
    SYM(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
    SYM(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
    SYM(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
    SYM(fmi2NewDiscreteStatesTYPE *, fmi2NewDiscreteStates)
    SYM(fmi2EnterContinuousTimeModeTYPE *, fmi2EnterContinuousTimeMode)
    SYM(fmi2GetContinuousStatesTYPE *, fmi2GetContinuousStates)
    SYM(fmi2SetContinuousStatesTYPE *, fmi2SetContinuousStates)
    SYM(fmi2GetDerivativesTYPE *, fmi2GetDerivatives)
    SYM(fmi2GetDirectionalDerivativeTYPE *, fmi2GetDirectionalDerivative)
    SYM(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
    const fmi2CallbackFunctions cb = { log_fmi2, calloc, free, NULL, NULL };
    fmi2Component c = fmi2Instantiate("t", fmi2ModelExchange, argv[2], argv[3], &cb, fmi2False, fmi2False);
    fmi2EventInfo info;
    if (!c || fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0) > fmi2Warning ||
        fmi2EnterInitializationMode(c) > fmi2Warning || fmi2ExitInitializationMode(c) > fmi2Warning ||
        fmi2NewDiscreteStates(c, &info) > fmi2Warning || fmi2EnterContinuousTimeMode(c) > fmi2Warning)
        return 1;
    double x[MAX_X], dx[MAX_X], col[MAX_X], sum = 0.0, best[2] = { 1e300, 1e300 };
    const double one = 1.0;
    if (fmi2GetContinuousStates(c, x, nx) > fmi2Warning) return 1;
    for (int way = 0; way < 2; way++)
        for (long k = 0; k < n; k += BLOCK) {
            const double b0 = now_ns();
            for (long j = k; j < k + BLOCK; j++) {
                x[nx - 1] += 1e-9;                          /* a new point */
                if (fmi2SetContinuousStates(c, x, nx) > fmi2Warning) return 1;
                for (size_t i = 0; i < nx; i++) {
                    if (way == 0) {                         /* difference quotient: a right-hand side */
                        x[i] += 1e-7;
                        if (fmi2SetContinuousStates(c, x, nx) > fmi2Warning || fmi2GetDerivatives(c, dx, nx) > fmi2Warning)
                            return 1;
                        x[i] -= 1e-7;
                        sum += dx[0];
                    } else {
                        if (fmi2GetDirectionalDerivative(c, dv, nx, &xv[i], 1, &one, col) > fmi2Warning) return 1;
                        sum += col[0];
                    }
                }
            }
            const double b1 = now_ns();
            if (b1 - b0 < best[way]) best[way] = b1 - b0;
        }
    fmi2FreeInstance(c);
    printf("%.1f %.1f %zu\n", best[0] / BLOCK, best[1] / BLOCK, nx);
    return sum == 12345.678 ? 3 : 0;                        /* keeps the sums alive */
}
