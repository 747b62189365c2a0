/* SteeringECU: the steering ECU of one module of seed 000's 36 m bus on
 * the steering CAN (section IV; issue 12), either driving direction (ecu.h),
 * as a discrete FMU: at each
 * sample instant t0 + k Ts inside a communication step it reads the inputs
 * (held over the step: what the CAN delivered at the tick), runs the
 * module's algorithm (ecu.c: guidance.c and forcemin.c, the same code as
 * TrainGuidance and ForceMinimization) and the stale detection and fallback
 * (can_fallback.c); outputs change only there, so they depend on no input
 * directly. */
#include <math.h>

#include "fmu.h"
#include "ecu.h"

#define S (&comp->v.s)

static const char *const MSG_NAME[ECU_NMSG] = {
    "SensorA1_Angle", "SensorG1_Angle", "SensorG2_Angle", "TractorECU_State", "SensorA6_Angle"
};
static const char *const MODE_NAME[] = { "normal", "holding", "ramping to straight", "at the safe angle" };

static EcuInputs inputs(ModelInstance *comp) {
    const EcuInputs in = { .gamma1 = D->gamma1, .gammaA6 = D->gammaA6, .v = D->v, .dPsi1 = D->dPsi[1],
                           .dPsi2 = D->dPsi[2], .direction = D->direction,
                           .alive = { D->aliveA1, D->aliveG1, D->aliveG2, D->aliveState, D->aliveA6 } };
    return in;
}

static EcuParams ecu_params(ModelInstance *comp) {
    const EcuParams p = {
        .module = D->module,
        .tg = { .l1 = D->l1, .lg1 = D->lg1, .l2 = D->l2, .lg2 = D->lg2, .l3 = D->l3,
                .S4 = D->S4, .S6 = D->S6, .Ts = D->Ts, .gamma4Max = D->gamma4Max, .gamma6Max = D->gamma6Max },
        .fm = { .l1 = D->l1, .lg1 = D->lg1, .l2 = D->l2, .lA3 = D->lA3, .lg2 = D->lg2, .l3 = D->l3,
                .lA5 = D->lA5, .gamma3Max = D->gamma3Max, .gamma5Max = D->gamma5Max },
        .nStale = D->nStale, .nRecover = D->nRecover, .tHold = D->tHold, .rampRate = D->rampRate,
        .vDir = D->vDir };
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const EcuParams p = ecu_params(comp);
    const EcuInputs in = inputs(comp);
    __typeof__(comp->v.s.e) scratch;
    const int bad = ecu_setup(&scratch, &p, &in);
    if (bad) return log_error(comp, "parameter %s is not valid for the steering ECU (module 1, 2 or 3, lengths "
                                    "and Ts > 0, S >= 0, 0 < limit < pi/2, nRecover >= 1, rampRate > 0)",
                              ecu_param_name(bad));
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    const EcuParams p = ecu_params(comp);
    const EcuInputs in = inputs(comp);
    if (ecu_setup(&S->e, &p, &in)) return log_error(comp, "the ECU's set-up failed");
    S->t0 = comp->v.time;
    S->k = 0;
    S->fault = 0;
    S->stale = 0;
    S->mode = CF_NORMAL;
    S->direction = S->e.direction;
    return OK;
}

void model_outputs(ModelInstance *comp) {
    D->gammaFront = S->e.cf.out[0];
    D->gammaRear = S->e.cf.out[1];
    D->fallback = (double)S->e.cf.mode;
    D->stale = (double)S->e.stale;
    D->fault = (double)S->e.fault;
    D->gammaFrontCalc = S->e.calc[0];
    D->gammaRearCalc = S->e.calc[1];
    D->drivingDirection = (double)S->e.direction;
}

