/* BusKinematics: seed 003, steps S1-S6 as an algorithm (kinematics.c),
 * integrated with ARKODE's explicit Runge-Kutta inside doStep (one-step: an
 * input that changes every communication step costs one restart of the
 * right-hand side, where CVODE's multistep methods start again at order 1
 * with tiny steps; the kinematics are not stiff: every rate scales with the
 * speed). The steering angles are inputs (the paper's eq. 13 integrates their
 * rates; an FMU takes the angles). */
#include <math.h>
#include <stdlib.h>

#include "fmu.h"
#include "ode.h"
#include "kinematics.h"

/* The jack-knife root is placed where cos(delta_i) falls to this margin
 * (|delta_i| = 90 deg - 0.00006 deg): the curvature (20) is still finite there. */
#define JACKKNIFE_MARGIN 1e-6
#define DEG (180.0 / M_PI)

typedef struct {
    ModelInstance *comp;
    Ode *ode;
    KinChain chain;
} Solver;

static void make_chain(ModelInstance *comp, KinChain *c) {
    c->N = D->N;
    c->k = D->k;
    c->L[0] = D->L0;
    c->Lh[0] = 0.0;
    c->gamma[0] = 0.0;                          /* assumption A5 */
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) {
        c->L[i] = D->L[i];
        c->Lh[i] = D->Lh[i];
        c->gamma[i] = D->steerable[i] ? D->gamma[i] : 0.0;
    }
}

/* the input plus the built-in test steering (an S-curve for running alone) */
static double gammaF_at(ModelInstance *comp, double t) {
    return D->gammaF + test_sine(D->testSteerAmp, D->testSteerPeriod, t);
}

static Status check_inputs(ModelInstance *comp, double t) {
    const double stim = t < D->testSteerPeriod ? fabs(D->testSteerAmp) : 0.0;
    if (!(fabs(D->gammaF) + stim < M_PI / 2))
        return log_error(comp, "gammaF = %.17g rad (with test steering amplitude %g) is at or "
                               "beyond pi/2: the tractor curvature (eq. 19) is unbounded",
                         D->gammaF, stim);
    for (int i = 1; i <= D->N; i++)
        if (D->steerable[i] && !(fabs(D->gamma[i]) < M_PI / 2))
            return log_error(comp, "gamma[%d] = %.17g rad is at or beyond pi/2 (eq. 14 needs "
                                   "cos(gamma_i) != 0)", i, D->gamma[i]);
    return OK;
}

Status model_check_parameters(ModelInstance *comp) {
    if (D->k > D->N)
        return log_error(comp, "k = %d: the driving axle must be on a segment 0..N = 0..%d", D->k, D->N);
    if (D->j > D->N)
        return log_error(comp, "j = %d: the distinguished segment must be 0..N = 0..%d", D->j, D->N);
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    if (check_inputs(comp, comp->v.time)) return Error;

    /* the initial state: tractor pose and joint angles, then the pose of j */
    for (int i = 0; i <= KIN_MAX_WAGONS; i++) D->theta[i] = D->x[i] = D->y[i] = 0.0;
    D->theta[0] = D->theta_start;
    D->x[0] = D->x_start;
    D->y[0] = D->y_start;
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) D->beta[i] = i <= D->N ? D->beta_start[i] : 0.0;
    KinChain c;
    make_chain(comp, &c);
    kin_poses(&c, 0, D->beta, D->theta, D->x, D->y);

    KinRates r;
    const int i = kin_rates(&c, gammaF_at(comp, comp->v.time), D->beta, D->v, &r);
    if (i)
        return log_error(comp, "beta_start[%d] = %.4f deg is beyond betaMax[%d] = %.4f deg: the "
                               "virtual steering angle delta_%d (eq. 17) is at or beyond 90 deg",
                         i, D->beta_start[i] * DEG, i, r.betaMax[i] * DEG, i);
    return OK;
}

/* the right-hand side's other inputs at time t (kinematics.h) */
static KinDrive drive(ModelInstance *comp, double t) {
    const KinDrive dr = { .j = D->j, .prediction = D->predictionModel, .gammaF = gammaF_at(comp, t),
                          .vk = D->v, .omegaMeas = D->omegaMeas };
    return dr;
}

/* kin_outputs' out[] into d: the values into the model's variables, or their
   derivatives along a seed into the tangent of model_directional_derivative */
