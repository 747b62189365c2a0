/* Steering actuators of one module: see actuator.h. Plain C99 and libm only. */
#include <math.h>
#include "actuator.h"

/* codes: -1 Tact, -2 rateMax; cf_setup's -1..-7 as -11..-17 */
const char *act_param_name(int code) {
    if (code == -1) return "Tact";
    if (code == -2) return "rateMax";
    if (code <= -11 && code >= -19) return cf_param_name(code + 10);
    return "?";
}

int act_setup(SteeringAct *s, const ActParams *p, const double cmd[2], double alive) {
    if (!(isfinite(p->Tact) && p->Tact >= 0)) return -1;
    if (!(isfinite(p->rateMax) && p->rateMax >= 0)) return -2;
    const CfParams cp = { .nMsg = 1, .nOut = 2, .nStale = p->nStale, .nRecover = p->nRecover,
                          .tHold = p->tHold, .rampRate = p->rampRate, .Ts = p->Ts };
    const int bad = cf_setup(&s->cf, &cp, &alive, cmd);
    if (bad) return bad - 10;
    s->p = *p;
    s->a = p->Tact > 0 ? -expm1(-p->Ts / p->Tact) : 1.0;
    for (int j = 0; j < 2; j++) {
        s->delta[j] = s->cf.out[j];
        s->cmdRx[j] = s->cf.out[j];
    }
    s->stale = 0;
    return 0;
}

void act_sample(SteeringAct *s, const double cmd[2], double alive) {
    const int fresh = alive != s->cf.last[0];
    s->stale = cf_sample(&s->cf, &alive, 1u, 0, cmd) & 1u;
    const double dmax = s->p.rateMax * s->p.Ts;
    for (int j = 0; j < 2; j++) {
        if (fresh) s->cmdRx[j] = cmd[j];
        const double y = s->p.Tact > 0 ? s->delta[j] + s->a * (s->cf.out[j] - s->delta[j])   /* first-order lag */
                                       : s->cf.out[j];
        const double d = y - s->delta[j];
        if (dmax > 0 && fabs(d) > dmax) s->delta[j] += d > 0 ? dmax : -dmax;                /* rate limit */
        else s->delta[j] = y;
    }
}
