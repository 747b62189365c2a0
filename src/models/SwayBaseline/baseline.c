/* An ACS5-like condition-based damping baseline (see baseline.h). Plain C99
 * and libm only. */
#include <math.h>
#include "baseline.h"

static const char *const PARAM_NAME[] = {
    "", "nGround", "groundSpeed (finite, strictly increasing)", "groundPct (0..50)", "vSSC",
    "LambdaDotSSC", "tHold", "pctSSC (0..50)", "LambdaEP0", "LambdaEP1 (> LambdaEP0)",
    "pctEP (0..50)", "pctMax (0..50)", "Ts"
};

const char *sb_param_name(int code) {
    return code < 0 && -code < (int)(sizeof PARAM_NAME / sizeof *PARAM_NAME) ? PARAM_NAME[-code] : "?";
}

static int pct_ok(double x) { return isfinite(x) && x >= 0 && x <= 50; }
static int nonneg(double x) { return isfinite(x) && x >= 0; }

int sb_setup(SbBaseline *b, const SbParams *p) {
    int i;
    if (p->nGround < 1 || p->nGround > SB_MAX_GROUND) return -1;
    for (i = 0; i < p->nGround; i++) {
        if (!isfinite(p->groundSpeed[i]) || (i > 0 && !(p->groundSpeed[i] > p->groundSpeed[i - 1])))
            return -2;
        if (!pct_ok(p->groundPct[i])) return -3;
    }
    if (!nonneg(p->vSSC)) return -4;
    if (!nonneg(p->LambdaDotSSC)) return -5;
    if (!nonneg(p->tHold)) return -6;
    if (!pct_ok(p->pctSSC)) return -7;
    if (!nonneg(p->LambdaEP0)) return -8;
    if (!(isfinite(p->LambdaEP1) && p->LambdaEP1 > p->LambdaEP0)) return -9;
    if (!pct_ok(p->pctEP)) return -10;
    if (!pct_ok(p->pctMax)) return -11;
    if (!(isfinite(p->Ts) && p->Ts > 0 && p->tHold / p->Ts < 1e9)) return -12;
    b->p = *p;
    b->nHold = (long long)floor(p->tHold / p->Ts + 0.5);
    b->k = b->kLast = 0;
    b->everHeld = 0;
    b->tSince = 0.0;
    b->pctGround = sb_ground(p, 0.0);
    b->pct = b->pctGround < p->pctMax ? b->pctGround : p->pctMax;
    b->ssc = b->ep = 0.0;
    return 0;
}

double sb_ground(const SbParams *p, double v) {
    const int n = p->nGround;
    int i;
    if (n <= 1 || v <= p->groundSpeed[0]) return p->groundPct[0];
    if (v >= p->groundSpeed[n - 1]) return p->groundPct[n - 1];
    for (i = 1; i < n - 1 && v > p->groundSpeed[i]; i++) {}
    {
        const double s = (v - p->groundSpeed[i - 1]) / (p->groundSpeed[i] - p->groundSpeed[i - 1]);
        return p->groundPct[i - 1] + s * (p->groundPct[i] - p->groundPct[i - 1]);
    }
}

unsigned sb_sample(SbBaseline *b, double v, double Lambda, double LambdaDot) {
    const SbParams *p = &b->p;
    unsigned fault = 0;
    double pct, ep, x;
    if (!(isfinite(v) && isfinite(Lambda) && isfinite(LambdaDot))) return SB_FAULT_NAN;
    if (v < 0) fault |= SB_FAULT_REVERSE;
    /* Sway Control (SSC): a fast lane change identified from the measured speed and
       articulation angular velocity (seed 001, 5.2.5), held tHold after it last held */
    if (v >= p->vSSC && fabs(LambdaDot) >= p->LambdaDotSSC) {
        b->kLast = b->k;
        b->everHeld = 1;
    }
    {
        const long long since = b->k - (b->everHeld ? b->kLast : 0);
        b->tSince = (double)since * p->Ts;
        b->ssc = b->everHeld && (since == 0 || since < b->nHold) ? 1.0 : 0.0;
    }
    b->k++;
    /* ground level rising with speed (seed 001, 1.4.1: 13.5 % at 100 km/h) */
    b->pctGround = sb_ground(p, v);
    /* End Protection Damping, towards the end stop */
    x = (fabs(Lambda) - p->LambdaEP0) / (p->LambdaEP1 - p->LambdaEP0);
    ep = p->pctEP * (x < 0 ? 0.0 : x > 1 ? 1.0 : x);
    b->ep = fabs(Lambda) > p->LambdaEP0 ? 1.0 : 0.0;
    pct = b->pctGround;
    if (b->ssc != 0.0 && p->pctSSC > pct) pct = p->pctSSC;
    if (ep > pct) pct = ep;
    b->pct = pct < p->pctMax ? pct : p->pctMax;   /* ACS5's maximum, 34 % (seed 001, 5.1.1) */
    return fault;
}