static void store_outputs(ModelData *d, int j, const double out[KIN_NOUT]) {
    for (int i = 0; i <= KIN_MAX_WAGONS; i++) {
        d->theta[i] = out[KIN_OUT_THETA + i];
        d->x[i] = out[KIN_OUT_X + i];
        d->y[i] = out[KIN_OUT_Y + i];
        d->omega[i] = out[KIN_OUT_OMEGA + i];
        d->vel[i] = out[KIN_OUT_VEL + i];
        d->kappa[i] = out[KIN_OUT_KAPPA + i];
        if (i >= 1) {
            d->betaDot[i] = out[KIN_OUT_BETADOT + i - 1];
            d->betaMax[i] = out[KIN_OUT_BETAMAX + i - 1];
        }
    }
    /* the Model Exchange states and their derivatives (eq. 22) */
    d->thetaj = d->theta[j];
    d->xj = d->x[j];
    d->yj = d->y[j];
    d->der_thetaj = out[KIN_OUT_YDOT + 0];
    d->der_xj = out[KIN_OUT_YDOT + 1];
    d->der_yj = out[KIN_OUT_YDOT + 2];
}

void model_outputs(ModelInstance *comp) {
    KinChain c;
    make_chain(comp, &c);
    const KinDrive dr = drive(comp, comp->v.time);
    double y[3 + KIN_MAX_WAGONS], out[KIN_NOUT];
    model_get_x(comp, y);
    kin_outputs(&c, &dr, y, out);
    store_outputs(D, D->j, out);
}

/* Forward mode through kinematics.c on dual numbers (kinematics_dual.cpp): the
 * seed of the states (thetaj, xj, yj, beta) and of the inputs (gammaF, the
 * steerable wagons' gamma, v, omegaMeas) */
Status model_directional_derivative(ModelInstance *comp, const ModelData *seed, ModelData *tangent) {
    if (check_inputs(comp, comp->v.time)) return Error;
    KinChain c;
    make_chain(comp, &c);
    double dgamma[KIN_MAX_WAGONS + 1] = { 0 }, y[3 + KIN_MAX_WAGONS], dy[3 + KIN_MAX_WAGONS];
    double out[KIN_NOUT], dout[KIN_NOUT];
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) dgamma[i] = D->steerable[i] ? seed->gamma[i] : 0.0;
    model_get_x(comp, y);
    dy[0] = seed->thetaj;
    dy[1] = seed->xj;
    dy[2] = seed->yj;
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) dy[2 + i] = i <= D->N ? seed->beta[i] : 0.0;
    kin_outputs_tangent(c.N, c.k, c.L, c.Lh, c.gamma, dgamma, D->j, D->predictionModel,
                        gammaF_at(comp, comp->v.time), seed->gammaF, D->v, seed->v, D->omegaMeas,
                        seed->omegaMeas, y, dy, out, dout);
    store_outputs(tangent, D->j, dout);
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) tangent->beta[i] = dy[2 + i];   /* beta: a state */
    return OK;
}

/* The right-hand side of the ODE y = [theta_j, x_j, y_j, beta_1 .. beta_N],
 * for the integrator in doStep and for Model Exchange (whose states are the same, with
 * beta padded to KIN_MAX_WAGONS): kin_derivs. Returns the jack-knifed joint, 0 if
 * none; ydot is filled either way. */
static int derivs(ModelInstance *comp, const KinChain *c, double t, const double *y, double *ydot) {
    const KinDrive dr = drive(comp, t);
    return kin_derivs(c, &dr, y, ydot, NULL);
}

static int rhs(double t, const double *y, double *ydot, void *user) {
    Solver *s = user;
    /* a stage beyond the jack-knife bound still has finite rates; the root
       function (cos(delta_i) - margin) ends the step before the bound */
    derivs(s->comp, &s->chain, t, y, ydot);
    return finite_all(ydot, 3 + s->chain.N) ? 0 : -1;
}

/* g_i = cos(delta_i) - margin: crosses zero where joint i jack-knifes;
   g has KIN_MAX_WAGONS entries, 1 beyond N (for Model Exchange) */
static void indicators(ModelInstance *comp, const KinChain *c, double t, const double *y, double *g) {
    double beta[KIN_MAX_WAGONS + 1] = { 0 };
    for (int i = 1; i <= c->N; i++) beta[i] = y[2 + i];
    KinRates r;
    kin_rates(c, gammaF_at(comp, t), beta, D->v, &r);
    for (int i = 1; i <= KIN_MAX_WAGONS; i++)
        g[i - 1] = i <= c->N ? cos(r.delta[i]) - JACKKNIFE_MARGIN : 1.0;
}

static int roots(double t, const double *y, double *g, void *user) {
    Solver *s = user;
    double all[KIN_MAX_WAGONS];
    indicators(s->comp, &s->chain, t, y, all);
    for (int i = 0; i < s->chain.N; i++) g[i] = all[i];     /* the integrator has N root functions */
    return 0;
}

/* the jack-knife of joint i at time t, as co-simulation (an error: the step
   fails) and Model Exchange (a warning: the simulation terminates) report it */
