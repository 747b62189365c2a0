/* Zero-side-slip proportional multi-axle steering, seed 004 (Yang), eq. 3
 * with delta_n = K(u) delta_1, the gain K(u) chosen so that the steady-state
 * side-slip beta of the linear model (eqs. 2, 4) is zero at every speed.
 *
 * Plain C99 with <math.h> only: no FMI types, no allocation, no globals, so it
 * compiles unchanged for an ECU. zs_prepare() once when the parameters are
 * known, then zs_step() every cycle.
 *
 * Conventions are seed 004's (see the plant, MultiAxle3DOF): axle i sits l[i]
 * ahead of the sprung mass's centre of gravity (l[1] > ... > l[n]); k[i] < 0.
 *
 * The law. Let r be the rearmost steerable axle (seed 004's axle n when all
 * axles steer). Steerable axles i between 1 and r share the steering linearly
 * in their position (eq. 3):
 *     delta_i = (1 - s_i) delta_1 + s_i delta_r,  s_i = (l_1 - l_i)/(l_1 - l_r);
 * fixed axles have delta_i = 0. With delta_i = (a_i + b_i K) delta_1 the first
 * two rows of eq. 4 in the steady state (w_r' = beta' = p' = 0) and beta = 0
 * give, multiplied by u (so nothing is divided by u),
 *     (u^2 sum m_i l_i - sum k l^2) sum k delta = (u^2 M - sum k l) sum k l delta,
 * linear in K:
 *     K(u) = (N2 u^2 + N0) / (D2 u^2 + D0)
 *     N2 = M S_kla - S_ml S_ka,   N0 = S_kl2 S_ka - S_kl S_kla,
 *     D2 = S_ml S_kb - M S_klb,   D0 = S_kl S_klb - S_kl2 S_kb,
 * with S_ka = sum k_i a_i, S_kla = sum k_i l_i a_i (the same with b), S_kl =
 * sum k_i l_i, S_kl2 = sum k_i l_i^2, S_ml = sum m_i l_i, M = m_b + sum m_i.
 * K(0) = N0/D0 is the standstill limit and is finite: at u = 0 the law gives
 * the low-speed zero-side-slip angles, with no division by u anywhere.
 *
 * Bad input (each reported in the returned flags, never NaN out):
 *   - delta_1 not finite: the last command is held; u not finite: the last
 *     finite speed is used (0 before any);
 *   - u < 0 (reversing): the linear model is derived for forward driving; the
 *     standstill gain K(0) is used;
 *   - |K| > ZS_K_LIMIT (near a pole of K(u), where D2 u^2 + D0 = 0): K is
 *     limited to +-ZS_K_LIMIT;
 *   - every delta_i is limited to +-deltaMax[i].
 */
#ifndef ZERO_SIDESLIP_H
#define ZERO_SIDESLIP_H

#define ZS_MAX_AXLES 6
#define ZS_K_LIMIT 10.0
#define ZS_U_CAP 1000.0           /* speeds above are taken as this [m/s] */

/* flags returned by zs_step */
#define ZS_INPUT_NOT_FINITE 1u
#define ZS_REVERSING 2u
#define ZS_SATURATED 4u
#define ZS_NEAR_POLE 8u

typedef struct {
    int n;                              /* axles, 2..ZS_MAX_AXLES */
    double l[ZS_MAX_AXLES + 1];         /* l[1..n] axle positions [m] */
    double k[ZS_MAX_AXLES + 1];         /* cornering stiffness, < 0 [N/rad] */
    double m[ZS_MAX_AXLES + 1];         /* unsprung masses [kg] */
    int steerable[ZS_MAX_AXLES + 1];    /* steerable[1] must be set */
    double m_b;                         /* sprung mass [kg] */
    double deltaMax[ZS_MAX_AXLES + 1];  /* steering limits [rad] */
} ZsVehicle;

typedef struct {
    int n, rear;                        /* rear: the control axle r */
    double a[ZS_MAX_AXLES + 1];         /* delta_i = (a_i + b_i K) delta_1 */
    double b[ZS_MAX_AXLES + 1];
    double N2, N0, D2, D0;              /* K(u) = (N2 u^2 + N0)/(D2 u^2 + D0) */
    double uPole;                       /* speed where D2 u^2 + D0 = 0, or -1 if none */
    double deltaMax[ZS_MAX_AXLES + 1];
} ZsGains;

typedef struct {
    double delta[ZS_MAX_AXLES + 1];     /* the last command */
    double u;                           /* the last finite speed */
} ZsMemory;

/* return values of zs_prepare */
enum { ZS_OK = 0, ZS_BAD_N, ZS_FRONT_NOT_STEERABLE, ZS_NO_REAR_AXLE, ZS_NOT_ORDERED,
       ZS_BAD_PARAMETER, ZS_SINGULAR };

/* Gains from the vehicle. Returns ZS_OK or the first problem found;
 * *bad_axle (if not NULL) names the axle concerned. */
int zs_prepare(const ZsVehicle *veh, ZsGains *g, int *bad_axle);

/* K(u) = delta_r/delta_1 for u >= 0, not limited. */
double zs_gain(const ZsGains *g, double u);

/* zero the memory (straight ahead, standstill) */
void zs_reset(ZsMemory *mem);

/* One cycle: delta[1..n] (and K_i[1..n] if not NULL) from the driver's
 * delta_1 and the speed u. delta[i] = 0 for i > n. Returns ZS_* flags. */
unsigned zs_step(const ZsGains *g, ZsMemory *mem, double delta1, double u,
                 double delta[], double K_i[]);

#endif
