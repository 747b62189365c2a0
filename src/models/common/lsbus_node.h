/* An FMI-LS-BUS 1.0 CAN network node on the 36 m bus's steering CAN (issue 24):
 * the Low-Cut (Network Abstraction) bus terminal of an FMU whose model is one of
 * the project's (SteeringECU, SteeringActuator, the plant's sensors), the frames
 * those models exchange today as Real signals encoded and decoded with
 * ssp/can/Bus36m.dbc by the runner's network (artibus.can.network), now carried
 * in Binary operations (fmi-ls-bus v1.0.0, docs/4____network_abstraction.adoc,
 * docs/4_4_1_can.adoc).
 *
 * Per node one terminal of four variables (their value references in the
 * generated model_lsbus.h, from modelDescription/lsbus/<Name>.xml by
 * src/fmi/lsbus_node.py):
 *   Rx_Data  Binary input, clocked by Rx_Clock (an input, triggered clock): the
 *            operations the bus (or the other node) hands this node;
 *   Tx_Data  Binary output, clocked by Tx_Clock (an input, time-based clock,
 *            periodic with the DBC's cycle time: the ECUs' 10 ms): the operations
 *            this node sends; size 0 when it has none.
 * The Tx clock's triggered form (a variant, <Name>_LSBUS_Triggered; LSBUS_TX_TRIGGERED
 * of model_lsbus.h): Tx_Clock an output triggered clock the node activates itself at the
 * same ticks, t0 + k txInterval (fmi-ls-bus 1.0, 4____network_abstraction.adoc, "Triggered
 * Tx Clocks"): fmi3DoStep ending at or past a tick returns eventHandlingNeeded (never an
 * early return), fmi3UpdateDiscreteStates announces the next tick as nextEventTime (FMI
 * 3.0.2, 4.2, fmi3EnterEventMode: the importer enters Event Mode when time reaches it), and
 * in the Event Mode at a tick fmi3GetClock(Tx_Clock) says active until the update.
 * In Event Mode (FMI 3.0, Co-Simulation with eventModeUsed) the importer sets the
 * active clocks and Rx_Data, reads Tx_Data while Tx_Clock is active, then calls
 * fmi3UpdateDiscreteStates. The node's output function runs once per Event Mode, at
 * the first of: fmi3GetBinary(Tx_Data) with Tx_Clock active (FMI 3.0.2, 2.2.8, "Model
 * Partitions and Clocked Variables": reading an output of an active clock computes it;
 * "Getting and Setting Variable Values": a clocked variable is read only while its clock
 * is active, and fmi3UpdateDiscreteStates ends the activation, 2.3 Event Mode), or
 * fmi3UpdateDiscreteStates (Rx_Data set after that read is received there). The tick's
 * frames stay readable until the Event Mode ends, for importers that read them after the
 * update. It
 *   1. reads Rx_Data operation by operation (lsbus_can_read): a CAN Transmit of a
 *      message the node listens to goes through the receivers' E2E check of the
 *      runner's network (Network._deliver: CRC, then the counter: repeated, or
 *      ahead by more than the cycles since the last accepted frame) and, accepted,
 *      into the model's inputs (node_rx); frames of other identifiers are not
 *      this node's (a CAN controller's acceptance filter); Confirm, Arbitration
 *      Lost, Bus Error, Status, Wakeup and the FD/XL formats are ignored, as the
 *      standard lets a node ignore what it does not use (4_4_1_can.adoc, "Bus
 *      Notification Parameter": a node ignores notifications it does not expect);
 *      an operation with a wrong Length, a value outside the defined ones or a
 *      truncated one is answered by a Format Error (0x01) carrying its bytes
 *      (4____network_abstraction.adoc, "Format Error"), an unknown OP Code skipped;
 *   2. when Tx_Clock is active: a Configuration (CAN_BAUDRATE, the DBC's
 *      Baudrate) before the first Transmit, then one CAN Transmit per message the
 *      node sends (node_tx: the model's outputs as they are at this instant, the
 *      last sample's), encoded by the generated codec (bus36m_can.c: the bytes of
 *      today's network, E2E CRC and alive counter included; the counter starts at
 *      0 and counts each frame, as Network._produce).
 * The model's own cycle runs in fmi3DoStep as in the FMI 2.0 FMU (model.c
 * unchanged), on the inputs the last accepted frames left: so the frames sent at
 * t are the outputs of the sample before t, and a frame received at t is used by
 * the sample at t, as the runner's network ticks today. At the first event
 * (t = startTime, before any step) the model is initialised again from the frames
 * received there, as the network's settle gives the receivers the senders'
 * initial values through the codec.
 *
 * Plain data only (the LsNode struct sits in the model's ModelState); the
 * functions take the instance (fmu.h), forward-declared here so that config.h
 * can include this header. */
