/* A condition-based articulation damping baseline like Scania's ACS5, as seed
 * 001 (the Scania thesis) describes it in 1.4.1, 5.2.5 and 6.1.4. Modelled from
 * that description, NOT from production code: the thesis gives the ground level
 * (13.5 % at 100 km/h, rising with speed), the maximum 34 % and the behaviour of
 * the sway control (static level, switched on when a threshold on the measured
 * speed and articulation angular velocity is passed); every threshold, the hold
 * time and the end-protection angles here are our estimates. Wheelspin damping
 * is left out (no longitudinal slip in the plant).
 *
 * Plain C99 and libm only: no FMI types, no heap, no globals (an ECU at 100 Hz,
 * the ACS5 unit's rate, seed 001, 4.1.1). Per sample:
 *   ground(v)  table over speed, linear interpolation, clamped at its ends;
 *   SSC        on at pctSSC while v >= vSSC and |LambdaDot| >= LambdaDotSSC,
 *              held for tHold after the condition last held;
 *   EP         end-protection damping pctEP * clamp((|Lambda| - LambdaEP0) /
 *              (LambdaEP1 - LambdaEP0), 0, 1);
 *   pct = min(pctMax, max(ground, SSC, EP)).
 */
#ifndef SWAY_BASELINE_H
#define SWAY_BASELINE_H

#define SB_MAX_GROUND 6

#define SB_FAULT_NAN     1u   /* an input is not finite: outputs and timers held */
#define SB_FAULT_REVERSE 2u   /* v < 0: the ground level of the first table point */

typedef struct {
    int nGround;                          /* points of the ground-level table, 1..SB_MAX_GROUND */
    double groundSpeed[SB_MAX_GROUND];    /* [m/s], strictly increasing */
    double groundPct[SB_MAX_GROUND];      /* [%] */
    double vSSC, LambdaDotSSC, tHold, pctSSC;          /* [m/s], [rad/s], [s], [%] */
    double LambdaEP0, LambdaEP1, pctEP;   /* [rad], [rad], [%] */
    double pctMax;                        /* [%] */
    double Ts;                            /* [s] */
} SbParams;

typedef struct {
    SbParams p;
    long long nHold;     /* tHold in samples */
    long long k;         /* index of the next sample (0 = the first) */
    long long kLast;     /* the last sample at which the SSC condition held */
    int everHeld;        /* has it held at all? */
    double tSince;       /* time since the SSC condition last held, or since the first sample [s] */
    double pct, pctGround, ssc, ep;       /* outputs of the last sample */
} SbBaseline;

/* 0, or -(1 + index) of the first bad parameter (sb_param_name) */
int sb_setup(SbBaseline *b, const SbParams *p);
const char *sb_param_name(int code);

double sb_ground(const SbParams *p, double v);

/* one sample; outputs always finite, pct within [0, pctMax] */
unsigned sb_sample(SbBaseline *b, double v, double Lambda, double LambdaDot);

#endif
