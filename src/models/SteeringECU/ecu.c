/* The steering ECU of module 2 or 3: see ecu.h. Plain C99 and libm only. */
#include <math.h>
#include "ecu.h"

/* codes: -1 module; tg_setup's -1..-10 as -11..-20, fm_setup's as -21..-29,
   cf_setup's as -31..-37 */
const char *ecu_param_name(int code) {
    if (code == -1) return "module";
    if (code <= -11 && code >= -20) return tg_param_name(code + 10);
    if (code <= -21 && code >= -29) return fm_param_name(code + 20);
    if (code <= -31 && code >= -39) return cf_param_name(code + 30);
    return "?";
}

/* the algorithm on the current inputs: the module's two angles in e->calc */
static unsigned compute(SteeringEcu *e, const EcuInputs *in) {
    unsigned fault = tg_sample(&e->g, in->gamma1, in->v);
    if (e->module == 2) {
        fault |= fm_sample(&e->f, in->gamma1, in->dPsi1, 0.0, e->g.gamma4, 0.0);
        e->calc[0] = e->f.gamma3;
        e->calc[1] = e->g.gamma4;
    } else {
        fault |= fm_sample(&e->f, in->gamma1, in->dPsi1, in->dPsi2, e->g.gamma4, e->g.gamma6);
        e->calc[0] = e->f.gamma5;
        e->calc[1] = e->g.gamma6;
    }
    return fault;
}

int ecu_setup(SteeringEcu *e, const EcuParams *p, const EcuInputs *in) {
    if (p->module != 2 && p->module != 3) return -1;
    int bad = tg_setup(&e->g, &p->tg);
    if (bad) return bad - 10;
    bad = fm_setup(&e->f, &p->fm);
    if (bad) return bad - 20;
    e->module = p->module;
    e->used = (1u << ECU_MSG_A1) | (1u << ECU_MSG_G1) | (1u << ECU_MSG_STATE) |
              (p->module == 3 ? 1u << ECU_MSG_G2 : 0u);
    tg_reset(&e->g, in->gamma1);                 /* the lags in the steady state of gamma1 */
    compute(e, in);
    const CfParams cp = { .nMsg = ECU_NMSG, .nOut = 2, .nStale = p->nStale, .nRecover = p->nRecover,
                          .tHold = p->tHold, .rampRate = p->rampRate, .Ts = p->tg.Ts };
    bad = cf_setup(&e->cf, &cp, in->alive, e->calc);
    if (bad) return bad - 30;
    e->stale = 0;
    e->fault = 0;
    return 0;
}

unsigned ecu_sample(SteeringEcu *e, const EcuInputs *in) {
    unsigned fault = compute(e, in);
    const int forwards = fabs(in->direction) < 0.5;   /* DrivingDirection 0 (a Real off the bus) */
    if (!forwards) fault |= ECU_FAULT_DIRECTION;
    e->stale = cf_sample(&e->cf, in->alive, e->used, !forwards, e->calc) & e->used;
    e->fault = fault;
    return fault;
}
