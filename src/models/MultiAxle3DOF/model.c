/* MultiAxle3DOF: seed 004, eqs. 1-5 (lateral3dof.c), integrated with CVODE
 * inside doStep, plus the heading and the path of the origin. */
#include <math.h>
#include <stdlib.h>

#include "fmu.h"
#include "ode.h"
#include "lateral3dof.h"

typedef struct {
    ModelInstance *comp;
    Ode *ode;
    MaVehicle veh;
    MaMass mm;
    double u;                           /* speed used in the equations, >= uMin */
    double delta[MA_MAX_AXLES + 1];     /* steering angles over the current segment */
    double Md;
} Solver;

static void make_vehicle(ModelInstance *comp, MaVehicle *veh) {
    veh->n = D->n;
    for (int i = 1; i <= MA_MAX_AXLES; i++) {
        veh->l[i] = D->l[i];
        veh->k[i] = D->k[i];
        veh->m[i] = D->m[i];
        veh->d[i] = D->d[i];
    }
    veh->m_b = D->m_b;
    veh->h_b = D->h_b;
    veh->I_ZZb = D->I_ZZb;
    veh->I_XXb = D->I_XXb;
    veh->I_XZb = D->I_XZb;
    veh->C_phi = D->C_phi;
    veh->K_phi = D->K_phi;
}

/* below uMin the linear model is not defined (it divides by u) */
static double speed(ModelInstance *comp) {
    return D->u >= D->uMin ? D->u : D->uMin;
}

/* communication points this close to testSteerTime count as on it */
static double step_tol(ModelInstance *comp) {
    return 1e-9 * fmax(1.0, fabs(D->testSteerTime));
}

/* the steering angles acting from time t on: fixed axles 0, plus the test step */
static void steering(ModelInstance *comp, double t, double delta[]) {
    for (int i = 1; i <= MA_MAX_AXLES; i++) delta[i] = D->steerable[i] ? D->delta[i] : 0.0;
    if (D->testSteerAmp != 0.0 && t >= D->testSteerTime - step_tol(comp))
        delta[1] += D->testSteerAmp;
}

Status model_check_parameters(ModelInstance *comp) {
    MaVehicle veh;
    MaMass mm;
    make_vehicle(comp, &veh);
    if (ma_prepare(&veh, &mm))
        return log_error(comp, "the mass matrix of eq. 2 (m_b = %g kg, I_ZZb = %g, I_XXb = %g, "
                               "I_XZb = %g kg m2, h_b = %g m) is not positive definite",
                         D->m_b, D->I_ZZb, D->I_XXb, D->I_XZb, D->h_b);
    if (!(D->K_phi > D->m_b * MA_G * D->h_b))
        return log_error(comp, "K_phi = %g N m/rad must exceed m_b g h_b = %g N m/rad, or the body "
                               "rolls over under its own weight (eq. 2, third row)",
                         D->K_phi, D->m_b * MA_G * D->h_b);
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    MaVehicle veh;
    MaMass mm;
    make_vehicle(comp, &veh);
    ma_prepare(&veh, &mm);
    D->w_r = D->v = D->p = D->phi = D->psi = D->x = D->y = 0.0;
    comp->v.s.warnedSpeed = 0;
    log_event(comp, "n = %d axles, M = %g kg, sum m_i l_i = %g kg m, I_ZZ = %g kg m2, I_XX = %g kg m2",
              D->n, mm.M, mm.sum_ml, mm.I_ZZ, mm.I_XX);
    return OK;
}

/* the outputs and derivatives of ma_outputs' out[] into d: the values into the
   model's variables, or their derivatives into the tangent of
   model_directional_derivative (the states' own fields are not touched) */
static void store_outputs(ModelData *d, const double out[MA_NOUT]) {
    d->der_w_r = out[MA_OUT_YDOT + 0];
    d->der_v = out[MA_OUT_YDOT + 1];
    d->der_p = out[MA_OUT_YDOT + 2];
    d->der_x = out[MA_OUT_YDOT + 5];
    d->der_y = out[MA_OUT_YDOT + 6];
    d->beta = out[MA_OUT_BETA];
    d->a_y = out[MA_OUT_AY];
    for (int i = 1; i <= MA_MAX_AXLES; i++) {
        d->alpha[i] = out[MA_OUT_ALPHA + i - 1];
        d->F_Y[i] = out[MA_OUT_FY + i - 1];
    }
}

void model_outputs(ModelInstance *comp) {
    MaVehicle veh;
    MaMass mm;
    make_vehicle(comp, &veh);
    ma_prepare(&veh, &mm);
    double delta[MA_MAX_AXLES + 1], y[7], out[MA_NOUT];
    steering(comp, comp->v.time, delta);
    model_get_x(comp, y);
    ma_outputs(&veh, &mm, speed(comp), delta, D->M_d, y, out);
    store_outputs(D, out);
}

/* Forward mode through lateral3dof.c on dual numbers (lateral3dof_dual.cpp).
 * The knowns act as in model_outputs: u only at or above uMin (below, the
 * equations take the constant uMin), delta[i] only on a steerable axle. */
