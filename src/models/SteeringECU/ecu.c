/* The steering ECU of module 1, 2 or 3: see ecu.h. Plain C99 and libm only. */
#include <math.h>
#include "ecu.h"

/* codes: -1 module, -2 vDir; tg_setup's -1..-10 as -11..-20, fm_setup's as -21..-29,
   cf_setup's as -31..-37 */
const char *ecu_param_name(int code) {
    if (code == -1) return "module";
    if (code == -2) return "vDir";
    if (code <= -11 && code >= -20) return tg_param_name(code + 10);
    if (code <= -21 && code >= -29) return fm_param_name(code + 20);
    if (code <= -31 && code >= -39) return cf_param_name(code + 30);
    return "?";
}

/* the direction this ECU steers for: module 1 decides it from its speed
   (hysteresis +-vDir), the others take the received one (a Real off the bus) */
static int direction(const SteeringEcu *e, const EcuInputs *in) {
    if (e->module == 1) {
        if (in->v < -e->vDir) return 1;
        if (in->v > e->vDir) return 0;
        return e->direction;
    }
    if (!isfinite(in->direction)) return 2;
    const double d = floor(in->direction + 0.5);
    return d >= 0.0 && d <= 3.0 ? (int)d : 2;
}

/* the messages a module's algorithm needs in a direction */
static unsigned used(int module, int backwards) {
    const unsigned state = 1u << ECU_MSG_STATE;
    if (!backwards) {
        if (module == 1) return 0u;                       /* steers nothing forwards */
        return state | 1u << ECU_MSG_A1 | 1u << ECU_MSG_G1 | (module == 3 ? 1u << ECU_MSG_G2 : 0u);
    }
    if (module == 3) return 0u;                           /* steers nothing backwards */
    /* module 1 sends TractorECU_State itself: its speed comes from the vehicle network */
    return (module == 1 ? 0u : state) | 1u << ECU_MSG_A6 | 1u << ECU_MSG_G1 | 1u << ECU_MSG_G2;
}

/* the algorithm on the current inputs: the module's two angles in e->calc */
static unsigned compute(SteeringEcu *e, const EcuInputs *in) {
    if (!e->backwards) {
        unsigned fault = tg_sample(&e->g, in->gamma1, in->v);
        if (e->module == 1) {
            e->calc[0] = e->calc[1] = 0.0;
        } else if (e->module == 2) {
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
    /* backwards: the A6 end leads, the leading module's speed is -v (seed 000's
       bidirectional operation; as TrainGuidance/ForceMinimization with backwards) */
    double d1, d2;
    leading_hinges(1, in->dPsi1, in->dPsi2, &d1, &d2);
    unsigned fault = tg_sample(&e->g, in->gammaA6, -in->v);
    if (e->module == 3) {
        e->calc[0] = e->calc[1] = 0.0;
    } else if (e->module == 2) {
        fault |= fm_sample(&e->f, in->gammaA6, d1, 0.0, e->g.gamma4, 0.0);
        e->calc[0] = e->g.gamma4;                         /* A3: the guided axle */
        e->calc[1] = e->f.gamma3;                         /* A4: force minimisation */
    } else {
        fault |= fm_sample(&e->f, in->gammaA6, d1, d2, e->g.gamma4, e->g.gamma6);
        e->calc[0] = e->g.gamma6;                         /* A1: the guided axle */
        e->calc[1] = e->f.gamma5;                         /* A2: force minimisation */
    }
    return fault;
}

int ecu_setup(SteeringEcu *e, const EcuParams *p, const EcuInputs *in) {
    if (p->module < 1 || p->module > 3) return -1;
    if (!(p->vDir >= 0.0 && p->vDir < 10.0)) return -2;
    int bad = tg_setup(&e->g, &p->tg);
    if (bad) return bad - 10;
    bad = fm_setup(&e->f, &p->fm);
    if (bad) return bad - 20;
    e->module = p->module;
    e->vDir = p->vDir;
    e->direction = 0;
    e->direction = direction(e, in);
    e->backwards = e->direction == 1;
    e->used = used(e->module, e->backwards);
    tg_reset(&e->g, e->backwards ? in->gammaA6 : in->gamma1);   /* the lags in the steady state */
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
    e->direction = direction(e, in);
    const int valid = e->direction == 0 || e->direction == 1;
    if (valid && (e->direction == 1) != e->backwards) {
        /* the guided axles change: the lags restart from the new leading angle */
        e->backwards = e->direction == 1;
        e->used = used(e->module, e->backwards);
        tg_reset(&e->g, e->backwards ? in->gammaA6 : in->gamma1);
        e->cf.rejoin = 1;       /* the set-points slew to the new roles' at rampRate (no step) */
    }
    unsigned fault = compute(e, in);
    if (!valid) fault |= ECU_FAULT_DIRECTION;
    e->stale = cf_sample(&e->cf, in->alive, e->used, !valid, e->calc) & e->used;
    e->fault = fault;
    return fault;
}
