/* The runner's stepping core: see core.h. Each block below names the line of
 * Simulation.run (src/artibus/runner.py) it does the same as. Compiled with
 * -ffp-contract=off: factor * out + offset must stay a multiply and an add,
 * as in Python, never a fused multiply-add. */
#define _POSIX_C_SOURCE 200809L
#include "core.h"

#include <string.h>
#include <time.h>

#if defined(__GNUC__)
#define AC_EXPORT __attribute__((visibility("default")))
#else
#define AC_EXPORT
#endif

static double now(void) {                     /* time.perf_counter(): CLOCK_MONOTONIC */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void record(ac_sim *sim, long row, double t) {   /* _Recorder.take */
    double *r = sim->table + (size_t)row * (size_t)sim->n_cols;
    r[0] = t;
    for (int c = 1; c < sim->n_cols; c++)
        r[c] = *sim->rec[c - 1];
}

static void propagate(ac_unit *u) {           /* Simulation._propagate(u, t) */
    for (int s = 0; s < u->n_sources; s++) {
        const ac_source *q = &u->sources[s];
        *q->dst = q->factor * *q->src + q->offset;
    }
}

static fmi2Status write_inputs(ac_unit *u) {  /* _RawCalls.write */
    if (!u->n_in)
        return fmi2OK;
    size_t bytes = u->n_in * sizeof(double);
    if (u->has_written && memcmp(u->in, u->written, bytes) == 0)
        return fmi2OK;                       /* the FMU holds them already */
    const double w = now();
    fmi2Status st = u->setReal(u->component, u->in_vrs, u->n_in, u->in);
    u->wall += now() - w;                    /* the FMU's time, as its doStep's */
    if (st > fmi2Warning)
        return st;
    memcpy(u->written, u->in, bytes);
    u->has_written = 1;
    return st;
}

static int fail(ac_sim *sim, int unit, int function, fmi2Status st, long k) {
    sim->fail_unit = unit;
    sim->fail_function = function;
    sim->fail_status = (int)st;
    sim->fail_k = k;
    return function;
}

AC_EXPORT int artibus_core_abi(void) { return ARTIBUS_CORE_ABI; }

AC_EXPORT void artibus_core_record_start(ac_sim *sim) { record(sim, 0, sim->start); }

AC_EXPORT int artibus_core_run(ac_sim *sim, long k0, long k1) {
    const double h = sim->h;
    sim->fail_unit = -1;
    sim->fail_function = AC_OK;
    sim->fail_status = 0;
    sim->fail_k = -1;
    for (long k = k0; k < k1; k++) {
        const double t = sim->start + (double)k * h;         /* t = start + k * h */
        const int p = (int)(k % sim->period);
        for (int i = sim->op_start[p]; i < sim->op_start[p + 1]; i++) {
            const int j = sim->op_unit[i];
            ac_unit *u = &sim->units[j];
            switch (sim->op_kind[i]) {
            case AC_PROPAGATE:
                propagate(u);
                break;
            case AC_WRITE: {
                fmi2Status st = write_inputs(u);
                if (st > fmi2Warning)
                    return fail(sim, j, AC_SET_REAL, st, k);
                break;
            }
            default: {                                       /* Simulation._step(u, t + h - u.step) */
                const double w = now();
                fmi2Status st = u->doStep(u->component, t + h - u->step, u->step, fmi2True);
                if (st > fmi2Warning)
                    return fail(sim, j, AC_DO_STEP, st, k);
                if (u->n_out) {
                    st = u->getReal(u->component, u->out_vrs, u->n_out, u->out);
                    if (st > fmi2Warning)
                        return fail(sim, j, AC_GET_REAL, st, k);
                }
                u->wall += now() - w;
                break;
            }
            }
        }
        record(sim, k + 1, sim->start + (double)(k + 1) * h);   /* t = start + (k + 1) * h */
    }
    return AC_OK;
}
