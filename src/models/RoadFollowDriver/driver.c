/* The road-follow driver (driver.h), seed 001, ch. 3.2. */
#include <math.h>

#include "driver.h"

/* search windows on the road table, in m */
#define BACK_WINDOW 5.0          /* behind the last foot of the reference point */
#define AHEAD_MARGIN 10.0        /* beyond the reference point plus 1.5 look-ahead */

static double clamp(double a, double lo, double hi) { return a < lo ? lo : a > hi ? hi : a; }

double driver_delta_for_direction(const DriverParams *p, double chi) {
    /* rear axle speed v along the body, yaw rate v tan(delta) / L0: the point
     * (a, b) moves along (1 - b tan(delta) / L0, a tan(delta) / L0), so
     * tan(chi) = a tan(delta) / (L0 - b tan(delta)), solved for delta */
    return atan2(p->L0 * sin(chi), p->refX * cos(chi) + p->refY * sin(chi));
}

static void reference_point(const DriverParams *p, const DriverInput *in, double *px, double *py) {
    const double c = cos(in->psi), s = sin(in->psi);
    *px = in->x + p->refX * c - p->refY * s;
    *py = in->y + p->refX * s + p->refY * c;
}

double driver_speed_set_point(const DriverParams *p, double s) {
    if (p->nSpeed < 2) return p->vSet;
    if (s <= p->speedS[0]) return p->speedV[0];
    for (int k = 1; k < p->nSpeed; k++)
        if (s <= p->speedS[k]) {
            const double w = (s - p->speedS[k - 1]) / (p->speedS[k] - p->speedS[k - 1]);
            return p->speedV[k - 1] + w * (p->speedV[k] - p->speedV[k - 1]);
        }
    return p->speedV[p->nSpeed - 1];
}

void driver_start(const Road *r, const DriverParams *p, const DriverInput *in, DriverMemory *m) {
    double px, py;
    reference_point(p, in, &px, &py);
    m->delta = 0.0;
    m->integral = 0.0;
    m->iRef = road_project(r, px, py, 0, r->n - 1).i;
}

void driver_sample(const Road *r, const DriverParams *p, const DriverInput *in,
                   DriverMemory *m, DriverOutput *out) {
    const double ds = r->ds;
    double px, py;
    reference_point(p, in, &px, &py);

    /* the reference point on the road: incremental search around the last foot */
    const int ahead = road_int(ceil((fabs(in->v) * p->Ts + AHEAD_MARGIN) / ds));
    const RoadFoot f0 = road_project(r, px, py, m->iRef - road_int(ceil(BACK_WINDOW / ds)), m->iRef + ahead);
    m->iRef = f0.i;
    out->s = f0.s;
    out->eLat = f0.eLat;
    out->ePsi = road_wrap(in->psi - f0.psi);
    out->finished = f0.s >= r->length;

    /* (1), (2): two points ahead of the reference point in module 1's
     * direction at speed-dependent distances; (3), (4): their nearest road
     * points, searched forward from the reference point's foot */
    const double lNear = p->lookNear0 + p->tNear * fabs(in->v);
    const double lFar = p->lookFar0 + p->tFar * fabs(in->v);
    const double c = cos(in->psi), s = sin(in->psi);
    const int hiNear = f0.i + road_int(ceil((1.5 * lNear + AHEAD_MARGIN) / ds));
    const int hiFar = f0.i + road_int(ceil((1.5 * lFar + AHEAD_MARGIN) / ds));
    const RoadFoot f3 = road_project(r, px + lNear * c, py + lNear * s, f0.i, hiNear);
    const RoadFoot f4 = road_project(r, px + lFar * c, py + lFar * s, f0.i, hiFar);

    /* all angles relative to module 1's heading, wrapped: a full circle and
     * headings across +/-pi need no special case */
    const double line = road_wrap(atan2(f4.y - py, f4.x - px) - in->psi);   /* line (7), eq. 3.3 */
    const double tangent = road_wrap(f4.psi - in->psi);                     /* angle (5) */
    /* method 1, eq. 3.1: the constant-curvature arc from the reference point
     * to (4) arriving with the road's tangent: its chord (7) halves the turn,
     * so it leaves in the direction line - (tangent - line) */
    const double chi1 = road_wrap(2.0 * line - tangent);
    /* method 2, eq. 3.2: straight at the near point (3) */
    const double chi2 = road_wrap(atan2(f3.y - py, f3.x - px) - in->psi);
    /* eq. 3.3: the one closest to the direction of the far point */
    const int one = fabs(road_wrap(chi1 - line)) <= fabs(road_wrap(chi2 - line));
    out->method = one ? 1 : 2;
    double delta = driver_delta_for_direction(p, one ? chi1 : chi2);
    if (p->sHold > 0 && f0.s >= p->sHold) delta = 0.0;   /* hands off: back to straight, then held */

    /* under-steer compensation (seed 001, 3.2.1): steer more while the front
     * axle's actual direction of motion chiF lags the steering angle */
    const double lag = m->delta - in->chiF;
    if (p->kUS > 0 && lag * m->delta > 0 && !(p->sHold > 0 && f0.s >= p->sHold)) delta += p->kUS * lag;

    /* the limits the thesis lacked (3.2.2): angle, then rate from the last sample */
    delta = clamp(delta, -p->deltaMax, p->deltaMax);
    const double step = p->deltaRateMax * p->Ts;
    delta = clamp(delta, m->delta - step, m->delta + step);
    m->delta = out->delta = delta;

    /* speed: the set point until the end of the road, then stop; PI on the
     * drive force with conditional integration (no wind-up in saturation) */
    out->vRef = out->finished ? 0.0 : driver_speed_set_point(p, f0.s);
    if (out->finished) {
        /* end of the road: brake to a stop and stay there. A brake only opposes
           the motion: proportional to the speed (Kp), no integral (the PI's
           integral, wound up while driving, overshot through zero and the bus
           crept back); with Kp Ts / m << 1 the speed decays without changing sign */
        m->integral = 0.0;
        out->Fx = clamp(-p->Kp * in->v, p->FxMin, p->FxMax);
        return;
    }
    const double e = out->vRef - in->v;
    const double I = m->integral + p->Ki * e * p->Ts;
    const double u = p->Kp * e + I;
    if (!((u > p->FxMax && e > 0) || (u < p->FxMin && e < 0))) m->integral = I;
    out->Fx = clamp(p->Kp * e + m->integral, p->FxMin, p->FxMax);
}
