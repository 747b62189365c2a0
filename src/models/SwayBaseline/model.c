/* SwayBaseline: a condition-based articulation damping like Scania's ACS5,
 * modelled from seed 001's description (1.4.1, 5.2.5, 6.1.4), not from
 * production code, as a discrete controller: at each sample instant t0 + k Ts
 * inside a communication step the held inputs give the request (baseline.c);
 * the outputs change only there. */
#include <math.h>

#include "fmu.h"
#include "baseline.h"

#define S (&comp->v.s)

static SbParams sb_params(ModelInstance *comp) {
    SbParams p = { .nGround = D->nGround, .vSSC = D->vSSC, .LambdaDotSSC = D->LambdaDotSSC,
                   .tHold = D->tHold, .pctSSC = D->pctSSC, .LambdaEP0 = D->LambdaEP0,
                   .LambdaEP1 = D->LambdaEP1, .pctEP = D->pctEP, .pctMax = D->pctMax, .Ts = D->Ts };
    for (int i = 0; i < SB_MAX_GROUND; i++) {
        p.groundSpeed[i] = D->groundSpeed[i + 1];
        p.groundPct[i] = D->groundPct[i + 1];
    }
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const SbParams p = sb_params(comp);
    __typeof__(comp->v.s.b) scratch;
    const int bad = sb_setup(&scratch, &p);
    if (bad == -2)
        return log_error(comp, "parameter groundSpeed[1..nGround] (nGround = %d) is not strictly increasing",
                         D->nGround);
    if (bad == -9)
        return log_error(comp, "parameter LambdaEP1 = %g rad must be above LambdaEP0 = %g rad",
                         D->LambdaEP1, D->LambdaEP0);
    if (bad) return log_error(comp, "parameter %s is not valid for the sway baseline", sb_param_name(bad));
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const SbParams p = sb_params(comp);
    if (sb_setup(&S->b, &p)) return log_error(comp, "the sway baseline's set-up failed");
    S->t0 = comp->v.time;
    S->k = 0;
    SbBaseline first = S->b;                 /* the outputs of the initial inputs (sample 0 is */
    sb_sample(&first, D->v, D->Lambda, D->LambdaDot);   /* taken again, with the inputs of t0, */
    S->b.pct = first.pct;                    /* at the first step) */
    S->b.pctGround = first.pctGround;
    S->b.ssc = first.ssc;
    S->b.ep = first.ep;
    S->fault = 0;
    return OK;
}

void model_outputs(ModelInstance *comp) {
    D->pct = S->b.pct;
    D->pctGround = S->b.pctGround;
    D->sscActive = S->b.ssc;
    D->epActive = S->b.ep;
    D->tSinceSSC = S->b.tSince;
}

static void report(ModelInstance *comp, unsigned fault, double t) {
    const unsigned now = fault & ~S->fault;
    if (now & SB_FAULT_REVERSE)
        log_warning(comp, "t = %.6g s: v = %g m/s < 0 is not a forward speed: ground level of "
                          "groundSpeed[1] used; warned once until v >= 0", t, D->v);
    if (now & SB_FAULT_NAN)
        log_warning(comp, "t = %.6g s: an input is not finite (v = %g, Lambda = %g, LambdaDot = %g): "
                          "outputs held; warned once until it clears", t, D->v, D->Lambda, D->LambdaDot);
    S->fault = fault;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = S->b.p.Ts;
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        const double was = S->b.ssc;
        report(comp, sb_sample(&S->b, D->v, D->Lambda, D->LambdaDot), tk);
        if (S->b.ssc != was)
            log_event(comp, "t = %.6g s: sway control %s (v = %g m/s, LambdaDot = %g rad/s)", tk,
                      S->b.ssc != 0.0 ? "on" : "off", D->v, D->LambdaDot);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters (from model_init), SSC timer, outputs, sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const SbBaseline *b = &s->b;
    if (b->p.nGround < 1 || b->p.nGround > SB_MAX_GROUND || b->nHold < 0 || b->nHold > (1LL << 52) ||
        b->k < 0 || b->k > (1LL << 52) || b->kLast > b->k || (b->everHeld != 0 && b->everHeld != 1))
        return STATE_INVALID("ground table of %d points, nHold %lld, k %lld, kLast %lld", b->p.nGround,
                             b->nHold, b->k, b->kLast);
    if (!finite_all(b->p.groundSpeed, SB_MAX_GROUND) || !finite_all(b->p.groundPct, SB_MAX_GROUND) ||
        !finite_all(&b->p.vSSC, (size_t)(&b->p.Ts - &b->p.vSSC) + 1) || !(b->p.Ts == d->Ts) ||
        !isfinite(b->tSince) || !isfinite(b->pct) || !isfinite(b->pctGround) || !isfinite(b->ssc) || !isfinite(b->ep))
        return STATE_INVALID("a parameter, timer or output is not finite");
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
