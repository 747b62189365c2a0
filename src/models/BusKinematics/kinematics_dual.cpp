/* The directional derivatives of BusKinematics: kinematics.c, the one source
 * of seed 003's equations, compiled a second time on a dual number (KIN_REAL =
 * artibus::Dual, src/models/common/dual.hpp) inside a namespace of its own, so
 * that its functions and structs (KinChain's gamma and KinRates on Dual) do not
 * meet the C build's. The derivative of every output along the seed is the
 * eps part of the result: exact to rounding. */
#include <math.h>
#include <stddef.h>

#include "dual.hpp"

namespace kin_dual {
using artibus::Dual;
#define KIN_REAL Dual
#include "kinematics.c"      /* with its kinematics.h, on Dual */
#undef KIN_REAL
}  // namespace kin_dual

extern "C" void kin_outputs_tangent(int N, int k, const double L[], const double Lh[], const double gamma[],
                                    const double dgamma[], int j, int prediction, double gammaF, double dgammaF,
                                    double vk, double dvk, double omegaMeas, double domegaMeas,
                                    const double y[], const double dy[], double out[], double dout[]) {
    using artibus::Dual;
    kin_dual::KinChain c;
    c.N = N;
    c.k = k;
    for (int i = 0; i <= KIN_MAX_WAGONS; i++) {
        c.L[i] = L[i];
        c.Lh[i] = Lh[i];
        c.gamma[i] = Dual(gamma[i], dgamma[i]);
    }
    kin_dual::KinDrive dr;
    dr.j = j;
    dr.prediction = prediction;
    dr.gammaF = Dual(gammaF, dgammaF);
    dr.vk = Dual(vk, dvk);
    dr.omegaMeas = Dual(omegaMeas, domegaMeas);
    Dual yy[3 + KIN_MAX_WAGONS], o[kin_dual::KIN_NOUT];
    for (int i = 0; i < 3 + KIN_MAX_WAGONS; i++) yy[i] = Dual(y[i], dy[i]);
    kin_dual::kin_outputs(&c, &dr, yy, o);
    for (int i = 0; i < kin_dual::KIN_NOUT; i++) {
        out[i] = o[i].v;
        dout[i] = o[i].d[0];
    }
}
