/* The kinetic single-track multibody model of an n-times articulated bus
 * (seed 000, section II, eqs. 1-28), for any number of modules 1..4 joined by
 * 1-DOF hinges and up to 8 axles. Plain C interface, no FMI types: the
 * matrices are built with Eigen in dynamics.cpp.
 *
 * Geometry. Every module m has its own frame K_m at its centre of mass (CG),
 * x forward, yaw angle psi_m. Hinge k joins module k (front) to module k+1
 * (rear): it lies lHf[k] behind the CG of module k and lHr[k] ahead of the CG
 * of module k+1. Axle a sits on module axleModule[a], xA[a] ahead of its CG
 * (negative: behind). All arrays are indexed from 1, as in the papers.
 *
 * Minimal coordinates (eq. 1): z = (x, y, psi_1 .. psi_n), (x, y) the CG of
 * module 1. Equations of motion (eq. 3 with eq. 8):
 *     M(z) z'' + G(z, z') z' = sum_a J_a^T A_IK f_a + J_M Mjoint
 * with M = sum_m m_m J_m^T J_m + I_m e_m e_m^T and G z' = sum_m m_m J_m^T (J_m' z')
 * (projected Newton-Euler, identical to Lagrange's eq. 2 for holonomic
 * constraints), built from the Jacobians of the points of the chain. */
#ifndef BUS_DYNAMICS_H
#define BUS_DYNAMICS_H

