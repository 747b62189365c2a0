/* ecu_steering: the steering algorithms of seed 000 (TrainGuidance's
 * guidance.c, ForceMinimization's forcemin.c) built alone, without any FMI
 * header, the way they would go on an ECU: static objects, no heap, a 10 ms
 * loop. Checks against geometry computed here by another route (explicit
 * centres and circle intersections), and that bad input never gives NaN or
 * an angle beyond the limits. The pathMemory mode (tg_pm_*) in the loop with
 * a kinematic model of the 36 m bus's chain written here (A2 rigid, A4 and
 * A6 steered, RK4 at 1 ms): A4 and A6 on the A2 circle, on the A2 trace
 * through entry and exit, standing still, bad input. Run by ctest; exit
 * status 1 on any failure.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "guidance.h"
#include "forcemin.h"

#define PI 3.14159265358979323846

static int checks = 0, failures = 0;
#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

/* the 36 m bus (ssp/parameters/Bus36m.ssv): axles 2.95 m and hinges 6.1 m from each CG */
static const TgParams TG = { .l1 = 5.9, .lg1 = 3.15, .l2 = 9.05, .lg2 = 3.15, .l3 = 9.05,
                             .S4 = 5.0, .S6 = 10.0, .Ts = 0.01, .gamma4Max = 0.75, .gamma6Max = 0.75 };
static const FmParams FM = { .l1 = 5.9, .lg1 = 3.15, .l2 = 9.05, .lA3 = 3.15, .lg2 = 3.15,
                             .l3 = 9.05, .lA5 = 3.15, .gamma3Max = 0.75, .gamma5Max = 0.75 };
static TgGuidance tg;      /* static: nothing on the heap */
static TgPath pm;
static FmSteering fm;

/* the intersection of the circles |P - M| = R and |P - G| = l farther back
 * along the heading hx, hy of the hinge's module; 0 if none */
static int trailing_point(double Mx, double My, double R, double Gx, double Gy, double l,
                          double hx, double hy, double *Px, double *Py) {
    const double dx = Gx - Mx, dy = Gy - My, d = hypot(dx, dy);
    const double a = (R * R - l * l + d * d) / (2 * d), h2 = R * R - a * a;
    if (h2 < 0) return 0;
    const double bx = Mx + a * dx / d, by = My + a * dy / d, h = sqrt(h2);
    const double p1x = bx - h * dy / d, p1y = by + h * dx / d, p2x = bx + h * dy / d, p2y = by - h * dx / d;
    const int first = (p1x - Gx) * hx + (p1y - Gy) * hy < (p2x - Gx) * hx + (p2y - Gy) * hy;
    *Px = first ? p1x : p2x;
    *Py = first ? p1y : p2y;
    return 1;
}

/* the steering angle that makes the axle at P (module heading from P to the
 * hinge G) roll on the circle about M, counter-clockwise positive */
static double angle_on_circle(double Mx, double My, double Px, double Py, double Gx, double Gy, double turn) {
    const double head = atan2(Gy - Py, Gx - Px);
    const double vel = atan2(turn * (Px - Mx), -turn * (Py - My));   /* perpendicular to P - M */
    return remainder(vel - head, 2 * PI);
}

static void guidance_steady_state(void) {
    const double radii[] = { 12, 17.5, 25, 50, 100, 1000 };
    for (int s = -1; s <= 1; s += 2)
        for (unsigned i = 0; i < sizeof radii / sizeof *radii; i++) {
            const double R2 = s * radii[i], gamma1 = atan(TG.l1 / R2);
            double g4, g6;
            const unsigned f = tg_steady_state(&tg, gamma1, &g4, &g6);
            /* module 1: A2 at the origin heading +x, centre M on its axle line */
            const double Mx = 0, My = R2, G1x = -TG.lg1, G1y = 0;
            double A4x = 0, A4y = 0, A6x = 0, A6y = 0;
            CHECK(trailing_point(Mx, My, fabs(R2), G1x, G1y, TG.l2, 1, 0, &A4x, &A4y), "no A4 for R2 = %g", R2);
            const double e4 = angle_on_circle(Mx, My, A4x, A4y, G1x, G1y, s);
            const double h2x = (G1x - A4x) / TG.l2, h2y = (G1y - A4y) / TG.l2;
            const double G2x = A4x - TG.lg2 * h2x, G2y = A4y - TG.lg2 * h2y;
            CHECK(trailing_point(Mx, My, fabs(R2), G2x, G2y, TG.l3, h2x, h2y, &A6x, &A6y), "no A6");
            const double e6 = angle_on_circle(Mx, My, A6x, A6y, G2x, G2y, s);
            CHECK(f == 0 && fabs(g4 - e4) < 1e-12 && fabs(g6 - e6) < 1e-12,
                  "R2 = %g: gamma4 = %.15g (expected %.15g), gamma6 = %.15g (expected %.15g), fault %u",
                  R2, g4, e4, g6, e6, f);
        }
    double g4, g6;
    CHECK(tg_steady_state(&tg, 0.0, &g4, &g6) == 0 && g4 == 0 && g6 == 0, "straight is not 0");
    double p4, p6, m4, m6;
    tg_steady_state(&tg, 1e-9, &p4, &p6);
    tg_steady_state(&tg, -1e-9, &m4, &m6);
    CHECK(fabs(p4) < 1e-8 && p4 == -m4 && p6 == -m6 && p4 < 0, "not continuous and odd at gamma1 = 0");
}

