/* The directional derivatives of MultiAxle3DOF: lateral3dof.c, the one source
 * of seed 004's equations, compiled a second time on a dual number (MA_REAL =
 * artibus::Dual, src/models/common/dual.hpp) inside a namespace of its own, so that its
 * functions do not meet the C build's. The derivative of every output along
 * the seed is the eps part of the result: exact to rounding. */
#include <math.h>
#include <stddef.h>

#include "dual.hpp"
#include "lateral3dof.h"     /* the structs and the C declarations, on double */

namespace ma_dual {
using artibus::Dual;
#undef MA_REAL
#define MA_REAL Dual
#include "lateral3dof.c"     /* its own #include "lateral3dof.h" is skipped: included above */
#undef MA_REAL
}  // namespace ma_dual

extern "C" void ma_outputs_tangent(const MaVehicle *veh, const MaMass *mm, double u, double du,
                                   const double delta[], const double ddelta[], double Md, double dMd,
                                   const double y[7], const double dy[7], double out[MA_NOUT],
                                   double dout[MA_NOUT]) {
    artibus::Dual dl[MA_MAX_AXLES + 1], yy[7], o[MA_NOUT];
    for (int i = 0; i <= MA_MAX_AXLES; i++) dl[i] = artibus::Dual(delta[i], ddelta[i]);
    for (int i = 0; i < 7; i++) yy[i] = artibus::Dual(y[i], dy[i]);
    ma_dual::ma_outputs(veh, mm, artibus::Dual(u, du), dl, artibus::Dual(Md, dMd), yy, o);
    for (int i = 0; i < MA_NOUT; i++) {
        out[i] = o[i].v;
        dout[i] = o[i].d[0];
    }
}
