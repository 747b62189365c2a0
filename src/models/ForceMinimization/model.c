/* ForceMinimization: the force-minimising steering of seed 000 (Task 2,
 * eqs. 43-48) as a discrete controller: at each sample instant t0 + k Ts
 * inside a communication step the held inputs give gamma3, gamma5
 * (forcemin.c); the outputs change only there.
 *
 * Driving direction: backwards, the A6 end leads and every role is mirrored
 * (module frames turned by 180 deg): the leading hinge is G2, seen from the
 * leading module as psi3 - psi2 = -dPsi[2], the second one -dPsi[1]; gamma1
 * is A6's angle, gamma4/gamma6 are A3's/A1's, and the outputs go to A4 and A2.
 * Steering angles keep their sign under the 180 deg turn.
 *
 * law selects what goes out (the force minimisation runs whatever it is):
 * 0 straight (gamma3 = gamma5 = 0), 1 the force minimisation (the default),
 * 2 like guided (gamma3, gamma5 = the gamma4, gamma6 inputs held at the
 * sample: the paper's counter-example with wrong A3/A5 angles). Its
 * warnings only where its angles go out (law 1); fault flags with any law. */
#include <math.h>

#include "fmu.h"
#include "leading_hinges.h"
#include "forcemin.h"

#define S (&comp->v.s)

static double gamma1_at(ModelInstance *comp, double t) {
    return D->gamma1 + test_sine(D->testSteerAmp, D->testSteerPeriod, t);
}

/* the leading module's view of the articulation angles */
static void hinges(ModelInstance *comp, double *d1, double *d2) {
    leading_hinges(D->backwards, D->dPsi[1], D->dPsi[2], d1, d2);
}

static unsigned sample(ModelInstance *comp, double t) {
    double d1, d2;
    hinges(comp, &d1, &d2);
    S->gamma4 = D->gamma4;                   /* held for law = likeGuided */
    S->gamma6 = D->gamma6;
    return fm_sample(&S->f, gamma1_at(comp, t), d1, d2, D->gamma4, D->gamma6);
}

static FmParams fm_params(ModelInstance *comp) {
    const FmParams p = { .l1 = D->l1, .lg1 = D->lg1, .l2 = D->l2, .lA3 = D->lA3, .lg2 = D->lg2,
                         .l3 = D->l3, .lA5 = D->lA5, .gamma3Max = D->gamma3Max,
                         .gamma5Max = D->gamma5Max };
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const FmParams p = fm_params(comp);
    __typeof__(comp->v.s.f) scratch;
    const int bad = fm_setup(&scratch, &p);
    if (bad) return log_error(comp, "parameter %s is not valid for the force minimisation "
                                    "(lengths must be > 0, 0 < limit < pi/2)", fm_param_name(bad));
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const FmParams p = fm_params(comp);
    if (fm_setup(&S->f, &p)) return log_error(comp, "the force minimisation's set-up failed");
    S->t0 = comp->v.time;
    S->k = 0;
    sample(comp, comp->v.time);              /* the outputs of the initial inputs */
    S->fault = 0;                            /* faults are reported from the first step on */
    return OK;
}

void model_outputs(ModelInstance *comp) {
    switch (D->law) {
    case LAW_STRAIGHT:                       /* A3, A5 not steered */
        D->gamma3 = 0.0;
        D->gamma5 = 0.0;
        break;
    case LAW_LIKE_GUIDED:                    /* seed 000's wrong A3/A5 angles: A3 like A4, A5 like A6 */
        D->gamma3 = S->gamma4;
        D->gamma5 = S->gamma6;
        break;
    default:                                 /* LAW_FORCE_MINIMIZATION: seed 000, eqs. 43-48 */
        D->gamma3 = S->f.gamma3;
        D->gamma5 = S->f.gamma5;
        break;
    }
    D->fault = (double)S->fault;
}

static void report(ModelInstance *comp, unsigned fault, double t) {
    /* warnings where the force minimisation is what goes out (the fault output flags with any law) */
    const unsigned now = D->law == LAW_FORCE_MINIMIZATION ? fault & ~S->fault : 0;
    if (now & FM_FAULT_GEOMETRY)
        log_warning(comp, "t = %.6g s: gamma1 = %g, dPsi[1] = %g, dPsi[2] = %g, gamma4 = %g, gamma6 = %g "
                          "rad: a hinge does not move forward relative to its module (jack-knifed) or an "
                          "angle is at or beyond 90 deg: no instantaneous centre ahead (seed 000, "
                          "eqs. 43-48), outputs saturated at gamma3Max = %g, gamma5Max = %g rad; warned "
                          "once until it clears", t, gamma1_at(comp, t), D->dPsi[1], D->dPsi[2],
                    D->gamma4, D->gamma6, D->gamma3Max, D->gamma5Max);
    if (now & FM_FAULT_NAN)
        log_warning(comp, "t = %.6g s: an input is not finite: outputs held", t);
    if (now & FM_FAULT_LIMIT)
        log_event(comp, "t = %.6g s: force-minimising angle beyond gamma3Max = %g or gamma5Max = %g rad, "
                        "saturated", t, D->gamma3Max, D->gamma5Max);
    S->fault = fault;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = D->Ts;
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        report(comp, sample(comp, tk), tk);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters (from model_init) and the last outputs; the sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    if (!finite_all((const double *)&s->f, sizeof s->f / sizeof(double)))
        return STATE_INVALID("a parameter or output of the force minimisation is not finite");
    if (!isfinite(s->gamma4) || !isfinite(s->gamma6))
        return STATE_INVALID("held gamma4 = %g, gamma6 = %g rad not finite", s->gamma4, s->gamma6);
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
