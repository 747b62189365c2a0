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

/* ---- pathMemory (see guidance.h) ----------------------------------------- */

#define TG_PI 3.14159265358979323846
#define PM_SEED_TAIL 5.0      /* straight seed behind A6 [m] */
#define PM_WINDOW 2.0         /* foot search half width, at least [m] */
#define PM_GAMMA1_DR 1.5      /* |gamma1| used for dead reckoning at most [rad] */
#define PM_AHEAD 0.5          /* feed-forward: the trace's heading PM_AHEAD v Ts ahead (the mean over the coming sample) */

const char *tg_pm_param_name(void) { return "kPath"; }

static double wrap(double a) { return remainder(a, 2 * TG_PI); }

static double chain_length(const TgParams *p) { return p->lg1 + p->l2 + p->lg2 + p->l3; }

int tg_pm_setup(TgPath *m, const TgGuidance *g, double kPath) {
    if (!(isfinite(kPath) && kPath >= 0 && kPath <= 1e3)) return -11;
    m->kPath = kPath;
    /* the arc of A2 from A6's foot to A2 is at most pi/2 times the chain (on a
       circle); twice the chain plus the seed tail and margin */
    m->dsGrid = (2 * chain_length(&g->p) + 2 * PM_SEED_TAIL) / (TG_PM_N - 1);
    m->window = PM_WINDOW;
    tg_pm_reset(m, g, 0.0, 0.0);
    return 0;
}

/* positions of A4 and A6 from the pose of A2 and the articulation angles */
static void guided_axles(const TgPath *m, const TgParams *p, double d1, double d2,
                         double *x4, double *y4, double *psi2, double *x6, double *y6, double *psi3) {
    *psi2 = m->psi - d1;
    *psi3 = *psi2 - d2;
    *x4 = m->x - p->lg1 * cos(m->psi) - p->l2 * cos(*psi2);
    *y4 = m->y - p->lg1 * sin(m->psi) - p->l2 * sin(*psi2);
    *x6 = *x4 - p->lg2 * cos(*psi2) - p->l3 * cos(*psi3);
    *y6 = *y4 - p->lg2 * sin(*psi2) - p->l3 * sin(*psi3);
}

static long long first_index(const TgPath *m) { return m->next > TG_PM_N ? m->next - TG_PM_N : 0; }

static int slot(long long i) { return (int)(i % TG_PM_N); }

static void store(TgPath *m, double x, double y, double th) {
    const int k = slot(m->next++);
    m->px[k] = x;
    m->py[k] = y;
    m->pth[k] = wrap(th);
}

/* the trace's heading at arc length s, clamped to the stored points */
static double heading_at(const TgPath *m, double s) {
    const long long first = first_index(m), last = m->next - 1;
    double fi = s / m->dsGrid;
    if (!(fi > (double)first)) return m->pth[slot(first)];
    if (!(fi < (double)last)) return m->pth[slot(last)];
    const long long j = (long long)floor(fi);
    const double u = fi - (double)j;
    const double a = m->pth[slot(j)], b = m->pth[slot(j + 1)];
    return wrap(a + u * wrap(b - a));
}

/* foot of (x, y) on the stored polyline near segment *seg; 0 if it lies
   beyond an end of the buffer */
