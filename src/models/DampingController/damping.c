/* seed 001: model-based articulation damping (see damping.h). Plain C99 and
 * libm only. */
#include <math.h>
#include "damping.h"

static const char *const PARAM_NAME[] = {
    "", "f1 + b1 (l1)", "f2 + b2 (l2)", "m2", "Crear", "option", "K1", "K2", "K3", "Krev",
    "nKc", "KcSpeed (finite, strictly increasing)", "KcGain (finite, >= 0)",
    "pctMax (0..50)", "pctFloor (0..pctMax)", "pctAtMmax", "vMin", "Ts",
    "f1, b1, b11, f2, b2 (finite)"
};

const char *dc_param_name(int code) {
    return code < 0 && -code < (int)(sizeof PARAM_NAME / sizeof *PARAM_NAME) ? PARAM_NAME[-code] : "?";
}

static int positive(double x) { return isfinite(x) && x > 0; }
static int nonneg(double x) { return isfinite(x) && x >= 0; }

int dc_setup(DcController *c, const DcParams *p) {
    int i;
    if (!(isfinite(p->f1) && isfinite(p->b1) && isfinite(p->b11) && isfinite(p->f2) && isfinite(p->b2)))
        return -18;
    if (!positive(p->f1 + p->b1)) return -1;
    if (!positive(p->f2 + p->b2)) return -2;
    if (!positive(p->m2)) return -3;
    if (!positive(p->Crear)) return -4;
    if (p->option < 0 || p->option > 5) return -5;
    if (!nonneg(p->K1)) return -6;
    if (!nonneg(p->K2)) return -7;
    if (!nonneg(p->K3)) return -8;
    if (!nonneg(p->Krev)) return -9;
    if (p->nKc < 1 || p->nKc > DC_MAX_KC) return -10;
    for (i = 0; i < p->nKc; i++) {
        if (!isfinite(p->KcSpeed[i]) || (i > 0 && !(p->KcSpeed[i] > p->KcSpeed[i - 1]))) return -11;
        if (!nonneg(p->KcGain[i])) return -12;
    }
    if (!(nonneg(p->pctMax) && p->pctMax <= 50)) return -13;
    if (!(nonneg(p->pctFloor) && p->pctFloor <= p->pctMax)) return -14;
    if (!positive(p->pctAtMmax)) return -15;
    if (!positive(p->vMin)) return -16;
    if (!positive(p->Ts)) return -17;
    c->p = *p;
    c->l1 = p->f1 + p->b1;
    c->l2 = p->f2 + p->b2;
    c->a = 1.0 / c->l1 + (p->b11 - p->b1) / (c->l1 * c->l2);     /* seed 001, eq. 2.9 */
    c->lamRef = c->fPrev = 0.0;
    c->pct = p->pctFloor;
    c->T = c->LambdaRef = c->LambdaDotRef = c->eLambda = c->eLambdaDot = c->active = 0.0;
    c->Kc = dc_kc(p, 0.0);
    return 0;
}

double dc_kc(const DcParams *p, double v) {
    const int n = p->nKc;
    int i;
    if (n <= 1 || v <= p->KcSpeed[0]) return p->KcGain[0];
    if (v >= p->KcSpeed[n - 1]) return p->KcGain[n - 1];
    for (i = 1; i < n - 1 && v > p->KcSpeed[i]; i++) {}
    {   /* KcSpeed[i-1] < v <= KcSpeed[i] */
        const double s = (v - p->KcSpeed[i - 1]) / (p->KcSpeed[i] - p->KcSpeed[i - 1]);
        return p->KcGain[i - 1] + s * (p->KcGain[i] - p->KcGain[i - 1]);
    }
}

double dc_ref_rate(const DcController *c, int exact, double L, double d, double v) {
    if (!exact)                                                          /* seed 001, eq. 2.9 */
        return -(v / c->l2) * L + v * c->a * d;
    return v * sin(d) / c->l1                                            /* seed 001, eq. 2.3 */
         - (v * cos(d) * sin(L) - v * sin(d) * (c->p.b11 - c->p.b1) * cos(L) / c->l1) / c->l2;
}

/* d f / d Lambda of eq. 2.3 */
static double exact_slope(const DcController *c, double L, double d, double v) {
    return -(v * cos(d) * cos(L) + v * sin(d) * (c->p.b11 - c->p.b1) * sin(L) / c->l1) / c->l2;
}

/* one trapezoidal (bilinear) step of the reference model to the new sample */
static double ref_step(const DcController *c, double dStar, double v) {
    const double h = 0.5 * c->p.Ts;
    if (!c->p.exactRef)            /* linear in LambdaRef_k: seed 001, eq. 2.9 with eq. 4.1 */
        return (c->lamRef + h * (c->fPrev + v * c->a * dStar)) / (1.0 + h * v / c->l2);
    {   /* eq. 2.3: F(L) = L - L_(k-1) - h (f_(k-1) + f(L)) = 0 by Newton, from explicit Euler */
        double L = c->lamRef + c->p.Ts * c->fPrev;
        int it;
        for (it = 0; it < 8; it++) {
            const double F = L - c->lamRef - h * (c->fPrev + dc_ref_rate(c, 1, L, dStar, v));
            const double dF = 1.0 - h * exact_slope(c, L, dStar, v);
            double step;
            if (!(fabs(dF) > 1e-6)) break;                /* singular: keep the iterate */
            step = F / dF;
            L -= step;
            if (fabs(step) <= 1e-15 * (1.0 + fabs(L))) break;
        }
        return isfinite(L) ? L : c->lamRef;
    }
}

