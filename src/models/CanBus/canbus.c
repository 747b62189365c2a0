/* The CAN bus simulation (canbus.h). The standard followed, fmi-ls-bus v1.0.0
 * docs/4_4_1_can.adoc, by section:
 *   Transmission and Acknowledge: a frame is delivered to every other node and
 *     confirmed to its sender; no Confirm if every other node is bus-off;
 *   Arbitration: frames waiting in the same instant go in identifier order;
 *     the losers are buffered and retried (BUFFER_AND_RETRANSMIT, no Arbitration
 *     Lost) or dropped with Arbitration Lost (DISCARD_AND_NOTIFY), as each node
 *     configured, else as the parameter says; ERROR_ACTIVE nodes are preferred
 *     to ERROR_PASSIVE ones;
 *   Error Handling, Bus Error: a corrupted frame gives every node a Bus Error,
 *     the sender's with Is Sender, the first receiver's the primary error flag;
 *   Configuration, Status: taken from the nodes, never passed on;
 *   Wakeup: passed to every node but its sender;
 *   Format Error (docs/4____network_abstraction.adoc): the answer to an
 *     operation that does not match its format, carrying its bytes.
 * The frame's bits: ISO 11898-1 (CAN 2.0 A/B) data and remote frames, with bit
 * stuffing over SOF..CRC and the CRC-15 computed, so that the stuff bits are
 * the real ones; then CRC delimiter, ACK slot and delimiter, EOF 7, and the
 * 3 bits of intermission before the next frame may start. */
#include "canbus.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void say(CanBus *b, int level, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static void say(CanBus *b, int level, const char *fmt, ...) {
    if (!b->log || (level == 0 && b->logEvents && !*b->logEvents)) return;   /* (a frame's vsnprintf: ~1 us) */
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    b->log(b->logCtx, level, text);
}

void canbus_init(CanBus *b, const CanBusParams *p, double t0, CanBusLog log, void *ctx) {
    memset(b, 0, sizeof *b);
    b->p = *p;
    b->baudrate = p->baudrate;
    b->t0 = t0;
    b->log = log;
    b->logCtx = ctx;
    b->sender = -1;
    for (int k = 0; k < CANBUS_NODES; k++) {
        b->node[k].status = LSBUS_CAN_ERROR_ACTIVE;
        b->node[k].arbitrationLost = (uint8_t)p->arbitrationLostBehavior;
    }
}

/* ---- the frame's bits ----------------------------------------------------------- */

/* The frame's bits SOF..CRC, taken one at a time as they are sent: the CRC-15 register
   over SOF..data (ISO 11898-1 10.4.2.6: generator x^15+x^14+x^10+x^8+x^7+x^4+x^3+1) and
   the bit stuffing over SOF..CRC (10.5: after five equal bits the transmitter inserts a
   complement bit, which counts as the first bit of the next run) */
typedef struct {
    uint32_t crc;
    int n, stuff, run, last;
} Bits;

static void put_bits(Bits *s, uint32_t value, int width, bool crc) {
    for (int i = width - 1; i >= 0; i--) {
        const int bit = (int)((value >> i) & 1u);
        if (crc) {
            const uint32_t next = (uint32_t)bit ^ ((s->crc >> 14) & 1u);
            s->crc = (s->crc << 1) & 0x7FFFu;
            if (next) s->crc ^= 0x4599u;
        }
        if (bit == s->last) {
            s->run++;
        } else {
            s->last = bit;
            s->run = 1;
        }
        if (s->run == 5) {
            s->stuff++;
            s->last = !s->last;
            s->run = 1;
        }
        s->n++;
    }
}

int canbus_frame_bits(const CanFrame *f) {
    Bits s = {.crc = 0, .n = 0, .stuff = 0, .run = 0, .last = -1};
    const uint32_t dlc = f->dl > 8 ? 8 : f->dl;
    put_bits(&s, 0, 1, true);                               /* SOF, dominant */
    if (f->ide == LSBUS_TRUE) {
        put_bits(&s, (f->id >> 18) & 0x7FFu, 11, true);     /* base identifier */
        put_bits(&s, 1, 1, true);                           /* SRR, recessive */
        put_bits(&s, 1, 1, true);                           /* IDE, recessive */
        put_bits(&s, f->id & 0x3FFFFu, 18, true);           /* identifier extension */
        put_bits(&s, f->rtr, 1, true);
        put_bits(&s, 0, 2, true);                           /* r1, r0 */
    } else {
        put_bits(&s, f->id & 0x7FFu, 11, true);
        put_bits(&s, f->rtr, 1, true);
        put_bits(&s, 0, 2, true);                           /* IDE, r0 */
    }
    put_bits(&s, dlc, 4, true);
    if (f->rtr != LSBUS_TRUE)
        for (uint32_t i = 0; i < dlc; i++) put_bits(&s, f->data[i], 8, true);
    put_bits(&s, s.crc, 15, false);                         /* the CRC sequence, stuffed too */
    return s.n + s.stuff + 1 + 2 + 7 + 3;   /* CRC delimiter, ACK slot + delimiter, EOF, intermission */
}

