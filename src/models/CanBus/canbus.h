/* A classic CAN (ISO 11898-1, CAN 2.0A/B) bus simulation for FMI-LS-BUS 1.0
 * (fmi-ls-bus v1.0.0 docs/4_4_1_can.adoc): nodes hand it Transmit operations,
 * it arbitrates by identifier, puts one frame at a time on the wire for the
 * time its bits take, and hands each node the operations for it (the frames of
 * the others, Confirm, Arbitration Lost, Bus Error, Format Error, Wakeup).
 * Plain C, no FMI types: the FMI 3.0 layer (fmi3_canbus.c) drives it.
 *
 * Time: the caller passes the current time to every function; a frame that
 * starts at tStart ends at tEnd = tStart + bits / baudrate (0 with wire time
 * off), and canbus_advance(t >= tEnd) completes it.
 */
#ifndef ARTIBUS_CANBUS_H
#define ARTIBUS_CANBUS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lsbus_can.h"

#define CANBUS_NODES 8        /* node terminals (modelDescription/fmi3/CanBus.xml) */
#define CANBUS_QUEUE 32       /* frames a node may have waiting for the bus */
#define CANBUS_OUTBOX 2048    /* bytes of operations for a node: Tx_Data's maxSize */
/* a frame ends at tStart + bits / baudrate; an importer's t + interval may differ
   from that by rounding: times this close count as the same (far below one bit,
   1 us at 1 Mbit/s) */
#define CANBUS_TIME_EPS 1e-10

typedef struct {
    uint32_t id;
    uint8_t ide, rtr;         /* LSBUS_TRUE / LSBUS_FALSE */
    uint16_t dl;              /* data bytes 0..8 */
    uint8_t data[LSBUS_CAN_MAX_DATA];
} CanFrame;

typedef struct {
    CanFrame queue[CANBUS_QUEUE];   /* waiting for the bus, first in first out */
    int nQueue;
    uint8_t out[CANBUS_OUTBOX];     /* operations for the node, not yet read */
    size_t nOut;
    uint8_t status;                 /* LSBUS_CAN_ERROR_ACTIVE .. BUS_OFF, from its Status */
    uint8_t arbitrationLost;        /* its Arbitration Lost Behavior */
    bool overflowTold;              /* its outbox overflowed: logged once */
} CanNode;

/* the parameters (the FMU's, modelDescription/fmi3/CanBus.xml) */
typedef struct {
    double baudrate;          /* bit/s until a node configures another */
    bool wireTime;            /* false: frames take no time */
    int arbitrationLostBehavior;
    int nNodes;               /* Node1..NodeN on the bus, the others unconnected */
    double faultStart;        /* s */
    int faultSilentNode;      /* 1..CANBUS_NODES, 0 none */
    long faultCorruptId;      /* -1 none */
    int faultBusOffNode;      /* 1..CANBUS_NODES, 0 none */
} CanBusParams;

/* a message for the log: level 0 event, 1 warning */
typedef void (*CanBusLog)(void *ctx, int level, const char *text);

typedef struct {
    CanBusParams p;
    double baudrate;          /* in force */
    CanNode node[CANBUS_NODES];
    bool busy;                /* a frame on the wire */
    int sender;               /* its node, 0-based */
    CanFrame wire;
    int wireBits;
    double tStart, tEnd;
    double t0;                /* start time, for the bus load */
    double busyTime;          /* s of bits of the frames completed */
    int nFrames, nBusErrors, nArbitrationLost;
    CanBusLog log;
    void *logCtx;
    const bool *logEvents;    /* NULL, or false: the events (level 0) are not even formatted */
} CanBus;

void canbus_init(CanBus *b, const CanBusParams *p, double t0, CanBusLog log, void *ctx);

/* Node k's (0-based) operations buf[0, size) at time t: Transmits queued,
 * Configuration and Status taken, Wakeup passed on to the others. Every
 * malformed operation is answered with a Format Error to the node and logged
 * as a warning; returns the number of them. Never reads outside buf. */
int canbus_receive(CanBus *b, int k, const uint8_t *buf, size_t size, double t);

/* Completes the frame on the wire if it ends at or before t (+ CANBUS_TIME_EPS), then arbitrates
 * among the waiting frames and starts the winner (with wire time off, every
 * waiting frame is delivered at t, in arbitration order). */
void canbus_advance(CanBus *b, double t);

/* the end of the frame on the wire, or INFINITY if the bus is idle */
double canbus_next_event(const CanBus *b);

/* the time node k has operations for it: t if it has some now beyond the first
   `read` bytes (handed out already), the end of the frame on the wire if that
   frame will give it some, INFINITY if neither */
double canbus_due(const CanBus *b, int k, double t, size_t read);

/* busy time / elapsed time at t (0 at the start) */
double canbus_load(const CanBus *b, double t);

/* the bits of a classic data or remote frame on the wire, stuff bits and the
   3 bits of intermission included (ISO 11898-1: 10.4 frame formats, 10.5 bit stuffing) */
int canbus_frame_bits(const CanFrame *f);

/* node k read n bytes of its operations: drop them */
void canbus_consume(CanBus *b, int k, size_t n);

#endif
