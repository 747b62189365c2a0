/* The two-cylinder articulation damper of seed 001 (1.3.1, App. B): see
 * damper.h for the geometry, the valves and the signs. Plain C99, <math.h>
 * only, no allocation. Compiled twice for the FMU: as C on double, and in
 * damper_dual.cpp on a dual number (DAMPER_REAL) for the directional
 * derivatives. */
#include <math.h>

#include "damper.h"

DAMPER_REAL damper_pset(const DamperParams *p, DAMPER_REAL pct) {
    const DAMPER_REAL u = pct > DAMPER_PCT_MAX ? DAMPER_PCT_MAX : (pct > 0.0 ? pct : 0.0);
    return p->pMax * u / DAMPER_PCT_MAX;              /* 50 % = pMax (seed 001, 5.1.1) */
}

int damper_geometry(const DamperParams *p, int s, DAMPER_REAL Lambda, DAMPER_REAL *L, DAMPER_REAL *h) {
    const DAMPER_REAL c = cos(Lambda), sn = sin(Lambda);
    /* seed 001, Fig. B.3 (reconstructed, spec 001 section 1): law of cosines in
     * the triangle articulation point - front pivot - rear pivot */
    const DAMPER_REAL L2 = p->Xrear * p->Xrear + p->Yrear * p->Yrear + p->R * p->R
                           - 2.0 * s * p->R * p->Xrear * sn - 2.0 * p->R * p->Yrear * c;
    int limited = 0;
    DAMPER_REAL len = L2 > 0.0 ? sqrt(L2) : (DAMPER_REAL)0.0;
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
static DAMPER_REAL mmax_dir(const DamperParams *p, DAMPER_REAL Lambda, double dir) {
    DAMPER_REAL m = 0.0;
    for (int i = 0; i < 2; i++) {
        const int s = i == 0 ? 1 : -1;
        DAMPER_REAL L, h;
        damper_geometry(p, s, Lambda, &L, &h);
        if (p->bothWays || h * dir < 0.0)            /* this cylinder compresses: it resists */
            m += p->Ap * p->pMax * fabs(h);
    }
    return m;
}

DAMPER_REAL damper_mmax(const DamperParams *p, DAMPER_REAL Lambda, double dir) {
    if (dir > 0.0) return mmax_dir(p, Lambda, 1.0);
    if (dir < 0.0) return mmax_dir(p, Lambda, -1.0);
    const DAMPER_REAL a = mmax_dir(p, Lambda, 1.0), b = mmax_dir(p, Lambda, -1.0);
    return a > b ? a : b;                            /* at rest: the larger direction */
}

int damper_eval(const DamperParams *p, DAMPER_REAL Lambda, DAMPER_REAL LambdaDot, DAMPER_REAL pValve,
                DamperOut *o) {
    int limited = 0;
    o->dMdp = 0.0;
    for (int i = 0; i < 2; i++) {
        const int s = i == 0 ? 1 : -1;
        limited |= damper_geometry(p, s, Lambda, &o->L[i], &o->h[i]);
        const DAMPER_REAL Ldot = o->h[i] * LambdaDot + 0.0; /* piston speed (seed 001, App. B); + 0.0: no -0 */
        o->Ldot[i] = Ldot;
        const int active = p->bothWays || Ldot < 0.0; /* compressing: through the valve */
        if (active) {
            const DAMPER_REAL t = tanh(Ldot / p->v0);     /* zero force at zero piston speed */
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
    const DAMPER_REAL pen = fabs(Lambda) - p->LambdaStop;
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

DAMPER_REAL damper_pressure_rate(DAMPER_REAL pValve, DAMPER_REAL pSet, double tauP) {
    return tauP > 0.0 ? (pSet - pValve) / tauP : (DAMPER_REAL)0.0;   /* tauP dp/dt = pSet - p */
}

DAMPER_REAL damper_step_energy(const DamperOut *o, DAMPER_REAL LambdaDot, DAMPER_REAL pInt, double h) {
    /* dMdp LambdaDot = sum Ap tanh(Ldot_s/v0) Ldot_s: every term of dMdp,
     * Ap tanh(h_s LambdaDot/v0) h_s, has the sign of LambdaDot, so the product
     * is >= 0 in floating point too; MstopC is cStop LambdaDot or 0 */
    return o->dMdp * LambdaDot * pInt + o->MstopC * LambdaDot * h;
}

DAMPER_REAL damper_valve(const DamperParams *p, DAMPER_REAL pValve, DAMPER_REAL pct, double tauP) {
    return tauP > 0.0 ? pValve : damper_pset(p, pct);
}

int damper_outputs(const DamperParams *p, DAMPER_REAL Lambda, DAMPER_REAL LambdaDot, DAMPER_REAL pct,
                   double tauP, DAMPER_REAL pValve, DAMPER_REAL out[DAMPER_NOUT]) {
    const DAMPER_REAL pv = damper_valve(p, pValve, pct, tauP);
    DamperOut o;
    const int limited = damper_eval(p, Lambda, LambdaDot, pv, &o);
    out[DAMPER_OUT_MJOINT] = o.Mjoint;
    for (int i = 0; i < 2; i++) {
        out[DAMPER_OUT_F + i] = o.F[i];
        out[DAMPER_OUT_P + i] = o.p[i];
        out[DAMPER_OUT_L + i] = o.L[i];
        out[DAMPER_OUT_LDOT + i] = o.Ldot[i];
    }
    out[DAMPER_OUT_MMAX] = o.Mmax;
    out[DAMPER_OUT_DPVALVE] = damper_pressure_rate(pValve, damper_pset(p, pct), tauP);
    /* the energy over a unit time at this pressure: the power */
    out[DAMPER_OUT_DEDISS] = damper_step_energy(&o, LambdaDot, pv, 1.0);
    return limited;
}
