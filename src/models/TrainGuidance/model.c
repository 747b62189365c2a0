/* TrainGuidance: the train-like guidance of seed 000 (Task 1, eqs. 29-42) as
 * a discrete controller. At each sample instant t0 + k Ts inside a
 * communication step it reads the inputs (held over the step), computes the
 * steady-state angles and advances the arc lags (guidance.c); the outputs
 * change only there, so they depend on no input directly.
 *
 * Driving direction: the bus is symmetric, so driving backwards mirrors every
 * role (the A6 end leads: gamma1 is A6's angle, v is A5's speed, the outputs
 * go to A3 and A1; module frames turned by 180 deg keep the sign of every
 * steering angle). The algorithm is the same; when `backwards` changes, the
 * lags restart from the steady state of the current gamma1 (the guided axles
 * change, their old lag states belong to other axles).
 *
 * mode = 1 (pathMemory, beyond the paper; guidance.h): A4 and A6 follow the
 * dead-reckoned, stored trace of A2 (inputs dPsi[1], dPsi[2] besides gamma1
 * and v). The arc lags run alongside (gamma4ss, gamma6ss stay the paper's
 * steady-state angles). Backwards the leading module sees G2 first, as
 * -dPsi[2], then G1 as -dPsi[1] (as in ForceMinimization); a change of
 * direction re-seeds the trace from the bus as it stands.
 *
 * guided = false holds gamma4 = gamma6 = 0 (A4, A6 not steered: the paper's
 * unsteered case, a variant of one bench rather than a bench without this
 * FMU); the guidance runs on unchanged behind it, silently (no warnings;
 * the fault output still flags). */
#include <math.h>

#include <stdlib.h>

#include "fmu.h"
#include "leading_hinges.h"
#include "guidance.h"

#define S (&comp->v.s)

static double gamma1_at(ModelInstance *comp, double t) {
    return D->gamma1 + test_sine(D->testSteerAmp, D->testSteerPeriod, t);
}

/* the leading module's view of the articulation angles */
static void hinges(ModelInstance *comp, double *d1, double *d2) {
    leading_hinges(D->backwards, D->dPsi[1], D->dPsi[2], d1, d2);
}

static TgParams tg_params(ModelInstance *comp) {
    const TgParams p = { .l1 = D->l1, .lg1 = D->lg1, .l2 = D->l2, .lg2 = D->lg2, .l3 = D->l3,
                         .S4 = D->S4, .S6 = D->S6, .Ts = D->Ts,
                         .gamma4Max = D->gamma4Max, .gamma6Max = D->gamma6Max };
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const TgParams p = tg_params(comp);
    __typeof__(comp->v.s.g) g;
    const int bad = tg_setup(&g, &p);
    if (bad) return log_error(comp, "parameter %s is not valid for the guidance (lengths and Ts "
                                    "must be > 0, S >= 0, 0 < limit < pi/2)", tg_param_name(bad));
    __typeof__(comp->v.s.pm) *pm = malloc(sizeof *pm);
    if (!pm) return log_error(comp, "out of memory");
    const int badPath = tg_pm_setup(pm, &g, D->kPath);
    free(pm);
    if (badPath)
        return log_error(comp, "parameter %s = %g is not valid (finite, 0 .. 1000 1/m)", tg_pm_param_name(), D->kPath);
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const TgParams p = tg_params(comp);
    if (tg_setup(&S->g, &p)) return log_error(comp, "the guidance's set-up failed");
    tg_reset(&S->g, gamma1_at(comp, comp->v.time));  /* starts in the steady state of gamma1 */
    if (tg_pm_setup(&S->pm, &S->g, D->kPath)) return log_error(comp, "the path memory's set-up failed");
    double d1, d2;
    hinges(comp, &d1, &d2);
    tg_pm_reset(&S->pm, &S->g, d1, d2);              /* the trace: the bus as it stands */
    S->t0 = comp->v.time;
    S->k = 0;
    S->fault = 0;
    S->backwards = D->backwards;
    return OK;
}

void model_outputs(ModelInstance *comp) {
    if (!D->guided) {                    /* A4, A6 not steered (seed 000's unsteered case) */
        D->gamma4 = 0.0;
        D->gamma6 = 0.0;
    } else if (D->mode == 1) {
        D->gamma4 = S->pm.gamma4;
        D->gamma6 = S->pm.gamma6;
    } else {
        D->gamma4 = S->g.gamma4;
        D->gamma6 = S->g.gamma6;
    }
    D->e4 = S->pm.e4;
    D->e6 = S->pm.e6;
    D->gamma4ss = S->g.gamma4ss;
    D->gamma6ss = S->g.gamma6ss;
    D->fault = (double)S->fault;
}