/* ---- the nodes' operations -------------------------------------------------------- */

/* append to node k's operations (the outbox is Tx_Data's maxSize: a full one
   loses the operation, logged) */
static LsBusBuffer outbox(CanBus *b, int k) {
    LsBusBuffer buf;
    lsbus_buffer_init(&buf, b->node[k].out, CANBUS_OUTBOX);
    buf.size = b->node[k].nOut;
    return buf;
}

static void sent(CanBus *b, int k, LsBusBuffer *buf, LsBusResult r, const char *what) {
    if (r == LSBUS_OK) {
        b->node[k].nOut = buf->size;
    } else if (!b->node[k].overflowTold) {
        b->node[k].overflowTold = true;
        say(b, 1, "node %d: %s not sent: %s (%zu bytes wait unread: is its Tx_Clock connected? "
            "Told once)", k + 1, what, lsbus_result_name(r), b->node[k].nOut);
    }
}

static void send_confirm(CanBus *b, int k, uint32_t id) {
    LsBusBuffer buf = outbox(b, k);
    sent(b, k, &buf, lsbus_can_append_confirm(&buf, id), "Confirm");
}

static void send_arbitration_lost(CanBus *b, int k, uint32_t id) {
    LsBusBuffer buf = outbox(b, k);
    sent(b, k, &buf, lsbus_can_append_arbitration_lost(&buf, id), "Arbitration Lost");
}

static void send_bus_error(CanBus *b, int k, uint32_t id, uint8_t code, uint8_t flag, uint8_t isSender) {
    LsBusBuffer buf = outbox(b, k);
    sent(b, k, &buf, lsbus_can_append_bus_error(&buf, id, code, flag, isSender), "Bus Error");
}

static void send_frame(CanBus *b, int k, const CanFrame *f) {
    LsBusBuffer buf = outbox(b, k);
    sent(b, k, &buf, lsbus_can_append_transmit(&buf, f->id, f->ide, f->rtr, f->data, f->dl), "CAN Transmit");
}

/* node k cannot take part: not connected (k >= nNodes), bus-off by its Status or
   by the fault, from faultStart */
static bool bus_off(const CanBus *b, int k, double t) {
    return k >= b->p.nNodes || b->node[k].status == LSBUS_CAN_BUS_OFF ||
           (b->p.faultBusOffNode == k + 1 && t >= b->p.faultStart);
}

static void format_error(CanBus *b, int k, const LsBusCanOp *op, LsBusResult r) {
    say(b, 1, "node %d: malformed operation 0x%02x (%s, Length %u, %zu bytes): %s; answered with a "
        "Format Error", k + 1, (unsigned)op->op, lsbus_op_name(op->op), (unsigned)op->length,
        op->rawSize, lsbus_result_name(r));
    LsBusBuffer buf = outbox(b, k);
    sent(b, k, &buf, lsbus_append_format_error(&buf, op->raw, op->rawSize), "Format Error");
}

static void take_transmit(CanBus *b, int k, const LsBusCanOp *op, double t) {
    if (b->p.faultSilentNode == k + 1 && t >= b->p.faultStart) {
        say(b, 0, "node %d silent (fault): frame 0x%x lost", k + 1, (unsigned)op->id);
        return;
    }
    if (bus_off(b, k, t)) {
        say(b, 1, "node %d is bus-off: frame 0x%x dropped (4_4_1_can.adoc, Status: a bus-off node "
            "shall not transmit)", k + 1, (unsigned)op->id);
        return;
    }
    CanNode *n = &b->node[k];
    if (n->nQueue == CANBUS_QUEUE) {
        say(b, 1, "node %d: %d frames already wait for the bus: frame 0x%x dropped", k + 1,
            CANBUS_QUEUE, (unsigned)op->id);
        return;
    }
    CanFrame *f = &n->queue[n->nQueue++];
    memset(f, 0, sizeof *f);
    f->id = op->id;
    f->ide = op->ide;
    f->rtr = op->rtr;
    f->dl = op->dataLength;
    memcpy(f->data, op->data, op->dataLength);   /* <= 8: checked by lsbus_can_read */
}

