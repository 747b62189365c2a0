/* seed 003's kinematics (see kinematics.h). Compiled twice: as C on double,
 * and in kinematics_dual.cpp on a dual number (KIN_REAL) for the directional
 * derivatives. */
#include <math.h>
#include <stddef.h>
#include "kinematics.h"

/* seed 003, eq. 14: u_i = J_i(beta_i, gamma_i, gamma_{i-1}) u_{i-1} */
static void J(const KinChain *c, int i, KIN_REAL beta, const KIN_REAL u[2], KIN_REAL out[2]) {
    const double L = c->L[i], Lh = c->Lh[i];
    const KIN_REAL g = c->gamma[i], gp = c->gamma[i - 1];
    const KIN_REAL cg = cos(g);
    out[0] = -Lh / L * cos(beta - g) / cg * u[0] + sin(beta - g + gp) / (L * cg) * u[1];
    out[1] = Lh * sin(beta) / cg * u[0] + cos(beta + gp) / cg * u[1];
}

/* seed 003, eq. 15: u_{i-1} = J_i^{-1}(beta_i, gamma_i, gamma_{i-1}) u_i */
static void Jinv(const KinChain *c, int i, KIN_REAL beta, const KIN_REAL u[2], KIN_REAL out[2]) {
    const double L = c->L[i], Lh = c->Lh[i];
    const KIN_REAL g = c->gamma[i], gp = c->gamma[i - 1];
    const KIN_REAL cgp = cos(gp);
    out[0] = -L / Lh * cos(beta + gp) / cgp * u[0] + sin(beta - g + gp) / (Lh * cgp) * u[1];
    out[1] = L * sin(beta) / cgp * u[0] + cos(beta - g) / cgp * u[1];
}

int kin_rates(const KinChain *c, KIN_REAL gammaF, const KIN_REAL beta[], KIN_REAL vk, KinRates *r) {
    const int N = c->N;
    int jackknife = 0;

    /* S5: curvatures from the angles alone, front to rear */
    r->kappa[0] = tan(gammaF) / c->L[0];                                   /* eq. 19 */
    r->delta[0] = 0.0;
    r->betaMax[0] = 0.0;
    for (int i = 1; i <= N; i++) {
        const KIN_REAL gp = c->gamma[i - 1];
        const KIN_REAL a = atan(c->Lh[i] * r->kappa[i - 1] / cos(gp) - tan(gp));
        r->delta[i] = beta[i] - a;                                          /* eq. 17 */
        /* |delta| < pi/2  <=>  a - pi/2 < beta < a + pi/2 (eq. 31 generalised);
           at beta = 0 the nearer bound, pi/2 - |a| */
        const double s = beta[i] > 0 ? 1.0 : beta[i] < 0 ? -1.0 : (a > 0 ? -1.0 : 1.0);
        r->betaMax[i] = M_PI / 2 + s * a;
        if (cos(r->delta[i]) <= 0.0 && !jackknife) jackknife = i;
        r->kappa[i] = sin(r->delta[i] - c->gamma[i]) / (c->L[i] * cos(r->delta[i]));  /* eqs. 18, 20 */
    }

    /* S4: u_k = [kappa_k, 1]^T v_k (eq. 21), then along the chain with eq. 14 / eq. 15 */
    KIN_REAL u[KIN_MAX_WAGONS + 1][2];
    u[c->k][0] = r->kappa[c->k] * vk;
    u[c->k][1] = vk;
    for (int i = c->k + 1; i <= N; i++) J(c, i, beta[i], u[i - 1], u[i]);
    for (int i = c->k; i >= 1; i--) Jinv(c, i, beta[i], u[i], u[i - 1]);

    r->betaDot[0] = 0.0;
    for (int i = 0; i <= N; i++) {
        r->omega[i] = u[i][0];
        r->vel[i] = u[i][1];
        if (i > 0) r->betaDot[i] = u[i - 1][0] - u[i][0];                  /* eq. 16 */
    }
    return jackknife;
}