/* a warning when a fault appears; once per episode (until it clears) */
static void report(ModelInstance *comp, unsigned fault, double t, double gamma1, double v) {
    const unsigned now = D->guided ? fault & ~S->fault : 0;   /* not guided: nothing it sends is at stake */
    if (now & TG_FAULT_SPEED)
        log_warning(comp, "t = %.6g s: v = %g m/s < 0 is not a driving speed (use backwards for the "
                          "direction): treated as v = 0, the arc lags hold; warned once until v >= 0",
                    t, v);
    if (now & TG_FAULT_GEOMETRY)
        log_warning(comp, "t = %.6g s: gamma1 = %g rad: no steady-state triangle with l1 = %g, lg1 = %g, "
                          "l2 = %g, lg2 = %g, l3 = %g m (the arccos argument of seed 000, eqs. 32/36, "
                          "leaves [-1, 1]): guided angles saturated at their limits; warned once "
                          "until it clears", t, gamma1, D->l1, D->lg1, D->l2, D->lg2, D->l3);
    if (now & TG_FAULT_NAN)
        log_warning(comp, "t = %.6g s: gamma1 = %g, v = %g, dPsi[1] = %g, dPsi[2] = %g: input not finite, "
                          "outputs held; warned once until it clears", t, gamma1, v, D->dPsi[1], D->dPsi[2]);
    if (now & TG_FAULT_TRACE)
        log_warning(comp, "t = %.6g s: pathMemory: a guided axle is not beside the stored trace of A2, or "
                          "v Ts = %g m is too long for it: the trace is re-seeded from the bus as it stands "
                          "(dPsi[1] = %g, dPsi[2] = %g rad); warned once until it clears",
                    t, v * D->Ts, D->dPsi[1], D->dPsi[2]);
    if (now & TG_FAULT_LIMIT)
        log_event(comp, "t = %.6g s: gamma1 = %g rad: steady-state angle beyond gamma4Max = %g or "
                        "gamma6Max = %g rad, saturated", t, gamma1, D->gamma4Max, D->gamma6Max);
    S->fault = fault;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = S->g.p.Ts;
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        const double gamma1 = gamma1_at(comp, tk);
        if (D->backwards != S->backwards) {
            log_event(comp, "t = %.6g s: driving direction now %s: lags restart from the steady "
                            "state of gamma1 = %g rad", tk, D->backwards ? "backwards" : "forwards", gamma1);
            tg_reset(&S->g, gamma1);
            S->backwards = D->backwards;
            double d1, d2;
            hinges(comp, &d1, &d2);
            tg_pm_reset(&S->pm, &S->g, d1, d2);
        }
        unsigned fault = tg_sample(&S->g, gamma1, D->v);
        if (D->mode == 1) {
            double d1, d2;
            hinges(comp, &d1, &d2);
            fault |= tg_pm_sample(&S->pm, &S->g, gamma1, D->v, d1, d2);
        }
        report(comp, fault, tk, gamma1, D->v);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters and lag states, the path memory (ring buffer indices)
 * and the sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const TgPath *m = &s->pm;
    if (!finite_all((const double *)&s->g, sizeof s->g / sizeof(double)))
        return STATE_INVALID("a parameter or lag state of the guidance is not finite");
    if (!(s->g.p.Ts == d->Ts)) return STATE_INVALID("the guidance's Ts = %g s is not Ts = %g s", s->g.p.Ts, d->Ts);
    if (!finite_all(m->px, TG_PM_N) || !finite_all(m->py, TG_PM_N) || !finite_all(m->pth, TG_PM_N) ||
        !isfinite(m->x) || !isfinite(m->y) || !isfinite(m->psi) || !isfinite(m->s) || !isfinite(m->kPath) ||
        !isfinite(m->s4) || !isfinite(m->s6) || !isfinite(m->e4) || !isfinite(m->e6) ||
        !isfinite(m->gamma4) || !isfinite(m->gamma6))
        return STATE_INVALID("a value of the path memory is not finite");
    if (!(m->dsGrid > 0 && m->window >= 0 && m->window / m->dsGrid < 1e6))
        return STATE_INVALID("path memory grid %g m, window %g m", m->dsGrid, m->window);
    if (m->next < 0 || m->next > (1LL << 40) || m->seg4 < -1 || m->seg4 > m->next || m->seg6 < -1 || m->seg6 > m->next)
        return STATE_INVALID("path memory indices next = %lld, seg4 = %lld, seg6 = %lld", m->next, m->seg4, m->seg6);
    if (!(m->s >= 0 && m->s < ((double)m->next + 2.0) * m->dsGrid + 1.0))
        return STATE_INVALID("path memory odometer s = %g m with %lld points stored", m->s, m->next);
    if (s->backwards != 0 && s->backwards != 1) return STATE_INVALID("backwards = %d", s->backwards);
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