static void guidance_lag(void) {
    tg_setup(&tg, &TG);
    tg_set(&tg, 0, 0);
    const double gamma1 = atan(TG.l1 / 17.5);
    double g4, g6;
    tg_steady_state(&tg, gamma1, &g4, &g6);
    for (int k = 0; k < 1000; k++) tg_sample(&tg, gamma1, 0.0);     /* standing: nothing moves */
    CHECK(tg.gamma4 == 0 && tg.gamma6 == 0, "the lag moved at v = 0");
    const double v = 3.0, ds = v * TG.Ts;
    const int n = 300;                                               /* 9 m */
    for (int k = 0; k < n; k++) tg_sample(&tg, gamma1, v);
    const double r4 = pow(TG.S4 / (TG.S4 + ds), n), r6 = pow(TG.S6 / (TG.S6 + ds), n);
    CHECK(fabs(tg.gamma4 - g4 * (1 - r4)) < 1e-12 && fabs(tg.gamma6 - g6 * (1 - r6)) < 1e-12,
          "arc lag: %.15g vs %.15g", tg.gamma4, g4 * (1 - r4));
    /* the same 9 m at another speed: the same angles (eqs. 38-42 in arc length) */
    TgGuidance slow;
    tg_setup(&slow, &TG);
    tg_set(&slow, 0, 0);
    for (int k = 0; k < 3 * n; k++) tg_sample(&slow, gamma1, v / 3);
    CHECK(fabs(slow.gamma4 - tg.gamma4) < 0.002 * fabs(g4), "lag depends on speed: %g vs %g", slow.gamma4, tg.gamma4);
}

static int bounded_tg(void) {
    return isfinite(tg.gamma4) && isfinite(tg.gamma6) && fabs(tg.gamma4) <= TG.gamma4Max &&
           fabs(tg.gamma6) <= TG.gamma6Max;
}

static void guidance_bad_input(void) {
    tg_setup(&tg, &TG);
    tg_reset(&tg, 0.2);
    const double held4 = tg.gamma4;
    CHECK(tg_sample(&tg, NAN, 3.0) & TG_FAULT_NAN, "NaN gamma1 not flagged");
    CHECK(tg_sample(&tg, 0.2, NAN) & TG_FAULT_NAN, "NaN v not flagged");
    CHECK(tg_sample(&tg, INFINITY, INFINITY) & TG_FAULT_NAN, "Inf not flagged");
    CHECK(tg.gamma4 == held4 && bounded_tg(), "not held on NaN");
    CHECK(tg_sample(&tg, 0.3, -2.0) & TG_FAULT_SPEED, "v < 0 not flagged");
    CHECK(tg.gamma4 == held4 && bounded_tg(), "moved with v < 0");
    const double bad_gamma1[] = { 1.2, -1.2, PI / 2, -PI / 2, 3.0, -100.0, 1e300 };
    for (unsigned i = 0; i < sizeof bad_gamma1 / sizeof *bad_gamma1; i++) {
        const unsigned f = tg_sample(&tg, bad_gamma1[i], 5.0);
        CHECK((f & TG_FAULT_GEOMETRY) && bounded_tg(), "gamma1 = %g: fault %u, gamma4 = %g", bad_gamma1[i], f, tg.gamma4);
    }
    /* a geometry whose steady-state triangle does not exist for moderate gamma1 */
    TgParams odd = TG;
    odd.l2 = 1.0; odd.lg1 = 8.0;
    tg_setup(&tg, &odd);
    const unsigned f = tg_sample(&tg, 0.5, 1.0);
    CHECK((f & TG_FAULT_GEOMETRY) && isfinite(tg.gamma4ss) && fabs(tg.gamma4ss) <= odd.gamma4Max,
          "odd geometry: fault %u, gamma4ss = %g", f, tg.gamma4ss);
    TgParams neg = TG;
    neg.l2 = -1;
    CHECK(tg_setup(&tg, &neg) != 0, "negative l2 accepted");
    neg = TG;
    neg.Ts = NAN;
    CHECK(tg_setup(&tg, &neg) != 0, "NaN Ts accepted");
}

