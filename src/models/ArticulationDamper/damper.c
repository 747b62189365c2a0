/* The two-cylinder articulation damper of seed 001 (1.3.1, App. B): see
 * damper.h for the geometry, the valves and the signs. Plain C99, <math.h>
 * only, no allocation. */
#include <math.h>

#include "damper.h"

double damper_pset(const DamperParams *p, double pct) {
    const double u = pct > DAMPER_PCT_MAX ? DAMPER_PCT_MAX : (pct > 0.0 ? pct : 0.0);
    return p->pMax * u / DAMPER_PCT_MAX;              /* 50 % = pMax (seed 001, 5.1.1) */
}

int damper_geometry(const DamperParams *p, int s, double Lambda, double *L, double *h) {
    const double c = cos(Lambda), sn = sin(Lambda);
    /* seed 001, Fig. B.3 (reconstructed, spec 001 section 1): law of cosines in
     * the triangle articulation point - front pivot - rear pivot */
    const double L2 = p->Xrear * p->Xrear + p->Yrear * p->Yrear + p->R * p->R
                      - 2.0 * s * p->R * p->Xrear * sn - 2.0 * p->R * p->Yrear * c;
    int limited = 0;
    double len = L2 > 0.0 ? sqrt(L2) : 0.0;
    if (!(len >= DAMPER_L_MIN)) { len = DAMPER_L_MIN; limited = 1; }
    *L = len;
    /* h_s = dL_s/dLambda: the lever arm of the cylinder force about the joint */
    *h = (-s * p->R * p->Xrear * c + p->R * p->Yrear * sn) / len;
    return limited;
}

int damper_check(const DamperParams *p, double *Lshortest, double *LambdaAt) {
    const double Lm = p->LambdaStop + DAMPER_CHECK_MARGIN;
    int worst = 0;
    double Lw = INFINITY, at = 0.0;
    for (int s = 1; s >= -1; s -= 2) {
        /* L_s^2 = rho^2 + R^2 - 2 R rho cos(Lambda - phi_s): shortest where
         * Lambda = phi_s (both pivots on one ray), else at an end of the range */
        const double phi = atan2(s * p->Xrear, p->Yrear);
        double cand[3] = { -Lm, Lm, phi };
        const int n = (phi >= -Lm && phi <= Lm) ? 3 : 2;
        for (int k = 0; k < n; k++) {
            const double c = cos(cand[k]), sn = sin(cand[k]);
            const double L2 = p->Xrear * p->Xrear + p->Yrear * p->Yrear + p->R * p->R
                              - 2.0 * s * p->R * p->Xrear * sn - 2.0 * p->R * p->Yrear * c;
            const double len = L2 > 0.0 ? sqrt(L2) : 0.0;
            if (len < Lw) { Lw = len; at = cand[k]; if (len < DAMPER_L_MIN) worst = s; }
        }
    }
    *Lshortest = Lw;
    *LambdaAt = at;
    return Lw < DAMPER_L_MIN ? worst : 0;
}

/* the hydraulic torque at 50 % for one direction of motion, |Ldot| >> v0 */
static double mmax_dir(const DamperParams *p, double Lambda, double dir) {
    double m = 0.0;
    for (int i = 0; i < 2; i++) {
        const int s = i == 0 ? 1 : -1;
        double L, h;
        damper_geometry(p, s, Lambda, &L, &h);
        if (p->bothWays || h * dir < 0.0)            /* this cylinder compresses: it resists */
            m += p->Ap * p->pMax * fabs(h);
    }
    return m;
}

double damper_mmax(const DamperParams *p, double Lambda, double dir) {
    if (dir > 0.0) return mmax_dir(p, Lambda, 1.0);
    if (dir < 0.0) return mmax_dir(p, Lambda, -1.0);
    const double a = mmax_dir(p, Lambda, 1.0), b = mmax_dir(p, Lambda, -1.0);
    return a > b ? a : b;                            /* at rest: the larger direction */
}

int damper_eval(const DamperParams *p, double Lambda, double LambdaDot, double pValve, DamperOut *o) {
    int limited = 0;
    o->dMdp = 0.0;
    for (int i = 0; i < 2; i++) {
        const int s = i == 0 ? 1 : -1;
        limited |= damper_geometry(p, s, Lambda, &o->L[i], &o->h[i]);
        const double Ldot = o->h[i] * LambdaDot + 0.0; /* piston speed (seed 001, App. B); + 0.0: no -0 */
        o->Ldot[i] = Ldot;
        const int active = p->bothWays || Ldot < 0.0; /* compressing: through the valve */
        if (active) {
            const double t = tanh(Ldot / p->v0);     /* zero force at zero piston speed */
            o->p[i] = pValve * fabs(t);
            o->F[i] = p->Ap * o->p[i];
            o->dMdp += p->Ap * t * o->h[i];          /* Mjoint = -sum F_signed h_s */
        } else {
            o->p[i] = 0.0;                           /* refilled through the check valve */
            o->F[i] = 0.0;
        }
    }
    o->Mdamp = o->dMdp * pValve;
    /* end stop at LambdaStop (seed 001, App. B: 54 deg) */
    const double pen = fabs(Lambda) - p->LambdaStop;
    o->MstopK = o->MstopC = 0.0;
    if (pen > 0.0) {
        const double sg = Lambda > 0.0 ? 1.0 : -1.0;
        o->MstopK = p->kStop * pen * sg;
        if (LambdaDot * sg > 0.0) o->MstopC = p->cStop * LambdaDot;
    }
    o->Mjoint = o->Mdamp + o->MstopK + o->MstopC;
    o->Mmax = damper_mmax(p, Lambda, LambdaDot > 0.0 ? 1.0 : (LambdaDot < 0.0 ? -1.0 : 0.0));
    return limited;
}

double damper_pressure_step(double pValve, double pSet, double tauP, double h, double *pInt) {
    if (!(tauP > 0.0)) {                             /* static valve, as in the thesis */
        *pInt = pSet * h;
        return pSet;
    }
    const double e = expm1(-h / tauP);               /* exp(-h/tauP) - 1, in (-1, 0] */
    const double I = pSet * h - (pValve - pSet) * tauP * e;
    *pInt = I > 0.0 ? I : 0.0;
    return pValve + (pValve - pSet) * e;
}

double damper_pressure_rate(double pValve, double pSet, double tauP) {
    return tauP > 0.0 ? (pSet - pValve) / tauP : 0.0;   /* tauP dp/dt = pSet - p */
}

double damper_step_energy(const DamperOut *o, double LambdaDot, double pInt, double h) {
    /* dMdp LambdaDot = sum Ap tanh(Ldot_s/v0) Ldot_s: every term of dMdp,
     * Ap tanh(h_s LambdaDot/v0) h_s, has the sign of LambdaDot, so the product
     * is >= 0 in floating point too; MstopC is cStop LambdaDot or 0 */
    return o->dMdp * LambdaDot * pInt + o->MstopC * LambdaDot * h;
}
