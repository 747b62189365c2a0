#include <stdlib.h>
#include <math.h>
#include <string.h>

#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "fmu.h"
#include "ode.h"

#if SUNDIALS_VERSION_MAJOR >= 7
#define ARTIBUS_COMM SUN_COMM_NULL
#else
#define ARTIBUS_COMM NULL
#endif

/* The first step after an input change is at most this many communication
   steps long (ODE_ERK; see erk_advance). */
#define ERK_RESTART_STEPS 10.0

struct Ode {
    ModelInstance *comp;
    SUNContext ctx;
    void *mem;          /* CVODE (ODE_BDF, ODE_ADAMS) */
    void *erk;          /* ARKODE ERKStep (ODE_ERK) */
    N_Vector y;
    SUNMatrix A;
    SUNLinearSolver LS;
    int n, nroots;
    OdeRhs rhs;
    OdeRoots roots;
    void *user;
    bool started;
    long nrhs;
    SUNMatrix J;        /* the last Jacobian computed, for reuse after a restart */
    bool haveJ;         /* J holds one that may be reused */
    bool reuseJ;        /* the next Jacobian request is the first after a restart */
    N_Vector ewt;
};

static int cv_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *p) {
    Ode *o = p;
    o->nrhs++;
    return o->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), o->user);
}

static int cv_roots(sunrealtype t, N_Vector y, sunrealtype *g, void *p) {
    Ode *o = p;
    return o->roots(t, N_VGetArrayPointer(y), g, o->user);
}

/* The Jacobian df/dy by difference quotients, column by column, with
   CVODE's own increments (cvLsDenseDQJac: sqrt(eps)|y_j|, at least
   1000 |h| eps n ||f||_wrms / ewt_j), kept for reuse.

   After a restart (an input changed: y is continuous, only f jumped) the
   first request gets the Jacobian kept from before the restart instead of a
   new one: CVODE's Newton iteration only needs an approximate Jacobian (it
   keeps one for up to 51 steps itself), and if the iteration does not
   converge with it CVODE asks again (CV_FAIL_OTHER) and gets a fresh one. */
static int cv_jac(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix Jac, void *p,
                  N_Vector tmp1, N_Vector tmp2, N_Vector tmp3) {
    (void)tmp3;
    Ode *o = p;
    if (o->reuseJ) {
        o->reuseJ = false;
        return SUNMatCopy(o->J, Jac) == 0 ? 0 : -1;
    }
    o->reuseJ = false;
    const int n = o->n;
    sunrealtype h = 0.0;
    CVodeGetCurrentStep(o->mem, &h);
    if (CVodeGetErrWeights(o->mem, o->ewt) != CV_SUCCESS) return -1;
    const sunrealtype fnorm = N_VWrmsNorm(fy, o->ewt);
    const sunrealtype eps = SUN_UNIT_ROUNDOFF, srur = sqrt(eps);
    const sunrealtype minInc = fnorm != 0.0 ? 1000.0 * fabs(h) * eps * n * fnorm : 1.0;
    const double *ew = N_VGetArrayPointer(o->ewt), *f0 = N_VGetArrayPointer(fy);
    double *yv = N_VGetArrayPointer(tmp1), *f1 = N_VGetArrayPointer(tmp2);
    N_VScale(1.0, y, tmp1);
    for (int j = 0; j < n; j++) {
        const double yj = yv[j];
        const double inc = fmax(srur * fabs(yj), minInc / ew[j]);
        yv[j] = yj + inc;
        o->nrhs++;
        const int flag = o->rhs(t, yv, f1, o->user);
        yv[j] = yj;
        if (flag) return flag;
        double *col = SUNDenseMatrix_Column(Jac, j);
        for (int i = 0; i < n; i++) col[i] = (f1[i] - f0[i]) / inc;
    }
    if (SUNMatCopy(Jac, o->J) != 0) return -1;
    o->haveJ = true;
    return 0;
}

#if SUNDIALS_VERSION_MAJOR >= 7
static void cv_error(int line, const char *func, const char *file, const char *msg,
                     SUNErrCode code, void *p, SUNContext ctx) {
    (void)line; (void)file; (void)ctx;
    Ode *o = p;
    log_error(o->comp, "CVODE %s (flag %d): %s", func, (int)code, msg);
}
#else
static void cv_error(int code, const char *module, const char *func, char *msg, void *p) {
    Ode *o = p;
    if (code > 0) log_warning(o->comp, "%s %s (flag %d): %s", module, func, code, msg);
    else log_error(o->comp, "%s %s (flag %d): %s", module, func, code, msg);
}
#endif

