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
void ma_forces(const MaVehicle *veh, double u, const double x[4], const double delta[],
               double alpha[], double FY[]);

/* dx/dt for steering angles delta[1..n] (fixed axles: 0), external yaw
 * moment Md; *a_y (if not NULL) receives the lateral acceleration v' + u w_r. */
void ma_derivatives(const MaVehicle *veh, const MaMass *mm, double u, const double delta[],
                    double Md, const double x[4], double xdot[4], double *a_y);

#endif
