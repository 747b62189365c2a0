/* The instance of CanBus's FMI 3.0 layer, shared by fmi3_canbus.c (life cycle,
 * event mode, clocks) and fmi3_canbus_vars.c (variables, the functions it does not
 * provide). Internal to the FMU. */
#ifndef ARTIBUS_FMI3_CANBUS_H
#define ARTIBUS_FMI3_CANBUS_H

#include <stdbool.h>

#include "fmi3Functions.h"
#include "canbus.h"
#include "canbus_vars.h"

#if CANBUS_NODES_DECLARED != CANBUS_NODES
#error "modelDescription/fmi3/CanBus.xml declares another number of nodes than canbus.h"
#endif

/* CANBUS_TRIGGERED_TX: the form with NodeK.Tx_Clock a triggered output clock (FMI 3.0.2, 2.2.9,
   "Triggered output Clock"; fmi-ls-bus 4____network_abstraction.adoc, "Triggered Tx Clocks"),
   fmus/fmi3/lsbus-triggered/CanBus_Triggered.fmu, for importers that deliver no countdown-clocked
   variable (fmu-manipulation-toolbox 2.0's container); its model description is written from
   CanBus.xml by gen_canbus.py triggered, with this token */
#ifdef CANBUS_TRIGGERED_TX
#define TOKEN "{a3c1b2d4-24ca-4b05-9f3e-ca7b05b1e025}"
#else
#define TOKEN "{a3c1b2d4-24ca-4b05-9f3e-ca7b05b1e024}"
#endif

typedef enum { INSTANTIATED, INIT_MODE, EVENT_MODE, STEP_MODE, TERMINATED, FAILED } State;
extern const char *const STATE_NAME[];

typedef struct {
    State state;
    double time;
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logMessage;
    bool logEvents;
    CanBusParams p;
    CanBus bus;
    bool rxActive[CANBUS_NODES], txActive[CANBUS_NODES];
    uint8_t rx[CANBUS_NODES][CANBUS_OUTBOX];   /* NodeK.Rx_Data as set */
    size_t rxSize[CANBUS_NODES];
    size_t txRead[CANBUS_NODES];               /* bytes of NodeK.Tx_Data handed out */
    size_t shown[CANBUS_NODES];                /* triggered form: the bytes NodeK.Tx_Data holds while active */
    double announced[CANBUS_NODES];            /* the tick of NodeK.Tx_Clock announced, or INFINITY */
    bool changed[CANBUS_NODES];                /* announced but not yet reported */
    double given[CANBUS_NODES];                /* the interval last reported (fmi3IntervalChanged) */
    bool updated, needUpdate;                  /* fmi3UpdateDiscreteStates in this Event Mode */
    bool eventModeUsed;                        /* false: an idle bus (no clock can tick) */
} Instance;

void canbus_logf(Instance *c, fmi3Status s, const char *cat, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* an error: logged, the instance in the error state */
#define FAIL(...) (canbus_logf(c, fmi3Error, "logStatusError", __VA_ARGS__), c->state = FAILED, fmi3Error)

#define ENTER(fn, mask)                                                                  \
    Instance *c = (Instance *)instance;                                                  \
    if (!c) return fmi3Error;                                                            \
    if (!((1 << c->state) & (mask)))                                                     \
        return FAIL("%s: illegal call sequence (the instance is in %s)", fn, STATE_NAME[c->state])
#define S(x) (1 << (x))
#define ANY (S(INSTANTIATED) | S(INIT_MODE) | S(EVENT_MODE) | S(STEP_MODE) | S(TERMINATED) | S(FAILED))

/* node k (0-based) and member of a value reference, or -1 */
static inline int node_of(fmi3ValueReference vr, unsigned member) {
    const unsigned k = vr / VR_NODE_STRIDE;
    if (k < 1 || k > CANBUS_NODES || vr % VR_NODE_STRIDE != member) return -1;
    return (int)k - 1;
}

#endif