/* gamma3 by explicit centres: M1 on A2's axle line, M2 where the normal of
 * G1's velocity meets A4's wheel axis; A3's wheel normal must pass through M2 */
static double gamma3_by_centres(double gamma1, double dPsi1, double gamma4) {
    const double psi2 = -dPsi1;                       /* module 1 heads along +x */
    const double M1x = 0, M1y = FM.l1 / tan(gamma1), G1x = -FM.lg1, G1y = 0;
    const double cx = cos(psi2), cy = sin(psi2);      /* module 2 axis */
    const double A4x = G1x - FM.l2 * cx, A4y = G1y - FM.l2 * cy;
    const double A3x = G1x - FM.lA3 * cx, A3y = G1y - FM.lA3 * cy;
    /* line G1 + s (M1 - G1) and line A4 + u n4, n4 = wheel axis of A4 */
    const double n4x = -sin(psi2 + gamma4), n4y = cos(psi2 + gamma4);
    const double ex = M1x - G1x, ey = M1y - G1y;
    const double det = ex * (-n4y) - ey * (-n4x);
    const double s = ((A4x - G1x) * (-n4y) - (A4y - G1y) * (-n4x)) / det;
    const double M2x = G1x + s * ex, M2y = G1y + s * ey;
    /* A3's heading is perpendicular to M2 - A3, pointing forward */
    double hx = -(M2y - A3y), hy = M2x - A3x;
    if (hx * cx + hy * cy < 0) { hx = -hx; hy = -hy; }
    return remainder(atan2(hy, hx) - psi2, 2 * PI);
}

static void force_minimisation(void) {
    CHECK(fm_setup(&fm, &FM) == 0, "fm_setup");
    double g3, g5;
    CHECK(fm_angles(&FM, 0, 0, 0, 0, 0, &g3, &g5) == 0 && g3 == 0 && g5 == 0, "straight is not 0");
    const double cases[][3] = { { 0.3, 0.4, -0.2 }, { -0.25, -0.1, 0.3 }, { 0.05, -0.3, 0.1 }, { 0.6, 0.9, -0.5 } };
    for (int i = 0; i < 4; i++) {
        fm_angles(&FM, cases[i][0], cases[i][1], 0, cases[i][2], 0, &g3, &g5);
        const double e3 = gamma3_by_centres(cases[i][0], cases[i][1], cases[i][2]);
        CHECK(fabs(g3 - e3) < 1e-10, "case %d: gamma3 = %.15g, by centres %.15g", i, g3, e3);
    }
    /* the steady circle: with the guidance's angles and the steady articulation
       every module turns about M, so A3 and A5 point at M as well */
    tg_setup(&tg, &TG);
    const double R2 = 17.5, gamma1 = atan(TG.l1 / R2);
    double g4, g6;
    tg_steady_state(&tg, gamma1, &g4, &g6);
    const double G1x = -TG.lg1, G1y = 0;
    double A4x = 0, A4y = 0;
    trailing_point(0, R2, R2, G1x, G1y, TG.l2, 1, 0, &A4x, &A4y);
    const double dPsi1 = -atan2(G1y - A4y, G1x - A4x);
    const double A3x = G1x + (A4x - G1x) * FM.lA3 / FM.l2, A3y = G1y + (A4y - G1y) * FM.lA3 / FM.l2;
    const double e3 = angle_on_circle(0, R2, A3x, A3y, G1x, G1y, 1);
    fm_angles(&FM, gamma1, dPsi1, 0, g4, 0, &g3, &g5);
    CHECK(fabs(g3 - e3) < 1e-12, "steady circle: gamma3 = %.15g, on the circle %.15g", g3, e3);

    /* bad input: held on NaN, saturated when jack-knifed, never NaN */
    fm_sample(&fm, 0.2, 0.1, 0.05, -0.1, -0.1);
    const double held = fm.gamma3;
    CHECK(fm_sample(&fm, NAN, 0, 0, 0, 0) & FM_FAULT_NAN, "NaN not flagged");
    CHECK(fm_sample(&fm, 0, INFINITY, 0, 0, 0) & FM_FAULT_NAN, "Inf not flagged");
    CHECK(fm.gamma3 == held, "not held on NaN");
    const double bad[][5] = { { 0, 2.0, 0, 0, 0 }, { 0.5, -3.0, 3.0, 0, 0 }, { PI / 2, 0, 0, 0, 0 },
                              { 0, 0, 0, 1.6, -1.6 }, { 0, PI / 2, 0, 0, 0 }, { 1e300, -1e300, 1e300, 1e300, 1e300 } };
    for (int i = 0; i < 6; i++) {
        const unsigned f = fm_sample(&fm, bad[i][0], bad[i][1], bad[i][2], bad[i][3], bad[i][4]);
        CHECK(f != 0 && isfinite(fm.gamma3) && isfinite(fm.gamma5) && fabs(fm.gamma3) <= FM.gamma3Max &&
              fabs(fm.gamma5) <= FM.gamma5Max, "bad case %d: fault %u, gamma3 = %g, gamma5 = %g", i, f,
              fm.gamma3, fm.gamma5);
    }
}