int canbus_receive(CanBus *b, int k, const uint8_t *buf, size_t size, double t) {
    if (k >= b->p.nNodes) {
        say(b, 1, "node %d sends, but nNodes = %d: its %zu bytes of operations are ignored", k + 1,
            b->p.nNodes, size);
        return 0;
    }
    int bad = 0;
    size_t pos = 0;
    LsBusCanOp op;
    LsBusResult r;
    while ((r = lsbus_can_read(buf, size, &pos, &op)) != LSBUS_END) {
        if (r != LSBUS_OK) {
            format_error(b, k, &op, r);
            bad++;
            continue;
        }
        switch (op.op) {
        case LSBUS_CAN_OP_TRANSMIT:
            take_transmit(b, k, &op, t);
            break;
        case LSBUS_CAN_OP_FD_TRANSMIT:
        case LSBUS_CAN_OP_XL_TRANSMIT:
            say(b, 1, "node %d: %s: this bus simulates classic CAN only", k + 1, lsbus_op_name(op.op));
            format_error(b, k, &op, LSBUS_E_VALUE);
            bad++;
            break;
        case LSBUS_CAN_OP_CONFIGURATION:
            if (op.parameterType == LSBUS_CAN_CONFIG_CAN_BAUDRATE) {
                if (op.baudrate != (uint32_t)b->baudrate)
                    say(b, 0, "node %d: baud rate %u bit/s", k + 1, (unsigned)op.baudrate);
                b->baudrate = op.baudrate;
            } else if (op.parameterType == LSBUS_CAN_CONFIG_ARBITRATION_LOST_BEHAVIOR) {
                b->node[k].arbitrationLost = op.arbitrationLostBehavior;
            }   /* CAN FD / XL baud rates: no FD or XL frames are simulated */
            break;
        case LSBUS_CAN_OP_STATUS:
            b->node[k].status = op.status;
            say(b, 0, "node %d: status %u", k + 1, (unsigned)op.status);
            break;
        case LSBUS_CAN_OP_WAKEUP:
            for (int j = 0; j < b->p.nNodes; j++)
                if (j != k) {
                    LsBusBuffer o = outbox(b, j);
                    sent(b, j, &o, lsbus_can_append_wakeup(&o), "Wakeup");
                }
            break;
        default:
            /* Format Error, Confirm, Arbitration Lost, Bus Error: the bus's own
               notifications; a node has no reason to send them: ignored */
            say(b, 0, "node %d: %s ignored", k + 1, lsbus_op_name(op.op));
            break;
        }
    }
    return bad;
}

/* ---- the wire ---------------------------------------------------------------------- */

/* the order of the arbitration field on the wire, dominant (0) winning
   (ISO 11898-1, 10.4.2.2): base identifier, then RTR (standard) or SRR = 1
   (extended), then IDE, then the extension and RTR: a smaller key wins */
static uint64_t arbitration_key(const CanFrame *f) {
    if (f->ide == LSBUS_TRUE)
        return (uint64_t)((f->id >> 18) & 0x7FFu) << 21 | 1u << 20 | 1u << 19 |
               (uint64_t)(f->id & 0x3FFFFu) << 1 | f->rtr;
    return (uint64_t)(f->id & 0x7FFu) << 21 | (uint64_t)f->rtr << 20;
}

static void pop(CanNode *n) {
    memmove(&n->queue[0], &n->queue[1], (size_t)(n->nQueue - 1) * sizeof n->queue[0]);
    n->nQueue--;
}

