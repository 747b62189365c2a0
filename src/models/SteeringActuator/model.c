/* SteeringActuator: the steering actuators of one trailing module on the
 * steering CAN (issue 12) as a discrete FMU: at each sample instant t0 + k Ts
 * inside a communication step the held inputs (the set-points and alive
 * counter the CAN delivered at the tick) go through the stale detection and
 * fallback and the optional actuator dynamics (actuator.c); the outputs
 * change only there. */
#include <math.h>

#include "fmu.h"
#include "actuator.h"

#define S (&comp->v.s)

static const char *const MODE_NAME[] = { "normal", "holding", "ramping to straight", "at the safe angle" };

static ActParams act_params(ModelInstance *comp) {
    const ActParams p = { .Tact = D->Tact, .rateMax = D->rateMax, .nStale = D->nStale, .nRecover = D->nRecover,
                          .tHold = D->tHold, .rampRate = D->rampRate, .Ts = D->Ts };
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const ActParams p = act_params(comp);
    const double cmd[2] = { D->cmd[1], D->cmd[2] };
    __typeof__(comp->v.s.a) scratch;
    const int bad = act_setup(&scratch, &p, cmd, D->alive);
    if (bad) return log_error(comp, "parameter %s is not valid for the steering actuator (Tact, rateMax >= 0, "
                                    "Ts > 0, nRecover >= 1, rampRate > 0)", act_param_name(bad));
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const ActParams p = act_params(comp);
    const double cmd[2] = { D->cmd[1], D->cmd[2] };
    if (act_setup(&S->a, &p, cmd, D->alive)) return log_error(comp, "the actuator's set-up failed");
    S->t0 = comp->v.time;
    S->k = 0;
    S->mode = CF_NORMAL;
    return OK;
}

void model_outputs(ModelInstance *comp) {
    D->delta[1] = S->a.delta[0];
    D->delta[2] = S->a.delta[1];
    D->fallback = (double)S->a.cf.mode;
    D->stale = (double)S->a.stale;
    D->cmdRx[1] = S->a.cmdRx[0];
    D->cmdRx[2] = S->a.cmdRx[1];
}

static void report(ModelInstance *comp, double t) {
    const int mode = S->a.cf.mode;
    if (mode == S->mode) return;
    if (S->mode == CF_NORMAL)
        log_warning(comp, "t = %.6g s: command message stale (no new alive counter for nStale = %d cycles of "
                          "%g s; last counter %g): fallback: holding %g, %g rad for tHold = %g s, then ramping "
                          "to straight at %g rad/s", t, D->nStale, D->Ts, S->a.cf.last[0], S->a.cf.out[0],
                    S->a.cf.out[1], D->tHold, D->rampRate);
    else if (mode == CF_NORMAL)
        log_warning(comp, "t = %.6g s: fallback ends: new commands for nRecover = %d cycles", t, D->nRecover);
    else
        log_event(comp, "t = %.6g s: fallback %s", t, MODE_NAME[mode]);
    S->mode = mode;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = D->Ts;
    const double cmd[2] = { D->cmd[1], D->cmd[2] };
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        act_sample(&S->a, cmd, D->alive);
        report(comp, tk);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters, the fallback, axle angles, the sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const SteeringAct *a = &s->a;
    if (!cf_state_valid(&a->cf) || s->mode < CF_NORMAL || s->mode > CF_SAFE)
        return STATE_INVALID("fallback counts or mode %d out of range", s->mode);
    if (!isfinite(a->p.Tact) || !isfinite(a->p.rateMax) || !isfinite(a->p.tHold) || !isfinite(a->p.rampRate) ||
        !(a->p.Ts == d->Ts) || !isfinite(a->a) || !finite_all(a->delta, 2) || !finite_all(a->cmdRx, 2))
        return STATE_INVALID("a parameter or angle is not finite");
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
