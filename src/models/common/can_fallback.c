/* Stale detection and fallback of a steering-CAN receiver: see can_fallback.h.
 * Plain C99 and libm only. */
#include <math.h>
#include "can_fallback.h"

#define CF_AGE_CAP 1000000

static const char *const PARAM_NAME[] = {
    "", "nMsg", "nOut", "nStale", "nRecover", "tHold", "rampRate", "Ts"
};

const char *cf_param_name(int code) {
    return code < 0 && -code < (int)(sizeof PARAM_NAME / sizeof *PARAM_NAME) ? PARAM_NAME[-code] : "?";
}

int cf_setup(CfFallback *f, const CfParams *p, const double *counters, const double *out) {
    if (!(p->nMsg >= 1 && p->nMsg <= CF_MAX_MSG)) return -1;
    if (!(p->nOut >= 1 && p->nOut <= CF_MAX_OUT)) return -2;
    if (!(p->nStale >= 0 && p->nStale <= 1000)) return -3;
    if (!(p->nRecover >= 1 && p->nRecover <= 100000)) return -4;
    if (!(isfinite(p->tHold) && p->tHold >= 0 && p->tHold <= 1e4)) return -5;
    if (!(isfinite(p->rampRate) && p->rampRate > 0)) return -6;
    if (!(isfinite(p->Ts) && p->Ts > 0)) return -7;
    if (!(p->tHold / p->Ts <= 1e9)) return -5;      /* nHold below is an int */
    f->p = *p;
    f->nHold = (int)ceil(p->tHold / p->Ts - 1e-9);
    if (f->nHold < 1) f->nHold = 1;                 /* the detection cycle holds at least */
    for (int i = 0; i < CF_MAX_MSG; i++) {
        f->last[i] = i < p->nMsg && isfinite(counters[i]) ? counters[i] : 0.0;
        f->age[i] = 0;
    }
    for (int j = 0; j < CF_MAX_OUT; j++)
        f->out[j] = j < p->nOut && isfinite(out[j]) ? out[j] : 0.0;
    f->mode = CF_NORMAL;
    f->cycles = f->fresh = f->rejoin = 0;
    return 0;
}

/* x moved toward target by at most step */
static double toward(double x, double target, double step) {
    return x < target - step ? x + step : x > target + step ? x - step : target;
}

/* one cycle of the ramp to the safe angle 0 */
static void ramp(CfFallback *f, double step) {
    int zero = 1;
    for (int j = 0; j < f->p.nOut; j++) {
        f->out[j] = toward(f->out[j], 0.0, step);
        zero &= f->out[j] == 0.0;
    }
    f->mode = zero ? CF_SAFE : CF_RAMP;
}

unsigned cf_sample(CfFallback *f, const double *counters, unsigned used, int bad, const double *want) {
    const CfParams *p = &f->p;
    unsigned stale = 0;
    int allNew = 1;
    for (int i = 0; i < p->nMsg; i++) {
        if (counters[i] != f->last[i] && isfinite(counters[i])) {   /* a new frame */
            f->last[i] = counters[i];
            f->age[i] = 0;
        } else if (f->age[i] < CF_AGE_CAP) {
            f->age[i]++;
        }
        if (p->nStale > 0 && f->age[i] >= p->nStale) stale |= 1u << i;
        if ((used >> i & 1u) && p->nStale > 0 && f->age[i] != 0) allNew = 0;
    }
    const int trouble = (stale & used) != 0 || bad;
    const double step = p->rampRate * p->Ts;
    int wantOk = 1;
    for (int j = 0; j < p->nOut; j++) wantOk &= isfinite(want[j]) != 0;

    if (f->mode != CF_NORMAL) {
        f->fresh = (!trouble && allNew) ? (f->fresh < CF_AGE_CAP ? f->fresh + 1 : f->fresh) : 0;
        if (f->fresh >= p->nRecover && wantOk) {    /* recovered: slew back from here */
            f->mode = CF_NORMAL;
            f->rejoin = 1;
        }
    } else if (trouble || !wantOk) {                /* enter the fallback: hold this cycle */
        f->mode = CF_HOLD;
        f->cycles = 0;
        f->fresh = 0;
        f->rejoin = 0;
    }

    switch (f->mode) {
    case CF_NORMAL: {
        int done = 1;
        for (int j = 0; j < p->nOut; j++) {
            f->out[j] = f->rejoin ? toward(f->out[j], want[j], step) : want[j];
            done &= f->out[j] == want[j];
        }
        if (done) f->rejoin = 0;
        break;
    }
    case CF_HOLD:
        if (++f->cycles <= f->nHold) break;         /* outputs as they were */
        ramp(f, step);                              /* the first ramp cycle */
        break;
    case CF_RAMP:
    case CF_SAFE:
        ramp(f, step);
        break;
    default:
        break;
    }
    return stale;
}

int cf_state_valid(const CfFallback *f) {
    const CfParams *p = &f->p;
    if (!(p->nMsg >= 1 && p->nMsg <= CF_MAX_MSG && p->nOut >= 1 && p->nOut <= CF_MAX_OUT &&
          p->nStale >= 0 && p->nStale <= 1000 && p->nRecover >= 1 && p->nRecover <= 100000 &&
          isfinite(p->tHold) && isfinite(p->rampRate) && p->rampRate > 0 && isfinite(p->Ts) && p->Ts > 0))
        return 0;
    if (f->nHold < 1 || f->nHold > 1000000000 || f->mode < CF_NORMAL || f->mode > CF_SAFE ||
        f->cycles < 0 || f->cycles > f->nHold + 1 || f->fresh < 0 || f->fresh > CF_AGE_CAP ||
        (f->rejoin != 0 && f->rejoin != 1))
        return 0;
    for (int i = 0; i < CF_MAX_MSG; i++)
        if (!isfinite(f->last[i]) || f->age[i] < 0 || f->age[i] > CF_AGE_CAP) return 0;
    for (int j = 0; j < CF_MAX_OUT; j++)
        if (!isfinite(f->out[j])) return 0;
    return 1;
}