/* ---- pathMemory in the loop with a kinematic chain ------------------------ */

/* the 36 m bus as a kinematic chain: A2 at (x, y), headings psi[0..2] of the
   modules; A2 rolls at speed v, A1 steered by gamma1, A4 and A6 roll in the
   directions psi2 + gamma4, psi3 + gamma6 (no slip) */
typedef struct { double x, y, psi[3]; } Chain;

static void chain_rates(const Chain *c, double v, double g1, double g4, double g6, Chain *d) {
    const double r1 = v * tan(g1) / TG.l1;
    d->x = v * cos(c->psi[0]);
    d->y = v * sin(c->psi[0]);
    d->psi[0] = r1;
    /* G1 = A2 - lg1 h(psi1) */
    const double vG1x = d->x + TG.lg1 * r1 * sin(c->psi[0]), vG1y = d->y - TG.lg1 * r1 * cos(c->psi[0]);
    /* A4 = G1 - l2 h(psi2): v_A4 = v_G1 - l2 r2 n(psi2), v_A4 . n(psi2 + g4) = 0 */
    const double n4x = -sin(c->psi[1] + g4), n4y = cos(c->psi[1] + g4);
    const double r2 = (vG1x * n4x + vG1y * n4y) / (TG.l2 * cos(g4));
    const double vA4x = vG1x + TG.l2 * r2 * sin(c->psi[1]), vA4y = vG1y - TG.l2 * r2 * cos(c->psi[1]);
    const double vG2x = vA4x + TG.lg2 * r2 * sin(c->psi[1]), vG2y = vA4y - TG.lg2 * r2 * cos(c->psi[1]);
    const double n6x = -sin(c->psi[2] + g6), n6y = cos(c->psi[2] + g6);
    d->psi[1] = r2;
    d->psi[2] = (vG2x * n6x + vG2y * n6y) / (TG.l3 * cos(g6));
}

static void chain_step(Chain *c, double v, double g1, double g4, double g6, double h) {
    Chain k[4], tmp;
    const double w[4] = { 0.0, 0.5, 0.5, 1.0 };
    for (int i = 0; i < 4; i++) {
        tmp = *c;
        if (i) {
            tmp.x += w[i] * h * k[i - 1].x;
            tmp.y += w[i] * h * k[i - 1].y;
            for (int j = 0; j < 3; j++) tmp.psi[j] += w[i] * h * k[i - 1].psi[j];
        }
        chain_rates(&tmp, v, g1, g4, g6, &k[i]);
    }
    c->x += h / 6 * (k[0].x + 2 * k[1].x + 2 * k[2].x + k[3].x);
    c->y += h / 6 * (k[0].y + 2 * k[1].y + 2 * k[2].y + k[3].y);
    for (int j = 0; j < 3; j++) c->psi[j] += h / 6 * (k[0].psi[j] + 2 * k[1].psi[j] + 2 * k[2].psi[j] + k[3].psi[j]);
}

