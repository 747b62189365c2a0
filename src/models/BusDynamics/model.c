/* BusDynamics: seed 000, section II as an FMU. The mechanics and the tyre
 * models are in dynamics.cpp (Eigen, no FMI types); this file is the FMI glue:
 * parameter checks, the initial state, outputs and CVODE inside doStep. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmu.h"
#include "ode.h"
#include "dynamics.h"

#define GRAVITY 9.81

/* d(der x)/dx at one point, all its columns from one vector-mode pass: an
   importer integrating the model asks for it a column at a time (one
   fmi2GetDirectionalDerivative per state, unknowns the derivatives), the later
   columns are read from here while the point is the same: no value set from
   outside (the layer's generation), the same time and states */
typedef struct {
    bool valid;
    unsigned long generation;
    double time, z[DYN_MAX_Q], zd[DYN_MAX_Q];
    DynParams p;
    double dzdd[2 * DYN_MAX_Q][DYN_MAX_Q];
} JacobianCache;

typedef struct {
    ModelInstance *comp;
    Ode *ode;           /* doStep's integrator (Co-Simulation), made at the first step */
    DynParams p;
    DynInputs u;        /* the inputs of the current step */
    bool uHeld;         /* they hold over the step (no test steering): rhs() reuses them */
    JacobianCache jac;  /* Model Exchange: model_directional_derivative's d(der x)/dx */
} Solver;

/* comp->solver, made on first use (doStep or the Jacobian) */
static Solver *solver_of(ModelInstance *comp) {
    if (!comp->solver) {
        Solver *sv = comp->solver = calloc(1, sizeof(Solver));
        if (!sv) return NULL;
        sv->comp = comp;
    }
    return comp->solver;
}

static void make_params(ModelInstance *comp, DynParams *p) {
    memset(p, 0, sizeof *p);
    p->nMod = D->nModules;
    p->nAxle = D->nAxles;
    for (int m = 1; m <= DYN_MAX_MODULES; m++) {
        p->m[m] = D->m[m];
        p->J[m] = D->Jz[m];
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) {
        p->lHf[k] = D->lHf[k];
        p->lHr[k] = D->lHr[k];
    }
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        p->axleModule[a] = D->axleModule[a];
        p->xA[a] = D->xA[a];
        p->C[a] = D->C[a];
        p->mu[a] = D->mu[a];
        p->Fz[a] = D->FzFromMasses ? 0.0 : D->Fz0[a];
    }
    p->tyreModel = D->tyreModel;
    p->vSlip = D->vSlip;
    for (int m = 1; m <= DYN_MAX_MODULES; m++) {
        p->lFront[m] = D->lFront[m];
        p->lRear[m] = D->lRear[m];
        p->width[m] = D->width[m];
    }
}

/* the inputs plus the built-in test steering (a lane change for running alone) */
static void make_inputs(ModelInstance *comp, double t, DynInputs *u) {
    memset(u, 0, sizeof *u);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        u->delta[a] = D->delta[a];
        u->Fx[a] = D->Fx[a];
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) u->Mjoint[k] = D->Mjoint[k];
    u->delta[1] += test_sine(D->testSteerAmp, D->testSteerPeriod, t);
    dyn_steer(u, D->nAxles);
}

static Status check_inputs(ModelInstance *comp, double t) {
    const double stim = t < D->testSteerPeriod ? fabs(D->testSteerAmp) : 0.0;
    for (int a = 1; a <= D->nAxles; a++) {
        const double s = a == 1 ? stim : 0.0;
        if (!(fabs(D->delta[a]) + s < M_PI / 2))
            return log_error(comp, "delta[%d] = %.12g rad (with test steering amplitude %g) is at or "
                                   "beyond pi/2: the wheel would stand across its module", a, D->delta[a], s);
    }
    return OK;
}