Ode *ode_new(ModelInstance *comp, int n, OdeRhs rhs, int nroots, OdeRoots roots,
             void *user, OdeMethod method, double rtol, double atol) {
    Ode *o = calloc(1, sizeof *o);
    if (!o) return NULL;
    if (comp->tolerance > 0) rtol = comp->tolerance;   /* fmi2SetupExperiment's tolerance wins */
    o->comp = comp; o->n = n; o->rhs = rhs; o->nroots = nroots; o->roots = roots; o->user = user;
    if (SUNContext_Create(ARTIBUS_COMM, &o->ctx)) goto fail;
#if SUNDIALS_VERSION_MAJOR >= 7
    SUNContext_ClearErrHandlers(o->ctx);
    SUNContext_PushErrHandler(o->ctx, cv_error, o);
#endif
    o->y = N_VNew_Serial(n, o->ctx);
    if (!o->y) goto fail;
    N_VConst(0.0, o->y);
    if (method == ODE_ERK) {
        o->erk = ERKStepCreate(cv_rhs, 0.0, o->y, o->ctx);   /* ARKODE's default 4th-order table */
        if (!o->erk) goto fail;
#if SUNDIALS_VERSION_MAJOR < 7
        ERKStepSetErrHandlerFn(o->erk, cv_error, o);
#endif
        if (ERKStepSetUserData(o->erk, o) != ARK_SUCCESS) goto fail;
        if (ERKStepSStolerances(o->erk, rtol, atol) != ARK_SUCCESS) goto fail;
        ERKStepSetMaxNumSteps(o->erk, 100000);
        if (nroots > 0) {
            if (ERKStepRootInit(o->erk, nroots, cv_roots) != ARK_SUCCESS) goto fail;
            ERKStepSetNoInactiveRootWarn(o->erk);
        }
        return o;
    }
    o->mem = CVodeCreate(method == ODE_ADAMS ? CV_ADAMS : CV_BDF, o->ctx);
    if (!o->mem) goto fail;
#if SUNDIALS_VERSION_MAJOR < 7
    CVodeSetErrHandlerFn(o->mem, cv_error, o);
#endif
    if (CVodeInit(o->mem, cv_rhs, 0.0, o->y) != CV_SUCCESS) goto fail;
    if (CVodeSetUserData(o->mem, o) != CV_SUCCESS) goto fail;
    if (CVodeSStolerances(o->mem, rtol, atol) != CV_SUCCESS) goto fail;
    CVodeSetMaxNumSteps(o->mem, 100000);
    o->A = SUNDenseMatrix(n, n, o->ctx);
    o->LS = SUNLinSol_Dense(o->y, o->A, o->ctx);
    if (!o->A || !o->LS || CVodeSetLinearSolver(o->mem, o->LS, o->A) != CV_SUCCESS) goto fail;
    o->J = SUNDenseMatrix(n, n, o->ctx);
    o->ewt = N_VNew_Serial(n, o->ctx);
    if (!o->J || !o->ewt || CVodeSetJacFn(o->mem, cv_jac) != CV_SUCCESS) goto fail;
    if (nroots > 0) {
        if (CVodeRootInit(o->mem, nroots, cv_roots) != CV_SUCCESS) goto fail;
        CVodeSetNoInactiveRootWarn(o->mem);
    }
    return o;
fail:
    log_error(comp, "%s could not be set up for %d states (out of memory or bad tolerances "
                    "rtol = %g, atol = %g)", method == ODE_ERK ? "ARKODE" : "CVODE", n, rtol, atol);
    ode_free(o);
    return NULL;
}

/* A failed integration: logged with the solver's flag (name allocated by
   SUNDIALS) and the time; the history is unusable now, the next call restarts. */
static OdeResult failed(Ode *o, const char *solver, int flag, char *name, double tret, double t1) {
    log_error(o->comp, "%s failed with flag %d (%s) at t = %.17g while stepping to t = %.17g",
              solver, flag, name ? name : "?", tret, t1);
    free(name);
    o->started = false;
    return ODE_FAILED;
}

/* ODE_ERK: a one-step method has no history to rebuild when an input
   changes: it goes on from (t0, y) with its last step size. While the inputs
   were held that step may have grown far beyond what the changed dynamics
   allow (driving straight is integrated exactly: the error estimate is zero),
   so the first step after a change is at most ERK_RESTART_STEPS communication
   steps long; the error control takes it from there. Where the FMI layer asks
   to forget, it starts afresh (ARKODE's own first-step estimate). */
