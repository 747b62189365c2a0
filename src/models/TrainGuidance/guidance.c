/* seed 000, Task 1 (eqs. 29-42): see guidance.h. Plain C99 and libm only. */
#include <math.h>
#include "guidance.h"

#define TG_HALF_PI 1.57079632679489661923

static const char *const PARAM_NAME[] = {
    "", "l1", "lg1", "l2", "lg2", "l3", "S4", "S6", "Ts", "gamma4Max", "gamma6Max"
};

const char *tg_param_name(int code) {
    return code < 0 && -code < (int)(sizeof PARAM_NAME / sizeof *PARAM_NAME) ? PARAM_NAME[-code] : "?";
}

static int positive(double x) { return isfinite(x) && x > 0; }

int tg_setup(TgGuidance *g, const TgParams *p) {
    if (!positive(p->l1)) return -1;
    if (!positive(p->lg1)) return -2;
    if (!positive(p->l2)) return -3;
    if (!positive(p->lg2)) return -4;
    if (!positive(p->l3)) return -5;
    if (!(isfinite(p->S4) && p->S4 >= 0)) return -6;
    if (!(isfinite(p->S6) && p->S6 >= 0)) return -7;
    if (!positive(p->Ts)) return -8;
    if (!(positive(p->gamma4Max) && p->gamma4Max < TG_HALF_PI)) return -9;
    if (!(positive(p->gamma6Max) && p->gamma6Max < TG_HALF_PI)) return -10;
    g->p = *p;

    /* module 2: triangle M-G1-A4 (eqs. 31-34), hinge G1 on R_g1^2 = R2^2 + e1^2 */
    const double e1sq = p->lg1 * p->lg1;
    const double xM2 = -(p->l2 * p->l2 + e1sq) / (2 * p->l2);
    g->a2 = (p->l2 * p->l2 - e1sq) / (2 * p->l2);          /* = l2 + x_M */
    g->d2 = e1sq - xM2 * xM2;
    /* hinge G2, lg2 behind A4: R_g2^2 = R2^2 + e2^2 (eq. 35, law of cosines) */
    const double xG2 = -(p->l2 + p->lg2);
    const double e2sq = (xM2 - xG2) * (xM2 - xG2) + e1sq - xM2 * xM2;
    /* module 3: triangle M-G2-A6 (eqs. 36, 37) */
    const double xM3 = -(p->l3 * p->l3 + e2sq) / (2 * p->l3);
    g->a3 = (p->l3 * p->l3 - e2sq) / (2 * p->l3);
    g->d3 = e2sq - xM3 * xM3;

    g->gamma4 = g->gamma6 = g->gamma4ss = g->gamma6ss = 0.0;
    return 0;
}

static double clamp(double x, double lim) { return x > lim ? lim : x < -lim ? -lim : x; }

/* tan(gamma) = -a kappa / sqrt(1 + d kappa^2), saturated at +-lim */
static unsigned guided_angle(double a, double d, double kappa, double lim, double *gamma) {
    const double q = 1.0 + d * kappa * kappa;
    const double toward = -a * kappa;                     /* sign of the exact answer */
    if (!(q > 0) || !isfinite(kappa)) {
        *gamma = toward > 0 ? lim : toward < 0 ? -lim : 0.0;
        return TG_FAULT_GEOMETRY;
    }
    const double gam = atan(toward / sqrt(q));
    if (fabs(gam) > lim) {
        *gamma = clamp(gam, lim);
        return TG_FAULT_LIMIT;
    }
    *gamma = gam;
    return 0;
}

unsigned tg_steady_state(const TgGuidance *g, double gamma1, double *gamma4, double *gamma6) {
    if (!isfinite(gamma1)) {
        *gamma4 = *gamma6 = 0.0;
        return TG_FAULT_NAN;
    }
    unsigned fault = 0;
    double kappa;                                          /* 1/R2, eq. 30 */
    if (fabs(gamma1) < TG_HALF_PI) {
        kappa = tan(gamma1) / g->p.l1;
    } else {                                               /* R2 = 0 or beyond: no circle */
        kappa = gamma1 > 0 ? INFINITY : -INFINITY;
        fault |= TG_FAULT_GEOMETRY;
    }
    fault |= guided_angle(g->a2, g->d2, kappa, g->p.gamma4Max, gamma4);
    fault |= guided_angle(g->a3, g->d3, kappa, g->p.gamma6Max, gamma6);
    return fault;
}

void tg_set(TgGuidance *g, double gamma4, double gamma6) {
    g->gamma4 = isfinite(gamma4) ? clamp(gamma4, g->p.gamma4Max) : 0.0;
    g->gamma6 = isfinite(gamma6) ? clamp(gamma6, g->p.gamma6Max) : 0.0;
}

void tg_reset(TgGuidance *g, double gamma1) {
    tg_steady_state(g, gamma1, &g->gamma4ss, &g->gamma6ss);
    tg_set(g, g->gamma4ss, g->gamma6ss);
}

/* eqs. 41, 42: T*_k = v_k dt / (v_k dt + S); S = 0 is no lag */
static double arc_lag(double y, double u, double ds, double S) {
    const double T = S > 0 ? ds / (ds + S) : 1.0;
    return y + T * (u - y);
}

unsigned tg_sample(TgGuidance *g, double gamma1, double v) {
    if (!isfinite(gamma1) || !isfinite(v)) return TG_FAULT_NAN;    /* hold */
    unsigned fault = 0;
    if (v < 0) {
        fault |= TG_FAULT_SPEED;
        v = 0.0;
    }
    fault |= tg_steady_state(g, gamma1, &g->gamma4ss, &g->gamma6ss);
    const double ds = v * g->p.Ts;                         /* arc length of this sample */
    g->gamma4 = clamp(arc_lag(g->gamma4, g->gamma4ss, ds, g->p.S4), g->p.gamma4Max);
    g->gamma6 = clamp(arc_lag(g->gamma6, g->gamma6ss, ds, g->p.S6), g->p.gamma6Max);
    return fault;
}
