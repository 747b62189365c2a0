/* seed 004, eq. 2: the linear 3-DOF multi-axle model. See lateral3dof.h.
 * Compiled twice: as C on double, and in lateral3dof_dual.cpp on a dual number
 * (MA_REAL) for the directional derivatives. */
#include <math.h>
#include <stddef.h>

#include "lateral3dof.h"

int ma_prepare(const MaVehicle *veh, MaMass *mm) {
    double M = veh->m_b, sml = 0.0, Izz = veh->I_ZZb;
    for (int i = 1; i <= veh->n; i++) {
        M += veh->m[i];
        sml += veh->m[i] * veh->l[i];
        Izz += veh->m[i] * veh->l[i] * veh->l[i];
    }
    const double Ixx = veh->I_XXb + veh->m_b * veh->h_b * veh->h_b;
    mm->M = M;
    mm->sum_ml = sml;
    mm->I_ZZ = Izz;
    mm->I_XX = Ixx;

    /* the symmetric mass matrix of eq. 2 for (v', w_r', p'):
       lateral [M, sum m l, -m_b h_b], yaw [sum m l, I_ZZ, I_XZb],
       roll [-m_b h_b, I_XZb, I_XX] */
    const double a = M, b = sml, c = -veh->m_b * veh->h_b;
    const double e = Izz, f = veh->I_XZb, i9 = Ixx;
    const double A11 = e * i9 - f * f, A12 = -(b * i9 - c * f), A13 = b * f - c * e;
    const double A22 = a * i9 - c * c, A23 = -(a * f - c * b), A33 = a * e - b * b;
    const double det = a * A11 + b * A12 + c * A13;
    /* positive definite: leading minors a, A33 and det positive */
    if (!(a > 0 && A33 > 0 && det > 0) || !isfinite(det)) return -1;
    mm->Minv[0][0] = A11 / det; mm->Minv[0][1] = A12 / det; mm->Minv[0][2] = A13 / det;
    mm->Minv[1][0] = A12 / det; mm->Minv[1][1] = A22 / det; mm->Minv[1][2] = A23 / det;
    mm->Minv[2][0] = A13 / det; mm->Minv[2][1] = A23 / det; mm->Minv[2][2] = A33 / det;
    return 0;
}

void ma_forces(const MaVehicle *veh, MA_REAL u, const MA_REAL x[4], const MA_REAL delta[],
               MA_REAL alpha[], MA_REAL FY[]) {
    const MA_REAL wr = x[0], v = x[1];
    for (int i = 1; i <= veh->n; i++) {
        alpha[i] = (v + veh->l[i] * wr) / u - delta[i];     /* beta + l_i w_r/u - delta_i */
        FY[i] = veh->k[i] * alpha[i];
    }
}

void ma_derivatives(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[],
                    MA_REAL Md, const MA_REAL x[4], MA_REAL xdot[4], MA_REAL *a_y) {
    const MA_REAL wr = x[0], p = x[2], phi = x[3];
    MA_REAL alpha[MA_MAX_AXLES + 1], FY[MA_MAX_AXLES + 1];
    ma_forces(veh, u, x, delta, alpha, FY);
    MA_REAL sF = 0.0, sFl = 0.0, sFd = 0.0;
    for (int i = 1; i <= veh->n; i++) {
        sF += FY[i];
        sFl += FY[i] * veh->l[i];
        sFd += FY[i] * veh->d[i];
    }
    const double mh = veh->m_b * veh->h_b;
    /* eq. 2, the velocity-dependent and elastic terms moved to the right */
    const MA_REAL r0 = sF - mm->M * u * wr;                                   /* lateral */
    const MA_REAL r1 = sFl + Md - mm->sum_ml * u * wr;                        /* yaw */
    const MA_REAL r2 = sFd - veh->C_phi * p - (veh->K_phi - veh->m_b * MA_G * veh->h_b) * phi
                      + mh * u * wr;                                         /* roll */
    const MA_REAL vdot = mm->Minv[0][0] * r0 + mm->Minv[0][1] * r1 + mm->Minv[0][2] * r2;
    xdot[0] = mm->Minv[1][0] * r0 + mm->Minv[1][1] * r1 + mm->Minv[1][2] * r2;
    xdot[1] = vdot;
    xdot[2] = mm->Minv[2][0] * r0 + mm->Minv[2][1] * r1 + mm->Minv[2][2] * r2;
    xdot[3] = p;                /* phi' = p (eq. 4's fourth row has the sign slipped) */
    if (a_y) *a_y = vdot + u * wr;
}

void ma_rhs(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[], MA_REAL Md,
            const MA_REAL y[7], MA_REAL ydot[7]) {
    ma_derivatives(veh, mm, u, delta, Md, y, ydot, NULL);
    ydot[4] = y[0];                                  /* psi' = w_r */
    ydot[5] = u * cos(y[4]) - y[1] * sin(y[4]);      /* the origin's velocity, ground frame */
    ydot[6] = u * sin(y[4]) + y[1] * cos(y[4]);
}

void ma_outputs(const MaVehicle *veh, const MaMass *mm, MA_REAL u, const MA_REAL delta[], MA_REAL Md,
                const MA_REAL y[7], MA_REAL out[MA_NOUT]) {
    MA_REAL xdot[4], alpha[MA_MAX_AXLES + 1], FY[MA_MAX_AXLES + 1];
    ma_derivatives(veh, mm, u, delta, Md, y, xdot, &out[MA_OUT_AY]);
    ma_forces(veh, u, y, delta, alpha, FY);
    ma_rhs(veh, mm, u, delta, Md, y, &out[MA_OUT_YDOT]);
    out[MA_OUT_BETA] = y[1] / u;
    for (int i = 1; i <= MA_MAX_AXLES; i++) {
        out[MA_OUT_ALPHA + i - 1] = i <= veh->n ? alpha[i] : 0.0;
        out[MA_OUT_FY + i - 1] = i <= veh->n ? FY[i] : 0.0;
    }
}
