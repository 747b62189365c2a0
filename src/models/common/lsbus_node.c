/* An FMI-LS-BUS 1.0 CAN network node: see lsbus_node.h. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmu_core.h"
#include "lsbus_can.h"
#include "lsbus_node.h"
#include "model_lsbus.h"      /* generated: LSBUS_VR_*, LSBUS_MAX_SIZE, LSBUS_TX_INTERVAL */

#define B (&comp->v.s.bus)

/* the node's state before its first use (the instance is zeroed at instantiation and reset):
   no counter received yet, cycles counted from the start time */
static void ready(ModelInstance *comp) {
    if (B->ready) return;
    for (int i = 0; i < BUS36M_NMSG; i++) {
        B->lastCounter[i] = -1;
        B->goodK[i] = -1;
    }
    B->t0 = comp->v.time;
    B->ready = 1;
}

/* the value reference's name, for messages */
static const char *bus_name(unsigned vr) {
    return vr == LSBUS_VR_RX_DATA ? "Rx_Data" : vr == LSBUS_VR_TX_DATA ? "Tx_Data" :
           vr == LSBUS_VR_RX_CLOCK ? "Rx_Clock" : vr == LSBUS_VR_TX_CLOCK ? "Tx_Clock" : "?";
}

static Status evaluate(ModelInstance *comp);

#define TICK_EPS 1e-9   /* s: a time this close to a tick is the tick (the importers' EPS) */

/* the triggered Tx_Clock's next tick, and whether it is due now (reached or passed) */
static double tx_tick(const ModelInstance *comp) { return B->t0 + (double)B->txK * LSBUS_TX_INTERVAL; }

static bool tx_due(ModelInstance *comp) {
    return LSBUS_TX_TRIGGERED && comp->v.time >= tx_tick(comp) - TICK_EPS;
}

bool lsnode_event_needed(ModelInstance *comp) {
    ready(comp);
    return tx_due(comp);
}

int lsnode_zero_step(ModelInstance *comp, bool *eventHandlingNeeded, bool *terminateSimulation, bool *earlyReturn,
                     double *lastSuccessfulTime) {
    if (!B->zeroSteps++)
        log_warning(comp, "t = %.6g s: fmi3DoStep with communicationStepSize = 0 (FMI 3.0.2, 4.2: it must be > 0): "
                          "taken as no step (this warning once)", comp->v.time);
    *eventHandlingNeeded = lsnode_event_needed(comp);
    *terminateSimulation = *earlyReturn = false;
    *lastSuccessfulTime = comp->v.time;
    return OK;
}

int lsnode_get_binary(ModelInstance *comp, unsigned vr, size_t *size, const uint8_t **value) {
    ready(comp);
    if (vr == LSBUS_VR_TX_DATA) {
        /* read while Tx_Clock is active, before the update: the tick's frames computed now
           (lsbus_node.h; FMI 3.0.2, 2.2.8) */
        if (comp->v.state == S_EVENT_MODE && B->txClock && !B->sent) {
            if (core_refresh(comp) > Warning || evaluate(comp) > Warning) return Error;
        }
        *size = B->txSize;
        *value = B->tx;
        return OK;
    }
    if (vr == LSBUS_VR_RX_DATA) {
        *size = B->rxSize;
        *value = B->rx;
        return OK;
    }
    return log_error(comp, "fmi3GetBinary: no Binary variable has value reference %u (Rx_Data is %u, Tx_Data %u)",
                     vr, LSBUS_VR_RX_DATA, LSBUS_VR_TX_DATA);
}

int lsnode_set_binary(ModelInstance *comp, unsigned vr, size_t size, const uint8_t *value) {
    ready(comp);
    if (vr != LSBUS_VR_RX_DATA)
        return log_error(comp, "fmi3SetBinary: value reference %u is not an input Binary (%s; Rx_Data is %u)",
                         vr, bus_name(vr), LSBUS_VR_RX_DATA);
    if (size > 0 && !value)
        return log_error(comp, "fmi3SetBinary: Rx_Data: a NULL value of size %zu", size);
    if (comp->v.state == S_EVENT_MODE) {
        /* FMI 3.0, 2.2.8.3: a clocked input is set only while its clock is active,
           before the discrete states are updated */
        if (B->updated)
            return log_error(comp, "fmi3SetBinary: Rx_Data set after fmi3UpdateDiscreteStates in this Event Mode "
                                   "(set Rx_Clock, then Rx_Data, then update: fmi-ls-bus 1.0, 4, \"Variables\")");
        if (!B->rxClock)
            return log_error(comp, "fmi3SetBinary: Rx_Data set while Rx_Clock is inactive (set the clock first)");
    } else if (size > 0) {
        return log_error(comp, "fmi3SetBinary: Rx_Data (%zu bytes) outside Event Mode: a clocked input is set "
                               "in Event Mode, its clock Rx_Clock active (state '%s')", size,
                         state_name(comp->v.state));
    }
    if (size > LSBUS_MAX_SIZE)
        return log_error(comp, "fmi3SetBinary: Rx_Data has %zu bytes, more than its maxSize %d", size,
                         LSBUS_MAX_SIZE);
    if (size > 0) memcpy(B->rx, value, size);
    B->rxSize = size;
    return OK;
}

