/* Train-like guidance of the guided wagon axles (seed 000, Task 1, eqs. 29-42)
 * as a plain-C algorithm: no FMI types, no heap, no globals. One TgGuidance
 * object per vehicle; tg_setup once, then tg_sample every sample period.
 *
 * Geometry (seed 000, Fig. 6), all lengths > 0, named as in the paper:
 *   l1   wheelbase A1-A2 of the leading module (eq. 30)
 *   lg1  A2 to hinge G1 (eq. 31, the paper's l_g)
 *   l2   G1 to the guided axle A4 (eq. 32)
 *   lg2  A4 to hinge G2 (eq. 35)
 *   l3   G2 to the guided axle A6 (eq. 36)
 * Angles in rad, positive counter-clockwise (to the left) relative to the
 * axle's own module; a left turn has gamma1 > 0 and gamma4, gamma6 < 0.
 *
 * Steady state (eqs. 29-37): the instantaneous centre M of module 1 lies on
 * the A2 axle line at R2 = l1 / tan(gamma1) (eq. 30); A4 is put on the circle
 * of A2 (eq. 29) and its wheel normal through M. In module 2's frame (origin
 * G1, x forward) the triangle M-G1-A4 of eqs. 31-34 gives M at
 *   x_M = -(l2^2 + e1^2) / (2 l2),  e1^2 = lg1^2   (R_g1^2 = R2^2 + e1^2, eq. 31)
 *   y_M = R2 sqrt(1 + (e1^2 - x_M^2) kappa^2)      (|M A4| = |R2|, eq. 29)
 * and tan(gamma4) = -(l2^2 - e1^2) kappa / (2 l2 sqrt(1 + (e1^2 - x_M^2) kappa^2)),
 * kappa = 1/R2 = tan(gamma1)/l1: the same triangle written in the curvature,
 * so it is finite and continuous through straight driving (kappa = 0) and for
 * both turn directions. Hinge G2 moves on R_g2^2 = R2^2 + e2^2 (eq. 35 as the
 * law of cosines, the slip the seeds' README lists) and A6 follows by the same
 * formula with (l3, e2). Where the square root's argument is <= 0 the
 * triangle does not exist (the paper's arccos argument leaves [-1, 1]; for
 * the 36 m bus below |R2| = 3.98 m, |gamma1| > 56 deg): the angle saturates
 * at its limit and TG_FAULT_GEOMETRY is raised.
 *
 * Transient (eqs. 38-42): each steady-state angle goes through a first-order
 * arc lag with way constant S (per axle), y_k = T*_k (u_k - y_{k-1}) + y_{k-1},
 * T*_k = v_k Ts / (v_k Ts + S): it advances with the distance travelled, so it
 * stands still at v = 0.
 */
#ifndef TRAIN_GUIDANCE_H
#define TRAIN_GUIDANCE_H

/* fault bits returned by tg_sample (0 = all good) */
#define TG_FAULT_NAN      1u   /* an input is NaN or infinite: outputs held */
#define TG_FAULT_SPEED    2u   /* v < 0: treated as v = 0, outputs held */
#define TG_FAULT_GEOMETRY 4u   /* no steady-state triangle (|gamma1| too large
                                  for the geometry, or |gamma1| >= pi/2): saturated */
#define TG_FAULT_LIMIT    8u   /* a steady-state angle beyond its steering limit: saturated */

typedef struct {
    double l1, lg1, l2, lg2, l3;   /* geometry [m] */
    double S4, S6;                 /* way constants of the arc lags [m], >= 0 */
    double Ts;                     /* sample period [s] */
    double gamma4Max, gamma6Max;   /* steering limits [rad], > 0 */
} TgParams;

typedef struct {
    TgParams p;
    /* constants of the two triangles, from tg_setup */
    double a2, d2;                 /* tan(gamma4) = -a2 kappa / sqrt(1 + d2 kappa^2) */
    double a3, d3;                 /* tan(gamma6) = -a3 kappa / sqrt(1 + d3 kappa^2) */
    /* state */
    double gamma4, gamma6;         /* lagged outputs, eq. 41 [rad] */
    double gamma4ss, gamma6ss;     /* steady-state angles of the last sample, eqs. 34, 37 [rad] */
} TgGuidance;

/* Check the parameters and precompute; 0 on success, otherwise a negative
 * number naming the first bad parameter (see tg_param_name). */
int tg_setup(TgGuidance *g, const TgParams *p);
const char *tg_param_name(int code);

/* steady-state angles for a front steering angle (eqs. 29-37, slips fixed);
 * returns fault bits (TG_FAULT_GEOMETRY, TG_FAULT_LIMIT, TG_FAULT_NAN) */
unsigned tg_steady_state(const TgGuidance *g, double gamma1, double *gamma4, double *gamma6);

/* set the lags to the steady state of gamma1 (start, or change of direction) */
void tg_reset(TgGuidance *g, double gamma1);
/* set the lags to given angles (clamped to the limits; NaN -> 0) */
void tg_set(TgGuidance *g, double gamma4, double gamma6);

/* One sample: steady state for gamma1, then the arc lags over the distance
 * v Ts. Outputs in g->gamma4, g->gamma6, always finite and within the limits. */
unsigned tg_sample(TgGuidance *g, double gamma1, double v);

#endif