Status model_directional_derivative(ModelInstance *comp, const ModelData *seed, ModelData *tangent) {
    MaVehicle veh;
    MaMass mm;
    make_vehicle(comp, &veh);
    ma_prepare(&veh, &mm);
    double delta[MA_MAX_AXLES + 1], ddelta[MA_MAX_AXLES + 1] = { 0 }, y[7], dy[7];
    double out[MA_NOUT], dout[MA_NOUT];
    steering(comp, comp->v.time, delta);
    for (int i = 1; i <= MA_MAX_AXLES; i++) ddelta[i] = D->steerable[i] ? seed->delta[i] : 0.0;
    model_get_x(comp, y);
    dy[0] = seed->w_r; dy[1] = seed->v; dy[2] = seed->p; dy[3] = seed->phi;
    dy[4] = seed->psi; dy[5] = seed->x; dy[6] = seed->y;
    ma_outputs_tangent(&veh, &mm, speed(comp), D->u >= D->uMin ? seed->u : 0.0, delta, ddelta,
                       D->M_d, seed->M_d, y, dy, out, dout);
    store_outputs(tangent, dout);
    return OK;
}

/* y = [w_r, v, p, phi, psi, x, y] */
static int rhs(double t, const double *y, double *ydot, void *user) {
    (void)t;
    Solver *s = user;
    ma_rhs(&s->veh, &s->mm, s->u, s->delta, s->Md, y, ydot);
    return 0;
}

static Status advance(ModelInstance *comp, Solver *s, bool restart, double t0, double t1) {
    double y[7] = { D->w_r, D->v, D->p, D->phi, D->psi, D->x, D->y };
    double tret;
    const OdeResult res = ode_advance(s->ode, restart, t0, y, t1, &tret, NULL);
    D->w_r = y[0]; D->v = y[1]; D->p = y[2]; D->phi = y[3];
    D->psi = y[4]; D->x = y[5]; D->y = y[6];
    if (res != ODE_REACHED) {
        comp->v.time = tret;
        return Error;               /* already logged with the CVODE flag and time */
    }
    comp->v.time = t1;
    return OK;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    Solver *s = comp->solver;
    if (!s) {
        s = comp->solver = calloc(1, sizeof(Solver));
        if (!s) return log_error(comp, "out of memory");
        s->comp = comp;
        s->ode = ode_new(comp, 7, rhs, 0, NULL, s, ODE_BDF, D->rtol, D->atol);
        if (!s->ode) return Error;
    }
    make_vehicle(comp, &s->veh);
    ma_prepare(&s->veh, &s->mm);

    Status status = OK;
    if (D->u < D->uMin && !comp->v.s.warnedSpeed) {
        comp->v.s.warnedSpeed = 1;
        log_warning(comp, "u = %g m/s is below uMin = %g m/s at t = %g s: the linear model divides "
                          "by u (eq. 2) and is evaluated at u = uMin while u < uMin (warned once "
                          "per episode)", D->u, D->uMin, t);
        status = Warning;
    }
    s->u = speed(comp);
    s->Md = D->M_d;

    /* the test step inside this step: integrate up to it, restart after it */
    const double ts = D->testSteerTime, t1 = t + h, tol = step_tol(comp);
    bool restart = comp->restart;
    if (D->testSteerAmp != 0.0 && t < ts - tol && ts < t1 - tol) {
        steering(comp, t, s->delta);
        if (advance(comp, s, restart, t, ts)) return Error;
        log_event(comp, "test step steer of %g rad on delta[1] at t = %g s", D->testSteerAmp, ts);
        restart = true;
        t = ts;
    }
    double delta[MA_MAX_AXLES + 1];
    steering(comp, t, delta);
    for (int i = 1; i <= MA_MAX_AXLES; i++) {
        if (delta[i] != s->delta[i]) restart = true;    /* the test step began at t */
        s->delta[i] = delta[i];
    }
    if (advance(comp, s, restart, t, t1)) return Error;
    return status;
}

void model_free(ModelInstance *comp) {
    const Solver *s = comp->solver;
    if (s) ode_free_solver(comp, s->ode);
}

/* ---- Model Exchange: x = [w_r, v, p, phi, psi, x, y], the CVODE state of
 * doStep, and the same right-hand side rhs() with the inputs of this instant */

void model_get_x(ModelInstance *comp, double x[]) {
    x[0] = D->w_r; x[1] = D->v; x[2] = D->p; x[3] = D->phi;
    x[4] = D->psi; x[5] = D->x; x[6] = D->y;
}

void model_set_x(ModelInstance *comp, const double x[]) {
    D->w_r = x[0]; D->v = x[1]; D->p = x[2]; D->phi = x[3];
    D->psi = x[4]; D->x = x[5]; D->y = x[6];
}

Status model_derivatives(ModelInstance *comp, double dx[]) {
    Solver s;
    s.comp = comp;
    make_vehicle(comp, &s.veh);
    ma_prepare(&s.veh, &s.mm);
    s.u = speed(comp);
    s.Md = D->M_d;
    steering(comp, comp->v.time, s.delta);
    double x[7];
    model_get_x(comp, x);
    return rhs(comp->v.time, x, dx, &s) ? Error : OK;
}

void model_event_indicators(ModelInstance *comp, double z[]) { (void)comp; (void)z; }

/* the built-in test step steer is a time event */
Status model_event_update(ModelInstance *comp, bool *terminate, double *tNext) {
    *terminate = false;
    const double ts = D->testSteerTime;
    *tNext = D->testSteerAmp != 0.0 && comp->v.time < ts - step_tol(comp) ? ts : INFINITY;
    return OK;
}

/* FMU state: a warning flag; the integrator is made again at the next step */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)d; (void)time;
    if (s->warnedSpeed != 0 && s->warnedSpeed != 1) return STATE_INVALID("warnedSpeed = %d", s->warnedSpeed);
    return true;
}

Status model_restored(ModelInstance *comp) {
    model_free(comp);
    return OK;
}
