/* ZeroSideslipSteering: seed 004, eq. 3 with delta_n = K(u) delta_1 and the
 * zero-side-slip gain K(u) (zero_sideslip.c, plain C for an ECU), sampled
 * every Ts from the inputs held over the communication step. */
#include <math.h>

#include "fmu.h"

static void make_vehicle(ModelInstance *comp, ZsVehicle *veh) {
    veh->n = D->n;
    for (int i = 0; i <= ZS_MAX_AXLES; i++) {
        const int on = i >= 1;
        veh->l[i] = on ? D->l[i] : 0.0;
        veh->k[i] = on ? D->k[i] : 0.0;
        veh->m[i] = on ? D->m[i] : 0.0;
        veh->steerable[i] = on ? D->steerable[i] : 0;
        veh->deltaMax[i] = on ? D->deltaMax[i] : 0.0;
    }
    veh->m_b = D->m_b;
}

/* one sample at time tk, from the inputs (plus the built-in test stimulus) */
static void sample(ModelInstance *comp, double tk) {
    ModelState *s = &comp->v.s;
    const double delta1 = D->delta1 + D->testSteerAmp;
    const double u = D->u + D->testSpeedRate * (tk - s->t0);
    s->flags = zs_step(&s->gains, &s->mem, delta1, u, s->delta, s->K);
    s->kNext++;
}

static const char *PREPARE_ERROR[] = {
    "", "n is not 2..6", "steerable[1] is false: the front axle carries the driver's angle delta_1",
    "no axle behind axle 1 is steerable: zero side-slip needs a second steered axle",
    "the axles are not ordered front to rear (l[i] < l[i-1] is needed)",
    "a parameter is out of its domain (k[i] < 0, m[i] >= 0, deltaMax[i] >= 0)",
    "K(u) is undefined: its denominator vanishes at every speed",
};

Status model_check_parameters(ModelInstance *comp) {
    ZsVehicle veh;
    make_vehicle(comp, &veh);
    ZsGains gains;
    int axle = 0;
    const int e = zs_prepare(&veh, &gains, &axle);
    if (e != ZS_OK) {
        if (axle)
            return log_error(comp, "axle %d (l[%d] = %g m, k[%d] = %g N/rad, steerable[%d] = %d): %s",
                             axle, axle, D->l[axle], axle, D->k[axle], axle, D->steerable[axle],
                             PREPARE_ERROR[e]);
        return log_error(comp, "n = %d: %s", D->n, PREPARE_ERROR[e]);
    }
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    ModelState *s = &comp->v.s;
    ZsVehicle veh;
    make_vehicle(comp, &veh);
    if (zs_prepare(&veh, &s->gains, NULL) != ZS_OK) return log_error(comp, "the gains' set-up failed");
    s->t0 = comp->v.time;
    s->kNext = 0;
    s->warned = 0;
    zs_reset(&s->mem);
    log_event(comp, "control axle r = %d; K(0) = %g, K(inf) = %g; pole of K(u) at u = %g m/s "
                    "(-1: none)", s->gains.rear, zs_gain(&s->gains, 0.0),
              s->gains.D2 != 0.0 ? s->gains.N2 / s->gains.D2 : INFINITY, s->gains.uPole);
    sample(comp, s->t0);                /* sample 0, at t0 */
    return OK;
}

void model_outputs(ModelInstance *comp) {
    const ModelState *s = &comp->v.s;
    for (int i = 1; i <= ZS_MAX_AXLES; i++) {
        D->delta[i] = s->delta[i];
        D->K[i] = s->K[i];
    }
}

/* bad input is warned about once per episode and kind */
static Status warn(ModelInstance *comp, double tk) {
    ModelState *s = &comp->v.s;
    const unsigned fresh = s->flags & ~s->warned;
    if (!fresh) return OK;
    s->warned |= fresh;
    const double u = D->u + D->testSpeedRate * (tk - s->t0);
    if (fresh & ZS_INPUT_NOT_FINITE)
        log_warning(comp, "t = %g s: delta1 = %g rad or u = %g m/s is not finite: the last command "
                          "is held (warned once per episode)", tk, D->delta1, u);
    if (fresh & ZS_REVERSING)
        log_warning(comp, "t = %g s: u = %g m/s < 0: the zero-side-slip gain of seed 004 is derived "
                          "for forward driving; the standstill gain K(0) = %g is used while reversing "
                          "(warned once per episode)", tk, u, zs_gain(&s->gains, 0.0));
    if (fresh & ZS_NEAR_POLE)
        log_warning(comp, "t = %g s: u = %g m/s is at the pole of K(u) (u = %g m/s): K is limited to "
                          "+-%g (warned once per episode)", tk, u, s->gains.uPole, ZS_K_LIMIT);
    if (fresh & ZS_SATURATED)
        log_warning(comp, "t = %g s: an axle's command reached its steering limit deltaMax (delta1 = "
                          "%g rad, u = %g m/s); the side-slip is no longer zero while it lasts "
                          "(warned once per episode)", tk, D->delta1 + D->testSteerAmp, u);
    return Warning;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelState *s = &comp->v.s;
    const double Ts = D->Ts;
    Status status = warn(comp, t);  /* sample 0's, if any */
    /* every sample instant in (t, t + h], from the inputs held over the step */
    const double end = t + h + 1e-9 * Ts;
    while (s->t0 + s->kNext * Ts <= end) {
        const double tk = s->t0 + s->kNext * Ts;
        sample(comp, tk);
        if (warn(comp, tk) == Warning) status = Warning;
    }
    comp->v.time = t + h;
    return status;
}

void model_free(ModelInstance *comp) {
    (void)comp;                         /* nothing on the heap */
}

/* FMU state: gains (from model_init), memory, held outputs, the sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const ZsGains *g = &s->gains;
    if (g->n < 2 || g->n > ZS_MAX_AXLES || g->n != d->n || g->rear < 1 || g->rear > g->n)
        return STATE_INVALID("gains for n = %d axles, rear = %d (n = %d)", g->n, g->rear, d->n);
    if (!finite_all(g->a, ZS_MAX_AXLES + 1) || !finite_all(g->b, ZS_MAX_AXLES + 1) ||
        !finite_all(g->deltaMax, ZS_MAX_AXLES + 1) || !isfinite(g->N2) || !isfinite(g->N0) ||
        !isfinite(g->D2) || !isfinite(g->D0) || !isfinite(g->uPole) ||
        !finite_all(s->mem.delta, ZS_MAX_AXLES + 1) || !isfinite(s->mem.u) ||
        !finite_all(s->delta, ZS_MAX_AXLES + 1) || !finite_all(s->K, ZS_MAX_AXLES + 1))
        return STATE_INVALID("a gain, memory or held output is not finite");
    if (!sample_index_ok(s->t0, s->kNext, d->Ts, time))
        return STATE_INVALID("sample kNext = %ld from t0 = %g (Ts = %g s) is not near t = %g s", s->kNext, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
