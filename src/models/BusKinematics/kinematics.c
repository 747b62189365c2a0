#include <math.h>
#include "kinematics.h"

/* seed 003, eq. 14: u_i = J_i(beta_i, gamma_i, gamma_{i-1}) u_{i-1} */
static void J(const KinChain *c, int i, double beta, const double u[2], double out[2]) {
    const double L = c->L[i], Lh = c->Lh[i], g = c->gamma[i], gp = c->gamma[i - 1];
    const double cg = cos(g);
    out[0] = -Lh / L * cos(beta - g) / cg * u[0] + sin(beta - g + gp) / (L * cg) * u[1];
    out[1] = Lh * sin(beta) / cg * u[0] + cos(beta + gp) / cg * u[1];
}

/* seed 003, eq. 15: u_{i-1} = J_i^{-1}(beta_i, gamma_i, gamma_{i-1}) u_i */
static void Jinv(const KinChain *c, int i, double beta, const double u[2], double out[2]) {
    const double L = c->L[i], Lh = c->Lh[i], g = c->gamma[i], gp = c->gamma[i - 1];
    const double cgp = cos(gp);
    out[0] = -L / Lh * cos(beta + gp) / cgp * u[0] + sin(beta - g + gp) / (Lh * cgp) * u[1];
    out[1] = L * sin(beta) / cgp * u[0] + cos(beta - g) / cgp * u[1];
}

int kin_rates(const KinChain *c, double gammaF, const double beta[], double vk, KinRates *r) {
    const int N = c->N;
    int jackknife = 0;

    /* S5: curvatures from the angles alone, front to rear */
    r->kappa[0] = tan(gammaF) / c->L[0];                                   /* eq. 19 */
    r->delta[0] = 0.0;
    r->betaMax[0] = 0.0;
    for (int i = 1; i <= N; i++) {
        const double gp = c->gamma[i - 1];
        const double a = atan(c->Lh[i] * r->kappa[i - 1] / cos(gp) - tan(gp));
        r->delta[i] = beta[i] - a;                                          /* eq. 17 */
        /* |delta| < pi/2  <=>  a - pi/2 < beta < a + pi/2 (eq. 31 generalised);
           at beta = 0 the nearer bound, pi/2 - |a| */
        const double s = beta[i] > 0 ? 1.0 : beta[i] < 0 ? -1.0 : (a > 0 ? -1.0 : 1.0);
        r->betaMax[i] = M_PI / 2 + s * a;
        if (cos(r->delta[i]) <= 0.0 && !jackknife) jackknife = i;
        r->kappa[i] = sin(r->delta[i] - c->gamma[i]) / (c->L[i] * cos(r->delta[i]));  /* eqs. 18, 20 */
    }

    /* S4: u_k = [kappa_k, 1]^T v_k (eq. 21), then along the chain with eq. 14 / eq. 15 */
    double u[KIN_MAX_WAGONS + 1][2];
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

void kin_poses(const KinChain *c, int j, const double beta[],
               double theta[], double x[], double y[]) {
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
