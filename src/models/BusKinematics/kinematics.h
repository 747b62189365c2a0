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

/* What depends on the state and the inputs is written on KIN_REAL: double
 * here (kinematics.c compiled as C), a dual number in kinematics_dual.cpp,
 * which compiles the same kinematics.c a second time in C++ for the FMU's
 * directional derivatives (one source of the equations). */
#ifndef KIN_REAL
#define KIN_REAL double
#endif

#define KIN_MAX_WAGONS 4

typedef struct {
    int N;                               /* wagons */
    int k;                               /* segment of the driving axle */
    double L[KIN_MAX_WAGONS + 1];        /* L[0] = L0 tractor wheelbase, L[i] wagon length */
    double Lh[KIN_MAX_WAGONS + 1];       /* Lh[i] hitching offset of joint i (Lh[0] unused) */
    KIN_REAL gamma[KIN_MAX_WAGONS + 1];  /* steering angle of each segment's axle: gamma[0] = 0
                                            (assumption A5), 0 for fixed wagon axles */
} KinChain;

typedef struct {
    KIN_REAL kappa[KIN_MAX_WAGONS + 1];    /* motion curvature (eqs. 19, 20) */
    KIN_REAL omega[KIN_MAX_WAGONS + 1];    /* angular velocity */
    KIN_REAL vel[KIN_MAX_WAGONS + 1];      /* speed of P(i) in its wheel plane */
    KIN_REAL delta[KIN_MAX_WAGONS + 1];    /* virtual steering angle at joint i (eq. 17) */
    KIN_REAL betaDot[KIN_MAX_WAGONS + 1];  /* joint rates (eq. 16) */
    KIN_REAL betaMax[KIN_MAX_WAGONS + 1];  /* |beta[i]| at which |delta[i]| = pi/2 (eq. 31 generalised) */
} KinRates;

/* Velocities of every segment for front steering gammaF and driving speed
 * vk of segment k. Returns 0, or the first joint i whose |delta[i]| >= pi/2
 * (the curvature (20) is unbounded there: jack-knife). */
int kin_rates(const KinChain *c, KIN_REAL gammaF, const KIN_REAL beta[], KIN_REAL vk, KinRates *r);

/* Poses of all segments from the pose of segment j and the joint angles. */
void kin_poses(const KinChain *c, int j, const KIN_REAL beta[],
               KIN_REAL theta[], KIN_REAL x[], KIN_REAL y[]);

/* The inputs of the right-hand side besides the chain: the front steering
 * angle gammaF, the speed vk of segment k, the distinguished segment j, and
 * the prediction model's measured angular velocity (used where prediction). */
typedef struct {
    int j, prediction;
    KIN_REAL gammaF, vk, omegaMeas;
} KinDrive;

/* The right-hand side of y = [theta_j, x_j, y_j, beta_1 .. beta_N] (eq. 22,
 * eq. 16) into ydot[3 + N]; returns kin_rates' jack-knifed joint, 0 if none
 * (ydot is filled either way). r (if not NULL) receives the rates. */
int kin_derivs(const KinChain *c, const KinDrive *dr, const KIN_REAL y[], KIN_REAL ydot[], KinRates *r);

/* Every output from the state y[3 + KIN_MAX_WAGONS] (beta beyond N: 0) into
 * out[KIN_NOUT] at these indices (segments beyond N: 0): the poses theta, x,
 * y of segments 0..KIN_MAX_WAGONS, omega, vel, kappa, then betaDot and
 * betaMax of joints 1..KIN_MAX_WAGONS, then ydot (3 + KIN_MAX_WAGONS). */
enum { KIN_SEG = KIN_MAX_WAGONS + 1, KIN_OUT_THETA = 0, KIN_OUT_X = KIN_SEG, KIN_OUT_Y = 2 * KIN_SEG,
       KIN_OUT_OMEGA = 3 * KIN_SEG, KIN_OUT_VEL = 4 * KIN_SEG, KIN_OUT_KAPPA = 5 * KIN_SEG,
       KIN_OUT_BETADOT = 6 * KIN_SEG, KIN_OUT_BETAMAX = KIN_OUT_BETADOT + KIN_MAX_WAGONS,
       KIN_OUT_YDOT = KIN_OUT_BETAMAX + KIN_MAX_WAGONS, KIN_NOUT = KIN_OUT_YDOT + 3 + KIN_MAX_WAGONS };
void kin_outputs(const KinChain *c, const KinDrive *dr, const KIN_REAL y[], KIN_REAL out[KIN_NOUT]);

/* kin_outputs and its derivative dout along the seed (dgamma of the chain's
 * gamma[1..], dgammaF, dvk, domegaMeas, dy): kinematics_dual.cpp, the same
 * equations on dual numbers. gamma and dgamma have KIN_MAX_WAGONS + 1 entries. */
#ifdef __cplusplus
extern "C"
#endif
void kin_outputs_tangent(int N, int k, const double L[], const double Lh[], const double gamma[],
                         const double dgamma[], int j, int prediction, double gammaF, double dgammaF,
                         double vk, double dvk, double omegaMeas, double domegaMeas,
                         const double y[], const double dy[], double out[], double dout[]);

#endif
