/* What a receiver on the steering CAN does when its messages stop (issue 12):
 * stale detection from the messages' alive counters, the way AUTOSAR E2E
 * profile 2 does it, and a defined fallback of the set-points it outputs.
 * Plain C99, no FMI types, no heap, no globals: one CfFallback per receiver,
 * used alike by the module ECUs (SteeringECU) and the steering actuators
 * (SteeringActuator).
 *
 * The CAN driver (the runner's network, src/artibus/can.py) drops every frame
 * whose CRC is wrong or whose counter repeats the last accepted one, so the
 * receiver's counter input changes exactly when a new valid frame arrived.
 * Per cycle (period Ts) and message i:
 *   age_i = 0 if counter_i changed since the last cycle, else age_i + 1;
 *   message i is stale when age_i >= nStale (nStale = 0: no check).
 * A message that stops is therefore stale in the nStale-th cycle without a new
 * frame (3 cycles = 30 ms at 10 ms).
 *
 * Fallback (output `fallback`):
 *   0 normal   the outputs are the wanted ones (the algorithm's, or the
 *              received set-points);
 *   1 holding  entered in the cycle a used message turns stale (or the caller
 *              reports another bad input): the outputs keep the values of the
 *              cycle before, for nHold = ceil(tHold / Ts) cycles including this one;
 *   2 ramping  then each output moves toward the safe angle 0 (straight ahead,
 *              the safe angle of a trailer axle) by rampRate Ts per cycle;
 *   3 safe     every output is at 0.
 * Fallback ends (back to 0) only after nRecover consecutive cycles in which
 * every used message brought a new frame (age 0) and nothing else was bad;
 * from there the outputs slew to the wanted ones at rampRate (no step), then
 * follow them. A message going stale again in between starts a new hold. */
#ifndef ARTIBUS_CAN_FALLBACK_H
#define ARTIBUS_CAN_FALLBACK_H

#define CF_MAX_MSG 5      /* messages per receiver */
#define CF_MAX_OUT 2      /* set-points per receiver */

enum { CF_NORMAL = 0, CF_HOLD = 1, CF_RAMP = 2, CF_SAFE = 3 };

typedef struct {
    int nMsg, nOut;       /* messages watched (1..CF_MAX_MSG), outputs (1..CF_MAX_OUT) */
    int nStale;           /* cycles without a new counter after which a message is stale; 0 = no check */
    int nRecover;         /* consecutive all-fresh cycles that end the fallback, >= 1 */
    double tHold;         /* hold time before the ramp [s], >= 0 */
    double rampRate;      /* ramp to the safe angle and back [rad/s], > 0 */
    double Ts;            /* cycle [s], > 0 */
} CfParams;

typedef struct {
    CfParams p;
    int nHold;                    /* ceil(tHold / Ts) */
    double last[CF_MAX_MSG];      /* counter of each message in the last cycle */
    int age[CF_MAX_MSG];          /* cycles since it last changed (capped) */
    int mode;                     /* CF_NORMAL .. CF_SAFE */
    int cycles;                   /* cycles spent in the current hold */
    int fresh;                    /* consecutive all-fresh cycles while in fallback */
    int rejoin;                   /* after a fallback: slewing to the wanted outputs */
    double out[CF_MAX_OUT];       /* the outputs [rad] */
} CfFallback;

/* 0, or a negative number naming the bad parameter (cf_param_name) */
int cf_setup(CfFallback *f, const CfParams *p, const double *counters, const double *out);
const char *cf_param_name(int code);

/* One cycle. counters: the messages' alive counters as received now; used:
 * bit i set if message i matters; bad: nonzero if the caller has another
 * reason for the fallback (an input it cannot use); want: the outputs it
 * would command. Returns the stale mask (bit i: message i stale, used or
 * not); outputs in f->out, always finite. */
unsigned cf_sample(CfFallback *f, const double *counters, unsigned used, int bad, const double *want);

/* 1 if a restored fallback state is usable: counts, modes and ages in range, values finite */
int cf_state_valid(const CfFallback *f);

#endif
