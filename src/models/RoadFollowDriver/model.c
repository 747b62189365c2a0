/* RoadFollowDriver: the road-follow driver of seed 001, ch. 3.2 (driver.c) on
 * the test roads (roads.c), as a discrete controller: its outputs change at
 * the sample instants t0 + k Ts only, from the inputs held over the step, so
 * no output depends directly on an input (ModelStructure dependencies ""). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu.h"
#include "driver.h"
#include "roads.h"

/* what a built-in road is made from: the road is built again only when one of
 * these changed (model_init runs at every read in initialisation mode) */
typedef struct {
    int road;
    double roadBefore, roadAfter, laneLength, laneOffset, R, isoWidth, roadStep, ds;
} RoadKey;

typedef struct {
    Road road;              /* built in initialisation, never in a step */
    int built;              /* road holds the built-in road of key */
    RoadKey key;
} Work;

static RoadKey road_key(ModelInstance *comp) {
    RoadKey k;
    memset(&k, 0, sizeof k);     /* padding too: keys are compared with memcmp */
    k.road = D->road;
    k.roadBefore = D->roadBefore;
    k.roadAfter = D->roadAfter;
    k.laneLength = D->laneLength;
    k.laneOffset = D->laneOffset;
    k.R = D->R;
    k.isoWidth = D->isoWidth;
    k.roadStep = D->roadStep;
    k.ds = D->ds;
    return k;
}

static void params(ModelInstance *comp, DriverParams *p) {
    p->L0 = D->L0;
    p->refX = D->refX;
    p->refY = D->refY;
    p->lookNear0 = D->lookNear0;
    p->tNear = D->tNear;
    p->lookFar0 = D->lookFar0;
    p->tFar = D->tFar;
    p->kUS = D->kUS;
    p->deltaMax = D->deltaMax;
    p->deltaRateMax = D->deltaRateMax;
    p->vSet = D->vSet;
    p->nSpeed = D->nSpeed;
    p->sHold = D->sHold;
    for (int k = 0; k < DRIVER_MAX_SPEED_POINTS; k++) {   /* speedS[1..10] -> speedS[0..9] */
        p->speedS[k] = D->speedS[k + 1];
        p->speedV[k] = D->speedV[k + 1];
    }
    p->Kp = D->Kp;
    p->Ki = D->Ki;
    p->FxMin = D->FxMin;
    p->FxMax = D->FxMax;
    p->Ts = D->Ts;
}

/* the file: an absolute path as given (on Windows also C:\dir, C:/dir, \\server),
   else a file name in resources/ */
static void road_path(ModelInstance *comp, char *path, size_t len) {
    const char *f = D->roadFile;
#ifdef _WIN32
    const bool absolute = f[0] == '/' || f[0] == '\\' || (f[0] && f[1] == ':');
#else
    const bool absolute = f[0] == '/';
#endif
    if (absolute || !comp->resourceDir) snprintf(path, len, "%s", f);
    else snprintf(path, len, "%s/%s", comp->resourceDir, f);
}

static Status build_road(ModelInstance *comp, Road *road) {
    double *x = malloc(ROAD_RAW_MAX * sizeof *x), *y = malloc(ROAD_RAW_MAX * sizeof *y);
    if (!x || !y) {
        free(x);
        free(y);
        return log_error(comp, "out of memory for the road");
    }
    char err[ROAD_ERRLEN] = "";
    int n;
    if (D->road == ROAD_CSV) {
        if (!D->roadFile[0]) {
            free(x);
            free(y);
            return log_error(comp, "road = 0 (CSV) but roadFile = '' names no file");
        }
        char path[ARTIBUS_STRLEN + 1200];
        road_path(comp, path, sizeof path);
        n = road_read_csv(path, x, y, ROAD_RAW_MAX, err, sizeof err);
    } else {
        const RoadParams q = { D->roadBefore, D->roadAfter, D->laneLength, D->laneOffset,
                               D->R, D->isoWidth, D->roadStep };
        n = road_generate(D->road, &q, x, y, ROAD_RAW_MAX, err, sizeof err);
    }
    if (n >= 0 && road_resample(x, y, n, D->ds, road, err, sizeof err) == 0) n = 0;
    else n = -1;
    free(x);
    free(y);
    if (n < 0) return log_error(comp, "road = %d: %s", D->road, err);
    log_event(comp, "road = %d: %.3f m, %d points at ds = %g m", D->road, road->length, road->n, D->ds);
    return OK;
}

