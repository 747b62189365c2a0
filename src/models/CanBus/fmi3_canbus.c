/* The FMI 3.0 Co-Simulation interface of CanBus, the FMI-LS-BUS 1.0 CAN bus
 * simulation FMU (canbus.c does the bus). FMI 3.0 only, with its own layer: the
 * shared one (src/fmi/fmi3Functions.c) serves models declared in FMI 2.0, which
 * has no Binary and no Clock variables.
 *
 * How an importer drives it (fmi-ls-bus v1.0.0 docs/4____network_abstraction.adoc,
 * "Time-based Tx Clocks", and FMI 3.0.2, 5.2: Co-Simulation with Event Mode):
 *   - a node sends: in Event Mode, fmi3SetClock(NodeK.Rx_Clock), then
 *     fmi3SetBinary(NodeK.Rx_Data), then fmi3UpdateDiscreteStates: the bus takes
 *     the operations, arbitrates and puts a frame on the wire;
 *   - the bus has operations for node K at a time (the frame's end): its countdown
 *     NodeK.Tx_Clock reports that interval (fmi3GetIntervalDecimal, qualifier
 *     changed once per announcement, then unchanged with the same interval until
 *     the clock is set); nextEventTime only for a frame's end no Tx clock
 *     announces; the importer steps to the tick, enters Event Mode,
 *     sets NodeK.Tx_Clock and reads NodeK.Tx_Data (0 bytes when nothing is due);
 *   - interval 0 (wire time off, an answer due at once): discreteStatesNeedUpdate
 *     is true, and the importer sets the clock in the next event iteration.
 * A clock set after fmi3UpdateDiscreteStates that did not ask for another
 * iteration is an illegal call sequence: fmi3Error. Malformed operations are
 * answered with a Format Error to the node (canbus.c), malformed calls (a binary
 * above maxSize, a clocked variable set while its clock is inactive) with
 * fmi3Error; every refusal names the function, the variable and the value.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_canbus.h"

const char *const STATE_NAME[] = {"Instantiated", "Initialization Mode", "Event Mode",
                                  "Step Mode", "Terminated", "Error"};

void canbus_logf(Instance *c, fmi3Status s, const char *cat, const char *fmt, ...) {
    if (!c->logMessage || (s == fmi3OK && !c->logEvents)) return;
    char text[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    c->logMessage(c->env, s, cat, text);
}

static void bus_log(void *ctx, int level, const char *text) {
    Instance *c = ctx;
    if (level == 0) canbus_logf(c, fmi3OK, "logEvents", "%s", text);
    else canbus_logf(c, fmi3Warning, "logStatusWarning", "%s", text);
}

static void start_values(Instance *c) {
    /* the start values of modelDescription/fmi3/CanBus.xml (canbus_vars.h) */
    c->p.baudrate = START_baudrate;
    c->p.wireTime = START_wireTime;
    c->p.arbitrationLostBehavior = START_arbitrationLostBehavior;
    c->p.nNodes = START_nNodes;
    c->p.faultStart = START_faultStart;
    c->p.faultSilentNode = START_faultSilentNode;
    c->p.faultCorruptId = START_faultCorruptId;
    c->p.faultBusOffNode = START_faultBusOffNode;
    c->time = 0;
    canbus_init(&c->bus, &c->p, 0, bus_log, c);
    c->bus.logEvents = &c->logEvents;
}

/* the announcements of the Tx clocks (canbus_due); true if one is due now */
static bool announce(Instance *c) {
    bool now = false;
    for (int k = 0; k < CANBUS_NODES; k++) {
        const double due = canbus_due(&c->bus, k, c->time, c->txRead[k]);
        if (!isfinite(due) || due == c->announced[k]) continue;
        c->announced[k] = due;
        c->changed[k] = true;
        if (due <= c->time + CANBUS_TIME_EPS) now = true;
    }
    return now;
}

/* the bus's next time event (a frame's end) if no Tx clock announces it, else INFINITY: FMI
   3.0.2, 2.3, Event Mode, time events are announced "through the argument nextEventTime of
   fmi3UpdateDiscreteStates, or the arguments of fmi3GetShift and fmi3GetInterval". A frame's end
   is its sender's and receivers' countdown tick: said once, there (an importer that cuts its step
   at nextEventTime and counts an unchanged interval down by that cut step, as fmu-manipulation-
   toolbox 2.0's container does, would lose the clock); a frame's end no Tx clock announces (none
   due by then) is a nextEventTime */
