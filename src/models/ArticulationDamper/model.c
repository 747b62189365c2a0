/* ArticulationDamper: the two-cylinder articulation damper of seed 001 (1.3.1,
 * App. B; damper.c) between BusDynamics (artAngle[1], artRate[1] in, Mjoint[1]
 * out) and a damping controller (pct in, Mmax out).
 *
 * The inputs are held over a step. The hydraulic torque is static as in the
 * thesis (tauP = 0) or follows the valve pressure, whose first-order lag
 * tauP is solved exactly over the step (no solver). The dissipated energy is
 * integrated exactly over each step with the inputs held. */
#include <math.h>
#include <string.h>

#include "fmu.h"
#include "damper.h"

#define S (&comp->v.s)

/* the valve pressure now: the lag's state, or the set pressure when static */
static double valve_pressure(ModelInstance *comp) {
    return damper_valve(&S->par, S->pValve, D->pct, D->tauP);
}

/* the damper's parameters from the variables */
static DamperParams damper_params(const ModelData *d) {
    DamperParams p;
    memset(&p, 0, sizeof p);
    p.R = d->R;
    p.Xrear = d->Xrear;
    p.Yrear = d->Yrear;
    p.Ap = d->Ap;
    p.pMax = d->pMax;
    p.v0 = d->v0;
    p.LambdaStop = d->LambdaStop;
    p.kStop = d->kStop;
    p.cStop = d->cStop;
    p.bothWays = d->bothWays ? 1 : 0;
    return p;
}

Status model_check_parameters(ModelInstance *comp) {
    const DamperParams p = damper_params(D);
    double Lshort, at;
    const int side = damper_check(&p, &Lshort, &at);
    if (side)
        return log_error(comp, "geometry R = %g m, Xrear = %g m, Yrear = %g m: the %s cylinder would be "
                               "%g m long at Lambda = %g rad (%g deg), shorter than %g m (or through zero "
                               "length), within |Lambda| <= LambdaStop + %g = %g rad (LambdaStop = %g rad)",
                         D->R, D->Xrear, D->Yrear, side > 0 ? "left" : "right", Lshort, at,
                         at * 180.0 / M_PI, DAMPER_L_MIN, DAMPER_CHECK_MARGIN,
                         D->LambdaStop + DAMPER_CHECK_MARGIN, D->LambdaStop);
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    S->par = damper_params(D);
    const DamperParams *p = &S->par;
    S->pValve = damper_pset(p, D->pct);      /* the valve settled at the initial command */
    S->Ediss = 0.0;
    S->warned = 0;
    return OK;
}

/* damper_outputs' out[] into d: the values into the model's variables, or
   their derivatives along a seed into the tangent of
   model_directional_derivative */
static void store_outputs(ModelData *d, const double out[DAMPER_NOUT]) {
    d->Mjoint = out[DAMPER_OUT_MJOINT];
    for (int i = 1; i <= 2; i++) {
        d->F[i] = out[DAMPER_OUT_F + i - 1];
        d->p[i] = out[DAMPER_OUT_P + i - 1];
        d->L[i] = out[DAMPER_OUT_L + i - 1];
        d->Ldot[i] = out[DAMPER_OUT_LDOT + i - 1];
    }
    d->Mmax = out[DAMPER_OUT_MMAX];
    d->der_pValve = out[DAMPER_OUT_DPVALVE];
    d->der_Ediss = out[DAMPER_OUT_DEDISS];
}

void model_outputs(ModelInstance *comp) {
    double out[DAMPER_NOUT];
    damper_outputs(&S->par, D->Lambda, D->LambdaDot, D->pct, D->tauP, S->pValve, out);
    store_outputs(D, out);
    /* the Model Exchange states */
    D->Ediss = S->Ediss;
    D->pValve = S->pValve;
}

/* Forward mode through damper.c on dual numbers (damper_dual.cpp): the seed of
 * the inputs Lambda, LambdaDot, pct and the states pValve, Ediss (on which
 * nothing but Ediss itself depends) */
