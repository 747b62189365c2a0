/* seed 004, eq. 3 with zero steady-state side-slip. See zero_sideslip.h. */
#include <math.h>

#include "zero_sideslip.h"

int zs_prepare(const ZsVehicle *veh, ZsGains *g, int *bad_axle) {
    int dummy;
    if (!bad_axle) bad_axle = &dummy;
    *bad_axle = 0;
    const int n = veh->n;
    if (n < 2 || n > ZS_MAX_AXLES) return ZS_BAD_N;
    if (!veh->steerable[1]) { *bad_axle = 1; return ZS_FRONT_NOT_STEERABLE; }
    double M = veh->m_b;
    if (!(M > 0) || !isfinite(M)) return ZS_BAD_PARAMETER;
    int rear = 0;
    for (int i = 1; i <= n; i++) {
        *bad_axle = i;
        if (!isfinite(veh->l[i]) || !(veh->k[i] < 0) || !isfinite(veh->k[i]) ||
            !(veh->m[i] >= 0) || !isfinite(veh->m[i]) ||
            !(veh->deltaMax[i] >= 0) || !isfinite(veh->deltaMax[i]))
            return ZS_BAD_PARAMETER;
        if (i > 1 && !(veh->l[i] < veh->l[i - 1])) return ZS_NOT_ORDERED;
        if (i > 1 && veh->steerable[i]) rear = i;
        M += veh->m[i];
    }
    *bad_axle = 0;
    if (!rear) return ZS_NO_REAR_AXLE;

    g->n = n;
    g->rear = rear;
    double Ska = 0, Skla = 0, Skb = 0, Sklb = 0, Skl = 0, Skl2 = 0, Sml = 0;
    for (int i = 0; i <= ZS_MAX_AXLES; i++) g->a[i] = g->b[i] = g->deltaMax[i] = 0.0;
    for (int i = 1; i <= n; i++) {
        const double l = veh->l[i], k = veh->k[i];
        if (veh->steerable[i]) {    /* eq. 3: linear in the position between 1 and r */
            const double s = (veh->l[1] - l) / (veh->l[1] - veh->l[rear]);
            g->a[i] = 1.0 - s;
            g->b[i] = s;
        }
        g->deltaMax[i] = veh->deltaMax[i];
        Ska += k * g->a[i];
        Skla += k * l * g->a[i];
        Skb += k * g->b[i];
        Sklb += k * l * g->b[i];
        Skl += k * l;
        Skl2 += k * l * l;
        Sml += veh->m[i] * l;
    }
    g->a[1] = 1.0;                  /* exactly, whatever the rounding */
    g->b[1] = 0.0;
    g->a[rear] = 0.0;
    g->b[rear] = 1.0;
    g->N2 = M * Skla - Sml * Ska;
    g->N0 = Skl2 * Ska - Skl * Skla;
    g->D2 = Sml * Skb - M * Sklb;
    g->D0 = Skl * Sklb - Skl2 * Skb;
    if (!(isfinite(g->N2) && isfinite(g->N0) && isfinite(g->D2) && isfinite(g->D0)))
        return ZS_BAD_PARAMETER;
    if (g->D2 == 0.0 && g->D0 == 0.0) return ZS_SINGULAR;
    const double u2 = g->D2 != 0.0 ? -g->D0 / g->D2 : -1.0;
    g->uPole = u2 >= 0.0 ? sqrt(u2) : -1.0;
    return ZS_OK;
}

double zs_gain(const ZsGains *g, double u) {
    const double u2 = u * u;
    return (g->N2 * u2 + g->N0) / (g->D2 * u2 + g->D0);
}

void zs_reset(ZsMemory *mem) {
    for (int i = 0; i <= ZS_MAX_AXLES; i++) mem->delta[i] = 0.0;
    mem->u = 0.0;
}

static double limit(double x, double lim, unsigned *flags) {
    if (x > lim) { *flags |= ZS_SATURATED; return lim; }
    if (x < -lim) { *flags |= ZS_SATURATED; return -lim; }
    return x;
}

unsigned zs_step(const ZsGains *g, ZsMemory *mem, double delta1, double u,
                 double delta[], double K_i[]) {
    unsigned flags = 0;
    if (isfinite(u)) mem->u = u;
    else flags |= ZS_INPUT_NOT_FINITE;
    double speed = mem->u;
    if (speed < 0.0) {
        flags |= ZS_REVERSING;
        speed = 0.0;
    }
    if (speed > ZS_U_CAP) speed = ZS_U_CAP;     /* keeps u^2 finite; K is at its limit there */
    const double num = g->N2 * speed * speed + g->N0, den = g->D2 * speed * speed + g->D0;
    double K;
    if (fabs(num) < ZS_K_LIMIT * fabs(den)) {
        K = num / den;
    } else {                        /* at or near the pole (den may be 0) */
        flags |= ZS_NEAR_POLE;
        K = (num >= 0) == (den >= 0) ? ZS_K_LIMIT : -ZS_K_LIMIT;
    }
    for (int i = 0; i <= ZS_MAX_AXLES; i++) {
        const double Ki = i >= 1 && i <= g->n ? g->a[i] + g->b[i] * K : 0.0;
        if (K_i) K_i[i] = Ki;
    }
    if (!isfinite(delta1)) {
        flags |= ZS_INPUT_NOT_FINITE;
        for (int i = 0; i <= ZS_MAX_AXLES; i++) delta[i] = mem->delta[i];
        return flags;
    }
    for (int i = 0; i <= ZS_MAX_AXLES; i++) {
        const double d = i >= 1 && i <= g->n ? (g->a[i] + g->b[i] * K) * delta1 : 0.0;
        delta[i] = i >= 1 && i <= g->n ? limit(d, g->deltaMax[i], &flags) : 0.0;
        mem->delta[i] = delta[i];
    }
    return flags;
}
