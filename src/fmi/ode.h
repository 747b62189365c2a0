/* A small SUNDIALS (CVODE, ARKODE) wrapper shared by the models that integrate inside doStep.
 * The ODE state lives in the model's own variables: each step packs it into
 * y[], advances, and unpacks it. CVODE's messages go to the FMI logger with
 * the CVODE flag and the time. */
#ifndef ARTIBUS_ODE_H
#define ARTIBUS_ODE_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

struct ModelInstance;

/* return 0 on success, > 0 for a recoverable failure (CVODE retries with a
   smaller step; ODE_ERK cannot and fails), < 0 for an unrecoverable one */
typedef int (*OdeRhs)(double t, const double *y, double *ydot, void *user);
typedef int (*OdeRoots)(double t, const double *y, double *g, void *user);

/* ODE_BDF, ODE_ADAMS: CVODE's multistep methods, restarted at order 1 when an
   input changes; ODE_ERK: ARKODE's explicit Runge-Kutta (ERKStep, 4th order),
   a one-step method that goes on with its step size when an input changes
   (cheap in co-simulation, where the inputs change every few steps), for
   non-stiff problems only: its step is bounded by stability where BDF's is not;
   root functions are located as CVODE locates them */
typedef enum { ODE_BDF, ODE_ADAMS, ODE_ERK } OdeMethod;

typedef struct Ode Ode;

/* rtol: the model's parameter; a tolerance given in fmi2SetupExperiment replaces it */
Ode *ode_new(struct ModelInstance *comp, int n, OdeRhs rhs, int nroots, OdeRoots roots,
             void *user, OdeMethod method, double rtol, double atol);

typedef enum { ODE_REACHED = 0, ODE_ROOT = 1, ODE_FAILED = -1 } OdeResult;

/* Advance y from t0 to t1. With restart, or on the first call, the integrator
   starts again at (t0, y) at order 1, keeping its last Jacobian and step size
   as first guesses unless the FMI layer asked it to forget them
   (ModelInstance.forget: initialisation, FMU state saved or restored);
   otherwise it continues its history (y must then be
   what the last call returned): its internal steps may then run past t1, and
   y(t1) is interpolated, as the right-hand side must not change in between. On ODE_ROOT, *t is the root's
   time and rootsfound[i] != 0 for the functions that crossed zero. */
OdeResult ode_advance(Ode *o, bool restart, double t0, double *y, double t1,
                      double *t, int *rootsfound);

/* right-hand-side evaluations so far (benchmarks) */
long ode_nrhs(const Ode *o);

void ode_free(Ode *o);

/* model_free of a model that integrates in doStep: its comp->solver is one
   block from calloc (the model's Solver) that holds the integrator o. Frees o
   and the block and clears comp->solver, so that the next doStep makes both
   anew (fmi2Reset, fmi2FreeInstance, model_restored). */
void ode_free_solver(struct ModelInstance *comp, Ode *o);

#ifdef __cplusplus
}
#endif

#endif
