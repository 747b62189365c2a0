/* seed 000, Task 2 (eqs. 43-48): see forcemin.h. Plain C99 and libm only. */
#include <math.h>
#include "forcemin.h"

#define FM_HALF_PI 1.57079632679489661923
/* a hinge moving forward slower than this (per unit speed of A2, relative to
   its lateral speed) is treated as jack-knifed */
#define FM_MIN_WX 1e-9

static const char *const PARAM_NAME[] = {
    "", "l1", "lg1", "l2", "lA3", "lg2", "l3", "lA5", "gamma3Max", "gamma5Max"
};

const char *fm_param_name(int code) {
    return code < 0 && -code < (int)(sizeof PARAM_NAME / sizeof *PARAM_NAME) ? PARAM_NAME[-code] : "?";
}

static int positive(double x) { return isfinite(x) && x > 0; }

int fm_setup(FmSteering *f, const FmParams *p) {
    const double len[] = { p->l1, p->lg1, p->l2, p->lA3, p->lg2, p->l3, p->lA5 };
    for (int i = 0; i < 7; i++)
        if (!positive(len[i])) return -(i + 1);
    if (!(positive(p->gamma3Max) && p->gamma3Max < FM_HALF_PI)) return -8;
    if (!(positive(p->gamma5Max) && p->gamma5Max < FM_HALF_PI)) return -9;
    f->p = *p;
    f->gamma3 = f->gamma5 = 0.0;
    return 0;
}

/* rotate (x, y) by angle a */
static void rotate(double a, double *x, double *y) {
    const double c = cos(a), s = sin(a), x0 = *x;
    *x = c * x0 - s * *y;
    *y = s * x0 + c * *y;
}

/* One trailing module: hinge velocity (wx, wy) in its frame, guided axle at
 * distance l behind the hinge at angle gammaG, the force-minimised axle lA
 * behind the hinge. Returns tan of its angle in *t; the next hinge (lg behind
 * the guided axle) moves with (wx, *wyNext). */
static unsigned module(double wx, double wy, double l, double lA, double lg, double gammaG,
                       double *t, double *wyNext) {
    unsigned fault = 0;
    if (!(fabs(gammaG) < FM_HALF_PI)) {                 /* tan(gammaG) unbounded */
        gammaG = gammaG > 0 ? FM_HALF_PI - 1e-9 : -(FM_HALF_PI - 1e-9);
        fault |= FM_FAULT_GEOMETRY;
    }
    const double omega = (wy - wx * tan(gammaG)) / l;  /* module's yaw rate about the hinge */
    const double vyA = wy - omega * lA;                /* lateral velocity of A3 (A5) */
    *wyNext = wy - omega * (l + lg);
    if (!(wx > FM_MIN_WX * (1.0 + fabs(vyA)))) {       /* the hinge does not move forward */
        *t = vyA >= 0 ? INFINITY : -INFINITY;
        return fault | FM_FAULT_GEOMETRY;
    }
    *t = vyA / wx;                                     /* eq. 48 as tan(gamma3) */
    return fault;
}

unsigned fm_angles(const FmParams *p, double gamma1, double dPsi1, double dPsi2,
                   double gamma4, double gamma6, double *gamma3, double *gamma5) {
    *gamma3 = *gamma5 = 0.0;
    if (!isfinite(gamma1) || !isfinite(dPsi1) || !isfinite(dPsi2) ||
        !isfinite(gamma4) || !isfinite(gamma6))
        return FM_FAULT_NAN;
    unsigned fault = 0;
    if (!(fabs(gamma1) < FM_HALF_PI)) {
        gamma1 = gamma1 > 0 ? FM_HALF_PI - 1e-9 : -(FM_HALF_PI - 1e-9);
        fault |= FM_FAULT_GEOMETRY;
    }
    /* hinge G1 per unit speed of A2, module 1's frame (eqs. 30, 43) */
    double wx = 1.0, wy = -p->lg1 * tan(gamma1) / p->l1;
    rotate(dPsi1, &wx, &wy);                           /* into module 2 (eq. 44) */
    double t3, t5, wy2;
    fault |= module(wx, wy, p->l2, p->lA3, p->lg2, gamma4, &t3, &wy2);   /* eqs. 45-48 */
    *gamma3 = atan(t3);
    double ux = wx, uy = wy2;
    rotate(dPsi2, &ux, &uy);                           /* hinge G2 into module 3 */
    double unused;
    fault |= module(ux, uy, p->l3, p->lA5, 0.0, gamma6, &t5, &unused);
    *gamma5 = atan(t5);
    return fault;
}

static double clamp(double x, double lim) { return x > lim ? lim : x < -lim ? -lim : x; }

unsigned fm_sample(FmSteering *f, double gamma1, double dPsi1, double dPsi2,
                   double gamma4, double gamma6) {
    double g3, g5;
    unsigned fault = fm_angles(&f->p, gamma1, dPsi1, dPsi2, gamma4, gamma6, &g3, &g5);
    if (fault & FM_FAULT_NAN) return fault;            /* hold the last outputs */
    if (fabs(g3) > f->p.gamma3Max || fabs(g5) > f->p.gamma5Max) fault |= FM_FAULT_LIMIT;
    f->gamma3 = clamp(g3, f->p.gamma3Max);
    f->gamma5 = clamp(g5, f->p.gamma5Max);
    return fault;
}