Status model_check_parameters(ModelInstance *comp) {
    const int N = D->nModules;
    for (int m = 1; m <= N; m++) {
        if (!(D->m[m] > 0)) return log_error(comp, "m[%d] = %.12g kg: a module mass must be > 0", m, D->m[m]);
        if (!(D->Jz[m] > 0)) return log_error(comp, "Jz[%d] = %.12g kg.m2: a yaw inertia must be > 0", m, D->Jz[m]);
        if (!(D->lFront[m] >= 0)) return log_error(comp, "lFront[%d] = %.12g m: a length must be >= 0", m, D->lFront[m]);
        if (!(D->lRear[m] >= 0)) return log_error(comp, "lRear[%d] = %.12g m: a length must be >= 0", m, D->lRear[m]);
        if (!(D->width[m] >= 0)) return log_error(comp, "width[%d] = %.12g m: a length must be >= 0", m, D->width[m]);
    }
    for (int k = 1; k < N; k++) {
        if (!(D->lHf[k] >= 0)) return log_error(comp, "lHf[%d] = %.12g m: a length must be >= 0", k, D->lHf[k]);
        if (!(D->lHr[k] >= 0)) return log_error(comp, "lHr[%d] = %.12g m: a length must be >= 0", k, D->lHr[k]);
    }
    for (int a = 1; a <= D->nAxles; a++) {
        if (D->axleModule[a] > N)
            return log_error(comp, "axleModule[%d] = %d: axle %d is on a module that does not exist "
                                   "(nModules = %d)", a, D->axleModule[a], a, N);
        if (!(D->C[a] >= 0)) return log_error(comp, "C[%d] = %.12g N/rad: a cornering stiffness must be >= 0", a, D->C[a]);
        if (!(D->mu[a] > 0)) return log_error(comp, "mu[%d] = %.12g: a friction coefficient must be > 0", a, D->mu[a]);
        if (!D->FzFromMasses && !(D->Fz0[a] >= 0))
            return log_error(comp, "Fz0[%d] = %.12g N: an axle load must be >= 0", a, D->Fz0[a]);
    }
    if (!(D->vSlip > 0)) return log_error(comp, "vSlip = %.12g m/s: must be > 0", D->vSlip);
    /* a parameter that does not act in this configuration is said so (issue 15) */
    if (D->tyreModel == 0)
        for (int a = 1; a <= D->nAxles; a++)
            if (D->mu[a] != 1.0)
                log_warning(comp, "mu[%d] = %g has no effect: tyreModel 0 is the linear tyre Fy = C alpha "
                                  "without friction (seed 000, eq. 24); use tyreModel 1, 2 or 3", a, D->mu[a]);
    return OK;
}

/* static axle loads into D->Fz */
static Status static_loads(ModelInstance *comp, DynParams *p) {
    if (D->FzFromMasses) {
        const int m = dyn_static_loads(p, GRAVITY);
        if (m)
            return log_error(comp, "module %d: static axle loads cannot be found from masses and "
                                   "geometry (fewer than two supports, supports at one point, or a "
                                   "negative load); set FzFromMasses = false and give Fz0[]", m);
    }
    for (int a = 1; a <= DYN_MAX_AXLES; a++) D->Fz[a] = a <= p->nAxle ? p->Fz[a] : 0.0;
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp) || check_inputs(comp, comp->v.time)) return Error;
    DynParams p;
    make_params(comp, &p);
    if (static_loads(comp, &p)) return Error;

    /* the initial state: pose of module 1 and the yaw angles, velocity of the
       CG of module 1 given in its own frame */
    ModelState *s = &comp->v.s;
    memset(s, 0, sizeof *s);
    D->nRhs = 0.0;
    s->z[0] = D->x_start;
    s->z[1] = D->y_start;
    for (int m = 1; m <= D->nModules; m++) {
        s->z[1 + m] = D->psi_start[m];
        s->zd[1 + m] = D->r_start[m];
    }
    const double c = cos(D->psi_start[1]), sn = sin(D->psi_start[1]);
    s->zd[0] = c * D->vx_start - sn * D->vy_start;
    s->zd[1] = sn * D->vx_start + c * D->vy_start;
    return OK;
}

/* the Model Exchange states z, zd and their derivatives zd, zdd (nq of each) into d */
static void store_states(ModelData *d, int nq, const double *z, const double *zd, const double *zdd) {
    for (int i = 0; i < DYN_MAX_Q; i++) {
        const int on = i < nq;
        d->z[i + 1] = on ? z[i] : 0.0;
        d->zd[i + 1] = on ? zd[i] : 0.0;
        d->zdd[i + 1] = on ? zdd[i] : 0.0;
    }
}

/* the outputs from dyn_eval's o, the coordinates z, rates zd and their
   derivatives zdd into d: the values into the model's variables, or their
   derivatives along a seed into the tangent of model_directional_derivative */