#ifndef ARTIBUS_LSBUS_NODE_H
#define ARTIBUS_LSBUS_NODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bus36m_can.h"

#define LSNODE_BUFFER 1024    /* bytes of operations per direction (the Binary's maxSize) */

typedef struct {
    uint8_t rx[LSNODE_BUFFER];    /* Rx_Data as set in this event */
    size_t rxSize;
    uint8_t tx[LSNODE_BUFFER];    /* Tx_Data: what this event sends (size 0: nothing) */
    size_t txSize;
    int rxClock, txClock;         /* the clocks active in this event */
    int updated;                  /* fmi3UpdateDiscreteStates done in this Event Mode */
    int sent;                     /* this Event Mode's Tx_Data built (Tx_Clock active) */
    int configured;               /* the Configuration (baud rate) sent */
    int stepped;                  /* a step was taken since the start */
    int initFromFrames;           /* the first event re-initialised the model from its frames */
    int lastCounter[BUS36M_NMSG]; /* per message: the receivers' reference counter, -1 none */
    long long goodK[BUS36M_NMSG]; /* its cycle index when last accepted */
    unsigned counter[BUS36M_NMSG];/* per message sent: the next alive counter */
    long long nRx, nRejected, nTx, nFormatErrors, nIgnored;   /* counts, for the log and the tests */
    double t0;                    /* start time: cycle k of a message at t0 + k cycle */
    long long txK;                /* triggered Tx_Clock: the index of its next tick, at t0 + txK interval */
    int ready;                    /* the above set up (lsbus_node.c, ready) */
    int zeroSteps;                /* steps of size 0 taken (lsnode_zero_step) */
} LsNode;

struct ModelInstance;

/* ---- called by fmi3Functions.c (MODEL_LSBUS); each returns a Status (fmu.h), logged ---- */
int lsnode_get_binary(struct ModelInstance *comp, unsigned vr, size_t *size, const uint8_t **value);
int lsnode_set_binary(struct ModelInstance *comp, unsigned vr, size_t size, const uint8_t *value);
int lsnode_get_clock(struct ModelInstance *comp, unsigned vr, bool *active);
int lsnode_set_clock(struct ModelInstance *comp, unsigned vr, bool active);
int lsnode_clock_outside_event_mode(struct ModelInstance *comp, unsigned vr);
int lsnode_interval(struct ModelInstance *comp, unsigned vr, double *interval);
/* fmi3UpdateDiscreteStates; *tNext: the triggered Tx_Clock's next tick (nextEventTime), else unchanged */
int lsnode_update(struct ModelInstance *comp, double *tNext);
void lsnode_enter_event_mode(struct ModelInstance *comp);
void lsnode_leave_event_mode(struct ModelInstance *comp);
void lsnode_step(struct ModelInstance *comp);
/* after fmi3DoStep: true when a triggered Tx_Clock's tick is due (eventHandlingNeeded) */
bool lsnode_event_needed(struct ModelInstance *comp);
/* fmi3DoStep with communicationStepSize 0 (FMI 3.0.2 wants > 0; an importer that serves a
   countdown clock due now so, as fmu-manipulation-toolbox 2.0's container): nothing done, a
   warning logged once, the outputs as after a step */
int lsnode_zero_step(struct ModelInstance *comp, bool *eventHandlingNeeded, bool *terminateSimulation,
                     bool *earlyReturn, double *lastSuccessfulTime);

/* ---- supplied by each node model (its model_lsbus.c) ---------------------------------- */
/* the messages (bit i: BUS36M_MESSAGES[i]) it receives, and those it sends at its Tx_Clock */
unsigned node_rx_mask(struct ModelInstance *comp);
unsigned node_tx_mask(struct ModelInstance *comp);
/* an accepted frame of message msg: its data signals (DBC units) and its alive counter,
   into the model's inputs */
void node_rx(struct ModelInstance *comp, int msg, const double *values, unsigned counter);
/* the data signals of message msg to send now (DBC units), from the model's variables */
void node_tx(struct ModelInstance *comp, int msg, double *values);
/* before each step and before the model starts from its first frames: inputs the node
   takes from elsewhere than the bus (SteeringECU module 1: v from the vehicle network) */
void node_sync(struct ModelInstance *comp);

#endif
