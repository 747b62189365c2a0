/* SteeringSensors_LSBUS: the sensors measure nothing of their own (the plant's angles are
 * their inputs) and send them at the node's Tx_Clock (model_lsbus.c): the model only keeps
 * time. */
#include "fmu.h"

Status model_check_parameters(ModelInstance *comp) { (void)comp; return OK; }

Status model_init(ModelInstance *comp) { (void)comp; return OK; }

void model_outputs(ModelInstance *comp) { (void)comp; }

Status model_do_step(ModelInstance *comp, double t, double h) {
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) { (void)comp; }

bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)d; (void)s; (void)time; (void)why; (void)n;
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