static void store_outputs(ModelData *d, const DynParams *p, const DynOut *o, const double *z,
                          const double *zd, const double *zdd) {
    const int N = p->nMod;
    for (int m = 1; m <= DYN_MAX_MODULES; m++) {
        const int on = m <= N;          /* modules beyond nModules read 0 */
        d->x[m] = on ? o->xCG[m] : 0.0;
        d->y[m] = on ? o->yCG[m] : 0.0;
        d->psi[m] = on ? z[1 + m] : 0.0;
        d->vx[m] = on ? o->vx[m] : 0.0;
        d->vy[m] = on ? o->vy[m] : 0.0;
        d->r[m] = on ? zd[1 + m] : 0.0;
        d->ay[m] = on ? o->ay[m] : 0.0;
        for (int c = 1; c <= 4; c++) {
            const int i = 4 * (m - 1) + c;
            d->xCorner[i] = on ? o->xCorner[i] : 0.0;
            d->yCorner[i] = on ? o->yCorner[i] : 0.0;
        }
    }
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        const int on = a <= p->nAxle;
        d->xAxle[a] = on ? o->xAxle[a] : 0.0;
        d->yAxle[a] = on ? o->yAxle[a] : 0.0;
        d->alpha[a] = on ? o->alpha[a] : 0.0;
        d->Fy[a] = on ? o->Fy[a] : 0.0;
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) {
        const int on = k < N;
        d->artAngle[k] = on ? z[1 + k] - z[2 + k] : 0.0;
        d->artRate[k] = on ? zd[1 + k] - zd[2 + k] : 0.0;
        d->FjointX[k] = on ? o->FjX[k] : 0.0;
        d->FjointY[k] = on ? o->FjY[k] : 0.0;
    }
    d->v = o->v;
    store_states(d, dyn_nq(p), z, zd, zdd);
}

void model_outputs(ModelInstance *comp) {
    const ModelState *s = &comp->v.s;
    DynParams p;
    make_params(comp, &p);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) p.Fz[a] = D->Fz[a];
    DynInputs u;
    make_inputs(comp, comp->v.time, &u);
    DynOut o;
    memset(&o, 0, sizeof o);
    double zdd[DYN_MAX_Q];
    dyn_eval(&p, &u, s->z, s->zd, zdd, &o);
    store_outputs(D, &p, &o, s->z, s->zd, zdd);
}

/* the one state whose seed is not 0 when nothing else is seeded (a column of
   the Jacobian, or a multiple of one): its index j into [z, zd] (0 .. 2 nq);
   NO_SEED when no state of the chain and no input is seeded (the padding
   states beyond nModules are held at 0: their columns are 0), else -1 */
#define NO_SEED (-2)
static int single_state_seed(const ModelData *seed, int nq) {
    for (int a = 1; a <= DYN_MAX_AXLES; a++)
        if (seed->delta[a] != 0.0 || seed->Fx[a] != 0.0) return -1;
    for (int k = 1; k <= DYN_MAX_HINGES; k++)
        if (seed->Mjoint[k] != 0.0) return -1;
    int j = NO_SEED;
    for (int i = 0; i < 2 * nq; i++)
        if ((i < nq ? seed->z[i + 1] : seed->zd[i - nq + 1]) != 0.0) {
            if (j != NO_SEED) return -1;
            j = i;
        }
    return j;
}

/* the cache at this point: filled by one vector-mode pass (dyn_eval_jacobian)
   when the point moved */
static const JacobianCache *jacobian_at(ModelInstance *comp) {
    const ModelState *st = &comp->v.s;
    Solver *sv = solver_of(comp);
    if (!sv) return log_error(comp, "out of memory"), NULL;
    JacobianCache *c = &sv->jac;
    const size_t nz = sizeof(double) * DYN_MAX_Q;
    if (c->valid && c->generation == comp->generation && c->time == comp->v.time && !memcmp(c->z, st->z, nz)
        && !memcmp(c->zd, st->zd, nz))
        return c;
    DynInputs u;
    double zdd[DYN_MAX_Q];
    make_params(comp, &c->p);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) c->p.Fz[a] = D->Fz[a];
    make_inputs(comp, comp->v.time, &u);
    c->valid = false;
    if (dyn_eval_jacobian(&c->p, &u, st->z, st->zd, zdd, c->dzdd))
        return log_error(comp, "t = %.17g: the mass matrix of the equations of motion is not "
                               "positive definite", comp->v.time), NULL;
    c->generation = comp->generation;
    c->time = comp->v.time;
    memcpy(c->z, st->z, nz);
    memcpy(c->zd, st->zd, nz);
    c->valid = true;
    return c;
}