#ifdef __cplusplus
extern "C" {
#endif

#define DYN_MAX_MODULES 4
#define DYN_MAX_HINGES (DYN_MAX_MODULES - 1)
#define DYN_MAX_AXLES 8
#define DYN_MAX_Q (2 + DYN_MAX_MODULES)     /* minimal coordinates */

typedef enum {
    TYRE_LINEAR = 0,        /* Fy = C alpha (eq. 24) */
    TYRE_LINEAR_FRICTION,   /* Fy = mu C alpha, saturated at |Fy| <= mu Fz */
    TYRE_FIALA,             /* brush model (Fiala): smooth saturation at mu Fz */
    TYRE_LINEAR_SCALED      /* Fy = mu C alpha, no saturation (seed 001's extensive model) */
} TyreModel;

typedef struct {
    int nMod, nAxle;
    double m[DYN_MAX_MODULES + 1], J[DYN_MAX_MODULES + 1];        /* kg, kg m^2 (about the CG) */
    double lHf[DYN_MAX_HINGES + 1], lHr[DYN_MAX_HINGES + 1];      /* m */
    int axleModule[DYN_MAX_AXLES + 1];
    double xA[DYN_MAX_AXLES + 1];                                 /* m */
    double C[DYN_MAX_AXLES + 1];      /* cornering stiffness of the axle (all its tyres), N/rad */
    double mu[DYN_MAX_AXLES + 1];     /* friction coefficient */
    double Fz[DYN_MAX_AXLES + 1];     /* vertical axle load, N */
    int tyreModel;
    double vSlip;                     /* low-speed blend of the slip angle, m/s (> 0) */
    double lFront[DYN_MAX_MODULES + 1], lRear[DYN_MAX_MODULES + 1];   /* body outline ahead of and */
    double width[DYN_MAX_MODULES + 1];                                /* behind the CG, its width, m */
} DynParams;

typedef struct {
    double delta[DYN_MAX_AXLES + 1];  /* steering angle, rad */
    double Fx[DYN_MAX_AXLES + 1];     /* longitudinal tyre force in the wheel frame, N */
    double Mjoint[DYN_MAX_HINGES + 1];/* hinge torque on the rear module (reaction on the front), N m */
    double cosDelta[DYN_MAX_AXLES + 1], sinDelta[DYN_MAX_AXLES + 1];   /* of delta: dyn_steer() */
} DynInputs;

/* cos and sin of the steering angles of axles 1..nAxle into u (once per set
   of inputs: they hold while the integrator evaluates the right-hand side
   many times) */
void dyn_steer(DynInputs *u, int nAxle);

/* everything that follows from (z, z', inputs) at one instant; world frame
   unless said otherwise */
typedef struct {
    double zdd[DYN_MAX_Q];
    double xCG[DYN_MAX_MODULES + 1], yCG[DYN_MAX_MODULES + 1];
    double vx[DYN_MAX_MODULES + 1], vy[DYN_MAX_MODULES + 1];     /* CG velocity in K_m */
    double ax[DYN_MAX_MODULES + 1], ay[DYN_MAX_MODULES + 1];     /* CG acceleration in K_m */
    double xAxle[DYN_MAX_AXLES + 1], yAxle[DYN_MAX_AXLES + 1];
    double alpha[DYN_MAX_AXLES + 1], Fy[DYN_MAX_AXLES + 1];      /* slip angle, lateral tyre force (wheel frame) */
    double FjX[DYN_MAX_HINGES + 1], FjY[DYN_MAX_HINGES + 1];     /* hinge force on the rear part, in K_k */
    double xCorner[4 * DYN_MAX_MODULES + 1], yCorner[4 * DYN_MAX_MODULES + 1];
                                      /* body outline of module m: 4 (m - 1) + 1..4 front left,
                                         front right, rear right, rear left */
    double v;                         /* speed of the CG of module 1 */
} DynOut;                             /* (dynamics.cpp's DualOut mirrors it field by field) */

/* number of minimal coordinates */
static inline int dyn_nq(const DynParams *p) { return 2 + p->nMod; }

/* z'' from z, z' and the inputs (zdd has dyn_nq entries); if out is not NULL,
   fill it too. Returns 0, or 1 if the mass matrix is not positive definite. */
int dyn_eval(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
             double *zdd, DynOut *out);

/* dyn_eval and its directional derivative, on dual numbers (dynamics.cpp): at
   (u, z, zd) the values zdd and out as dyn_eval's, and their derivatives along
   the seed (du: delta, Fx and Mjoint only; dz, dzd) into dzdd and dout. The
   one source of the equations, Chain::eval, templated on the scalar type. */
int dyn_eval_tangent(const DynParams *p, const DynInputs *u, const DynInputs *du,
                     const double *z, const double *dz, const double *zd, const double *dzd,
                     double *zdd, double *dzdd, DynOut *out, DynOut *dout);

/* dyn_eval's zdd and its Jacobian with respect to the states, in one pass on
   vector dual numbers (dynamics.cpp): for state j of [z, zd] (2 nq of them)
   dzdd[j][0 .. nq). The inputs are held; no outputs. */
int dyn_eval_jacobian(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
                      double *zdd, double (*dzdd)[DYN_MAX_Q]);

/* the world position of the point xi ahead of the CG of module m */
void dyn_point(const DynParams *p, const double *z, int m, double xi, double *px, double *py);

/* the slip angle of an axle whose wheel-plane velocity components are u
   (along the wheel) and w (across it, to the left): atan2(-w, sqrt(u^2 + vSlip^2)) */
double dyn_slip(double u, double w, double vSlip);

/* the lateral tyre force of axle a for slip angle alpha */
double dyn_tyre(const DynParams *p, int a, double alpha);

/* Static axle loads p->Fz[] from masses and geometry, module by module from
   the rear: each module's axles and (when it has fewer than two axles) its
   front hinge carry its weight and the load its rear hinge passes on
   (vertical force and pitch moment balance). A trailer with two or more axles
   is taken as a full trailer whose front hinge carries no vertical load; more
   than two unknown loads on one module (tandem axles) are shared by the
   minimum-norm solution of the two balances. Returns 0, or the module whose
   loads cannot be found (fewer than two supports, supports at one point, or a
   negative load). */
int dyn_static_loads(DynParams *p, double g);

#ifdef __cplusplus
}
#endif

#endif