int lsnode_get_clock(ModelInstance *comp, unsigned vr, bool *active) {
    if (vr == LSBUS_VR_RX_CLOCK) *active = B->rxClock != 0;
    else if (vr == LSBUS_VR_TX_CLOCK)   /* an output clock's activation ends with the update (FMI 3.0.2, 2.3) */
        *active = B->txClock != 0 && !(LSBUS_TX_TRIGGERED && B->updated);
    else
        return log_error(comp, "fmi3GetClock: no Clock has value reference %u (Rx_Clock %u, Tx_Clock %u)", vr,
                         LSBUS_VR_RX_CLOCK, LSBUS_VR_TX_CLOCK);
    return OK;
}

int lsnode_set_clock(ModelInstance *comp, unsigned vr, bool active) {
    ready(comp);
    if (vr != LSBUS_VR_RX_CLOCK && vr != LSBUS_VR_TX_CLOCK)
        return log_error(comp, "fmi3SetClock: no Clock has value reference %u (Rx_Clock %u, Tx_Clock %u)", vr,
                         LSBUS_VR_RX_CLOCK, LSBUS_VR_TX_CLOCK);
    if (vr == LSBUS_VR_TX_CLOCK && LSBUS_TX_TRIGGERED)
        return log_error(comp, "fmi3SetClock: Tx_Clock is an output clock (triggered: the node activates it at "
                               "its ticks; read it with fmi3GetClock, FMI 3.0.2, 2.2.9)");
    /* FMI 3.0.2, 2.3, Event Mode, fmi3SetClock: "Periodic Clocks must not be active for more than one
       call of fmi3UpdateDiscreteStates per Event Mode. This restriction does not apply to triggered
       Clocks"; "The event mode may consist of several super-dense time instants", each begun by
       setting clocks. So after an update: Rx_Clock (triggered) begins a new instant; the periodic
       Tx_Clock too, unless it was active at an update of this Event Mode already (its tick sent) */
    if (B->updated && active) {
        if (vr == LSBUS_VR_TX_CLOCK && B->sent)
            return log_error(comp, "%s: t = %.6g s: fmi3SetClock: %s.Tx_Clock set again after fmi3UpdateDiscreteStates "
                                   "in this Event Mode, where it was active already (a periodic clock: FMI 3.0.2, "
                                   "2.3, at most one update per Event Mode; enter a new Event Mode)",
                             comp->instanceName, comp->v.time, LSBUS_TERMINAL);
        B->updated = 0;         /* a new super-dense instant: the clocks active at the last update are over */
        B->txClock = B->rxClock = 0;
        B->rxSize = 0;
    }
    if (vr == LSBUS_VR_RX_CLOCK) B->rxClock = active;
    else B->txClock = active;
    return OK;
}

/* fmi3SetClock outside Event Mode (FMI 3.0.2, 4.2, Step Mode: "clocked variables can not be set or
   get because Clocks are only active during Event Mode"): refused, naming the node, the clock and
   the time (FMI 3.0's log callback carries no instance name) */
int lsnode_clock_outside_event_mode(ModelInstance *comp, unsigned vr) {
    char clock[96];
    if (vr == LSBUS_VR_RX_CLOCK || vr == LSBUS_VR_TX_CLOCK)
        snprintf(clock, sizeof clock, "%s.%s", LSBUS_TERMINAL, bus_name(vr));
    else
        snprintf(clock, sizeof clock, "value reference %u (no Clock of it)", vr);
    return log_error(comp, "%s: t = %.6g s: fmi3SetClock: %s activated in %s: clocks are active only in Event "
                           "Mode (FMI 3.0.2, 4.2, Step Mode; enter Event Mode first)", comp->instanceName,
                     comp->v.time, clock, state_name(comp->v.state));
}