/* column j of d(der x)/dx times s into the tangent's states and derivatives */
static Status jacobian_column(ModelInstance *comp, int j, double s, ModelData *tangent) {
    const JacobianCache *c = jacobian_at(comp);
    if (!c) return Error;
    const int nq = dyn_nq(&c->p);
    double dz[DYN_MAX_Q] = { 0 }, dzd[DYN_MAX_Q] = { 0 }, dzdd[DYN_MAX_Q] = { 0 };
    if (j < nq) dz[j] = s;
    else dzd[j - nq] = s;
    for (int i = 0; i < nq; i++) dzdd[i] = s * c->dzdd[j][i];
    store_states(tangent, nq, dz, dzd, dzdd);
    return OK;
}

/* Forward mode through dynamics.cpp on dual numbers (dyn_eval_tangent): the
 * seed of the states z[i], zd[i] and of the inputs delta, Fx, Mjoint. A seed
 * of one state alone (a column of the Jacobian) from jacobian_column. */
Status model_directional_derivative(ModelInstance *comp, const ModelData *seed, ModelData *tangent) {
    if (check_inputs(comp, comp->v.time)) return Error;
    const int nq = 2 + D->nModules, j = single_state_seed(seed, nq);
    double dz[DYN_MAX_Q] = { 0 }, dzd[DYN_MAX_Q] = { 0 }, zdd[DYN_MAX_Q], dzdd[DYN_MAX_Q] = { 0 };
    if (j >= 0 && !comp->ddOutputs)      /* a column of d(der x)/dx: no output asked */
        return jacobian_column(comp, j, j < nq ? seed->z[j + 1] : seed->zd[j - nq + 1], tangent);
    if (j == NO_SEED && !comp->ddOutputs) {      /* a padding state's column, or a zero seed */
        store_states(tangent, nq, dz, dzd, dzdd);
        return OK;
    }
    const ModelState *s = &comp->v.s;
    DynParams p;
    make_params(comp, &p);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) p.Fz[a] = D->Fz[a];
    DynOut o, dout;
    memset(&dout, 0, sizeof dout);
    if (j == NO_SEED) {
        store_outputs(tangent, &p, &dout, dz, dzd, dzdd);
        return OK;
    }
    DynInputs u, du;
    make_inputs(comp, comp->v.time, &u);
    memset(&du, 0, sizeof du);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        du.delta[a] = seed->delta[a];
        du.Fx[a] = seed->Fx[a];
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) du.Mjoint[k] = seed->Mjoint[k];
    for (int i = 0; i < nq; i++) {      /* states beyond nModules are held at 0 */
        dz[i] = seed->z[i + 1];
        dzd[i] = seed->zd[i + 1];
    }
    memset(&o, 0, sizeof o);
    if (dyn_eval_tangent(&p, &u, &du, s->z, dz, s->zd, dzd, zdd, dzdd, &o, &dout))
        return log_error(comp, "t = %.17g: the mass matrix of the equations of motion is not "
                               "positive definite", comp->v.time);
    store_outputs(tangent, &p, &dout, dz, dzd, dzdd);
    return OK;
}

