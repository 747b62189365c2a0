/* CanBus's variables through the FMI 3.0 get/set functions, and the functions
 * of FMI 3.0 it does not provide (each answers fmi3Error with a message naming
 * the capability flag of its model description that says so).
 * The variables (modelDescription/fmi3/CanBus.xml): the parameters (fixed:
 * set in Instantiated and Initialization Mode only, checked against their
 * declared min/max), the outputs, and per node the Binary Rx_Data (set in Event
 * Mode while its Rx_Clock is active, at most maxSize = CANBUS_OUTBOX bytes) and
 * Tx_Data (the bus's operations for the node while its Tx_Clock is active, else
 * 0 bytes: fmi-ls-bus 4____network_abstraction.adoc, Tx/Rx Data Variables). */
#include <math.h>
#include <string.h>

#include "fmi3_canbus.h"

#define SETTABLE (S(INSTANTIATED) | S(INIT_MODE))
#define READABLE (S(INIT_MODE) | S(EVENT_MODE) | S(STEP_MODE) | S(TERMINATED) | S(FAILED))

static fmi3Status set_param_state(Instance *c, const char *fn, const char *name) {
    if ((1 << c->state) & SETTABLE) return fmi3OK;
    return FAIL("%s: %s is a fixed parameter: set it before fmi3ExitInitializationMode (the instance is "
                "in %s)", fn, name, STATE_NAME[c->state]);
}

#define REQUIRE(p, n) \
    if ((n) > 0 && !(p)) return FAIL("%s: NULL argument %s", fn, #p)

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    static const char fn[] = "fmi3GetFloat64";
    ENTER(fn, READABLE);
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case VR_time: values[i] = c->time; break;
        case VR_faultStart: values[i] = c->p.faultStart; break;
        case VR_busLoad: values[i] = c->state == INIT_MODE ? 0.0 : canbus_load(&c->bus, c->time); break;
        default: return FAIL("%s: value reference %u is no Float64 of CanBus", fn, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    static const char fn[] = "fmi3SetFloat64";
    ENTER(fn, SETTABLE | S(EVENT_MODE) | S(STEP_MODE));
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] != VR_faultStart) return FAIL("%s: value reference %u is no Float64 parameter of CanBus", fn, vr[i]);
        if (set_param_state(c, fn, "faultStart") != fmi3OK) return fmi3Error;
        if (!isfinite(values[i])) return FAIL("%s: faultStart = %g is not finite", fn, values[i]);
        c->p.faultStart = values[i];
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues) {
    static const char fn[] = "fmi3GetInt32";
    ENTER(fn, READABLE);
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case VR_baudrate: values[i] = (fmi3Int32)c->p.baudrate; break;
        case VR_arbitrationLostBehavior: values[i] = c->p.arbitrationLostBehavior; break;
        case VR_nNodes: values[i] = c->p.nNodes; break;
        case VR_faultSilentNode: values[i] = c->p.faultSilentNode; break;
        case VR_faultCorruptId: values[i] = (fmi3Int32)c->p.faultCorruptId; break;
        case VR_faultBusOffNode: values[i] = c->p.faultBusOffNode; break;
        case VR_nFrames: values[i] = c->bus.nFrames; break;
        case VR_nBusErrors: values[i] = c->bus.nBusErrors; break;
        case VR_nArbitrationLost: values[i] = c->bus.nArbitrationLost; break;
        default: return FAIL("%s: value reference %u is no Int32 of CanBus", fn, vr[i]);
        }
    }
    return fmi3OK;
}