/* warnings when a message turns stale, the fallback starts or ends, a fault appears */
static void report(ModelInstance *comp, double t) {
    const SteeringEcu *e = &S->e;
    const unsigned turned = e->stale & e->used & ~S->stale;
    for (int i = 0; i < ECU_NMSG; i++)
        if (turned >> i & 1u)
            log_warning(comp, "t = %.6g s: module %d: message %s stale (no new alive counter for nStale = %d "
                              "cycles of %g s; counter %g)", t, e->module, MSG_NAME[i], D->nStale, D->Ts,
                        e->cf.last[i]);
    if (e->cf.mode != S->mode) {
        if (S->mode == CF_NORMAL)
            log_warning(comp, "t = %.6g s: module %d: fallback: holding the set-points %g, %g rad for tHold = %g s, "
                              "then ramping to straight at %g rad/s (stale mask %u, fault %u)", t, e->module,
                        e->cf.out[0], e->cf.out[1], D->tHold, D->rampRate, e->stale & e->used, e->fault);
        else if (e->cf.mode == CF_NORMAL)
            log_warning(comp, "t = %.6g s: module %d: fallback ends: every message fresh for nRecover = %d cycles",
                        t, e->module, D->nRecover);
        else
            log_event(comp, "t = %.6g s: module %d: fallback %s", t, e->module, MODE_NAME[e->cf.mode]);
    }
    const unsigned now = e->fault & ~S->fault;
    if (now & ECU_FAULT_DIRECTION)
        log_warning(comp, "t = %.6g s: direction = %g is neither forwards (0) nor backwards (1) (J1939: error or "
                          "not available): fallback; warned once until it clears", t, D->direction);
    if (e->direction != S->direction && (e->direction == 0 || e->direction == 1))
        log_event(comp, "t = %.6g s: module %d: driving direction now %s: %s", t, e->module,
                  e->direction ? "backwards (the A6 end leads)" : "forwards (the A1 end leads)",
                  "the guidance's lags restart from the steady state of the leading angle");
    S->direction = e->direction;
    if (now & (TG_FAULT_GEOMETRY | TG_FAULT_SPEED | FM_FAULT_NAN))
        log_warning(comp, "t = %.6g s: gamma1 = %g rad, v = %g m/s, dPsi[1] = %g, dPsi[2] = %g rad: fault %u "
                          "(2 v < 0, treated as 0; 4 no steady-state triangle or a hinge not moving forward: "
                          "saturated); warned once until it clears", t, D->gamma1, D->v, D->dPsi[1], D->dPsi[2],
                    e->fault);
    S->fault = e->fault;
    S->stale = e->stale & e->used;
    S->mode = e->cf.mode;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    const double Ts = D->Ts;
    const EcuInputs in = inputs(comp);
    for (double tk; sample_due(S->t0, S->k, Ts, t, h, &tk); S->k++) {   /* samples in [t, t + h) */
        ecu_sample(&S->e, &in);
        report(comp, tk);
    }
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters, lag states, the fallback, the sample counter */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    const SteeringEcu *e = &s->e;
    if (e->module < 1 || e->module > 3 || e->direction < 0 || e->direction > 3 || !(e->vDir >= 0.0 && e->vDir < 10.0) ||
        (e->backwards != 0 && e->backwards != 1) || !cf_state_valid(&e->cf) || s->mode < CF_NORMAL || s->mode > CF_SAFE)
        return STATE_INVALID("module %d, direction %d, vDir %g, fallback counts or mode %d out of range",
                             e->module, e->direction, e->vDir, s->mode);
    if (!finite_all((const double *)&e->g, sizeof e->g / sizeof(double)) ||
        !finite_all((const double *)&e->f, sizeof e->f / sizeof(double)) || !finite_all(e->calc, 2))
        return STATE_INVALID("a parameter, lag state or angle is not finite");
    if (!sample_index_ok(s->t0, s->k, d->Ts, time))
        return STATE_INVALID("sample k = %lld from t0 = %g (Ts = %g s) is not near t = %g s", s->k, s->t0, d->Ts, time);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
