/* Seed 000's 36 m bus is symmetric, so driving backwards mirrors every role:
 * the A6 end leads and the module frames are turned by 180 deg. The leading
 * module then sees hinge G2 first, as psi3 - psi2 = -dPsi[2], and G1 second,
 * as -dPsi[1] (steering angles keep their sign under the turn). Shared by the
 * seed 000 controllers (TrainGuidance, ForceMinimization). */
#ifndef ARTIBUS_LEADING_HINGES_H
#define ARTIBUS_LEADING_HINGES_H

/* dPsi1, dPsi2: articulation angles of G1, G2 as measured (psi_front - psi_rear
   in the forward numbering); d1, d2: the same seen from the leading module */
static inline void leading_hinges(int backwards, double dPsi1, double dPsi2,
                                  double *d1, double *d2) {
    *d1 = backwards ? -dPsi2 : dPsi1;
    *d2 = backwards ? -dPsi1 : dPsi2;
}

#endif
