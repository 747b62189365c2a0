/* One dense CVODE problem: what the Model Exchange facade (me.c, one FMU) and the ME group
 * (me_group.c, a bench's ME components in one integrator) both make, restart and free:
 * SUNDIALS' context with an error handler that writes CVODE's message into its owner's (where
 * the owner has said nothing yet: a right-hand side's own message comes first), the state and
 * absolute-tolerance vectors, CVODE (BDF or Adams-Moulton, Newton with a dense linear solver). */
#ifndef ARTIBUS_CV_DENSE_H
#define ARTIBUS_CV_DENSE_H

#include <stddef.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

typedef struct {
    SUNContext ctx;
    void *mem;
    N_Vector y, abstol;
    SUNMatrix A;
    SUNLinearSolver LS;
    size_t n;                   /* CVODE's states (at least 1) */
    char *message;              /* the owner's message buffer (message_size bytes) */
    size_t message_size;
} cv_dense;

/* the context, y (zero) and abstol of n entries, CVODE's memory (adams: Adams-Moulton, else
   BDF), its errors into message; 0 when out of memory (what was made: cv_dense_free) */
int cv_dense_create(cv_dense *cv, size_t n, int adams, char *message, size_t message_size);

/* CVODE from cv->y at t0: rhs with user, rtol and cv->abstol, the dense linear solver,
   max_steps internal steps a call; 0 when CVODE refuses one of them */
int cv_dense_init(cv_dense *cv, CVRhsFn rhs, double t0, void *user, double rtol, long max_steps);

/* cv->abstol = rtol |nominal[i]| (rtol where a nominal is 0 or not finite, and from nx on): as
   FMPy's CVodeSolver takes them */
void cv_dense_abstol(cv_dense *cv, const double *nominal, size_t nx, double rtol);

/* CVODE again from cv->y at t (after an event: its history is of the old equations), the
   tolerances again; 0 when refused */
int cv_dense_restart(cv_dense *cv, double t, double rtol);

/* what cv_dense_create and cv_dense_init made; cv zeroed but its message */
void cv_dense_free(cv_dense *cv);

#endif
