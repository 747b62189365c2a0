/* DampingController: the model-based articulation damping of seed 001 (the
 * thesis's reference model, ch. 2 and 4.1; control options 1-3 of ch. 5 and
 * the revised law of 6.1.3) as a discrete controller. At each sample instant
 * t0 + k Ts inside a communication step it reads the inputs (held over the
 * step) and computes the damping request (damping.c); the outputs change only
 * there, so they depend on no input directly. Sample 0 starts the reference
 * model at the measured articulation angle and rate. */
#include <math.h>

#include "fmu.h"
#include "damping.h"

#define S (&comp->v.s)

static DcInputs inputs(ModelInstance *comp) {
    const DcInputs in = { .Lambda = D->Lambda, .LambdaDot = D->LambdaDot, .v = D->v, .v2 = D->v2,
                          .delta = D->delta, .Mmax = D->Mmax, .pctExternal = D->pctExternal };
    return in;
}

static DcParams dc_params(ModelInstance *comp) {
    DcParams p = { .f1 = D->f1, .b1 = D->b1, .b11 = D->b11, .f2 = D->f2, .b2 = D->b2,
                   .m2 = D->m2, .Crear = D->Crear, .option = D->option,
                   .K1 = D->K1, .K2 = D->K2, .K3 = D->K3, .Krev = D->Krev,
                   .exactRef = D->exactRef, .nKc = D->nKc,
                   .pctMax = D->pctMax, .pctFloor = D->pctFloor, .pctAtMmax = D->pctAtMmax,
                   .vMin = D->vMin, .Ts = D->Ts };
    for (int i = 0; i < DC_MAX_KC; i++) {
        p.KcSpeed[i] = D->KcSpeed[i + 1];
        p.KcGain[i] = D->KcGain[i + 1];
    }
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const DcParams p = dc_params(comp);
    DcController scratch;
    const int bad = dc_setup(&scratch, &p);
    if (bad == -14)
        return log_error(comp, "parameter pctFloor = %g %% is above pctMax = %g %%: the floor must "
                               "lie within the range of the request", D->pctFloor, D->pctMax);
    if (bad == -11)
        return log_error(comp, "parameter KcSpeed[1..nKc] (nKc = %d) is not strictly increasing",
                         D->nKc);
    if (bad == -1)
        return log_error(comp, "parameters f1 = %g m, b1 = %g m: l1 = f1 + b1 must be > 0 "
                               "(seed 001, eq. 2.1)", D->f1, D->b1);
    if (bad == -2)
        return log_error(comp, "parameters f2 = %g m, b2 = %g m: l2 = f2 + b2 must be > 0 "
                               "(seed 001, eq. 2.3)", D->f2, D->b2);
    if (bad) return log_error(comp, "parameter %s is not valid for the damping controller",
                              dc_param_name(bad));
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const DcParams p = dc_params(comp);
    if (dc_setup(&S->c, &p)) return log_error(comp, "the damping controller's set-up failed");
    S->t0 = comp->v.time;
    S->k = 0;
    const DcInputs in = inputs(comp);
    dc_reset(&S->c, &in);                    /* the outputs of the initial inputs */
    S->fault = 0;                            /* faults are reported from the first step on */
    return OK;
}

void model_outputs(ModelInstance *comp) {
    D->pct = S->c.pct;
    D->T = S->c.T;
    D->LambdaRef = S->c.LambdaRef;
    D->LambdaDotRef = S->c.LambdaDotRef;
    D->eLambda = S->c.eLambda;
    D->eLambdaDot = S->c.eLambdaDot;
    D->Kc = S->c.Kc;
    D->active = S->c.active;
}

/* a message when a fault appears; once per episode (until it clears) */
static void report(ModelInstance *comp, unsigned fault, double t) {
    const unsigned now = fault & ~S->fault;
    if (now & DC_FAULT_REVERSE)
        log_warning(comp, "t = %.6g s: v = %g m/s < 0 is not a forward speed (the reference model "
                          "of seed 001 is for forward driving): reference held at the measured "
                          "Lambda, LambdaDot, only the floor pctFloor = %g %% requested; warned once "
                          "until v >= 0", t, D->v, D->pctFloor);
    else if (now & DC_FAULT_SLOW)
        log_event(comp, "t = %.6g s: v = %g m/s below vMin = %g m/s: reference held at the measured "
                        "Lambda, LambdaDot, only the floor requested", t, D->v, D->vMin);
    if (now & DC_FAULT_NAN)
        log_warning(comp, "t = %.6g s: an input is not finite (Lambda = %g, LambdaDot = %g, v = %g, "
                          "v2 = %g, delta = %g, Mmax = %g, pctExternal = %g): outputs and reference "
                          "held; warned once until it clears", t, D->Lambda, D->LambdaDot, D->v,
                    D->v2, D->delta, D->Mmax, D->pctExternal);
    if (now & DC_FAULT_MMAX)
        log_warning(comp, "t = %.6g s: Mmax = %g N.m: the dampers give no torque, yet a torque is "
                          "requested: pctMax = %g %% requested; warned once until it clears",
                    t, D->Mmax, D->pctMax);
    if (now & DC_FAULT_V2)
        log_event(comp, "t = %.6g s: v2 = %g m/s below vMin = %g m/s: eq. 5.4 divides by vMin",
                  t, D->v2, D->vMin);
    if (now & DC_FAULT_LIMIT)
        log_event(comp, "t = %.6g s: requested damping beyond pctMax = %g %%, saturated", t, D->pctMax);
    S->fault = fault;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = S->c.p.Ts;
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        const DcInputs in = inputs(comp);
        report(comp, S->k == 0 ? dc_reset(&S->c, &in) : dc_sample(&S->c, &in), tk);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters (from model_init), reference model, outputs, sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const DcController *c = &s->c;
    if (c->p.nKc < 1 || c->p.nKc > DC_MAX_KC || c->p.option < 0 || c->p.option > 5 ||
        (c->p.exactRef != 0 && c->p.exactRef != 1))
        return STATE_INVALID("Kc table of %d points, option %d, exactRef %d", c->p.nKc, c->p.option, c->p.exactRef);
    if (!finite_all(c->p.KcSpeed, DC_MAX_KC) || !finite_all(c->p.KcGain, DC_MAX_KC) ||
        !finite_all(&c->l1, (size_t)(&c->active - &c->l1) + 1) || !isfinite(c->p.Ts) || !(c->p.Ts == d->Ts) ||
        !isfinite(c->p.f1) || !isfinite(c->p.b1) || !isfinite(c->p.b11) || !isfinite(c->p.f2) ||
        !isfinite(c->p.b2) || !isfinite(c->p.m2) || !isfinite(c->p.Crear) || !isfinite(c->p.K1) ||
        !isfinite(c->p.K2) || !isfinite(c->p.K3) || !isfinite(c->p.Krev) || !isfinite(c->p.vMin) ||
        !isfinite(c->p.pctMax) || !isfinite(c->p.pctFloor) || !isfinite(c->p.pctAtMmax))
        return STATE_INVALID("a parameter, reference model state or output is not finite");
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