static int all_finite(const DcInputs *in) {
    return isfinite(in->Lambda) && isfinite(in->LambdaDot) && isfinite(in->v) && isfinite(in->v2) &&
           isfinite(in->delta) && isfinite(in->Mmax) && isfinite(in->pctExternal);
}

static double clamp(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* the request from the errors (steps 3 and 4 of damping.h) */
static unsigned request(DcController *c, const DcInputs *in, int held) {
    const DcParams *p = &c->p;
    unsigned fault = 0;
    double T = 0.0;
    c->active = 0.0;
    if (p->option == 5) {                          /* another function's request, passed through */
        c->T = 0.0;
        c->pct = clamp(in->pctExternal, p->pctFloor, p->pctMax);
        c->active = in->pctExternal > p->pctFloor ? 1.0 : 0.0;
        return 0;
    }
    if (!held && p->option != 0) {
        const double l2 = c->l2;
        double v2 = in->v2, T1, T2;
        if ((p->option == 2 || p->option == 3) && v2 < p->vMin) {
            v2 = p->vMin;
            fault |= DC_FAULT_V2;
        }
        T1 = p->K1 * p->Crear * l2 * c->eLambda;                         /* seed 001, eq. 5.3 */
        T2 = p->K2 * p->Crear * l2 * l2 * c->eLambdaDot / v2;            /* seed 001, eq. 5.4 */
        switch (p->option) {
        case 1: T = T1; break;
        case 2: T = T2; break;
        case 3: T = p->K3 * (T1 + T2); break;                            /* seed 001, eq. 5.5 */
        default: T = p->Krev * p->m2 * c->eLambdaDot; break;             /* seed 001, 6.1.3 */
        }
        if (!(T * in->LambdaDot > 0)) T = 0.0;    /* only against the motion (5.1.1) */
    }
    c->T = T;
    {
        double pct = 0.0;
        if (T != 0.0) {
            if (in->Mmax > 0) {
                pct = p->pctAtMmax * fabs(T) / in->Mmax;                  /* 5.1.3 */
                if (!isfinite(pct)) pct = p->pctMax;
            } else {
                pct = p->pctMax;
                fault |= DC_FAULT_MMAX;
            }
            if (pct > p->pctMax) {
                pct = p->pctMax;
                fault |= DC_FAULT_LIMIT;
            }
            if (pct > p->pctFloor) c->active = 1.0;
        }
        c->pct = pct > p->pctFloor ? pct : p->pctFloor;                   /* the floor (5.1.1) */
    }
    return fault;
}

/* reference held at the measured values (first sample, low speed) */
static void hold(DcController *c, const DcInputs *in, double dStar, double v) {
    c->lamRef = c->LambdaRef = in->Lambda;
    c->fPrev = dc_ref_rate(c, c->p.exactRef, in->Lambda, dStar, v);
    c->LambdaDotRef = in->LambdaDot;
    c->eLambda = c->eLambdaDot = 0.0;
}

unsigned dc_reset(DcController *c, const DcInputs *in) {
    unsigned fault;
    double v, dStar;
    if (!all_finite(in)) {
        c->lamRef = c->fPrev = c->LambdaRef = c->LambdaDotRef = c->eLambda = c->eLambdaDot = 0.0;
        c->T = c->active = 0.0;
        c->pct = c->p.pctFloor;
        return DC_FAULT_NAN;
    }
    v = in->v > 0 ? in->v : 0.0;
    c->Kc = dc_kc(&c->p, v);
    dStar = c->Kc * in->delta;                                           /* 4.1.2 */
    hold(c, in, dStar, v);
    fault = request(c, in, 1);
    if (in->v < c->p.vMin) fault |= DC_FAULT_SLOW;
    if (in->v < 0) fault |= DC_FAULT_REVERSE;
    return fault;
}

unsigned dc_sample(DcController *c, const DcInputs *in) {
    double v, dStar;
    int slow;
    if (!all_finite(in)) return DC_FAULT_NAN;      /* hold the last outputs and state */
    slow = !(in->v >= c->p.vMin);
    v = in->v > 0 ? in->v : 0.0;
    c->Kc = dc_kc(&c->p, v);
    dStar = c->Kc * in->delta;                                           /* 4.1.2 */
    if (slow) {
        hold(c, in, dStar, v);
    } else {
        c->lamRef = c->LambdaRef = ref_step(c, dStar, v);
        c->fPrev = c->LambdaDotRef = dc_ref_rate(c, c->p.exactRef, c->LambdaRef, dStar, v);
        c->eLambda = in->Lambda - c->LambdaRef;                          /* Table of Variables */
        c->eLambdaDot = in->LambdaDot - c->LambdaDotRef;
    }
    {
        unsigned fault = request(c, in, slow);
        if (slow) fault |= DC_FAULT_SLOW;
        if (in->v < 0) fault |= DC_FAULT_REVERSE;
        return fault;
    }
}
