/* What the C timers of the benchmarks share (dostep_timer.c, jacobian_timer.c): the loggers
 * that print an FMU's errors, the monotonic clock, and the lookup of an FMI function in the
 * loaded binary (a missing one ends the timer with status 1). */
#ifndef ARTIBUS_FMI_TIMER_H
#define ARTIBUS_FMI_TIMER_H

#include <dlfcn.h>
#include <stdio.h>
#include <time.h>

#include "fmi2Functions.h"

static void log_fmi2(fmi2ComponentEnvironment e, fmi2String i, fmi2Status s, fmi2String c, fmi2String m, ...) {
    (void)e; (void)i; (void)c;
    if (s > fmi2Warning) fprintf(stderr, "%s\n", m);
}

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e9 + ts.tv_nsec;
}

#define SYM(T, name) T name = (T)dlsym(lib, #name); if (!name) { fprintf(stderr, "no %s\n", #name); return 1; }

#endif
