/* Linear 3-DOF (lateral, yaw, roll) model of an n-axle vehicle, seed 004
 * (Yang, 3-DOF Multi-axle Vehicle Steering Characteristic Analysis), eqs. 2
 * and 4. Plain C, no FMI types, no allocation.
 *
 * Axes: x forward, y left, z up (ISO); the origin is the sprung mass's centre
 * of gravity, axle i sits l[i] ahead of it (l < 0 behind). Seed 004's sign
 * conventions are kept: the cornering stiffness k[i] is negative and the side
 * force of axle i is F_Yi = k_i (beta + l_i w_r/u - delta_i) (eq. 2).
 *
 * The state is x = [w_r, v, p, phi] with the lateral velocity v = u beta in
 * place of the paper's beta: eq. 2 holds as written for a speed u that
 * changes, and for a constant u it is eq. 4 exactly.
 */
#ifndef LATERAL3DOF_H
#define LATERAL3DOF_H

/* The equations that depend on the state and the inputs are written on
 * MA_REAL: double here (lateral3dof.c compiled as C), a dual number in
 * lateral3dof_dual.cpp, which compiles the same lateral3dof.c a second time in
 * C++ for the FMU's directional derivatives (one source of the equations). */
#ifndef MA_REAL
#define MA_REAL double
#endif

#define MA_MAX_AXLES 6
#define MA_G 9.81              /* gravity in the roll equation (m_b g h_b) [m/s2] */

typedef struct {
    int n;                              /* axles, 2..MA_MAX_AXLES */
    double l[MA_MAX_AXLES + 1];         /* l[1..n] axle positions [m] */
    double k[MA_MAX_AXLES + 1];         /* cornering stiffness, < 0 [N/rad] */
    double m[MA_MAX_AXLES + 1];         /* unsprung masses [kg] */
    double d[MA_MAX_AXLES + 1];         /* roll offsets d_i [m] (eq. 2, third row) */
    double m_b, h_b;                    /* sprung mass [kg], its CG above the roll axis [m] */
    double I_ZZb, I_XXb, I_XZb;         /* sprung-mass inertias [kg m2] */
    double C_phi, K_phi;                /* roll damping [N m s/rad], stiffness [N m/rad] */
} MaVehicle;

typedef struct {
    double M;                           /* total mass, sum m_i + m_b */
    double sum_ml;                      /* sum m_i l_i */
    double I_ZZ, I_XX;                  /* eq. 2's definitions */
    double Minv[3][3];                  /* inverse mass matrix of eq. 2 in (v', w_r', p') */
} MaMass;

/* The mass terms of eq. 2. Returns 0, or -1 if the mass matrix is not
 * positive definite (inconsistent inertias). */
int ma_prepare(const MaVehicle *veh, MaMass *mm);

/* Slip angles alpha[1..n] and side forces F_Y[1..n] (eq. 2) at speed u > 0. */
void ma_forces(const MaVehicle *veh, MA_REAL u, const MA_REAL x[4], const MA_REAL delta[],
               MA_REAL alpha[], MA_REAL FY[]);

/* dx/dt for steering angles delta[1..n] (fixed axles: 0), external yaw
 * moment Md; *a_y (if not NULL) receives the lateral acceleration v' + u w_r. */
void ma_derivatives(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[],
                    MA_REAL Md, const MA_REAL x[4], MA_REAL xdot[4], MA_REAL *a_y);

/* The whole right-hand side with the heading and the path of the origin:
 * y = [w_r, v, p, phi, psi, x, y], ydot its derivative. */
void ma_rhs(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[], MA_REAL Md,
            const MA_REAL y[7], MA_REAL ydot[7]);

/* Every output the model computes, into out[MA_NOUT] at these indices:
 * ydot (7), beta = v/u, a_y, alpha[1..MA_MAX_AXLES], F_Y[1..MA_MAX_AXLES]
 * (0 beyond n). */
enum { MA_OUT_YDOT = 0, MA_OUT_BETA = 7, MA_OUT_AY = 8, MA_OUT_ALPHA = 9,
       MA_OUT_FY = MA_OUT_ALPHA + MA_MAX_AXLES, MA_NOUT = MA_OUT_FY + MA_MAX_AXLES };
void ma_outputs(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[], MA_REAL Md,
                const MA_REAL y[7], MA_REAL out[MA_NOUT]);

/* ma_outputs and its derivative dout along the seed (du, ddelta, dMd, dy):
 * lateral3dof_dual.cpp, the same equations on dual numbers */
#ifdef __cplusplus
extern "C"
#endif
void ma_outputs_tangent(const MaVehicle *veh, const MaMass *mm, double u, double du,
                        const double delta[], const double ddelta[], double Md, double dMd,
                        const double y[7], const double dy[7], double out[MA_NOUT], double dout[MA_NOUT]);

#endif