static OdeResult erk_advance(Ode *o, bool restart, double t0, double *y, double t1, double *t,
                             int *rootsfound) {
    double *yv = N_VGetArrayPointer(o->y);
    if (restart || !o->started) {
        const bool keep = o->started && !o->comp->forget;
        memcpy(yv, y, sizeof(double) * (size_t)o->n);
        if (keep) {
            sunrealtype hlast = 0.0;
            ERKStepGetLastStep(o->erk, &hlast);
            ERKStepSetInitStep(o->erk, fmin(fabs(hlast), ERK_RESTART_STEPS * (t1 - t0)));
            if (ERKStepReset(o->erk, t0, o->y) != ARK_SUCCESS) return ODE_FAILED;
        } else {
            ERKStepSetInitStep(o->erk, 0.0);
            if (ERKStepReInit(o->erk, cv_rhs, t0, o->y) != ARK_SUCCESS) return ODE_FAILED;
        }
        o->started = true;
    }
    sunrealtype tret = t0;
    const int flag = ERKStepEvolve(o->erk, t1, o->y, &tret, ARK_NORMAL);
    *t = tret;
    memcpy(y, yv, sizeof(double) * (size_t)o->n);
    if (flag == ARK_ROOT_RETURN) {
        ERKStepGetRootInfo(o->erk, rootsfound);
        return ODE_ROOT;
    }
    if (flag < 0) return failed(o, "ARKODE ERKStep", flag, ERKStepGetReturnFlagName(flag), tret, t1);
    return ODE_REACHED;
}

OdeResult ode_advance(Ode *o, bool restart, double t0, double *y, double t1,
                      double *t, int *rootsfound) {
    if (o->erk) return erk_advance(o, restart, t0, y, t1, t, rootsfound);
    double *yv = N_VGetArrayPointer(o->y);
    if (restart || !o->started) {
        /* An input changed (restart): y is continuous, only f jumped. The
           Jacobian kept from before serves the first Newton iteration, and
           the first step starts from a tenth of the last one (that was taken
           at order >= 2, the restart is at order 1; CVODE grows it again)
           instead of CVODE's conservative estimate, which starts ~1e-6 s.
           Where the FMI layer asks to forget (initialisation, FMU state saved
           or restored) both come from CVODE afresh, so such restarts are
           reproducible bit for bit. */
        const bool keep = o->started && !o->comp->forget;
        sunrealtype hlast = 0.0;
        if (keep) CVodeGetLastStep(o->mem, &hlast);
        memcpy(yv, y, sizeof(double) * (size_t)o->n);
        if (CVodeReInit(o->mem, t0, o->y) != CV_SUCCESS) return ODE_FAILED;
        CVodeSetInitStep(o->mem, keep ? 0.1 * hlast : 0.0);
        o->reuseJ = keep && o->haveJ;
        if (!keep) o->haveJ = false;
        o->started = true;
    }
    /* no stop time: with the inputs held, CVODE may step past t1 and
       interpolate back to it, so a long steady run costs a few internal steps
       instead of one per communication point; a changed input restarts it */
    sunrealtype tret = t0;
    int flag = CVode(o->mem, t1, o->y, &tret, CV_NORMAL);
    *t = tret;
    memcpy(y, yv, sizeof(double) * (size_t)o->n);
    if (flag == CV_ROOT_RETURN) {
        CVodeGetRootInfo(o->mem, rootsfound);
        return ODE_ROOT;
    }
    if (flag < 0) return failed(o, "CVODE", flag, CVodeGetReturnFlagName(flag), tret, t1);
    return ODE_REACHED;
}

long ode_nrhs(const Ode *o) { return o ? o->nrhs : 0; }

void ode_free(Ode *o) {
    if (!o) return;
    if (o->mem) CVodeFree(&o->mem);
    if (o->erk) ERKStepFree(&o->erk);
    if (o->LS) SUNLinSolFree(o->LS);
    if (o->A) SUNMatDestroy(o->A);
    if (o->J) SUNMatDestroy(o->J);
    if (o->ewt) N_VDestroy(o->ewt);
    if (o->y) N_VDestroy(o->y);
    if (o->ctx) SUNContext_Free(&o->ctx);
    free(o);
}

void ode_free_solver(ModelInstance *comp, Ode *o) {
    ode_free(o);
    free(comp->solver);
    comp->solver = NULL;
}
