/* Force-minimising steering of the middle axles A3 and A5 (seed 000, Task 2,
 * eqs. 43-48) as a plain-C algorithm: no FMI types, no heap, no globals.
 *
 * Each trailing module has one degree of freedom left once its hinge's
 * velocity is known (it rotates about the hinge): the guided axle A4 (A6)
 * fixes its instantaneous centre M2 (M3), and A3 (A5) rolls without side
 * force only if its wheel normal passes through the same centre. The paper
 * finds M2 as a point (eqs. 43-46: alpha1 from R2, beta1 = -alpha1 + dPsi1,
 * the law of sines for R_gM2) and A3's angle from the triangle A3-G1-M2
 * (eqs. 47, 48). Those radii are infinite in straight driving; here the same
 * triangles are written with velocity directions instead of centres (a
 * centre at infinity is a direction), which is finite everywhere:
 *
 *   module 1 (A2 rigid, A1 at gamma1): per unit speed of A2, hinge G1 moves
 *     with (1, -lg1 kappa1) in module 1's frame, kappa1 = tan(gamma1)/l1 (eq. 30);
 *   rotated by the articulation angle dPsi1 = psi1 - psi2 into module 2's
 *     frame: (wx, wy);
 *   module 2 rotates about G1 with omega2 = (wy - wx tan(gamma4)) / l2 so that
 *     A4 moves along its wheel plane; A3, lA3 behind G1, then moves with
 *     (wx, wy - omega2 lA3), hence
 *       tan(gamma3) = (1 - lA3/l2) wy/wx + (lA3/l2) tan(gamma4)      (eq. 48)
 *   and hinge G2 (lg2 behind A4) moves with (wx, wy - omega2 (l2 + lg2)),
 *   rotated by dPsi2 into module 3's frame; gamma5 follows with (l3, lA5, gamma6).
 *
 * Lengths (> 0): l1 (A1-A2), lg1 (A2-G1), l2 (G1-A4), lA3 (G1-A3, the paper's
 * eq. 47 reuses l3 for it), lg2 (A4-G2), l3 (G2-A6), lA5 (G2-A5).
 * Angles in rad, positive counter-clockwise relative to the axle's module;
 * dPsi_i = psi_i - psi_(i+1). The result does not depend on the speed or on
 * its sign, so it holds at standstill and when reversing.
 */
#ifndef FORCE_MINIMIZATION_H
#define FORCE_MINIMIZATION_H

#define FM_FAULT_NAN      1u   /* an input is NaN or infinite: outputs held */
#define FM_FAULT_GEOMETRY 4u   /* no forward-moving hinge (jack-knifed state, |angle| >= pi/2):
                                  saturated */
#define FM_FAULT_LIMIT    8u   /* an angle beyond its steering limit: saturated */

typedef struct {
    double l1, lg1, l2, lA3, lg2, l3, lA5;   /* geometry [m] */
    double gamma3Max, gamma5Max;             /* steering limits [rad] */
} FmParams;

typedef struct {
    FmParams p;
    double gamma3, gamma5;                   /* outputs of the last sample [rad] */
} FmSteering;

int fm_setup(FmSteering *f, const FmParams *p);
const char *fm_param_name(int code);

/* the exact angles (no limits, no state): fault bits, results in *gamma3, *gamma5 */
unsigned fm_angles(const FmParams *p, double gamma1, double dPsi1, double dPsi2,
                   double gamma4, double gamma6, double *gamma3, double *gamma5);

/* One sample: outputs in f->gamma3, f->gamma5, finite and within the limits;
 * held if an input is not finite. */
unsigned fm_sample(FmSteering *f, double gamma1, double dPsi1, double dPsi2,
                   double gamma4, double gamma6);

#endif