#ifndef CANBUS_TRIGGERED_TX
static double unannounced_event(const Instance *c) {
    const double next = canbus_next_event(&c->bus);
    for (int k = 0; k < CANBUS_NODES; k++)
        if (c->announced[k] <= next + CANBUS_TIME_EPS) return INFINITY;
    return next;
}
#endif

#ifdef CANBUS_TRIGGERED_TX
/* triggered form, in fmi3UpdateDiscreteStates: what NodeK.Tx_Data held while its clock was active
   is gone (read or not: a clocked output is a value of its activation), the active clocks end (FMI
   3.0.2, 2.3: "Any Clock active during fmi3UpdateDiscreteStates must be deactivated by the FMU
   itself"), and a node with operations now gets its Tx_Clock activated for the next super-dense
   instant, which discreteStatesNeedUpdate asks for: the importer reads fmi3GetClock and Tx_Data
   there (2.3, fmi3GetClock: "it might be necessary to call this function several times").
   Returns true if a clock was activated */
static bool activate_triggered(Instance *c) {
    bool any = false;
    for (int k = 0; k < CANBUS_NODES; k++) {
        if (c->txActive[k]) canbus_consume(&c->bus, k, c->shown[k]);
        c->txActive[k] = false;
        c->shown[k] = c->txRead[k] = 0;
        if (canbus_due(&c->bus, k, c->time, 0) <= c->time + CANBUS_TIME_EPS) {
            c->txActive[k] = any = true;
            c->shown[k] = c->bus.node[k].nOut;
        }
    }
    return any;
}
#endif

/* the operations of the nodes whose Rx clock ticked, in node order */
static void take_inputs(Instance *c) {
    for (int k = 0; k < CANBUS_NODES; k++) {
        if (c->rxActive[k] && c->rxSize[k] > 0) canbus_receive(&c->bus, k, c->rx[k], c->rxSize[k], c->time);
        c->rxActive[k] = false;
        c->rxSize[k] = 0;
    }
}

/* what the nodes read of their Tx_Data is gone */
static void consume_read(Instance *c) {
    for (int k = 0; k < CANBUS_NODES; k++) {
        canbus_consume(&c->bus, k, c->txRead[k]);
        c->txRead[k] = 0;
    }
}

/* ---- inquiry, logging, life cycle ------------------------------------------------ */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    ENTER("fmi3SetDebugLogging", ANY);
    (void)nCategories; (void)categories;
    c->logEvents = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback logMessage) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    if (logMessage) logMessage(env, fmi3Error, "logStatusError",
                               "fmi3InstantiateModelExchange: CanBus is a Co-Simulation FMU only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage) logMessage(env, fmi3Error, "logStatusError",
                               "fmi3InstantiateScheduledExecution: CanBus is a Co-Simulation FMU only");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath; (void)visible; (void)earlyReturnAllowed; (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    const char *why = NULL;
    if (!instantiationToken || strcmp(instantiationToken, TOKEN) != 0)
        why = "fmi3InstantiateCoSimulation: instantiationToken is not this FMU's " TOKEN;
    else if (nRequiredIntermediateVariables > 0)
        why = "fmi3InstantiateCoSimulation: CanBus provides no intermediate update";
    if (why) {
        if (logMessage) logMessage(env, fmi3Error, "logStatusError", why);
        return NULL;
    }
    Instance *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->name = strdup(instanceName ? instanceName : "CanBus");
    c->env = env;
    c->logMessage = logMessage;
    c->logEvents = loggingOn;
    c->eventModeUsed = eventModeUsed;
    /* without Event Mode no clock can tick (FMI 3.0.2, 4.2.1): the bus carries no frame. It still
       runs, idle (busLoad 0), so that a plain importer (fmpy simulate) steps it; said once */
    if (!eventModeUsed && logMessage)
        logMessage(env, fmi3Warning, "logStatusWarning",
                   "fmi3InstantiateCoSimulation: eventModeUsed = false: CanBus exchanges its frames through "
                   "clocks, which need Event Mode (fmi-ls-bus 2____common_concepts.adoc: hasEventMode); "
                   "without it the bus stays idle and carries no frame");
    start_values(c);
    for (int k = 0; k < CANBUS_NODES; k++) c->announced[k] = INFINITY;
    return c;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = instance;
    if (!c) return;
    free(c->name);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    ENTER("fmi3EnterInitializationMode", S(INSTANTIATED));
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!isfinite(startTime)) return FAIL("fmi3EnterInitializationMode: startTime = %g", startTime);
    c->time = startTime;
    c->state = INIT_MODE;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    ENTER("fmi3ExitInitializationMode", S(INIT_MODE));
    canbus_init(&c->bus, &c->p, c->time, bus_log, c);
    c->bus.logEvents = &c->logEvents;
    c->state = c->eventModeUsed ? EVENT_MODE : STEP_MODE;   /* FMI 3.0.2, 4.2.1 */
    c->updated = c->needUpdate = false;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER("fmi3EnterEventMode", S(STEP_MODE));
    if (!c->eventModeUsed)
        return FAIL("fmi3EnterEventMode: instantiated with eventModeUsed = false (FMI 3.0.2, 4.2.1)");
    c->state = EVENT_MODE;
    c->updated = c->needUpdate = false;
    canbus_advance(&c->bus, c->time);
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ENTER("fmi3Terminate", S(EVENT_MODE) | S(STEP_MODE));
    c->state = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    ENTER("fmi3Reset", ANY);
    memset(c->rxActive, 0, sizeof c->rxActive);
    memset(c->txActive, 0, sizeof c->txActive);
    memset(c->rxSize, 0, sizeof c->rxSize);
    memset(c->txRead, 0, sizeof c->txRead);
    memset(c->changed, 0, sizeof c->changed);
    for (int k = 0; k < CANBUS_NODES; k++) c->announced[k] = INFINITY;
    start_values(c);
    c->state = INSTANTIATED;
    return fmi3OK;
}

