/* The two-cylinder articulation damper (Hübner system) of seed 001: 1.3.1 and
 * Appendix B of the thesis, with what its extraction lost reconstructed in
 * ../shared/specs/001-damping.md, section 1.
 *
 * Plain C99 with <math.h> only: no FMI types, no allocation, no globals, so it
 * compiles unchanged for an ECU (or a controller's look-up, damper_mmax).
 *
 * Frames and signs. The front section's frame has its origin at the
 * articulation point, x forward, y left. Lambda = psi1 - psi2 (BusDynamics
 * artAngle), LambdaDot = r1 - r2. Side s = +1 left (index 0), -1 right
 * (index 1). The front pivots sit at (0, s R) (seed 001, Fig. B.3: R from the
 * articulation point); the rear pivots at (-Xrear, s Yrear) in the rear frame,
 * which is the front frame turned by -Lambda, so in the front frame
 *     P_r,s = (-Xrear cos L + s Yrear sin L,  Xrear sin L + s Yrear cos L).
 * The articulation angle is then the angle between the line through the front
 * pivots and the line through the rear pivots (seed 001, App. B).
 *
 * Length (exact), lever arm (virtual work) and piston speed:
 *     L_s^2 = Xrear^2 + Yrear^2 + R^2 - 2 s R Xrear sin L - 2 R Yrear cos L
 *     h_s   = dL_s/dLambda = (-s R Xrear cos L + R Yrear sin L) / L_s
 *     Ldot_s = h_s LambdaDot   ("the derivative of a damper's length is equal
 *                               to its respective piston velocity", App. B)
 * The left cylinder is the inner one when Lambda grows (bend to the left):
 * it is compressed.
 *
 * Valves (1.3.1: "the valve at one of the cylinders is shut ... the pressure
 * in that cylinder is increased, creating a force along it, resisting the
 * bending"): each cylinder has a proportional pressure valve, both set by the
 * damping percentage u in 0..50 % (50 % = maximum, 5.1.1), p_set = pMax u/50;
 * a compressed cylinder pushes its oil through it; a check valve refills it
 * when it extends, with no force (bothWays = 1: it resists extension too).
 * The force is zero at zero piston speed (App. B) and regularised as
 *     F_s = Ap p_valve tanh(|Ldot_s| / v0)      (resisting, >= 0)
 * in place of the thesis's look-up table over (%, piston velocity).
 *
 * Torque. The cylinder's push F along the unit vector from front to rear
 * pivot acts on the rear section at its pivot and, reversed, on the front
 * section at its pivot; both pivots lie on that line, so about the
 * articulation point the two moments are equal and opposite: a pure torque
 * pair, the forces themselves are carried by the pin (front torque = - rear
 * torque, seed 001, Fig. 5.14). By virtual work the generalised force on
 * Lambda is Q = sum F_signed,s h_s (F_signed > 0 pushing), and since the
 * BusDynamics hinge torque Mjoint turns the rear section counter-clockwise
 * (+psi2, -psi1, i.e. -Lambda),
 *     Mjoint = -Q = sum_active Ap p_valve tanh(Ldot_s / v0) h_s
 * and Mjoint LambdaDot = sum Ap p_valve tanh(Ldot_s/v0) Ldot_s >= 0: the
 * dampers only take energy from the bus.
 *
 * End stop (54 deg, App. B: "a structural stop will be hit by a cylinder"):
 * beyond LambdaStop a stiff spring kStop (|L| - LambdaStop) sign(L), plus a
 * damper cStop LambdaDot while moving further in; both are added to Mjoint
 * (positive Mjoint reduces Lambda).
 */
#ifndef DAMPER_H
#define DAMPER_H

/* What depends on the inputs and the state is written on DAMPER_REAL: double
 * here (damper.c compiled as C, or for an ECU), a dual number in
 * damper_dual.cpp, which compiles the same damper.c a second time in C++ for
 * the FMU's directional derivatives (one source of the equations). */
#ifndef DAMPER_REAL
#define DAMPER_REAL double
#endif

#define DAMPER_PCT_MAX 50.0         /* damping percentage at maximum damping (seed 001, 5.1.1) */
#define DAMPER_L_MIN 0.05           /* shortest cylinder length the geometry may reach [m] */
#define DAMPER_CHECK_MARGIN 0.1745  /* the geometry is checked over |Lambda| <= LambdaStop + this (10 deg) [rad] */

typedef struct {
    double R;           /* articulation point to the front pivots [m] */
    double Xrear;       /* articulation point to the rear pivots, longitudinal [m] */
    double Yrear;       /* rear pivots to the rear section's centre line [m] */
    double Ap;          /* piston area [m2] */
    double pMax;        /* valve pressure at 50 % [Pa] */
    double v0;          /* piston speed of the tanh regularisation [m/s] */
    double LambdaStop;  /* end stop [rad] */
    double kStop;       /* end stop stiffness [N.m/rad] */
    double cStop;       /* end stop damping, while moving into the stop [N.m.s/rad] */
    int bothWays;       /* 1: each cylinder resists extension too */
} DamperParams;