/* an Int32 parameter: its name, its field, its declared range */
static fmi3Status set_int(Instance *c, const char *fn, const char *name, long lo, long hi, fmi3Int32 x) {
    if (set_param_state(c, fn, name) != fmi3OK) return fmi3Error;
    if (x < lo || x > hi) return FAIL("%s: %s = %d is outside its range [%ld, %ld]", fn, name, (int)x, lo, hi);
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues) {
    static const char fn[] = "fmi3SetInt32";
    ENTER(fn, SETTABLE | S(EVENT_MODE) | S(STEP_MODE));
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        const fmi3Int32 x = values[i];
        switch (vr[i]) {
        case VR_baudrate:
            if (set_int(c, fn, "baudrate", MIN_baudrate, MAX_baudrate, x)) return fmi3Error;
            c->p.baudrate = x;
            break;
        case VR_arbitrationLostBehavior:
            if (set_int(c, fn, "arbitrationLostBehavior", MIN_arbitrationLostBehavior,
                        MAX_arbitrationLostBehavior, x)) return fmi3Error;
            c->p.arbitrationLostBehavior = x;
            break;
        case VR_nNodes:
            if (set_int(c, fn, "nNodes", MIN_nNodes, MAX_nNodes, x)) return fmi3Error;
            c->p.nNodes = x;
            break;
        case VR_faultSilentNode:
            if (set_int(c, fn, "faultSilentNode", MIN_faultSilentNode, MAX_faultSilentNode, x)) return fmi3Error;
            c->p.faultSilentNode = x;
            break;
        case VR_faultCorruptId:
            if (set_int(c, fn, "faultCorruptId", MIN_faultCorruptId, MAX_faultCorruptId, x)) return fmi3Error;
            c->p.faultCorruptId = x;
            break;
        case VR_faultBusOffNode:
            if (set_int(c, fn, "faultBusOffNode", MIN_faultBusOffNode, MAX_faultBusOffNode, x)) return fmi3Error;
            c->p.faultBusOffNode = x;
            break;
        default: return FAIL("%s: value reference %u is no Int32 parameter of CanBus", fn, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues) {
    static const char fn[] = "fmi3GetBoolean";
    ENTER(fn, READABLE);
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == VR_wireTime) values[i] = c->p.wireTime;
        else if (node_of(vr[i], VR_NODE_BUSNOTIFICATIONS) >= 0) values[i] = fmi3True;   /* constant */
        else return FAIL("%s: value reference %u is no Boolean of CanBus", fn, vr[i]);
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    static const char fn[] = "fmi3SetBoolean";
    ENTER(fn, SETTABLE | S(EVENT_MODE) | S(STEP_MODE));
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] != VR_wireTime)
            return FAIL("%s: value reference %u is no Boolean parameter of CanBus (NodeK.BusNotifications "
                        "is a constant output)", fn, vr[i]);
        if (set_param_state(c, fn, "wireTime") != fmi3OK) return fmi3Error;
        c->p.wireTime = values[i];
    }
    return fmi3OK;
}

