/* The runner's stepping core (issue 13): the per-step loop of
 * artibus.runner.Simulation.run in C, called with ctypes.
 *
 * Python sets the bench up, initialises it, builds the plan below and calls
 * artibus_core_run() for a range of base steps; the core calls the FMUs'
 * fmi2SetReal/fmi2DoStep/fmi2GetReal through their function pointers, on the
 * same value buffers the Python loop uses, with the same floating-point
 * operations in the same order, so the results are bit for bit those of the
 * Python loop. Plain C11, no Python headers, no heap use: every array is
 * Python's (see src/artibus/runner.py, _Core).
 */
#ifndef ARTIBUS_RUNNER_CORE_H
#define ARTIBUS_RUNNER_CORE_H

#include <stddef.h>

#include "fmi2FunctionTypes.h"

#define ARTIBUS_CORE_ABI 1          /* artibus_core_abi(): Python checks it */

/* one connection into a unit's input: *dst = factor * *src + offset */
typedef struct {
    double *dst;                    /* the input's place in the unit's input buffer */
    const double *src;              /* the output's place in the source unit's output buffer */
    double factor, offset;
} ac_source;

typedef struct {
    fmi2Component component;
    fmi2DoStepTYPE *doStep;
    fmi2GetRealTYPE *getReal;
    fmi2SetRealTYPE *setReal;
    double step;                    /* its communication step (s) */
    size_t n_out, n_in;
    const fmi2ValueReference *out_vrs;
    double *out;                    /* n_out: read by fmi2GetReal after each of its steps */
    const fmi2ValueReference *in_vrs;
    double *in;                     /* n_in: its inputs */
    double *written;                /* n_in: the input values last set */
    int has_written;                /* 0: never set, the next write sets them */
    int n_sources;
    const ac_source *sources;
    double wall;                    /* seconds inside fmi2DoStep, fmi2GetReal, fmi2SetReal, accumulated */
} ac_unit;

/* what the plan does with a unit */
enum { AC_PROPAGATE = 0, AC_WRITE = 1, AC_STEP = 2 };

/* which functions failed (ac_sim.fail_function) */
enum { AC_OK = 0, AC_DO_STEP = 1, AC_GET_REAL = 2, AC_SET_REAL = 3 };

typedef struct {
    int n_units;
    ac_unit *units;
    /* the plan: base step k does ops op_start[k % period] .. op_start[k % period + 1] - 1,
     * each (op_kind[i], op_unit[i]) */
    int period;
    const int *op_start;            /* period + 1 */
    const int *op_kind;
    const int *op_unit;
    double start, h;                /* t = start + k * h */
    /* recording: row r of table (n_cols doubles, row-major) is time then *rec[c] */
    int n_cols;                     /* 1 + recorded columns */
    const double *const *rec;       /* n_cols - 1 */
    double *table;                  /* (steps + 1) * n_cols */
    /* on failure */
    int fail_unit, fail_function, fail_status;
    long fail_k;                    /* the base step that failed */
} ac_sim;

int artibus_core_abi(void);

/* Record row 0 at t = start (after the initialisation). */
void artibus_core_record_start(ac_sim *sim);

/* Base steps k0 .. k1 - 1, each recorded into row k + 1. Returns 0, or the
 * failing function (AC_DO_STEP, ...) with fail_unit/fail_status/fail_k set:
 * rows 0 .. fail_k are then filled, as the Python loop keeps them. */
int artibus_core_run(ac_sim *sim, long k0, long k1);

#endif
