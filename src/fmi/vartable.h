/* The variable table of a model, generated from its modelDescription.xml by
 * gen_vars.py: value reference -> field of ModelData, type, causality,
 * variability and range. The shared FMI layer reads and writes variables only
 * through this table. */
#ifndef VARTABLE_H
#define VARTABLE_H

#include <stddef.h>
#include "model_vars.h"

#ifdef __cplusplus
extern "C" {
#endif

/* T_ENUMERATION: an Enumeration in the FMI 3.0 build (Int64 there); the FMI 2.0
   build reads and writes it as an Integer (T_INTEGER) */
typedef enum { T_REAL, T_INTEGER, T_BOOLEAN, T_STRING, T_ENUMERATION } VarType;

typedef enum {
    C_PARAMETER, C_CALCULATEDPARAMETER, C_INPUT, C_OUTPUT, C_LOCAL, C_INDEPENDENT
} Causality;

typedef enum {
    V_CONSTANT, V_FIXED, V_TUNABLE, V_DISCRETE, V_CONTINUOUS
} Variability;

typedef struct {
    const char *name;
    unsigned vr;
    VarType type;
    Causality causality;
    Variability variability;
    size_t offset;          /* byte offset of the value in ModelData */
    double min, max;        /* -INFINITY / INFINITY where the XML gives none */
} VarInfo;

extern const VarInfo VARS[MODEL_NVARS];

/* the Real outputs (causality output), in the order of VARS, ended by NULL */
extern const VarInfo *const REAL_OUTPUTS[];

/* the variable with this type and value reference, or NULL */
const VarInfo *vars_find(VarType type, unsigned vr);

/* all variables to their start values (the rest to zero) */
void vars_set_start_values(ModelData *d);

#ifdef MODEL_NX
/* Model Exchange: the continuous states' names and nominal values, in the
   order of <Derivatives> in the model description */
extern const char *const X_NAME[MODEL_NX];
extern const double X_NOMINAL[MODEL_NX];
#endif

#ifdef __cplusplus
}
#endif

#endif