void kin_poses(const KinChain *c, int j, const KIN_REAL beta[],
               KIN_REAL theta[], KIN_REAL x[], KIN_REAL y[]) {
    for (int i = j + 1; i <= c->N; i++) {          /* rearwards from j */
        theta[i] = theta[i - 1] - beta[i];
        x[i] = x[i - 1] - c->Lh[i] * cos(theta[i - 1]) - c->L[i] * cos(theta[i]);
        y[i] = y[i - 1] - c->Lh[i] * sin(theta[i - 1]) - c->L[i] * sin(theta[i]);
    }
    for (int i = j; i >= 1; i--) {                 /* forwards from j */
        theta[i - 1] = theta[i] + beta[i];
        x[i - 1] = x[i] + c->L[i] * cos(theta[i]) + c->Lh[i] * cos(theta[i - 1]);
        y[i - 1] = y[i] + c->L[i] * sin(theta[i]) + c->Lh[i] * sin(theta[i - 1]);
    }
}

int kin_derivs(const KinChain *c, const KinDrive *dr, const KIN_REAL y[], KIN_REAL ydot[], KinRates *r) {
    KIN_REAL beta[KIN_MAX_WAGONS + 1] = { 0 };
    for (int i = 1; i <= c->N; i++) beta[i] = y[2 + i];
    KinRates own;
    if (!r) r = &own;
    const int jackknife = kin_rates(c, dr->gammaF, beta, dr->vk, r);
    const int j = dr->j;
    /* eq. 22; the prediction model (seed 003, sec. V, Fig. 11): the measured
       angular velocity (omega_1tacho, eq. 51) in place of the model's */
    ydot[0] = dr->prediction ? dr->omegaMeas : r->omega[j];
    ydot[1] = r->vel[j] * cos(y[0] + c->gamma[j]);
    ydot[2] = r->vel[j] * sin(y[0] + c->gamma[j]);
    for (int i = 1; i <= c->N; i++) ydot[2 + i] = r->betaDot[i];   /* eq. 16 */
    return jackknife;
}

void kin_outputs(const KinChain *c, const KinDrive *dr, const KIN_REAL y[], KIN_REAL out[KIN_NOUT]) {
    KIN_REAL beta[KIN_MAX_WAGONS + 1] = { 0 }, theta[KIN_MAX_WAGONS + 1] = { 0 };
    KIN_REAL x[KIN_MAX_WAGONS + 1] = { 0 }, yy[KIN_MAX_WAGONS + 1] = { 0 };
    for (int i = 1; i <= c->N; i++) beta[i] = y[2 + i];
    theta[dr->j] = y[0];
    x[dr->j] = y[1];
    yy[dr->j] = y[2];
    kin_poses(c, dr->j, beta, theta, x, yy);
    KinRates r;
    for (int i = 0; i < 3 + KIN_MAX_WAGONS; i++) out[KIN_OUT_YDOT + i] = 0.0;
    kin_derivs(c, dr, y, &out[KIN_OUT_YDOT], &r);
    for (int i = 0; i <= KIN_MAX_WAGONS; i++) {
        const int on = i <= c->N;       /* segments beyond N read 0 */
        out[KIN_OUT_THETA + i] = on ? theta[i] : 0.0;
        out[KIN_OUT_X + i] = on ? x[i] : 0.0;
        out[KIN_OUT_Y + i] = on ? yy[i] : 0.0;
        out[KIN_OUT_OMEGA + i] = on ? r.omega[i] : 0.0;
        out[KIN_OUT_VEL + i] = on ? r.vel[i] : 0.0;
        out[KIN_OUT_KAPPA + i] = on ? r.kappa[i] : 0.0;
        if (i >= 1) {
            out[KIN_OUT_BETADOT + i - 1] = on ? r.betaDot[i] : 0.0;
            out[KIN_OUT_BETAMAX + i - 1] = on ? r.betaMax[i] : 0.0;
        }
    }
}