/* ODE state y = [z, z'] */
static int rhs(double t, const double *y, double *ydot, void *user) {
    Solver *sv = user;
    const int nq = dyn_nq(&sv->p);
    if (!sv->uHeld) make_inputs(sv->comp, t, &sv->u);
    memcpy(ydot, y + nq, sizeof(double) * (size_t)nq);
    return dyn_eval(&sv->p, &sv->u, y, y + nq, ydot + nq, NULL) ? -1 : 0;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    if (check_inputs(comp, t)) return Error;
    Solver *sv = solver_of(comp);
    if (!sv) return log_error(comp, "out of memory");
    if (!sv->ode) {
        sv->ode = ode_new(comp, 2 * (2 + D->nModules), rhs, 0, NULL, sv,
                          D->solver == 2 ? ODE_ERK : D->solver == 1 ? ODE_ADAMS : ODE_BDF,
                          D->rtol, D->atol);
        if (!sv->ode) return Error;
    }
    make_params(comp, &sv->p);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) sv->p.Fz[a] = D->Fz[a];
    /* the inputs hold over the step unless the built-in test steering runs */
    make_inputs(comp, t, &sv->u);
    sv->uHeld = D->testSteerAmp == 0.0 || t >= D->testSteerPeriod;

    ModelState *s = &comp->v.s;
    const int nq = dyn_nq(&sv->p);
    double y[2 * DYN_MAX_Q];
    memcpy(y, s->z, sizeof(double) * (size_t)nq);
    memcpy(y + nq, s->zd, sizeof(double) * (size_t)nq);
    const long n0 = ode_nrhs(sv->ode);
    double tret;
    const OdeResult res = ode_advance(sv->ode, comp->restart, t, y, t + h, &tret, NULL);
    D->nRhs += (double)(ode_nrhs(sv->ode) - n0);
    memcpy(s->z, y, sizeof(double) * (size_t)nq);
    memcpy(s->zd, y + nq, sizeof(double) * (size_t)nq);
    if (res == ODE_REACHED) {
        comp->v.time = t + h;
        return OK;
    }
    comp->v.time = tret;
    return Error;   /* CVODE failure, already logged with its flag and time */
}

void model_free(ModelInstance *comp) {
    const Solver *sv = comp->solver;
    if (sv) ode_free_solver(comp, sv->ode);
}

/* ---- Model Exchange: x = [z_1 .. z_6, z'_1 .. z'_6], the CVODE state of
 * doStep ([z, z'] of length 2 nq) padded to DYN_MAX_Q, with the same
 * right-hand side rhs() at this instant */

void model_get_x(ModelInstance *comp, double x[]) {
    const ModelState *s = &comp->v.s;
    for (int i = 0; i < DYN_MAX_Q; i++) {
        x[i] = s->z[i];
        x[DYN_MAX_Q + i] = s->zd[i];
    }
}

void model_set_x(ModelInstance *comp, const double x[]) {
    ModelState *s = &comp->v.s;
    const int nq = 2 + D->nModules;
    for (int i = 0; i < DYN_MAX_Q; i++) {      /* beyond nModules: 0 */
        s->z[i] = i < nq ? x[i] : 0.0;
        s->zd[i] = i < nq ? x[DYN_MAX_Q + i] : 0.0;
    }
}

Status model_derivatives(ModelInstance *comp, double dx[]) {
    if (check_inputs(comp, comp->v.time)) return Error;
    Solver sv = { .comp = comp, .uHeld = false };
    make_params(comp, &sv.p);
    for (int a = 1; a <= DYN_MAX_AXLES; a++) sv.p.Fz[a] = D->Fz[a];
    const ModelState *s = &comp->v.s;
    const int nq = dyn_nq(&sv.p);
    double y[2 * DYN_MAX_Q], ydot[2 * DYN_MAX_Q];
    memcpy(y, s->z, sizeof(double) * (size_t)nq);
    memcpy(y + nq, s->zd, sizeof(double) * (size_t)nq);
    if (rhs(comp->v.time, y, ydot, &sv))
        return log_error(comp, "t = %.17g: the mass matrix of the equations of motion is not "
                               "positive definite", comp->v.time);
    for (int i = 0; i < 2 * DYN_MAX_Q; i++) dx[i] = 0.0;
    for (int i = 0; i < nq; i++) {
        dx[i] = ydot[i];
        dx[DYN_MAX_Q + i] = ydot[nq + i];
    }
    return OK;
}

void model_event_indicators(ModelInstance *comp, double z[]) { (void)comp; (void)z; }

Status model_event_update(ModelInstance *comp, bool *terminate, double *tNext) {
    (void)comp;
    *terminate = false;
    *tNext = INFINITY;
    return OK;
}

/* FMU state: the coordinates and their rates; the integrator (its size from
 * nModules) is made again at the next step */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)time;
    if (!finite_all(s->z, 6) || !finite_all(s->zd, 6)) return STATE_INVALID("a coordinate z or rate zd is not finite");
    (void)d;     /* its parameters: model_check_parameters, which the layer runs first */
    return true;
}

Status model_restored(ModelInstance *comp) {
    model_free(comp);
    return OK;
}
