/* Model-based articulation damping of an articulated (pusher) bus, seed 001
 * (master thesis, Scania), as a plain-C algorithm: no FMI types, no heap, no
 * globals, ISO C99 and libm only, so that it can go on an ECU (50 Hz in the
 * thesis, 4.1.1).
 *
 * Per sample (period Ts, inputs held):
 *  1. the kinematic reference model of the articulation angle (seed 001,
 *     ch. 2), driven by delta* = Kc(v) delta (4.1.2; Kc a table over speed,
 *     linear interpolation, clamped at its ends):
 *       small-angle, eq. 2.9:  LambdaDot = -(v/l2) Lambda + v a delta*,
 *           l1 = f1 + b1, l2 = f2 + b2, a = 1/l1 + (b11 - b1)/(l1 l2);
 *       exact, eq. 2.3:        LambdaDot = v sin(delta*)/l1
 *           - [v cos(delta*) sin(Lambda) - v sin(delta*) (b11 - b1) cos(Lambda)/l1]/l2;
 *     discretised by the bilinear transform s = (2/Ts)(z - 1)/(z + 1) (4.1.1),
 *     written as the trapezoidal rule it is,
 *       LambdaRef_k = LambdaRef_(k-1) + Ts/2 (f_(k-1) + f(LambdaRef_k, delta*_k, v_k)),
 *     with the speed of each sample in its own term (for a constant speed this
 *     is exactly the bilinear transform of eq. 2.9); linear in LambdaRef_k for
 *     eq. 2.9, solved by Newton's method for eq. 2.3. LambdaDotRef_k =
 *     f(LambdaRef_k, delta*_k, v_k).
 *  2. control errors dLambda = Lambda - LambdaRef, dLambdaDot = LambdaDot -
 *     LambdaDotRef (Table of Variables);
 *  3. requested torque, in BusDynamics' Mjoint convention (positive
 *     counter-clockwise on the rear section, i.e. reducing Lambda = psi1 - psi2):
 *       option 1 (eq. 5.3): T = K1 Crear l2 dLambda
 *       option 2 (eq. 5.4): T = K2 Crear l2^2 dLambdaDot / v2
 *       option 3 (eq. 5.5): T = K3 (T1 + T2)            (torques added, may cancel)
 *       option 4 (6.1.3):   T = Krev m2 dLambdaDot       (the revised law, no 1/v)
 *     gate (5.1.1): the dampers only resist motion, so T is applied only when it
 *     opposes the articulation motion, T LambdaDot > 0; otherwise T = 0;
 *  4. pct = pctAtMmax |T| / Mmax (5.1.3: Mmax the dampers' torque at 50 % for
 *     the present angle and direction), at most pctMax (34 % in the thesis), at
 *     least the floor pctFloor (3.5 %, "always present").
 *  Option 0: no control (the floor only). Option 5: the input pctExternal
 *  passed through, clamped to [pctFloor, pctMax] (another damping function
 *  driving the same damper).
 *  Below the speed vMin the reference model is held at the measured values
 *  (LambdaRef = Lambda, LambdaDotRef = LambdaDot) and only the floor is
 *  requested (options 0-4).
 */
#ifndef DAMPING_CONTROLLER_H
#define DAMPING_CONTROLLER_H

#define DC_MAX_KC 12

/* fault bits of a sample (0 = all good) */
#define DC_FAULT_NAN    1u   /* an input is not finite: outputs and state held */
#define DC_FAULT_SLOW   2u   /* v < vMin: reference held at the measured values, floor only */
#define DC_FAULT_REVERSE 4u  /* v < 0: not a forward speed (also DC_FAULT_SLOW) */
#define DC_FAULT_MMAX   8u   /* Mmax <= 0 with a torque requested: pctMax requested */
#define DC_FAULT_LIMIT 16u   /* request beyond pctMax: saturated */
#define DC_FAULT_V2    32u   /* v2 < vMin in option 2/3: divided by vMin instead */

typedef struct {
    double f1, b1, b11, f2, b2;   /* geometry, Table 2.1/3.1 [m] */
    double m2;                    /* rear-section mass [kg] */
    double Crear;                 /* rear tyre coefficient, Table 5.1 [N/rad] */
    int option;                   /* 0 none, 1 angle, 2 rate, 3 both, 4 revised, 5 external */
    double K1, K2, K3, Krev;      /* gains, Table 5.3 and 6.1.3 */
    int exactRef;                 /* 0: eq. 2.9, 1: eq. 2.3 */
    int nKc;                      /* points of the Kc table, 1..DC_MAX_KC */
    double KcSpeed[DC_MAX_KC];    /* [m/s], strictly increasing */
    double KcGain[DC_MAX_KC];     /* [-] */
    double pctMax, pctFloor, pctAtMmax;   /* [%] */
    double vMin;                  /* [m/s] */
    double Ts;                    /* [s] */
} DcParams;

typedef struct {
    double Lambda;       /* measured articulation angle psi1 - psi2 [rad] */
    double LambdaDot;    /* measured articulation rate [rad/s] */
    double v;            /* vehicle (front wheel) speed [m/s] */
    double v2;           /* rear-section forward speed [m/s] */
    double delta;        /* front steering angle, positive left [rad] */
    double Mmax;         /* dampers' torque at 50 % for this angle and direction [N m] */
    double pctExternal;  /* option 5: another function's request [%] */
} DcInputs;

typedef struct {
    DcParams p;
    double l1, l2, a;             /* derived geometry */
    /* reference model: state after the last sample */
    double lamRef;                /* LambdaRef_(k-1) [rad] */
    double fPrev;                 /* the model's f(LambdaRef, delta*, v) at the last sample [rad/s] */
    /* outputs of the last sample */
    double pct, T, LambdaRef, LambdaDotRef, eLambda, eLambdaDot, Kc, active;
} DcController;

/* 0, or -(1 + index) of the first bad parameter (dc_param_name) */
int dc_setup(DcController *c, const DcParams *p);
const char *dc_param_name(int code);

/* Kc(v): the table, linear interpolation, clamped at its ends */
double dc_kc(const DcParams *p, double v);

/* the reference model's right-hand side: eq. 2.9 (exact = 0) or eq. 2.3 */
double dc_ref_rate(const DcController *c, int exact, double Lambda, double deltaStar, double v);

/* The first sample: the reference model starts at the measured values. */
unsigned dc_reset(DcController *c, const DcInputs *in);

/* Every later sample. Outputs always finite; pct always in [pctFloor, pctMax]. */
unsigned dc_sample(DcController *c, const DcInputs *in);

#endif