static int foot(const TgPath *m, double x, double y, double half, long long *seg, double *s, double *e) {
    const long long first = first_index(m), lastSeg = m->next - 2;
    if (lastSeg < first) return 0;
    const long long w = (long long)ceil(half / m->dsGrid);
    long long lo = *seg - w, hi = *seg + w;
    if (lo < first) lo = first;
    if (hi > lastSeg) hi = lastSeg;
    if (lo > hi) return 0;
    double best = INFINITY, bu = 0.0, braw = 0.0;
    long long bj = lo;
    for (long long j = lo; j <= hi; j++) {
        const int a = slot(j), b = slot(j + 1);
        const double dx = m->px[b] - m->px[a], dy = m->py[b] - m->py[a];
        const double rx = x - m->px[a], ry = y - m->py[a], len2 = dx * dx + dy * dy;
        const double raw = len2 > 0 ? (rx * dx + ry * dy) / len2 : 0.0;
        const double u = raw < 0 ? 0.0 : raw > 1 ? 1.0 : raw;
        const double ex = rx - u * dx, ey = ry - u * dy, d2 = ex * ex + ey * ey;
        if (d2 < best) { best = d2; bj = j; bu = u; braw = raw; }
    }
    if ((bj == first && braw < 0) || (bj == lastSeg && braw > 1)) return 0;
    const int a = slot(bj), b = slot(bj + 1);
    const double th = m->pth[a] + bu * wrap(m->pth[b] - m->pth[a]);
    const double fx = m->px[a] + bu * (m->px[b] - m->px[a]), fy = m->py[a] + bu * (m->py[b] - m->py[a]);
    *seg = bj;
    *s = ((double)bj + bu) * m->dsGrid;
    *e = -(x - fx) * sin(th) + (y - fy) * cos(th);
    return 1;
}

/* the angle that points the axle of a module heading psiMod along the trace
   at arc length s + ahead, with feedback on its offset e */
static double follow(const TgPath *m, double s, double ahead, double e, double psiMod, double lim,
                     unsigned *fault) {
    const double chi = heading_at(m, s + ahead) - atan(m->kPath * e);
    const double gam = wrap(chi - psiMod);
    if (!isfinite(gam)) { *fault |= TG_FAULT_NAN; return 0.0; }
    if (fabs(gam) > lim) { *fault |= TG_FAULT_LIMIT; return clamp(gam, lim); }
    return gam;
}

/* an arc from P heading th with curvature k: the point and heading at arc length sig */
static void arc_at(double px, double py, double th, double k, double sig, double *x, double *y, double *h) {
    const double half = 0.5 * k * sig;
    const double sinc = fabs(half) > 1e-9 ? sin(half) / half : 1.0;
    *x = px + sig * sinc * cos(th + half);
    *y = py + sig * sinc * sin(th + half);
    *h = th + k * sig;
}

/* the arc from P heading th through Q: curvature and length (a chord when
   Q is not ahead of P: only in a jack-knifed state) */
static void arc_through(double px, double py, double th, double qx, double qy, double *k, double *len) {
    const double cx = qx - px, cy = qy - py, L = hypot(cx, cy);
    const double a = atan2(cos(th) * cy - sin(th) * cx, cos(th) * cx + sin(th) * cy);
    if (!(L > 0) || !(fabs(a) < TG_HALF_PI)) {
        *k = 0.0;
        *len = L;
        return;
    }
    *k = 2 * sin(a) / L;
    *len = fabs(a) > 1e-9 ? L * a / sin(a) : L;
}

void tg_pm_reset(TgPath *m, const TgGuidance *g, double dPsi1, double dPsi2) {
    const TgParams *p = &g->p;
    if (!isfinite(dPsi1)) dPsi1 = 0.0;
    if (!isfinite(dPsi2)) dPsi2 = 0.0;
    m->x = m->y = m->psi = 0.0;
    double x4, y4, psi2, x6, y6, psi3;
    guided_axles(m, p, dPsi1, dPsi2, &x4, &y4, &psi2, &x6, &y6, &psi3);
    /* backwards from A2 (heading psi1 + pi): the arc tangent to module 1 at A2
       through A4, the arc tangent to it at A4 through A6, 5 m straight on */
    double k1, len1, k2, len2, xa, ya, ha, xb, yb, hb;
    arc_through(0.0, 0.0, TG_PI, x4, y4, &k1, &len1);
    arc_at(0.0, 0.0, TG_PI, k1, len1, &xa, &ya, &ha);
    if (k1 == 0.0) ha = atan2(y4, x4);                     /* chord: along it */
    arc_through(x4, y4, ha, x6, y6, &k2, &len2);
    arc_at(x4, y4, ha, k2, len2, &xb, &yb, &hb);
    if (k2 == 0.0) hb = atan2(y6 - y4, x6 - x4);
    const double total = PM_SEED_TAIL + len2 + len1;
    m->next = 0;
    m->s = total;
    while ((double)m->next * m->dsGrid <= total && m->next < TG_PM_N) {
        const double b = total - (double)m->next * m->dsGrid;    /* back from A2 */
        double x, y, h;
        if (b <= len1) {
            if (k1 == 0.0) { x = b * cos(ha); y = b * sin(ha); h = ha; }
            else arc_at(0.0, 0.0, TG_PI, k1, b, &x, &y, &h);
        } else if (b <= len1 + len2) {
            if (k2 == 0.0) { x = x4 + (b - len1) * cos(hb); y = y4 + (b - len1) * sin(hb); h = hb; }
            else arc_at(x4, y4, ha, k2, b - len1, &x, &y, &h);
        } else {
            x = x6 + (b - len1 - len2) * cos(hb);
            y = y6 + (b - len1 - len2) * sin(hb);
            h = hb;
        }
        store(m, x, y, h + TG_PI);                           /* the direction of travel */
    }
    m->s4 = PM_SEED_TAIL + len2;
    m->s6 = PM_SEED_TAIL;
    m->seg4 = (long long)floor(m->s4 / m->dsGrid);
    m->seg6 = (long long)floor(m->s6 / m->dsGrid);
    m->e4 = m->e6 = 0.0;
    unsigned fault = 0;
    m->gamma4 = follow(m, m->s4, 0.0, 0.0, psi2, p->gamma4Max, &fault);
    m->gamma6 = follow(m, m->s6, 0.0, 0.0, psi3, p->gamma6Max, &fault);
}

