/* Modular kinematics of an N-times articulated bus, seed 003 (Michalek,
 * Patkowski, Gawron), eqs. 14-22 and steps S1-S6, for any number of wagons,
 * any steerable set I_s, any driving-axle segment k and any distinguished
 * segment j. Plain C, no FMI types, no allocation.
 *
 * Segments i = 0..N: 0 is the tractor (wheelbase L[0] = L0, steered by
 * gammaF), 1..N the wagons. Joint i sits Lh[i] behind the axle mid-point
 * P(i-1) of segment i-1; P(i) sits L[i] behind joint i. beta[i] =
 * theta[i-1] - theta[i] (eq. 3).
 */
#ifndef KINEMATICS_H
#define KINEMATICS_H

#define KIN_MAX_WAGONS 4

typedef struct {
    int N;                               /* wagons */
    int k;                               /* segment of the driving axle */
    double L[KIN_MAX_WAGONS + 1];        /* L[0] = L0 tractor wheelbase, L[i] wagon length */
    double Lh[KIN_MAX_WAGONS + 1];       /* Lh[i] hitching offset of joint i (Lh[0] unused) */
    double gamma[KIN_MAX_WAGONS + 1];    /* steering angle of each segment's axle: gamma[0] = 0
                                            (assumption A5), 0 for fixed wagon axles */
} KinChain;

typedef struct {
    double kappa[KIN_MAX_WAGONS + 1];    /* motion curvature (eqs. 19, 20) */
    double omega[KIN_MAX_WAGONS + 1];    /* angular velocity */
    double vel[KIN_MAX_WAGONS + 1];      /* speed of P(i) in its wheel plane */
    double delta[KIN_MAX_WAGONS + 1];    /* virtual steering angle at joint i (eq. 17) */
    double betaDot[KIN_MAX_WAGONS + 1];  /* joint rates (eq. 16) */
    double betaMax[KIN_MAX_WAGONS + 1];  /* |beta[i]| at which |delta[i]| = pi/2 (eq. 31 generalised) */
} KinRates;

/* Velocities of every segment for front steering gammaF and driving speed
 * vk of segment k. Returns 0, or the first joint i whose |delta[i]| >= pi/2
 * (the curvature (20) is unbounded there: jack-knife). */
int kin_rates(const KinChain *c, double gammaF, const double beta[], double vk, KinRates *r);

/* Poses of all segments from the pose of segment j and the joint angles. */
void kin_poses(const KinChain *c, int j, const double beta[],
               double theta[], double x[], double y[]);

#endif