static const fmi3Byte EMPTY[1] = {0};

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    static const char fn[] = "fmi3GetBinary";
    ENTER(fn, READABLE);
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    REQUIRE(valueSizes, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    if (c->state == EVENT_MODE) canbus_advance(&c->bus, c->time);
    for (size_t i = 0; i < nvr; i++) {
        const int tx = node_of(vr[i], VR_NODE_TX_DATA), rx = node_of(vr[i], VR_NODE_RX_DATA);
        if (tx >= 0) {
            /* the operations for the node while its clock ticks; the pointer is
               valid until the next call of this instance (FMI 3.0.2, 2.2.6.1) */
            const bool ticks = c->state == EVENT_MODE && c->txActive[tx];
            valueSizes[i] = ticks ? c->bus.node[tx].nOut : 0;
            values[i] = ticks ? c->bus.node[tx].out : EMPTY;
            if (ticks) c->txRead[tx] = c->bus.node[tx].nOut;
        } else if (rx >= 0) {
            valueSizes[i] = c->rxSize[rx];
            values[i] = c->rx[rx];
        } else {
            return FAIL("%s: value reference %u is no Binary of CanBus", fn, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    static const char fn[] = "fmi3SetBinary";
    ENTER(fn, SETTABLE | S(EVENT_MODE));
    REQUIRE(vr, nvr);
    REQUIRE(values, nvr);
    REQUIRE(valueSizes, nvr);
    if (nValues < nvr) return FAIL("%s: nValues = %zu < nValueReferences = %zu", fn, nValues, nvr);
    for (size_t i = 0; i < nvr; i++) {
        const int k = node_of(vr[i], VR_NODE_RX_DATA);
        if (k < 0) return FAIL("%s: value reference %u is no Binary input of CanBus", fn, vr[i]);
        if (valueSizes[i] > CANBUS_OUTBOX)
            return FAIL("%s: Node%d.Rx_Data of %zu bytes exceeds its maxSize %d", fn, k + 1, valueSizes[i],
                        CANBUS_OUTBOX);
        if (valueSizes[i] > 0 && !values[i]) return FAIL("%s: Node%d.Rx_Data: NULL data of %zu bytes", fn,
                                                         k + 1, valueSizes[i]);
        if (c->state == EVENT_MODE && !c->rxActive[k]) {
            if (valueSizes[i] == 0) continue;
            return FAIL("%s: Node%d.Rx_Data set while Node%d.Rx_Clock is not active (a clocked variable: "
                        "fmi3SetClock first, FMI 3.0.2, 2.2.8)", fn, k + 1, k + 1);
        }
        if (c->state != EVENT_MODE) {      /* its start value: nothing to send */
            if (valueSizes[i] > 0)
                return FAIL("%s: Node%d.Rx_Data: %zu bytes outside Event Mode (only its start value, 0 "
                            "bytes, before initialisation)", fn, k + 1, valueSizes[i]);
            continue;
        }
        if (valueSizes[i] > 0) memcpy(c->rx[k], values[i], valueSizes[i]);
        c->rxSize[k] = valueSizes[i];
    }
    return fmi3OK;
}

/* ---- what CanBus does not provide -------------------------------------------------- */

#define NOT_PROVIDED(name, why, ...)                                    \
    fmi3Status name(fmi3Instance instance, __VA_ARGS__) {              \
        ENTER(#name, ANY);                                              \
        return FAIL("%s: %s", #name, why);                              \
    }
#define NOT_PROVIDED0(name, why)                                        \
    fmi3Status name(fmi3Instance instance) {                            \
        ENTER(#name, ANY);                                              \
        return FAIL("%s: %s", #name, why);                              \
    }
#define NO_TYPE(T, CT)                                                                          \
    NOT_PROVIDED(fmi3Get##T, "CanBus has no " #T " variables", const fmi3ValueReference vr[],   \
                 size_t nvr, CT values[], size_t nValues)                                       \
    NOT_PROVIDED(fmi3Set##T, "CanBus has no " #T " variables", const fmi3ValueReference vr[],   \
                 size_t nvr, const CT values[], size_t nValues)

NO_TYPE(Float32, fmi3Float32)
NO_TYPE(Int8, fmi3Int8)
NO_TYPE(UInt8, fmi3UInt8)
NO_TYPE(Int16, fmi3Int16)
NO_TYPE(UInt16, fmi3UInt16)
NO_TYPE(UInt32, fmi3UInt32)
NO_TYPE(Int64, fmi3Int64)
NO_TYPE(UInt64, fmi3UInt64)
NO_TYPE(String, fmi3String)

NOT_PROVIDED(fmi3GetNumberOfVariableDependencies, "no dependency information is provided",
             fmi3ValueReference vr, size_t *n)
NOT_PROVIDED(fmi3GetVariableDependencies, "no dependency information is provided",
             fmi3ValueReference dependent, size_t elementIndicesOfDependent[],
             fmi3ValueReference independents[], size_t elementIndicesOfIndependents[],
             fmi3DependencyKind dependencyKinds[], size_t nDependencies)
NOT_PROVIDED(fmi3GetFMUState, "canGetAndSetFMUState is false", fmi3FMUState *s)
NOT_PROVIDED(fmi3SetFMUState, "canGetAndSetFMUState is false", fmi3FMUState s)
NOT_PROVIDED(fmi3FreeFMUState, "canGetAndSetFMUState is false", fmi3FMUState *s)
NOT_PROVIDED(fmi3SerializedFMUStateSize, "canSerializeFMUState is false", fmi3FMUState s, size_t *size)
NOT_PROVIDED(fmi3SerializeFMUState, "canSerializeFMUState is false", fmi3FMUState s,
             fmi3Byte serializedState[], size_t size)
NOT_PROVIDED(fmi3DeserializeFMUState, "canSerializeFMUState is false", const fmi3Byte serializedState[],
             size_t size, fmi3FMUState *s)
NOT_PROVIDED(fmi3GetDirectionalDerivative, "providesDirectionalDerivatives is false",
             const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[],
             size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
             size_t nSensitivity)
NOT_PROVIDED(fmi3GetAdjointDerivative, "providesAdjointDerivatives is false",
             const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[],
             size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
             size_t nSensitivity)
NOT_PROVIDED0(fmi3EnterConfigurationMode, "CanBus has no structural parameters")
NOT_PROVIDED0(fmi3ExitConfigurationMode, "CanBus has no structural parameters")
NOT_PROVIDED(fmi3GetIntervalFraction, "the Tx clocks' intervals are decimal: fmi3GetIntervalDecimal",
             const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
             fmi3IntervalQualifier qualifiers[])
NOT_PROVIDED(fmi3GetShiftDecimal, "CanBus has no periodic clocks", const fmi3ValueReference vr[],
             size_t nvr, fmi3Float64 shifts[])
NOT_PROVIDED(fmi3GetShiftFraction, "CanBus has no periodic clocks", const fmi3ValueReference vr[],
             size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
NOT_PROVIDED(fmi3SetIntervalDecimal, "CanBus has no tunable or changing clocks",
             const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 intervals[])
NOT_PROVIDED(fmi3SetIntervalFraction, "CanBus has no tunable or changing clocks",
             const fmi3ValueReference vr[], size_t nvr, const fmi3UInt64 counters[],
             const fmi3UInt64 resolutions[])
NOT_PROVIDED(fmi3SetShiftDecimal, "CanBus has no periodic clocks", const fmi3ValueReference vr[],
             size_t nvr, const fmi3Float64 shifts[])
NOT_PROVIDED(fmi3SetShiftFraction, "CanBus has no periodic clocks", const fmi3ValueReference vr[],
             size_t nvr, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
NOT_PROVIDED0(fmi3EvaluateDiscreteStates, "providesEvaluateDiscreteStates is false")
NOT_PROVIDED0(fmi3EnterContinuousTimeMode, "Model Exchange only; CanBus is Co-Simulation")
NOT_PROVIDED(fmi3CompletedIntegratorStep, "Model Exchange only; CanBus is Co-Simulation",
             fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *enterEventMode,
             fmi3Boolean *terminateSimulation)
NOT_PROVIDED(fmi3SetTime, "Model Exchange only; CanBus is Co-Simulation", fmi3Float64 time)
NOT_PROVIDED(fmi3SetContinuousStates, "CanBus has no continuous states", const fmi3Float64 x[], size_t nx)
NOT_PROVIDED(fmi3GetContinuousStateDerivatives, "CanBus has no continuous states", fmi3Float64 dx[],
             size_t nx)
NOT_PROVIDED(fmi3GetEventIndicators, "CanBus has no event indicators", fmi3Float64 z[], size_t nz)
NOT_PROVIDED(fmi3GetContinuousStates, "CanBus has no continuous states", fmi3Float64 x[], size_t nx)
NOT_PROVIDED(fmi3GetNominalsOfContinuousStates, "CanBus has no continuous states", fmi3Float64 x[],
             size_t nx)
NOT_PROVIDED(fmi3GetOutputDerivatives, "maxOutputDerivativeOrder is 0", const fmi3ValueReference vr[], size_t nvr,
             const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
NOT_PROVIDED(fmi3ActivateModelPartition, "Scheduled Execution only", fmi3ValueReference clockReference,
             fmi3Float64 activationTime)

/* ME only, but answer the question: no states, no indicators */
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    ENTER("fmi3GetNumberOfEventIndicators", ANY);
    if (n) *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    ENTER("fmi3GetNumberOfContinuousStates", ANY);
    if (n) *n = 0;
    return fmi3OK;
}