Status model_directional_derivative(ModelInstance *comp, const ModelData *seed, ModelData *tangent) {
    double out[DAMPER_NOUT], dout[DAMPER_NOUT];
    damper_outputs_tangent(&S->par, D->Lambda, seed->Lambda, D->LambdaDot, seed->LambdaDot, D->pct, seed->pct,
                           D->tauP, S->pValve, seed->pValve, out, dout);
    store_outputs(tangent, dout);
    return OK;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    Status status = OK;
    const double pv = valve_pressure(comp);
    DamperOut o;
    if (damper_eval(&S->par, D->Lambda, D->LambdaDot, pv, &o) && !S->warned) {
        S->warned = 1;
        log_warning(comp, "t = %g s: Lambda = %g rad: a cylinder would be shorter than %g m (beyond the "
                          "end stop at LambdaStop = %g rad); its length is held at %g m (warned once)",
                    t, D->Lambda, DAMPER_L_MIN, D->LambdaStop, DAMPER_L_MIN);
        status = Warning;
    }
    double pInt;
    const double pNew = damper_pressure_step(pv, damper_pset(&S->par, D->pct), D->tauP, h, &pInt);
    S->Ediss += damper_step_energy(&o, D->LambdaDot, pInt, h);
    S->pValve = pNew;
    comp->v.time = t + h;
    return status;
}

void model_free(ModelInstance *comp) { (void)comp; }

/* FMU state: parameters (from model_init), valve pressure, dissipated energy */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)time;
    const DamperParams *p = &s->par;
    const DamperParams q = damper_params(d);      /* the parameters model_init copied */
    if (p->R != q.R || p->Xrear != q.Xrear || p->Yrear != q.Yrear || p->Ap != q.Ap || p->pMax != q.pMax ||
        p->v0 != q.v0 || p->LambdaStop != q.LambdaStop || p->kStop != q.kStop || p->cStop != q.cStop ||
        p->bothWays != q.bothWays)
        return STATE_INVALID("the damper's parameters are not those of its variables");
    if (!finite_all(&p->R, (size_t)(&p->cStop - &p->R) + 1) || !isfinite(s->pValve) || !isfinite(s->Ediss))
        return STATE_INVALID("a parameter, the valve pressure or the energy is not finite");
    if ((p->bothWays != 0 && p->bothWays != 1) || (s->warned != 0 && s->warned != 1))
        return STATE_INVALID("bothWays = %d, warned = %d", p->bothWays, s->warned);
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }

/* ---- Model Exchange: x = [pValve, Ediss]. Co-simulation solves the valve lag
 * in closed form over a step with the inputs held (damper_pressure_step) and
 * integrates the power exactly (damper_step_energy); here an outside
 * integrator gets the ODE that closed form solves and the power itself. The
 * event indicators mark the end stop (Lambda = +-LambdaStop) and the reversal
 * of the motion (LambdaDot = 0: the check valves and the stop damper switch). */

void model_get_x(ModelInstance *comp, double x[]) {
    x[0] = S->pValve;
    x[1] = S->Ediss;
}

void model_set_x(ModelInstance *comp, const double x[]) {
    S->pValve = x[0];
    S->Ediss = x[1];
}

Status model_derivatives(ModelInstance *comp, double dx[]) {
    double out[DAMPER_NOUT];
    damper_outputs(&S->par, D->Lambda, D->LambdaDot, D->pct, D->tauP, S->pValve, out);
    dx[0] = out[DAMPER_OUT_DPVALVE];
    dx[1] = out[DAMPER_OUT_DEDISS];
    return OK;
}

void model_event_indicators(ModelInstance *comp, double z[]) {
    z[0] = D->Lambda - D->LambdaStop;
    z[1] = D->Lambda + D->LambdaStop;
    z[2] = D->LambdaDot;
}

Status model_event_update(ModelInstance *comp, bool *terminate, double *tNext) {
    (void)comp;
    *terminate = false;
    *tNext = INFINITY;
    return OK;
}
