/* What fmi2Functions.c and fmi3Functions.c share (fmu_core.c): the call-order
 * gate, variables through the generated table, the FMU state, stepping and the
 * Model Exchange functions, all on the neutral Status and ModelInstance of
 * fmu.h. Each function takes the name of the API function it serves (fn), so
 * that every message names the call the importer made. A function that ends in
 * Error moves the instance to the error state (leave). Internal to the layers:
 * a model includes fmu.h only.
 *
 * A layer supplies the three functions below the line: where its callbacks
 * differ (FMI 2.0: the importer's logger and memory functions; FMI 3.0: a
 * logger, memory from the C library).
 */
#ifndef ARTIBUS_FMU_CORE_H
#define ARTIBUS_FMU_CORE_H

#include <stddef.h>
#include "fmu.h"

/* every state but fatal */
#define ANY_BUT_FATAL (S_INSTANTIATED | S_INIT_MODE | S_STEP_COMPLETE | S_STEP_FAILED | \
                       S_TERMINATED | S_ERROR | S_EVENT_MODE | S_CONT_TIME_MODE)

extern const char *const LOG_CATEGORY[LOG_NCATEGORIES];

const char *state_name(InstanceState s);

/* the call-order gate: true if comp->v.state is in mask; else logged */
bool core_allowed(ModelInstance *comp, int mask, const char *fn);
/* the status a function returns; an error moves the instance to S_ERROR */
Status core_leave(ModelInstance *comp, Status status);

/* a new instance, allocated (zeroed) by the layer, its callbacks and type set:
   its name copied, the instantiation token (FMI 2.0: GUID) checked, its
   resources' path decoded from resourceLocation (isUri: a file: URI, FMI 2.0;
   else a plain path, FMI 3.0), its variables at their start values. On Error
   (logged) the layer frees comp. */
Status core_init_instance(ModelInstance *comp, const char *fn, const char *instanceName,
                          const char *token, const char *resourceLocation, bool isUri);
void core_free_instance(ModelInstance *comp);
Status core_reset(ModelInstance *comp);
Status core_setup_experiment(ModelInstance *comp, const char *fn, bool toleranceDefined,
                             double tolerance, double startTime, bool stopTimeDefined, double stopTime);
Status core_exit_init(ModelInstance *comp, const char *fn);
Status core_set_debug_logging(ModelInstance *comp, const char *fn, bool on, size_t n,
                              const char *const categories[]);

/* variables: look-up (fn for the message), the lazy outputs, and one value */
const VarInfo *core_lookup(ModelInstance *comp, const char *fn, VarType type, unsigned vr);
Status core_refresh(ModelInstance *comp);
void *core_field(ModelInstance *comp, const VarInfo *v);
/* checks that v may be set now, then that x is finite and in range */
Status core_settable(ModelInstance *comp, const char *fn, const VarInfo *v);
Status core_check_range(ModelInstance *comp, const char *fn, const VarInfo *v, double x);
void core_changed(ModelInstance *comp);

/* the instance's values changed (a set, a restored state, a new mode, the time, the
   states): its outputs are recalculated before the next get (dirty), and a model's
   cache of a derived quantity keyed on the generation is stale */
void core_dirty(ModelInstance *comp);
Status core_set_string(ModelInstance *comp, const char *fn, const VarInfo *v, const char *value);

/* FMU state: an opaque block the layer hands out */
Status core_get_state(ModelInstance *comp, const char *fn, void **state);
Status core_set_state(ModelInstance *comp, const char *fn, const void *state);
Status core_free_state(ModelInstance *comp, void **state);
Status core_state_size(ModelInstance *comp, const char *fn, const void *state, size_t *size);
Status core_serialize(ModelInstance *comp, const char *fn, const void *state,
                      unsigned char bytes[], size_t size);
Status core_deserialize(ModelInstance *comp, const char *fn, const unsigned char bytes[],
                        size_t size, void **state);

/* a communication step from t by h (checked against the instance's time and
   the stop time); the outputs computed and checked after it */
Status core_do_step(ModelInstance *comp, const char *fn, double t, double h);

/* Model Exchange (only where MODEL_NX is defined) */
#ifdef MODEL_NX
Status core_event_update(ModelInstance *comp, const char *fn, bool *terminate, double *tNext);
Status core_set_time(ModelInstance *comp, const char *fn, double time);
Status core_set_x(ModelInstance *comp, const char *fn, const double x[], size_t nx);
Status core_get_x(ModelInstance *comp, const char *fn, double x[], size_t nx);
Status core_derivatives(ModelInstance *comp, const char *fn, double dx[], size_t nx);
Status core_event_indicators(ModelInstance *comp, const char *fn, double z[], size_t nz);
Status core_nominals(ModelInstance *comp, const char *fn, double x[], size_t nx);
#endif

/* directional derivatives (fmu.h: models with MODEL_DIRECTIONAL_DERIVATIVE):
   sensitivity = J seed (directional) or J^T seed (adjoint: one forward pass
   per known), J = d unknowns / d knowns; the value references checked */
#ifdef MODEL_DIRECTIONAL_DERIVATIVE
Status core_directional_derivative(ModelInstance *comp, const char *fn, const unsigned unknowns[],
                                   size_t nUnknowns, const unsigned knowns[], size_t nKnowns,
                                   const double seed[], double sensitivity[]);
Status core_adjoint_derivative(ModelInstance *comp, const char *fn, const unsigned unknowns[],
                               size_t nUnknowns, const unsigned knowns[], size_t nKnowns,
                               const double seed[], double sensitivity[]);
#endif

/* ---- supplied by the layer ------------------------------------------------ */

/* pass one message (plain text, already formatted) to the importer's logger */
void layer_log(ModelInstance *comp, Status status, LogCategory cat, const char *text);
/* zeroed memory; free */
void *layer_calloc(ModelInstance *comp, size_t n, size_t size);
void layer_free(ModelInstance *comp, void *p);

#endif