int lsnode_interval(ModelInstance *comp, unsigned vr, double *interval) {
    if (LSBUS_TX_TRIGGERED)
        return log_error(comp, "fmi3GetIntervalDecimal: value reference %u: this node has no time-based clock "
                               "(Tx_Clock is a triggered output clock, Rx_Clock a triggered input clock)", vr);
    if (vr != LSBUS_VR_TX_CLOCK)
        return log_error(comp, "fmi3GetIntervalDecimal: value reference %u is not a time-based clock (Tx_Clock "
                               "is %u; Rx_Clock is triggered)", vr, LSBUS_VR_TX_CLOCK);
    *interval = LSBUS_TX_INTERVAL;
    return OK;
}

void lsnode_enter_event_mode(ModelInstance *comp) {
    ready(comp);
    B->rxClock = 0;
    B->txClock = tx_due(comp);   /* a triggered Tx_Clock: active from here to the update */
    B->updated = B->sent = 0;
    B->txSize = 0;            /* a new activation: Tx_Data holds only what it computes */
}

void lsnode_leave_event_mode(ModelInstance *comp) {
    B->rxClock = B->txClock = 0;
    B->updated = B->sent = 0;
    B->rxSize = 0;
}

void lsnode_step(ModelInstance *comp) {
    ready(comp);
    node_sync(comp);
    B->stepped = 1;
    B->txSize = 0;            /* what the last event sent is gone: nothing to send */
    B->rxSize = 0;
}

/* a frame the E2E check let through, or not (Network._deliver, AUTOSAR E2E profile 2
   receiver with MaxDeltaCounterInit 1) */
static bool e2e_accept(ModelInstance *comp, int msg, const uint8_t *data, long long k) {
    const Bus36mMessage *m = &BUS36M_MESSAGES[msg];
    const int counter = data[1] & 0x0F;
    if (bus36m_e2e_crc(data, m->dlc, m->dataId) != data[0]) {
        log_event(comp, "t = %.6g s: %s: wrong CRC 0x%02X: frame rejected", comp->v.time, m->name, data[0]);
        return false;
    }
    if (B->lastCounter[msg] >= 0) {
        const int delta = (counter - B->lastCounter[msg] + 16) % 16;
        long long allowed = k - B->goodK[msg];
        allowed = allowed < 1 ? 1 : allowed > 15 ? 15 : allowed;
        if (delta == 0) {
            log_event(comp, "t = %.6g s: %s: counter %d repeated: frame rejected", comp->v.time, m->name, counter);
            return false;
        }
        if (delta > allowed) {
            log_event(comp, "t = %.6g s: %s: counter %d after %d, more than %lld cycles on: wrong sequence, "
                            "frame rejected (and the new reference)", comp->v.time, m->name, counter,
                      B->lastCounter[msg], allowed);
            B->lastCounter[msg] = counter;
            return false;
        }
    }
    B->lastCounter[msg] = counter;
    B->goodK[msg] = k;
    return true;
}

static Status format_error(ModelInstance *comp, const LsBusCanOp *op, LsBusResult r) {
    B->nFormatErrors++;
    log_warning(comp, "t = %.6g s: Rx_Data: %s (OP Code 0x%X, Length %u): answered with a Format Error", comp->v.time,
                lsbus_result_name(r), op->op, op->length);
    LsBusBuffer out = { B->tx, B->txSize, LSBUS_MAX_SIZE };
    if (lsbus_append_format_error(&out, op->raw, op->rawSize) != LSBUS_OK)
        log_warning(comp, "t = %.6g s: Tx_Data is full (%d bytes): the Format Error is dropped", comp->v.time,
                    LSBUS_MAX_SIZE);
    B->txSize = out.size;
    return OK;
}