/* ---- event mode and stepping ------------------------------------------------------ */

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    ENTER("fmi3UpdateDiscreteStates", S(EVENT_MODE));
    take_inputs(c);
#ifdef CANBUS_TRIGGERED_TX
    canbus_advance(&c->bus, c->time);
    c->needUpdate = activate_triggered(c);
    c->updated = true;
    const double next = canbus_next_event(&c->bus);      /* the frame's end: no countdown says it */
#else
    consume_read(c);
    canbus_advance(&c->bus, c->time);
    c->needUpdate = announce(c);
    c->updated = true;
    const double next = unannounced_event(c);
#endif
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = c->needUpdate;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = isfinite(next) && next > c->time;
    if (nextEventTime) *nextEventTime = isfinite(next) ? next : 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER("fmi3EnterStepMode", S(EVENT_MODE));
    take_inputs(c);                       /* set without fmi3UpdateDiscreteStates: not lost */
#ifdef CANBUS_TRIGGERED_TX
    for (int k = 0; k < CANBUS_NODES; k++)
        if (c->txActive[k]) c->txRead[k] = c->shown[k];
#endif
    consume_read(c);
    canbus_advance(&c->bus, c->time);
    memset(c->txActive, 0, sizeof c->txActive);
    c->state = STEP_MODE;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    ENTER("fmi3DoStep", S(STEP_MODE));
    (void)noSetFMUStatePriorToCurrentPoint;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    if (!(fabs(t - c->time) <= 1e-9 * fmax(1.0, fabs(c->time))))
        return FAIL("fmi3DoStep: currentCommunicationPoint = %.17g, but the FMU is at %.17g", t, c->time);
    if (!(h >= 0) || !isfinite(h)) return FAIL("fmi3DoStep: communicationStepSize = %g", h);
    c->time = t + h;
    canbus_advance(&c->bus, c->time);
    bool due = false;
    for (int k = 0; k < CANBUS_NODES; k++)
        if (canbus_due(&c->bus, k, c->time, c->txRead[k]) <= c->time + CANBUS_TIME_EPS) due = true;
    if (eventHandlingNeeded) *eventHandlingNeeded = due && c->eventModeUsed;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = c->time;
    return fmi3OK;
}

