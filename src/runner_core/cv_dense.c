/* One dense CVODE problem (cv_dense.h). */
#include "cv_dense.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#if SUNDIALS_VERSION_MAJOR >= 7
#define CV_COMM SUN_COMM_NULL

static void cv_error(int line, const char *func, const char *file, const char *msg, SUNErrCode code, void *p,
                     SUNContext ctx) {
    (void)line, (void)file, (void)ctx;
    cv_dense *cv = p;
    if (!cv->message[0])
        snprintf(cv->message, cv->message_size, "CVODE %s (flag %d): %s", func, (int)code, msg);
}
#else
#define CV_COMM NULL

static void cv_error(int code, const char *module, const char *func, char *msg, void *p) {
    cv_dense *cv = p;
    if (code < 0 && !cv->message[0])
        snprintf(cv->message, cv->message_size, "%s %s (flag %d): %s", module, func, code, msg);
}
#endif

int cv_dense_create(cv_dense *cv, size_t n, int adams, char *message, size_t message_size) {
    memset(cv, 0, sizeof *cv);
    cv->n = n ? n : 1;
    cv->message = message;
    cv->message_size = message_size;
    if (SUNContext_Create(CV_COMM, &cv->ctx))
        return 0;
#if SUNDIALS_VERSION_MAJOR >= 7
    SUNContext_ClearErrHandlers(cv->ctx);
    SUNContext_PushErrHandler(cv->ctx, cv_error, cv);
#endif
    cv->y = N_VNew_Serial((sunindextype)cv->n, cv->ctx);
    cv->abstol = N_VNew_Serial((sunindextype)cv->n, cv->ctx);
    cv->mem = CVodeCreate(adams ? CV_ADAMS : CV_BDF, cv->ctx);
    if (!cv->y || !cv->abstol || !cv->mem)
        return 0;
    N_VConst(0.0, cv->y);
#if SUNDIALS_VERSION_MAJOR < 7
    CVodeSetErrHandlerFn(cv->mem, cv_error, cv);
#endif
    return 1;
}

int cv_dense_init(cv_dense *cv, CVRhsFn rhs, double t0, void *user, double rtol, long max_steps) {
    cv->A = SUNDenseMatrix((sunindextype)cv->n, (sunindextype)cv->n, cv->ctx);
    cv->LS = cv->A ? SUNLinSol_Dense(cv->y, cv->A, cv->ctx) : NULL;
    return CVodeInit(cv->mem, rhs, t0, cv->y) == CV_SUCCESS && CVodeSetUserData(cv->mem, user) == CV_SUCCESS
        && CVodeSVtolerances(cv->mem, rtol, cv->abstol) == CV_SUCCESS && cv->LS
        && CVodeSetLinearSolver(cv->mem, cv->LS, cv->A) == CV_SUCCESS
        && CVodeSetMaxNumSteps(cv->mem, max_steps) == CV_SUCCESS;
}

void cv_dense_abstol(cv_dense *cv, const double *nominal, size_t nx, double rtol) {
    double *a = N_VGetArrayPointer(cv->abstol);
    for (size_t i = 0; i < cv->n; i++) {
        const double m = i < nx ? fabs(nominal[i]) : 1.0;
        a[i] = rtol * (isfinite(m) && m > 0 ? m : 1.0);
    }
}

int cv_dense_restart(cv_dense *cv, double t, double rtol) {
    return CVodeReInit(cv->mem, t, cv->y) == CV_SUCCESS && CVodeSVtolerances(cv->mem, rtol, cv->abstol) == CV_SUCCESS;
}

void cv_dense_free(cv_dense *cv) {
    if (cv->mem)
        CVodeFree(&cv->mem);
    if (cv->LS)
        SUNLinSolFree(cv->LS);
    if (cv->A)
        SUNMatDestroy(cv->A);
    if (cv->y)
        N_VDestroy(cv->y);
    if (cv->abstol)
        N_VDestroy(cv->abstol);
    if (cv->ctx)
        SUNContext_Free(&cv->ctx);
    char *message = cv->message;
    const size_t size = cv->message_size;
    memset(cv, 0, sizeof *cv);
    cv->message = message, cv->message_size = size;
}