/* the frame on the wire has ended at tEnd: delivered, or corrupted (fault) */
static void complete(CanBus *b) {
    const int s = b->sender;
    const CanFrame *f = &b->wire;
    b->busy = false;
    b->busyTime += b->wireBits / b->baudrate;
    if (b->p.faultCorruptId >= 0 && f->id == (uint32_t)b->p.faultCorruptId &&
        b->tStart >= b->p.faultStart) {
        /* 4_4_1_can.adoc, Bus Error: to every node; Is Sender for the sender,
           the primary error flag once, for the first receiver to detect it */
        bool primary = false;
        for (int j = 0; j < CANBUS_NODES; j++) {
            if (bus_off(b, j, b->tEnd)) continue;
            const bool isSender = j == s;
            const bool first = !isSender && !primary;
            if (first) primary = true;
            send_bus_error(b, j, f->id, LSBUS_CAN_CRC_ERROR,
                           first ? LSBUS_CAN_PRIMARY_ERROR_FLAG : LSBUS_CAN_SECONDARY_ERROR_FLAG,
                           isSender ? LSBUS_TRUE : LSBUS_FALSE);
        }
        b->nBusErrors++;
        say(b, 0, "t = %.6f s: frame 0x%x from node %d corrupted (fault): CRC Bus Error", b->tEnd,
            (unsigned)f->id, s + 1);
        return;
    }
    int receivers = 0;
    for (int j = 0; j < CANBUS_NODES; j++)
        if (j != s && !bus_off(b, j, b->tEnd)) {
            send_frame(b, j, f);
            receivers++;
        }
    /* Transmission and Acknowledge: no Confirm when every other node is bus-off */
    if (receivers > 0) send_confirm(b, s, f->id);
    b->nFrames++;
    say(b, 0, "t = %.6f s: frame 0x%x from node %d delivered to %d nodes (%d bits)", b->tEnd,
        (unsigned)f->id, s + 1, receivers, b->wireBits);
}

/* arbitration at time t among the first waiting frame of each node; the winner
   goes on the wire. ERROR_PASSIVE nodes only when no ERROR_ACTIVE one waits
   (4_4_1_can.adoc, Arbitration: the Suspend Transmission Time) */
static bool arbitrate(CanBus *b, double t) {
    int win = -1;
    for (int pass = 0; pass < 2 && win < 0; pass++)
        for (int k = 0; k < CANBUS_NODES; k++) {
            const CanNode *n = &b->node[k];
            if (n->nQueue == 0) continue;
            if (pass == 0 && n->status == LSBUS_CAN_ERROR_PASSIVE) continue;
            if (win < 0 || arbitration_key(&n->queue[0]) < arbitration_key(&b->node[win].queue[0]))
                win = k;
        }
    if (win < 0) return false;
    for (int k = 0; k < CANBUS_NODES; k++) {
        CanNode *n = &b->node[k];
        if (k == win || n->nQueue == 0) continue;
        b->nArbitrationLost++;
        say(b, 0, "t = %.6f s: node %d's frame 0x%x lost arbitration to 0x%x", t, k + 1,
            (unsigned)n->queue[0].id, (unsigned)b->node[win].queue[0].id);
        if (n->arbitrationLost == LSBUS_CAN_DISCARD_AND_NOTIFY) {
            send_arbitration_lost(b, k, n->queue[0].id);
            pop(n);
        }   /* BUFFER_AND_RETRANSMIT: it stays first in its queue, retried next */
    }
    b->wire = b->node[win].queue[0];
    pop(&b->node[win]);
    b->sender = win;
    b->busy = true;
    b->wireBits = canbus_frame_bits(&b->wire);
    b->tStart = t;
    b->tEnd = b->p.wireTime ? t + b->wireBits / b->baudrate : t;
    return true;
}

void canbus_advance(CanBus *b, double t) {
    /* a frame ends at tEnd; the next starts then, among the frames waiting by then */
    for (int guard = 0; guard < CANBUS_NODES * CANBUS_QUEUE + 1; guard++) {
        double now = t;
        if (b->busy) {   /* the next frame starts when this one ends */
            if (b->tEnd > t + CANBUS_TIME_EPS) return;
            now = b->tEnd;
            complete(b);
        }
        if (!arbitrate(b, now)) return;
    }
}

double canbus_next_event(const CanBus *b) { return b->busy ? b->tEnd : INFINITY; }

double canbus_due(const CanBus *b, int k, double t, size_t read) {
    if (b->node[k].nOut > read) return t;
    if (!b->busy || bus_off(b, k, b->tEnd)) return INFINITY;
    return b->tEnd;     /* the frame on the wire ends: its sender or a receiver */
}

double canbus_load(const CanBus *b, double t) {
    const double elapsed = t - b->t0;
    if (!(elapsed > 0)) return 0.0;
    double busy = b->busyTime;
    if (b->busy && b->p.wireTime && t > b->tStart)
        busy += fmin(t - b->tStart, b->tEnd - b->tStart);
    return busy / elapsed;
}

void canbus_consume(CanBus *b, int k, size_t n) {
    CanNode *node = &b->node[k];
    if (n >= node->nOut) {
        node->nOut = 0;
        return;
    }
    memmove(node->out, node->out + n, node->nOut - n);
    node->nOut -= n;
}