static void input(ModelInstance *comp, DriverInput *in) {
    const ModelState *s = &comp->v.s;
    if (D->testVehicle) {
        *in = (DriverInput){ s->xv, s->yv, s->psiv, s->vv, s->mem.delta };
    } else {
        *in = (DriverInput){ D->x, D->y, D->psi, D->v, D->chiF };
    }
}

/* one sample, then the test vehicle (if used) moves on by Ts with the new
 * steering angle and speed vRef */
static void sample(ModelInstance *comp, const Road *road, const DriverParams *p) {
    ModelState *s = &comp->v.s;
    DriverInput in;
    input(comp, &in);
    const int was = s->out.finished;
    driver_sample(road, p, &in, &s->mem, &s->out);
    if (s->out.finished && !was) log_event(comp, "end of road reached at s = %.3f m", s->out.s);
    s->kNext++;
    if (D->testVehicle) {
        const double v = s->out.vRef, h = p->Ts;
        s->xv += v * cos(s->psiv) * h;
        s->yv += v * sin(s->psiv) * h;
        s->psiv += v * tan(s->out.delta) / p->L0 * h;
        s->vv = v;
    }
}

Status model_check_parameters(ModelInstance *comp) {
    if (D->nSpeed == 1)
        return log_error(comp, "nSpeed = 1: a speed profile needs 2..10 points (0: constant vSet)");
    for (int k = 2; k <= D->nSpeed; k++)
        if (!(D->speedS[k] > D->speedS[k - 1]))
            return log_error(comp, "speedS[%d] = %g m is not beyond speedS[%d] = %g m: the speed profile's "
                                   "distances must increase", k, D->speedS[k], k - 1, D->speedS[k - 1]);
    if (!(D->lookNear0 > 0))
        return log_error(comp, "lookNear0 = %g m: the near look-ahead distance must be > 0", D->lookNear0);
    if (!(D->lookFar0 > D->lookNear0) || !(D->tFar >= D->tNear))
        return log_error(comp, "lookFar0 = %g m, tFar = %g s: the far look-ahead point must lie beyond "
                               "the near one (lookNear0 = %g m, tNear = %g s) at every speed",
                         D->lookFar0, D->tFar, D->lookNear0, D->tNear);
    if (!(D->FxMin <= D->FxMax))
        return log_error(comp, "FxMin = %g N is above FxMax = %g N", D->FxMin, D->FxMax);
    return OK;
}

Status model_init(ModelInstance *comp) {
    if (model_check_parameters(comp)) return Error;
    Work *w = comp->solver;
    if (!w) {
        w = comp->solver = malloc(sizeof(Work));
        if (!w) return log_error(comp, "out of memory");
        w->built = 0;
    }
    const RoadKey key = road_key(comp);
    if (!(w->built && D->road != ROAD_CSV && memcmp(&key, &w->key, sizeof key) == 0)) {
        w->built = 0;                         /* a CSV road is read again: its file may have changed */
        if (build_road(comp, &w->road)) return Error;
        w->built = 1;
        w->key = key;
    }

    DriverParams p;
    params(comp, &p);
    ModelState *s = &comp->v.s;
    memset(s, 0, sizeof *s);
    s->t0 = comp->v.time;
    if (D->testVehicle) {       /* the reference point at the road's start, on its tangent */
        const Road *r = &w->road;
        s->psiv = r->psi[0];
        s->xv = r->x[0] - D->refX * cos(s->psiv) + D->refY * sin(s->psiv);
        s->yv = r->y[0] - D->refX * sin(s->psiv) - D->refY * cos(s->psiv);
        s->vv = 0.0;
    }
    DriverInput in;
    input(comp, &in);
    driver_start(&w->road, &p, &in, &s->mem);
    sample(comp, &w->road, &p);       /* sample 0, at t0 */
    return OK;
}