unsigned tg_pm_sample(TgPath *m, const TgGuidance *g, double gamma1, double v, double dPsi1, double dPsi2) {
    const TgParams *p = &g->p;
    if (!isfinite(gamma1) || !isfinite(v) || !isfinite(dPsi1) || !isfinite(dPsi2)) return TG_FAULT_NAN;
    if (v < 0) return TG_FAULT_SPEED;                         /* hold */
    if (v == 0) return 0;                                     /* no motion, no update */
    unsigned fault = 0;
    const double ds = v * p->Ts;
    if (!(ds <= (double)TG_PM_N * m->dsGrid / 8)) {          /* too long a step for the buffer */
        tg_pm_reset(m, g, dPsi1, dPsi2);
        return TG_FAULT_TRACE;
    }
    const double half = fmax(m->window, 3 * ds);              /* at most 3/8 of the buffer */
    double x4, y4, psi2, x6, y6, psi3;
    guided_axles(m, p, dPsi1, dPsi2, &x4, &y4, &psi2, &x6, &y6, &psi3);
    long long seg4 = m->seg4, seg6 = m->seg6;
    double s4, s6, e4, e6;
    if (foot(m, x4, y4, half, &seg4, &s4, &e4) && foot(m, x6, y6, half, &seg6, &s6, &e6)) {
        m->seg4 = seg4; m->seg6 = seg6;
        m->s4 = s4; m->s6 = s6; m->e4 = e4; m->e6 = e6;
        m->gamma4 = follow(m, s4, PM_AHEAD * ds, e4, psi2, p->gamma4Max, &fault);
        m->gamma6 = follow(m, s6, PM_AHEAD * ds, e6, psi3, p->gamma6Max, &fault);
    } else {
        fault |= TG_FAULT_TRACE;
        tg_pm_reset(m, g, dPsi1, dPsi2);
        return fault;
    }
    /* dead reckoning of A2 over the coming sample, and the trace */
    const double g1 = clamp(gamma1, PM_GAMMA1_DR);
    const double dpsi = ds * tan(g1) / p->l1;
    const double x0 = m->x, y0 = m->y, psi0 = m->psi, s0 = m->s;
    m->x += ds * cos(psi0 + 0.5 * dpsi);
    m->y += ds * sin(psi0 + 0.5 * dpsi);
    m->psi = wrap(psi0 + dpsi);
    m->s += ds;
    while ((double)m->next * m->dsGrid <= m->s) {
        const double f = ((double)m->next * m->dsGrid - s0) / ds;
        store(m, x0 + f * (m->x - x0), y0 + f * (m->y - y0), psi0 + f * dpsi);
    }
    return fault;
}
