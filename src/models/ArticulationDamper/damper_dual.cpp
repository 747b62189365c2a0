/* The directional derivatives of ArticulationDamper: damper.c, the one source
 * of seed 001's damper equations, compiled a second time on a dual number
 * (DAMPER_REAL = artibus::Dual, src/models/common/dual.hpp) inside a namespace
 * of its own, so that its functions and DamperOut (on Dual) do not meet the C
 * build's. DamperParams holds no DAMPER_REAL: the same layout in both. */
#include <math.h>
#include <stddef.h>

#include "dual.hpp"

namespace damper_dual {
using artibus::Dual;
#define DAMPER_REAL Dual
#include "damper.c"          /* with its damper.h, on Dual */
#undef DAMPER_REAL
}  // namespace damper_dual

extern "C" void damper_outputs_tangent(const damper_dual::DamperParams *p, double Lambda, double dLambda,
                                       double LambdaDot, double dLambdaDot, double pct, double dpct,
                                       double tauP, double pValve, double dpValve,
                                       double out[damper_dual::DAMPER_NOUT], double dout[damper_dual::DAMPER_NOUT]) {
    using artibus::Dual;
    Dual o[damper_dual::DAMPER_NOUT];
    damper_dual::damper_outputs(p, Dual(Lambda, dLambda), Dual(LambdaDot, dLambdaDot), Dual(pct, dpct), tauP,
                                Dual(pValve, dpValve), o);
    for (int i = 0; i < damper_dual::DAMPER_NOUT; i++) {
        out[i] = o[i].v;
        dout[i] = o[i].d[0];
    }
}
