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
#define TG_FAULT_TRACE   16u   /* pathMemory: a guided axle is not beside the stored trace of
                                  A2 (its foot would be beyond an end of the buffer), or v Ts
                                  is too long for the buffer: the trace is re-seeded */

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

/* ---- pathMemory: follow-the-leader on the stored trace of A2 -------------
 *
 * Beyond the paper (issue 6). The controller dead-reckons the path of A2 from
 * what an ECU on the bus measures and stores it; A4 and A6 are steered to
 * follow that stored trace at their own arc-length position.
 *
 * Dead reckoning (frame of the ECU: A2 at the origin heading +x at the last
 * reset). Per sample, with the held inputs, A2 advances by ds = v Ts along
 * module 1's heading psi1, which turns by ds tan(gamma1) / l1 (the kinematic
 * single-track: A2 rolls without side slip, yaw rate v tan(gamma1) / l1):
 *   psi1 += ds kappa, x += ds cos(psi1 - ds kappa / 2), y += ds sin(...).
 * Every TG_PM_N-th of the buffer length of arc length (spacing ds_grid, the
 * buffer holding 2 (lg1 + l2 + lg2 + l3) + 10 m: on any circle the arc of A2
 * between A6's foot and A2 is at most pi/2 times the chain) a point
 * (x, y, psi1) of the trace goes into a ring buffer, interpolated to the grid.
 *
 * Where the guided axles are: from the pose of A2 and the measured
 * articulation angles, psi2 = psi1 - dPsi1, psi3 = psi2 - dPsi2,
 *   A4 = A2 - lg1 h(psi1) - l2 h(psi2),  A6 = A4 - lg2 h(psi2) - l3 h(psi3).
 * Each one's foot on the stored polyline is searched near its last foot (a
 * window of max(2 m, 3 ds) either side; never across the whole buffer, so a
 * trace that passes near itself cannot capture it): arc length s, the
 * trace's heading theta(s) interpolated, the signed lateral offset e (left +).
 *
 * Steering (follow-the-leader): the guided axle's velocity points along the
 * trace at its position, plus feedback on its offset,
 *   chi = theta(s + ds/2) - atan(kPath e),   gamma = chi - psi_module,
 * theta half a sample ahead being the feed-forward of the trace's curvature
 * over the coming sample (theta(s) + kappa(s) ds/2). Kinematically the axle
 * then rolls along the trace and an offset decays as exp(-kPath s) in
 * distance; angles are wrapped to (-pi, pi] and saturated at the limits.
 *
 * Odometry drift. The ECU only knows v, gamma1, dPsi: where A2 really slips
 * sideways (tyre side slip beta2 of a few mrad on the circle at 3 m/s), or
 * its yaw rate differs from v tan(gamma1) / l1 (under-steer, side slip of A1),
 * the stored trace is rotated and bent against the real one. Only the last
 * arc between A6's foot and A2 matters (the feet are found relative to the
 * current estimated pose): a curvature error dk (a gamma1 sensor biased by b:
 * dk = tan(b)/l1) puts an axle the arc s behind A2 about
 *   dk (s^2/2 - s/kPath)
 * off the real trace (s ~ 12 m for A4, ~ 24 m for A6; the bent estimate turns
 * under the bus and the feedback follows it with an estimated offset of
 * -dk s/kPath: 0.074 m and 0.37 m for a 0.5 deg bias, checked in
 * tests/test_path_memory.py); a side slip beta2 of A2 rotates the trace by
 * beta2, about beta2 s. The error does not accumulate with the distance
 * driven (the global drift of the pose is common to trace and bus); it grows
 * with lateral acceleration (slip) and with the square of the distance A2-A6.
 * An error of v (scale) only stretches the trace and shifts the feet along
 * it. On the 36 m bench (3 m/s, ~0.6 m/s^2) the dead-reckoning error is most
 * of what is left: A4/A6 5-10 cm off the real trace while their estimated
 * offsets stay below 3 cm.
 *
 * Start, change of driving direction, an axle beyond an end of the buffer,
 * v Ts longer than an eighth of the buffer (TG_FAULT_TRACE): the trace is seeded
 * from the bus as it stands (the measured articulation angles): going back
 * from A2, the arc tangent to module 1 at A2 through A4, the arc tangent to
 * that at A4 through A6, then 5 m straight on. The axles start on it with
 * zero offset; a bus standing in a steady circle gets exactly its circle, a
 * straight bus a straight line (a chord replaces an arc only when the axle
 * is not behind the point before it: jack-knifed). v = 0: no
 * motion, nothing is recorded, the outputs hold. Bad input (not finite,
 * v < 0): nothing is updated, the outputs hold (fault bits as above).
 */
#define TG_PM_N 1024                 /* points in the ring buffer */

typedef struct {
    double kPath;                    /* feedback gain on the lateral offset [1/m], >= 0 */
    double dsGrid;                   /* arc length between stored points [m] */
    double window;                   /* foot search: half width [m] */
    /* dead-reckoned pose of A2 (ECU frame) */
    double x, y, psi;                /* psi wrapped to (-pi, pi] */
    double s;                        /* odometer of A2 [m] */
    /* the trace: point i (global index) at arc length i dsGrid, in slot i % TG_PM_N;
       stored are i = first .. next - 1, first = max(0, next - TG_PM_N) */
    double px[TG_PM_N], py[TG_PM_N], pth[TG_PM_N];
    long long next;
    /* the guided axles: segment index of the last foot, arc length, offset */
    long long seg4, seg6;
    double s4, s6, e4, e6;
    /* outputs [rad] */
    double gamma4, gamma6;
} TgPath;

/* the path memory for a set-up TgGuidance: 0, or -11 (kPath not valid) */
int tg_pm_setup(TgPath *m, const TgGuidance *g, double kPath);
/* seed the trace from the bus as it stands (see above); outputs from it */
void tg_pm_reset(TgPath *m, const TgGuidance *g, double dPsi1, double dPsi2);
/* One sample: steer A4 and A6 from the pose at this instant (outputs in
 * m->gamma4, m->gamma6, finite and within the limits), then advance the pose
 * by v Ts and record the trace. Returns fault bits (TG_FAULT_NAN, TG_FAULT_SPEED:
 * outputs held; TG_FAULT_TRACE: re-seeded; TG_FAULT_LIMIT: saturated). */
unsigned tg_pm_sample(TgPath *m, const TgGuidance *g, double gamma1, double v, double dPsi1, double dPsi2);
const char *tg_pm_param_name(void);   /* "kPath" (the code -11 of tg_pm_setup) */

#endif