static void chain_axles(const Chain *c, double *x4, double *y4, double *x6, double *y6) {
    *x4 = c->x - TG.lg1 * cos(c->psi[0]) - TG.l2 * cos(c->psi[1]);
    *y4 = c->y - TG.lg1 * sin(c->psi[0]) - TG.l2 * sin(c->psi[1]);
    *x6 = *x4 - TG.lg2 * cos(c->psi[1]) - TG.l3 * cos(c->psi[2]);
    *y6 = *y4 - TG.lg2 * sin(c->psi[1]) - TG.l3 * sin(c->psi[2]);
}

/* the true trace of A2, a point every 5 cm (static) */
#define TRACE_MAX 8000
static double trx[TRACE_MAX], try_[TRACE_MAX];
static int ntr;

static double trace_distance(double x, double y) {
    double best = INFINITY;
    for (int i = 0; i + 1 < ntr; i++) {
        const double dx = trx[i + 1] - trx[i], dy = try_[i + 1] - try_[i], l2 = dx * dx + dy * dy;
        double u = l2 > 0 ? ((x - trx[i]) * dx + (y - try_[i]) * dy) / l2 : 0.0;
        if (i == 0 && u < 0) continue;                   /* behind the reference's start */
        u = u < 0 ? 0 : u > 1 ? 1 : u;
        const double d = hypot(x - trx[i] - u * dx, y - try_[i] - u * dy);
        if (d < best) best = d;
    }
    return best;
}

/* drive the chain (straight at the start) with pathMemory at 10 ms; gamma1
   as a function of the distance; returns the largest distance of A4 and A6
   from the true A2 trace (checked every 0.25 m), and in r46 the largest
   |radius - R2| of A4, A6 about A2's centre over the last half lap of a
   constant gamma1 (when R2 != 0) */
static double pm_drive(double (*gamma1_of)(double), double length, double v, double R2, double *r46) {
    Chain c = { 0.0, 0.0, { 0.0, 0.0, 0.0 } };
    tg_setup(&tg, &TG);
    tg_pm_setup(&pm, &tg, 0.5);
    tg_reset(&tg, 0.0);
    tg_pm_reset(&pm, &tg, 0.0, 0.0);
    ntr = 0;
    const int sub = 10, n = (int)(length / (v * TG.Ts));
    double s = 0.0, worst = 0.0, nextCheck = 0.0, nextTrace = 0.0;
    *r46 = 0.0;
    for (int k = 0; k < n; k++) {
        const double g1 = gamma1_of(s);
        tg_sample(&tg, g1, v);
        const unsigned f = tg_pm_sample(&pm, &tg, g1, v, c.psi[0] - c.psi[1], c.psi[1] - c.psi[2]);
        CHECK((f & ~(unsigned)TG_FAULT_LIMIT) == 0, "pathMemory fault %u at s = %g", f, s);
        for (int i = 0; i < sub; i++) chain_step(&c, v, g1, pm.gamma4, pm.gamma6, TG.Ts / sub);
        s += v * TG.Ts;
        if (s >= nextTrace && ntr < TRACE_MAX) {
            trx[ntr] = c.x; try_[ntr] = c.y; ntr++;
            nextTrace += 0.05;
        }
        double x4, y4, x6, y6;
        chain_axles(&c, &x4, &y4, &x6, &y6);
        if (s >= nextCheck && s > 30.0) {                /* A6 is beside the trace from 24.4 m on */
            const double d = fmax(trace_distance(x4, y4), trace_distance(x6, y6));
            if (d > worst) worst = d;
            nextCheck += 0.25;
        }
        if (R2 != 0 && s > length - PI * fabs(R2)) {
            const double Mx = c.x - R2 * sin(c.psi[0]), My = c.y + R2 * cos(c.psi[0]);
            const double r = fmax(fabs(hypot(x4 - Mx, y4 - My) - fabs(R2)), fabs(hypot(x6 - Mx, y6 - My) - fabs(R2)));
            if (r > *r46) *r46 = r;
        }
    }
    return worst;
}

static double circle_R2;
static double circle_gamma1(double s) { return s < 20.0 ? 0.0 : atan(TG.l1 / circle_R2); }
static double s_curve(double s) {
    return s < 20.0 ? 0.0 : s < 60.0 ? atan(TG.l1 / 15.0) : s < 100.0 ? -atan(TG.l1 / 20.0) : 0.0;
}