/* ---- clocks ------------------------------------------------------------------------- */

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    ENTER("fmi3SetClock", S(EVENT_MODE));
    if (nvr > 0 && (!vr || !values)) return FAIL("fmi3SetClock: NULL arguments");
    for (size_t i = 0; i < nvr; i++) {
        const int rx = node_of(vr[i], VR_NODE_RX_CLOCK), tx = node_of(vr[i], VR_NODE_TX_CLOCK);
        if (rx < 0 && tx < 0) return FAIL("fmi3SetClock: value reference %u is no clock of CanBus", vr[i]);
        const int k = rx >= 0 ? rx : tx;
#ifdef CANBUS_TRIGGERED_TX
        if (tx >= 0)
            return FAIL("fmi3SetClock: Node%d.Tx_Clock is an output clock of this form of CanBus (triggered: "
                        "read it with fmi3GetClock, FMI 3.0.2, 2.2.9)", k + 1);
#endif
        /* NodeK.Rx_Clock is triggered: it may be active for more than one fmi3UpdateDiscreteStates
           of an Event Mode (FMI 3.0.2, 2.3, fmi3SetClock: the restriction to one update "does not
           apply to triggered Clocks"): set after an update, it begins a new super-dense instant */
        if (values[i] && rx >= 0) c->updated = false;
        /* a Tx clock announced due now (interval 0) may be set after an update that asked for
           no further iteration: it begins a new super-dense instant of this Event Mode (FMI
           3.0.2, 2.2.9, "Countdown aperiodic Clock": T_interval >= 0; 2.3, Event Mode,
           fmi3SetClock: "No further constraints are imposed on the activation of time-based
           Clocks", aperiodic clocks with interval 0 may be active for more than one update) */
        if (values[i] && tx >= 0 && c->updated && !c->needUpdate && c->announced[k] <= c->time + CANBUS_TIME_EPS) {
            c->updated = false;
        }
        if (values[i] && c->updated && !c->needUpdate)
            return FAIL("fmi3SetClock: Node%d.%s set after fmi3UpdateDiscreteStates, which asked for no "
                        "further event iteration: illegal call sequence (FMI 3.0.2, 5.2.2: clocks, then "
                        "inputs, then fmi3UpdateDiscreteStates)", k + 1, rx >= 0 ? "Rx_Clock" : "Tx_Clock");
        if (rx >= 0) {
            c->rxActive[k] = values[i];
            if (!values[i]) c->rxSize[k] = 0;
        } else {
            c->txActive[k] = values[i];
            if (values[i]) {
                c->announced[k] = INFINITY;
                c->changed[k] = false;
            }
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
#ifdef CANBUS_TRIGGERED_TX
    ENTER("fmi3GetClock", S(EVENT_MODE));
    if (nvr > 0 && (!vr || !values)) return FAIL("fmi3GetClock: NULL arguments");
    for (size_t i = 0; i < nvr; i++) {
        const int k = node_of(vr[i], VR_NODE_TX_CLOCK);
        if (k < 0) return FAIL("fmi3GetClock: value reference %u is no output clock of CanBus (the NodeK.Tx_Clock)", vr[i]);
        values[i] = c->txActive[k];
    }
    return fmi3OK;
#else
    ENTER("fmi3GetClock", ANY);
    (void)values;
    return FAIL("fmi3GetClock: CanBus has no output clocks (value reference %u: its clocks are inputs, "
                "the Tx clocks countdown: fmi3GetIntervalDecimal)", nvr > 0 && vr ? vr[0] : 0u);
#endif
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    ENTER("fmi3GetIntervalDecimal", S(INIT_MODE) | S(EVENT_MODE) | S(STEP_MODE));
#ifdef CANBUS_TRIGGERED_TX
    (void)intervals; (void)qualifiers;
    return FAIL("fmi3GetIntervalDecimal: value reference %u: this form of CanBus has no countdown clock (its "
                "NodeK.Tx_Clock is triggered, an output: fmi3GetClock)", nvr > 0 && vr ? vr[0] : 0u);
#endif
    if (nvr > 0 && (!vr || !intervals || !qualifiers)) return FAIL("fmi3GetIntervalDecimal: NULL arguments");
    if (c->state != INIT_MODE) announce(c);
    for (size_t i = 0; i < nvr; i++) {
        const int k = node_of(vr[i], VR_NODE_TX_CLOCK);
        if (k < 0)
            return FAIL("fmi3GetIntervalDecimal: value reference %u is no countdown clock of CanBus (the "
                        "NodeK.Tx_Clock; NodeK.Rx_Clock is triggered)", vr[i]);
        /* FMI 3.0.2, 2.2.9, fmi3GetIntervalDecimal: fmi3IntervalChanged gives the interval relative
           to the current Event Mode; fmi3IntervalUnchanged "returns the unchanged interval value
           provided in a previous call" (the same number, relative to the Event Mode it was given
           in, not the time left); fmi3IntervalNotYetKnown only until an interval is known after
           the clock's last activation (fmi3SetClock consumes the announcement) */
        if (c->changed[k]) {
            qualifiers[i] = fmi3IntervalChanged;
            intervals[i] = c->given[k] = fmax(0.0, c->announced[k] - c->time);
            c->changed[k] = false;
        } else if (isfinite(c->announced[k])) {
            qualifiers[i] = fmi3IntervalUnchanged;
            intervals[i] = c->given[k];
        } else {
            qualifiers[i] = fmi3IntervalNotYetKnown;
            intervals[i] = 0.0;
        }
    }
    return fmi3OK;
}