/* the operations of Rx_Data (see lsbus_node.h, step 1); true if a frame was accepted */
static bool receive(ModelInstance *comp) {
    const unsigned listen = node_rx_mask(comp);
    bool any = false;
    size_t pos = 0;
    for (;;) {
        LsBusCanOp op;
        const LsBusResult r = lsbus_can_read(B->rx, B->rxSize, &pos, &op);
        if (r == LSBUS_END) break;
        if (r == LSBUS_E_UNKNOWN_OP) {          /* not an operation this node knows: skipped by its Length */
            B->nIgnored++;
            log_event(comp, "t = %.6g s: Rx_Data: unknown OP Code 0x%X (%u bytes) ignored", comp->v.time, op.op,
                      op.length);
            continue;
        }
        if (r != LSBUS_OK) {
            format_error(comp, &op, r);
            if (r == LSBUS_E_TRUNCATED) break;
            continue;
        }
        if (op.op != LSBUS_CAN_OP_TRANSMIT) {   /* notifications, configuration, FD/XL frames */
            B->nIgnored++;
            log_event(comp, "t = %.6g s: Rx_Data: %s ignored", comp->v.time, lsbus_op_name(op.op));
            continue;
        }
        const int msg = op.ide == LSBUS_FALSE && op.rtr == LSBUS_FALSE ? bus36m_index(op.id) : -1;
        if (msg < 0 || !(listen >> msg & 1u)) {  /* not for this node (acceptance filter) */
            B->nIgnored++;
            continue;
        }
        const Bus36mMessage *m = &BUS36M_MESSAGES[msg];
        if (op.dataLength != m->dlc) {
            B->nRejected++;
            log_warning(comp, "t = %.6g s: %s (0x%03X) with %u data bytes, the DBC's DLC is %d: frame rejected",
                        comp->v.time, m->name, (unsigned)m->id, (unsigned)op.dataLength, m->dlc);
            continue;
        }
        const long long k = llround((comp->v.time - B->t0) / (m->cycleMs * 1e-3));
        if (!e2e_accept(comp, msg, op.data, k)) {
            B->nRejected++;
            continue;
        }
        double values[BUS36M_MAX_SIGNALS];
        bus36m_decode(msg, op.data, values);
        node_rx(comp, msg, values, op.data[1] & 0x0Fu);
        core_changed(comp);
        B->nRx++;
        any = true;
    }
    B->rxSize = 0;
    return any;
}

/* the frames of this Tx_Clock tick (lsbus_node.h, step 2) */
static Status transmit(ModelInstance *comp) {
    LsBusBuffer out = { B->tx, B->txSize, LSBUS_MAX_SIZE };
    if (!B->configured) {   /* fmi-ls-bus 4_4_1_can.adoc, "Configuration": the baud rate before any frame */
        if (lsbus_can_append_config_baudrate(&out, LSBUS_CAN_CONFIG_CAN_BAUDRATE, BUS36M_BAUDRATE) != LSBUS_OK)
            return log_error(comp, "Tx_Data: no room for the Configuration (maxSize %d)", LSBUS_MAX_SIZE);
        B->configured = 1;
    }
    const unsigned send = node_tx_mask(comp);
    for (int msg = 0; msg < BUS36M_NMSG; msg++) {
        if (!(send >> msg & 1u)) continue;
        const Bus36mMessage *m = &BUS36M_MESSAGES[msg];
        double values[BUS36M_MAX_SIGNALS] = { 0 };
        uint8_t data[8];
        node_tx(comp, msg, values);
        const int bad = bus36m_encode(msg, values, B->counter[msg], data);
        if (bad)    /* as the runner's network: a value outside its signal's range is an error */
            return log_error(comp, "t = %.6g s: message %s, signal %s: %.6g %s is outside the signal's range "
                                   "[%g, %g]", comp->v.time, m->name, m->signals[bad - 1].name, values[bad - 1],
                             m->signals[bad - 1].unit, m->signals[bad - 1].minimum, m->signals[bad - 1].maximum);
        if (lsbus_can_append_transmit(&out, m->id, LSBUS_FALSE, LSBUS_FALSE, data, (uint16_t)m->dlc) != LSBUS_OK)
            return log_error(comp, "Tx_Data: no room for %s (maxSize %d)", m->name, LSBUS_MAX_SIZE);
        B->counter[msg] = (B->counter[msg] + 1u) % 16u;
        B->nTx++;
    }
    B->txSize = out.size;
    return OK;
}

/* the node's output function in this Event Mode (lsbus_node.h): the Rx_Data set so far
   received, then, Tx_Clock active and not yet done, the tick's frames built */
static Status evaluate(ModelInstance *comp) {
    if (B->rxClock && receive(comp) && !B->stepped) {
        /* the first event: the model starts from its first frames (the network's settle) */
        node_sync(comp);
        if (model_init(comp)) return Error;
        B->initFromFrames = 1;
        model_outputs(comp);
    }
    if (!B->txClock || B->sent) return OK;
    B->sent = 1;
    if (LSBUS_TX_TRIGGERED) { /* this tick done: the next one after now (bounded: after a huge step no
                                 later tick is representable beyond 2^53 intervals) */
        const double k = floor((comp->v.time + TICK_EPS - B->t0) / LSBUS_TX_INTERVAL) + 1.0;
        B->txK = k < 9e15 ? (k > (double)B->txK ? (long long)k : B->txK + 1) : 9000000000000000LL;
    }
    return transmit(comp);
}

int lsnode_update(ModelInstance *comp, double *tNext) {
    ready(comp);
    B->updated = 1;
    const int status = evaluate(comp);
    if (LSBUS_TX_TRIGGERED) *tNext = tx_tick(comp);
    return status;
}