void model_outputs(ModelInstance *comp) {
    const DriverOutput *o = &comp->v.s.out;
    D->delta = o->delta;
    D->Fx = o->Fx;
    D->vRef = o->vRef;
    D->s = o->s;
    D->eLat = o->eLat;
    D->ePsi = o->ePsi;
    D->finished = o->finished;
    D->method = o->method;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    Work *w = comp->solver;
    if (!w) return log_error(comp, "fmi2DoStep: the road was not built (model not initialised)");
    DriverParams p;
    params(comp, &p);
    ModelState *s = &comp->v.s;
    /* every sample instant in (t, t + h], from the inputs held over the step */
    const double end = t + h + 1e-9 * p.Ts;
    while (s->t0 + s->kNext * p.Ts <= end) sample(comp, &w->road, &p);
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) {
    free(comp->solver);
    comp->solver = NULL;
}

/* FMU state: the sample counter, the driver's memory (its road index checked
 * against the road again in model_restored), held outputs, the test vehicle */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    if (!sample_index_ok(s->t0, s->kNext, d->Ts, time))
        return STATE_INVALID("sample kNext = %ld from t0 = %g (Ts = %g s) is not near t = %g s",
                             s->kNext, s->t0, d->Ts, time);
    if (s->mem.iRef < 0 || s->mem.iRef >= ROAD_MAX_POINTS)
        return STATE_INVALID("road index iRef = %d is outside the table (0 .. %d)", s->mem.iRef, ROAD_MAX_POINTS - 1);
    const DriverOutput *o = &s->out;
    if (!isfinite(s->mem.delta) || !isfinite(s->mem.integral) || !isfinite(o->delta) || !isfinite(o->Fx) ||
        !isfinite(o->vRef) || !isfinite(o->s) || !isfinite(o->eLat) || !isfinite(o->ePsi) ||
        !isfinite(s->xv) || !isfinite(s->yv) || !isfinite(s->psiv) || !isfinite(s->vv))
        return STATE_INVALID("a memory, output or test vehicle value is not finite");
    if ((o->finished != 0 && o->finished != 1) || (o->method != 1 && o->method != 2 && o->method != 0))
        return STATE_INVALID("finished = %d, method = %d", o->finished, o->method);
    return true;
}

/* the road of the restored parameters (built again unless it is the one built) */
Status model_restored(ModelInstance *comp) {
    /* before initialisation the road is built by model_init, from the parameters then */
    if (comp->v.state & (S_INSTANTIATED | S_INIT_MODE)) return OK;
    Work *w = comp->solver;
    const RoadKey key = road_key(comp);
    if (w && w->built && D->road != ROAD_CSV && memcmp(&key, &w->key, sizeof key) == 0) {
        if (comp->v.s.mem.iRef >= w->road.n)
            return log_error(comp, "road index iRef = %d is beyond the road's %d points",
                             comp->v.s.mem.iRef, w->road.n);
        return OK;
    }
    Work *nw = malloc(sizeof(Work));
    if (!nw) return log_error(comp, "out of memory");
    if (build_road(comp, &nw->road)) {
        free(nw);
        return Error;
    }
    if (comp->v.s.mem.iRef >= nw->road.n) {
        const int np = nw->road.n;
        free(nw);
        return log_error(comp, "road index iRef = %d is beyond the road's %d points", comp->v.s.mem.iRef, np);
    }
    nw->built = 1;
    nw->key = key;
    free(w);
    comp->solver = nw;
    return OK;
}