/* everything at one instant; index 0 = left cylinder (s = +1), 1 = right */
typedef struct {
    DAMPER_REAL L[2];        /* cylinder lengths [m] */
    DAMPER_REAL h[2];        /* lever arms dL/dLambda [m] */
    DAMPER_REAL Ldot[2];     /* piston speeds [m/s], < 0 compressing */
    DAMPER_REAL F[2];        /* resisting forces (>= 0) [N] */
    DAMPER_REAL p[2];        /* working pressures [Pa] */
    DAMPER_REAL Mdamp;       /* hydraulic part of Mjoint [N.m] */
    DAMPER_REAL dMdp;        /* d Mdamp / d p_valve [m3]: Mdamp = dMdp p_valve */
    DAMPER_REAL MstopK;      /* end stop spring part of Mjoint [N.m] */
    DAMPER_REAL MstopC;      /* end stop damper part of Mjoint [N.m] */
    DAMPER_REAL Mjoint;      /* the total, counter-clockwise on the rear section [N.m] */
    DAMPER_REAL Mmax;        /* hydraulic torque at 50 % for this direction, |Ldot| >> v0 [N.m] */
} DamperOut;

/* valve set pressure from the damping percentage, clamped to 0..50 % [Pa] */
DAMPER_REAL damper_pset(const DamperParams *p, DAMPER_REAL pct);

/* length and lever arm of cylinder s (+1 left, -1 right) at Lambda; L is not
 * allowed below DAMPER_L_MIN (returns 1 if it had to be limited, else 0) */
int damper_geometry(const DamperParams *p, int s, DAMPER_REAL Lambda, DAMPER_REAL *L, DAMPER_REAL *h);

/* Checks the geometry: every cylinder stays at least DAMPER_L_MIN long over
 * |Lambda| <= LambdaStop + DAMPER_CHECK_MARGIN. Returns 0 if it does, else the
 * side (+1 / -1) of the offending cylinder, with its shortest length and the
 * angle where it occurs. */
int damper_check(const DamperParams *p, double *Lshortest, double *LambdaAt);

/* The torque magnitude at 50 % for the direction dir (+1: LambdaDot > 0,
 * -1: < 0, 0: the larger of both), once |Ldot| >> v0: the controller's
 * look-up of seed 001, 5.1.3. */
DAMPER_REAL damper_mmax(const DamperParams *p, DAMPER_REAL Lambda, double dir);

/* Every output at (Lambda, LambdaDot) with the valve pressure pValve; returns
 * 1 if a cylinder length had to be limited at DAMPER_L_MIN, else 0. */
int damper_eval(const DamperParams *p, DAMPER_REAL Lambda, DAMPER_REAL LambdaDot, DAMPER_REAL pValve,
                DamperOut *o);

/* Over a step h with held inputs: the valve pressure's first-order lag
 * tauP dp/dt = pSet - p solved exactly (tauP = 0: p = pSet at once); returns
 * the new pressure and its exact integral over the step in *pInt [Pa s]. */
double damper_pressure_step(double pValve, double pSet, double tauP, double h, double *pInt);

/* The same lag as an ODE (for an integrator outside, Model Exchange): the
 * rate dpValve/dt = (pSet - pValve)/tauP that damper_pressure_step solves in
 * closed form; 0 for tauP = 0 (the valve is static, pValve is not used) [Pa/s]. */
DAMPER_REAL damper_pressure_rate(DAMPER_REAL pValve, DAMPER_REAL pSet, double tauP);

/* The energy the damper dissipates over that step (inputs held), exactly:
 * LambdaDot (dMdp int p dt + MstopC h) >= 0 [J]. The stop spring's work is
 * not dissipated and not counted. */
DAMPER_REAL damper_step_energy(const DamperOut *o, DAMPER_REAL LambdaDot, DAMPER_REAL pInt, double h);

/* The valve pressure acting now: the lag's state pValve, or the set pressure
 * of pct when the valve is static (tauP = 0) [Pa]. */
DAMPER_REAL damper_valve(const DamperParams *p, DAMPER_REAL pValve, DAMPER_REAL pct, double tauP);

/* Every output of the FMU at (Lambda, LambdaDot, pct) and the state pValve
 * into out[DAMPER_NOUT]: Mjoint, F, p, L, Ldot (2 each), Mmax, and the
 * derivatives of the states pValve and Ediss; returns damper_eval's. */
enum { DAMPER_OUT_MJOINT = 0, DAMPER_OUT_F = 1, DAMPER_OUT_P = 3, DAMPER_OUT_L = 5, DAMPER_OUT_LDOT = 7,
       DAMPER_OUT_MMAX = 9, DAMPER_OUT_DPVALVE = 10, DAMPER_OUT_DEDISS = 11, DAMPER_NOUT = 12 };
int damper_outputs(const DamperParams *p, DAMPER_REAL Lambda, DAMPER_REAL LambdaDot, DAMPER_REAL pct,
                   double tauP, DAMPER_REAL pValve, DAMPER_REAL out[DAMPER_NOUT]);

/* damper_outputs and its derivative dout along the seed (dLambda,
 * dLambdaDot, dpct, dpValve): damper_dual.cpp, the same equations on dual
 * numbers (for the FMU, not the ECU) */
#ifdef __cplusplus
extern "C"
#endif
void damper_outputs_tangent(const DamperParams *p, double Lambda, double dLambda, double LambdaDot,
                            double dLambdaDot, double pct, double dpct, double tauP, double pValve,
                            double dpValve, double out[DAMPER_NOUT], double dout[DAMPER_NOUT]);

#endif
