/* TypesTest: every output a plain function of the input of its type, so a
 * test knows each value exactly; count is the only state. No physics. */
#include <stdio.h>
#include <string.h>

#include "fmu.h"

/* string_out = prefix + string_in must fit the layer's string buffer */
static Status check(ModelInstance *comp) {
    if (strlen(D->prefix) + strlen(D->string_in) >= ARTIBUS_STRLEN)
        return log_error(comp, "prefix + string_in is %zu bytes, longer than string_out's %d",
                         strlen(D->prefix) + strlen(D->string_in), ARTIBUS_STRLEN - 1);
    return OK;
}

Status model_check_parameters(ModelInstance *comp) {
    return check(comp);
}

Status model_init(ModelInstance *comp) {
    comp->v.s.steps = 0;
    return model_check_parameters(comp);
}

void model_outputs(ModelInstance *comp) {
    D->real_out = D->factor * D->real_in;
    D->int_out = D->int_in + D->offset;
    D->bool_out = (D->bool_in != 0) != (D->invert != 0);
    /* prefix, then as much of string_in as fits (all of it: model_init and
       model_do_step refuse a pair that does not fit) */
    const size_t np = strlen(D->prefix), room = sizeof D->string_out - 1 - np;
    memcpy(D->string_out, D->prefix, np);
    const size_t ns = strlen(D->string_in) < room ? strlen(D->string_in) : room;
    memcpy(D->string_out + np, D->string_in, ns);
    D->string_out[np + ns] = '\0';
    D->enum_out = D->enum_in;
    D->count = comp->v.s.steps;
}

Status model_do_step(ModelInstance *comp, double t, double h) {
    if (check(comp) != OK) return Error;
    comp->v.s.steps++;
    comp->v.time = t + h;
    return OK;
}

void model_free(ModelInstance *comp) {
    (void)comp;
}

/* FMU state: the step count, and every String ends inside its buffer */
bool model_state_valid(const ModelData *d, const ModelState *s, double time, char *why, size_t n) {
    (void)time;
    if (s->steps < 0) {
        snprintf(why, n, "steps = %d", s->steps);
        return false;
    }
    if (!memchr(d->prefix, 0, sizeof d->prefix) || !memchr(d->string_in, 0, sizeof d->string_in)
        || !memchr(d->string_out, 0, sizeof d->string_out)) {
        snprintf(why, n, "a String does not end inside its %d bytes", ARTIBUS_STRLEN);
        return false;
    }
    return true;
}

Status model_restored(ModelInstance *comp) { (void)comp; return OK; }