static void jackknife_message(ModelInstance *comp, const KinChain *c, int i, double t, bool error) {
    KinRates r;
    kin_rates(c, gammaF_at(comp, t), D->beta, D->v, &r);
#define JACKKNIFE_MSG "jack-knife at joint %d at t = %.6f s: beta[%d] = %.4f deg reached betaMax[%d] = " \
                      "%.4f deg (virtual steering angle delta_%d at 90 deg, eq. 17); not integrated further"
    if (error)
        log_error(comp, JACKKNIFE_MSG, i, t, i, D->beta[i] * DEG, i, r.betaMax[i] * DEG, i);
    else
        log_warning(comp, JACKKNIFE_MSG, i, t, i, D->beta[i] * DEG, i, r.betaMax[i] * DEG, i);
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    if (check_inputs(comp, t)) return Error;
    Solver *s = comp->solver;
    if (!s) {
        s = comp->solver = calloc(1, sizeof(Solver));
        if (!s) return log_error(comp, "out of memory");
        s->comp = comp;
        s->ode = ode_new(comp, 3 + D->N, rhs, D->N, roots, s, ODE_ERK, D->rtol, D->atol);
        if (!s->ode) return Error;
    }
    make_chain(comp, &s->chain);

    const int j = D->j, N = D->N;
    double y[3 + KIN_MAX_WAGONS] = { D->theta[j], D->x[j], D->y[j] };
    for (int i = 1; i <= N; i++) y[2 + i] = D->beta[i];
    double tret;
    int found[KIN_MAX_WAGONS] = { 0 };
    const OdeResult res = ode_advance(s->ode, comp->restart, t, y, t + h, &tret, found);
    D->theta[j] = y[0];
    D->x[j] = y[1];
    D->y[j] = y[2];
    for (int i = 1; i <= N; i++) D->beta[i] = y[2 + i];

    if (res == ODE_REACHED) {
        comp->v.time = t + h;
        return OK;
    }
    comp->v.time = tret;
    if (res == ODE_ROOT) {
        for (int i = 1; i <= N; i++) {
            if (!found[i - 1]) continue;
            jackknife_message(comp, &s->chain, i, tret, true);
            return Error;
        }
    }
    return Error;   /* integrator failure, already logged with its flag and time */
}

void model_free(ModelInstance *comp) {
    const Solver *s = comp->solver;
    if (s) ode_free_solver(comp, s->ode);
}

/* ---- Model Exchange: x = [theta_j, x_j, y_j, beta_1 .. beta_4], the integrator's
 * state of doStep with beta padded to KIN_MAX_WAGONS (beyond N: 0, constant) */

void model_get_x(ModelInstance *comp, double x[]) {
    const int j = D->j;
    x[0] = D->theta[j];
    x[1] = D->x[j];
    x[2] = D->y[j];
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) x[2 + i] = i <= D->N ? D->beta[i] : 0.0;
}

void model_set_x(ModelInstance *comp, const double x[]) {
    const int j = D->j;
    D->theta[j] = x[0];
    D->x[j] = x[1];
    D->y[j] = x[2];
    for (int i = 1; i <= KIN_MAX_WAGONS; i++) D->beta[i] = i <= D->N ? x[2 + i] : 0.0;
}

Status model_derivatives(ModelInstance *comp, double dx[]) {
    if (check_inputs(comp, comp->v.time)) return Error;
    KinChain c;
    make_chain(comp, &c);
    double x[3 + KIN_MAX_WAGONS];
    model_get_x(comp, x);
    for (int i = 0; i < 3 + KIN_MAX_WAGONS; i++) dx[i] = 0.0;
    /* beyond the jack-knife bound (the integrator may try a step there before
       it locates the event) the equations still give finite rates */
    derivs(comp, &c, comp->v.time, x, dx);
    return OK;
}

void model_event_indicators(ModelInstance *comp, double z[]) {
    KinChain c;
    make_chain(comp, &c);
    double x[3 + KIN_MAX_WAGONS];
    model_get_x(comp, x);
    indicators(comp, &c, comp->v.time, x, z);
}

/* a jack-knife ends the simulation, as it ends a co-simulation step */
Status model_event_update(ModelInstance *comp, bool *terminate, double *tNext) {
    *tNext = INFINITY;
    if (check_inputs(comp, comp->v.time)) return Error;
    KinChain c;
    make_chain(comp, &c);
    double x[3 + KIN_MAX_WAGONS], g[KIN_MAX_WAGONS];
    model_get_x(comp, x);
    indicators(comp, &c, comp->v.time, x, g);
    for (int i = 1; i <= D->N; i++) {
        if (g[i - 1] > 0.0) continue;
        jackknife_message(comp, &c, i, comp->v.time, false);
        *terminate = true;
        return Warning;
    }
    return OK;
}

/* FMU state: ModelState holds nothing; the integrator (of size 3 + N) is made again */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)d; (void)s; (void)time; (void)why; (void)n;
    return true;
}

Status model_restored(ModelInstance *comp) {
    model_free(comp);
    return OK;
}
