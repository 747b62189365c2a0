/* The road-follow driver of seed 001, ch. 3.2 (two look-ahead points,
 * method 1 / method 2, eq. 3.3, under-steer compensation), with the steering
 * angle and rate limits the thesis lacked (3.2.2), and a PI speed controller
 * on the drive force. A discrete controller: driver_sample() is one sample.
 * Plain C, no FMI types, no allocation.
 *
 * Vehicle: module 1 of the bus as a kinematic single-track vehicle. The pose
 * (x, y, psi) is that of its rear (unsteered) axle mid-point; the front axle
 * is L0 ahead; the guided reference point is (refX, refY) in module 1's frame
 * from the rear axle mid-point (refX = L0, refY = 0: the front axle mid-point).
 */
#ifndef DRIVER_H
#define DRIVER_H

#include "roads.h"

#define DRIVER_MAX_SPEED_POINTS 10

typedef struct {
    double L0;                   /* wheelbase of module 1 [m] */
    double refX, refY;           /* reference point in module 1's frame [m] */
    double lookNear0, tNear;     /* near look-ahead = lookNear0 + tNear |v| [m, s] */
    double lookFar0, tFar;       /* far look-ahead = lookFar0 + tFar |v| [m, s] */
    double kUS;                  /* under-steer compensation gain [-] */
    double deltaMax;             /* steering angle limit [rad] */
    double deltaRateMax;         /* steering rate limit [rad/s] */
    double vSet;                 /* speed set point [m/s], when there is no profile */
    int nSpeed;                  /* points of the speed profile against distance (0: vSet) */
    double speedS[DRIVER_MAX_SPEED_POINTS];   /* road distance of each point, increasing [m] */
    double speedV[DRIVER_MAX_SPEED_POINTS];   /* speed set point there [m/s] */
    double sHold;                /* hands off from this road distance on: steer back to straight (0: never) [m] */
    double Kp, Ki;               /* PI on the drive force [N/(m/s)], [N/m] */
    double FxMin, FxMax;         /* drive force limits [N] */
    double Ts;                   /* sample time [s] */
} DriverParams;

/* what the driver remembers from sample to sample */
typedef struct {
    double delta;                /* last steering angle [rad] */
    double integral;             /* PI integral part [N] */
    int iRef;                    /* table index of the reference point's foot */
} DriverMemory;

typedef struct {
    double x, y, psi;            /* rear axle mid-point of module 1 [m, m, rad] */
    double v;                    /* speed [m/s] */
    double chiF;                 /* front axle's direction of motion in module 1's frame [rad] */
} DriverInput;

typedef struct {
    double delta, Fx, vRef, s, eLat, ePsi;
    int finished;
    int method;                  /* 1 or 2: the steering angle chosen by eq. 3.3 */
} DriverOutput;

/* the steering angle that makes the reference point move in direction chi
 * (module 1's frame), for the kinematic single-track vehicle */
double driver_delta_for_direction(const DriverParams *p, double chi);

/* Put the memory at the start: wheels straight, integral 0, and the reference
 * point's foot searched on the whole road (the only full scan). */
void driver_start(const Road *r, const DriverParams *p, const DriverInput *in, DriverMemory *m);

/* The speed set point at road distance s: vSet, or the profile, linear
 * between its points and held beyond its ends. */
double driver_speed_set_point(const DriverParams *p, double s);

/* One sample: outputs from the inputs; updates the memory. */
void driver_sample(const Road *r, const DriverParams *p, const DriverInput *in,
                   DriverMemory *m, DriverOutput *out);

#endif