static void path_memory(void) {
    CHECK(tg_pm_setup(&pm, &tg, NAN) == -11 && tg_pm_setup(&pm, &tg, -1.0) == -11, "bad kPath accepted");
    const double radii[] = { 12.0, -12.0, 17.5, -17.5, 50.0, -50.0 };
    for (unsigned i = 0; i < sizeof radii / sizeof *radii; i++) {
        circle_R2 = radii[i];
        const double length = 20.0 + 2 * 2 * PI * fabs(circle_R2);
        const double v = 5.0;
        double r46;
        pm_drive(circle_gamma1, length, v, circle_R2, &r46);
        CHECK(r46 < 0.01, "R2 = %g: A4/A6 %.4f m off the A2 circle", circle_R2, r46);
        printf("pathMemory, R2 = %6.1f m: A4/A6 at most %.2f mm off the A2 circle\n", circle_R2, r46 * 1e3);
        CHECK(pm.gamma4 * circle_R2 < 0 && pm.gamma6 * circle_R2 < 0, "R2 = %g: not opposite to A1", circle_R2);
    }
    double r46;
    const double worst = pm_drive(s_curve, 150.0, 5.0, 0.0, &r46);
    printf("pathMemory, S-curve with entry and exit: A4/A6 at most %.2f mm from the A2 trace\n", worst * 1e3);
    CHECK(worst < 0.03, "S-curve: %.4f m from the A2 trace", worst);

    /* standing still: nothing changes, bit for bit */
    static TgPath before;
    memcpy(&before, &pm, sizeof pm);
    for (int k = 0; k < 500; k++) CHECK(tg_pm_sample(&pm, &tg, 0.3 * sin(k), 0.0, 0.1 * k, -0.2) == 0, "v = 0 fault");
    CHECK(memcmp(&before, &pm, sizeof pm) == 0, "pathMemory moved at v = 0");
    /* bad input: held, flagged */
    CHECK(tg_pm_sample(&pm, &tg, NAN, 3.0, 0, 0) == TG_FAULT_NAN, "NaN gamma1 not flagged");
    CHECK(tg_pm_sample(&pm, &tg, 0.1, INFINITY, 0, 0) == TG_FAULT_NAN, "Inf v not flagged");
    CHECK(tg_pm_sample(&pm, &tg, 0.1, 3.0, NAN, 0) == TG_FAULT_NAN, "NaN dPsi1 not flagged");
    CHECK(tg_pm_sample(&pm, &tg, 0.1, 3.0, 0, -INFINITY) == TG_FAULT_NAN, "Inf dPsi2 not flagged");
    CHECK(tg_pm_sample(&pm, &tg, 0.1, -1.0, 0, 0) == TG_FAULT_SPEED, "v < 0 not flagged");
    CHECK(memcmp(&before, &pm, sizeof pm) == 0, "pathMemory moved on bad input");
    /* absurd but finite input: finite, within the limits, never NaN */
    const double bad[][4] = { { 1.5, 3.0, 0, 0 }, { -PI / 2, 3.0, 3.0, -3.0 }, { 3.0, 3.0, PI, PI },
                              { 1e300, 3.0, -1e300, 1e300 }, { 0.2, 1e6, 0, 0 }, { 0.2, 1e300, 0.1, 0.1 },
                              { 0.0, 3.0, 0.0, 0.0 } };
    for (unsigned i = 0; i < sizeof bad / sizeof *bad; i++)
        for (int k = 0; k < 200; k++) {
            const unsigned f = tg_pm_sample(&pm, &tg, bad[i][0], bad[i][1], bad[i][2], bad[i][3]);
            CHECK(isfinite(pm.gamma4) && isfinite(pm.gamma6) && fabs(pm.gamma4) <= TG.gamma4Max &&
                  fabs(pm.gamma6) <= TG.gamma6Max && isfinite(pm.e4) && isfinite(pm.e6) && isfinite(pm.x) &&
                  isfinite(pm.psi), "bad case %u: fault %u, gamma4 = %g, gamma6 = %g", i, f, pm.gamma4, pm.gamma6);
            if (bad[i][1] > 1e5) CHECK(f & TG_FAULT_TRACE, "bad case %u: too long a step not flagged", i);
        }
}

int main(void) {
    CHECK(tg_setup(&tg, &TG) == 0, "tg_setup");
    guidance_steady_state();
    guidance_lag();
    guidance_bad_input();
    force_minimisation();
    path_memory();
    printf("ecu_steering: %d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
