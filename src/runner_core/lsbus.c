/* The FMI-LS-BUS 1.0 importer of the stepping core: see lsbus.h. Each function
 * does what the method of artibus.runner.lsbus.Network (or .Fmu) of the same
 * name does, in the same order, so that the FMUs see the same calls with the
 * same arguments as under the Python master. The sections cited:
 *
 * - FMI 3.0.2 docs/2_2_common_mechanisms.adoc, Clocks: the nodes' time-based
 *   periodic Tx clocks are set by the importer in Event Mode at
 *   t0 + shift + k * interval; a countdown clock's next tick is read with
 *   fmi3GetIntervalDecimal (qualifier fmi3IntervalChanged);
 * - FMI 3.0.2 5.2.2 (Event Mode of Co-Simulation): the inputs, fmi3SetClock,
 *   fmi3SetBinary, then fmi3UpdateDiscreteStates, repeated while
 *   discreteStatesNeedUpdate; no clock set after an update that asked for no
 *   further iteration;
 * - fmi-ls-bus 1.0 docs/4____network_abstraction.adoc, "Time-based Tx Clocks",
 *   "Rx Clocks" (triggered: a zero-size Tx_Data activates nothing), "Bus
 *   Terminal"; docs/2____common_concepts.adoc, "Composition with dedicated Bus
 *   Simulation FMU" (node Tx_Data -> bus NodeK.Rx_Data, bus NodeK.Tx_Data ->
 *   node Rx_Data); docs/4_4_1_can.adoc, Transmit (the frames on the wire) and
 *   "Arbitration" (the instant's frames given to the bus in one Event Mode). */
#define _POSIX_C_SOURCE 200809L
#include "lsbus.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define EPS 1e-9                    /* lsbus.EPS: two times this close are one instant */
#define MAX_ITERATIONS 100          /* lsbus.MAX_ITERATIONS */
#define MAX_TERMS 64                /* terminals of one FMU (artibus.runner.lsbus_core checks) */
#define CHANGED 2                   /* fmi3IntervalChanged */

/* --- failures: the FMU, the function and its status, or the master's refusal --- */

static int fail_call(ac_lsbus *n, int fmu, const char *function, fmi3Status st) {
    n->fail_fmu = fmu;
    n->fail_status = (int)st;
    snprintf(n->fail_function, sizeof n->fail_function, "%s", function);
    n->message[0] = '\0';
    return 1;
}

static int refuse(ac_lsbus *n, int fmu, const char *message) {
    n->fail_fmu = fmu;
    n->fail_status = 0;
    n->fail_function[0] = '\0';
    snprintf(n->message, sizeof n->message, "%s", message);
    return 1;
}

#define CALL(n, i, name, call)                              \
    do {                                                    \
        const unsigned long long s0_ = (n)->timed ? artibus_stamp() : 0; \
        const fmi3Status st_ = (call);                      \
        if ((n)->timed)                                     \
            (n)->fmu_stamps += artibus_stamp() - s0_;       \
        if (st_ > fmi3Warning)                              \
            return fail_call((n), (i), (name), st_);        \
    } while (0)

#define TRY(x)                                              \
    do {                                                    \
        if (x)                                              \
            return 1;                                       \
    } while (0)

static int bus_index(const ac_lsbus *n) { return n->n_nodes; }

/* --- lsbus.Terminal: the periodic Tx clock's ticks --- */

/* the first tick after the instant t, later than t + EPS (Terminal.next_tick) */
static double next_tick(const ac_ls_terminal *q, double t0, double t) {
    const double k = floor((t + EPS - t0 - q->shift) / q->period) + 1.0;
    return t0 + q->shift + (k > 0.0 ? k : 0.0) * q->period;
}

/* whether it ticks at t (Terminal.ticks_at; Python's round is half to even, as rint) */
static int ticks_at(const ac_ls_terminal *q, double t0, double t) {
    if (q->period <= 0.0)
        return 0;
    const double k = rint((t - t0 - q->shift) / q->period);
    return k >= 0.0 && fabs(t0 + q->shift + k * q->period - t) <= EPS;
}

/* --- lsbus.Fmu: the standard's call order (FMI 3.0.2, 5.2.2) --- */

/* Event Mode with nothing set yet: from Step Mode, or a further Event Mode at the
 * same time after an update that asked for no iteration */
static int fresh_event(ac_lsbus *n, int i) {
    ac_ls_fmu *f = &n->fmus[i];
    if (f->mode == AC_LS_UPDATED && !f->need) {
        CALL(n, i, "fmi3EnterStepMode", f->enterStepMode(f->instance));
        f->mode = AC_LS_STEP;
    }
    if (f->mode == AC_LS_STEP) {
        CALL(n, i, "fmi3EnterEventMode", f->enterEventMode(f->instance));
        f->mode = AC_LS_EVENT;
        f->need = 0;
        f->n_events++;
    }
    return 0;
}

/* fmi3SetClock of vrs, all ticking; refused in Step Mode and after an update that
 * asked for no further iteration, before the FMU sees it */
static int set_clocks(ac_lsbus *n, int i, const fmi3ValueReference *vrs, size_t nvr) {
    ac_ls_fmu *f = &n->fmus[i];
    if (!nvr)
        return 0;
    if (f->mode == AC_LS_STEP)
        return refuse(n, i, "fmi3SetClock in Step Mode (clocks tick in Event Mode, FMI 3.0.2, 5.2.2)");
    if (f->mode == AC_LS_UPDATED && !f->need) {
        char m[sizeof n->message];
        int at = snprintf(m, sizeof m, "fmi3SetClock(value reference");
        for (size_t j = 0; j < nvr && at < (int)sizeof m - 16; j++)
            at += snprintf(m + at, sizeof m - (size_t)at, " %u", (unsigned)vrs[j]);
        snprintf(m + at, sizeof m - (size_t)at, ") after fmi3UpdateDiscreteStates, which asked for no further "
                 "event iteration: refused (FMI 3.0.2, 5.2.2: clocks, then inputs, then fmi3UpdateDiscreteStates)");
        return refuse(n, i, m);
    }
    fmi3Clock on[MAX_TERMS * 2];
    for (size_t j = 0; j < nvr; j++)
        on[j] = fmi3ClockActive;
    CALL(n, i, "fmi3SetClock", f->setClock(f->instance, vrs, nvr, on));
    return 0;
}

static int update(ac_lsbus *n, int i) {
    ac_ls_fmu *f = &n->fmus[i];
    fmi3Boolean need = fmi3False, terminate = fmi3False, nominals = fmi3False, values = fmi3False;
    fmi3Boolean defined = fmi3False;
    fmi3Float64 t_next = 0.0;
    CALL(n, i, "fmi3UpdateDiscreteStates",
         f->updateDiscreteStates(f->instance, &need, &terminate, &nominals, &values, &defined, &t_next));
    if (terminate)
        return refuse(n, i, "asked to terminate the simulation");
    f->mode = AC_LS_UPDATED;
    f->need = need ? 1 : 0;
    f->next_event = defined ? t_next : INFINITY;
    return 0;
}

/* fmi3UpdateDiscreteStates until the FMU asks for no further iteration */
static int settle(ac_lsbus *n, int i) {
    for (int k = 0; k < MAX_ITERATIONS; k++) {
        TRY(update(n, i));
        if (!n->fmus[i].need)
            return 0;
    }
    return refuse(n, i, "discreteStatesNeedUpdate after 100 event iterations");
}

static int leave_event_mode(ac_lsbus *n, int i) {
    ac_ls_fmu *f = &n->fmus[i];
    if (f->mode != AC_LS_STEP) {
        if (f->mode == AC_LS_EVENT)
            TRY(settle(n, i));
        CALL(n, i, "fmi3EnterStepMode", f->enterStepMode(f->instance));
        f->mode = AC_LS_STEP;
    }
    return 0;
}

/* --- routing through the terminals --- */

static int append(ac_lsbus *n, int i, ac_ls_terminal *q, const unsigned char *data, size_t len) {
    if (q->len + len > q->cap)
        return refuse(n, i, "more data routed to one terminal within an instant than its buffer holds");
    memcpy(q->buf + q->len, data, len);
    q->len += len;
    if (!q->seq)                     /* a new key of the dict: at its end */
        q->seq = ++n->seq;
    return 0;
}

static unsigned le32(const unsigned char *p) {
    return (unsigned)p[0] | (unsigned)p[1] << 8 | (unsigned)p[2] << 16 | (unsigned)p[3] << 24;
}

/* the CAN Transmit operations of a delivered buffer into the frames on the wire, each
 * once per instant (lsbus.can_transmits, Network.wire_frames; 4_4_1_can.adoc,
 * Transmit: OP Code 0x10 u32, Length u32, ID u32, Ide u8, Rtr u8, DL u16, Data) */
static int record_transmits(ac_lsbus *n, const unsigned char *buf, size_t len) {
    size_t pos = 0;
    while (pos + 8 <= len) {
        const unsigned code = le32(buf + pos), length = le32(buf + pos + 4);
        if (length < 8 || pos + length > len)
            break;
        if (code == 0x10 && length >= 16) {
            const unsigned id = le32(buf + pos + 8);
            const int ide = buf[pos + 12];
            const int dl = buf[pos + 14] | buf[pos + 15] << 8;
            const unsigned char *data = buf + pos + 16;
            if (length == 16u + (unsigned)dl) {
                int seen = 0;
                for (long j = n->frames - 1; j >= 0 && n->frame_t[j] == n->t && !seen; j--)
                    seen = n->frame_id[j] == id && n->frame_ide[j] == ide && n->frame_dl[j] == dl
                           && !memcmp(n->pool + n->frame_at[j], data, (size_t)dl);
                if (!seen) {
                    if (n->frames >= n->frame_cap || n->pool_used + dl > n->pool_cap)
                        return refuse(n, bus_index(n), "the record of the frames on the wire is full");
                    n->frame_t[n->frames] = n->t;
                    n->frame_id[n->frames] = id;
                    n->frame_ide[n->frames] = ide;
                    n->frame_dl[n->frames] = dl;
                    n->frame_at[n->frames] = n->pool_used;
                    memcpy(n->pool + n->pool_used, data, (size_t)dl);
                    n->pool_used += dl;
                    n->frames++;
                }
            }
        }
        pos += length;
    }
    return 0;
}

/* Network._route from the bus's terminal k: to its node's Rx_Data (pending), copied
 * before the next FMU is called; zero-size data activate no clock */
static int route_from_bus(ac_lsbus *n, int k, const unsigned char *data, size_t len) {
    const int node = n->fmus[bus_index(n)].terms[k].peer;
    if (!len || node < 0)
        return 0;
    TRY(record_transmits(n, data, len));
    return append(n, node, &n->fmus[node].terms[0], data, len);
}

/* --- the bus simulation FMU --- */

static int bus_read_intervals(ac_lsbus *n) {
    ac_ls_fmu *b = &n->fmus[bus_index(n)];
    fmi3ValueReference vrs[MAX_TERMS];
    int which[MAX_TERMS];
    size_t m = 0;
    for (int k = 0; k < b->n_terms; k++)
        if (b->terms[k].countdown) {
            which[m] = k;
            vrs[m++] = b->terms[k].tx_clock;
        }
    if (!m)
        return 0;
    fmi3Float64 iv[MAX_TERMS];
    fmi3IntervalQualifier q[MAX_TERMS];
    CALL(n, bus_index(n), "fmi3GetIntervalDecimal", b->getIntervalDecimal(b->instance, vrs, m, iv, q));
    for (size_t j = 0; j < m; j++)
        if (q[j] == CHANGED) {
            ac_ls_terminal *t = &b->terms[which[j]];
            t->tick = n->t + iv[j];
            if (!t->tick_seq)
                t->tick_seq = ++n->seq;
        }
    return 0;
}

/* the bus terminals whose countdown tick is due now, in the order they were announced */
static int bus_due_now(const ac_lsbus *n, int *now) {
    const ac_ls_fmu *b = &n->fmus[bus_index(n)];
    int m = 0;
    for (int k = 0; k < b->n_terms; k++)
        if (b->terms[k].tick_seq && b->terms[k].tick <= n->t + EPS) {
            int j = m++;
            for (; j > 0 && b->terms[now[j - 1]].tick_seq > b->terms[k].tick_seq; j--)
                now[j] = now[j - 1];
            now[j] = k;
        }
    return m;
}

/* the Tx clocks of now ticked (removed from the announced ticks), fmi3UpdateDiscreteStates,
 * their Tx_Data routed to the nodes */
static int bus_tick_now(ac_lsbus *n, const int *now, int m) {
    ac_ls_fmu *b = &n->fmus[bus_index(n)];
    fmi3ValueReference vrs[MAX_TERMS];
    for (int j = 0; j < m; j++) {
        b->terms[now[j]].tick_seq = 0;
        vrs[j] = b->terms[now[j]].tx_clock;
    }
    TRY(set_clocks(n, bus_index(n), vrs, (size_t)m));
    TRY(update(n, bus_index(n)));
    if (!m)
        return 0;
    for (int j = 0; j < m; j++)
        vrs[j] = b->terms[now[j]].tx_data;
    size_t sizes[MAX_TERMS];
    fmi3Binary data[MAX_TERMS];
    CALL(n, bus_index(n), "fmi3GetBinary", b->getBinary(b->instance, vrs, (size_t)m, sizes, data, (size_t)m));
    for (int j = 0; j < m; j++) {
        if (sizes[j] && !data[j])     /* the FMU's own error: refused, never read */
            return refuse(n, bus_index(n), "fmi3GetBinary gave a NULL value of size > 0");
        TRY(route_from_bus(n, now[j], data[j], sizes[j]));
    }
    return 0;
}

/* Network._bus_settle: in the bus's Event Mode fmi3UpdateDiscreteStates, then the
 * countdown Tx clocks due now in the further iterations it asks for */
static int bus_settle(ac_lsbus *n) {
    const int bus = bus_index(n);
    if (n->fmus[bus].mode == AC_LS_EVENT)
        TRY(update(n, bus));
    for (int k = 0; k < MAX_ITERATIONS; k++) {
        int now[MAX_TERMS];
        TRY(bus_read_intervals(n));
        const int m = bus_due_now(n, now);
        if (!m || !n->fmus[bus].need)
            return 0;
        TRY(bus_tick_now(n, now, m));
    }
    return refuse(n, bus, "the bus simulation FMU asked for further event iterations with clocks "
                          "due at the same instant 100 times (MAX_ITERATIONS)");
}

/* Network._bus_due: the bus's operations due at this instant (frames that end now) */
static int bus_due(ac_lsbus *n) {
    const int bus = bus_index(n);
    int now[MAX_TERMS];
    int m = bus_due_now(n, now);
    if (!m && !n->bus_flagged)
        return 0;
    n->bus_flagged = 0;
    TRY(fresh_event(n, bus));
    if (n->fmus[bus].mode == AC_LS_EVENT) {    /* announced by the step that ended here */
        TRY(bus_read_intervals(n));
        m = bus_due_now(n, now);
    }
    TRY(bus_tick_now(n, now, m));
    return bus_settle(n);
}

/* Network._bus_send: the nodes' Tx_Data of the instant into the bus's NodeK.Rx_Data in
 * one Event Mode, in the order they came (4_4_1_can.adoc, "Arbitration") */
static int bus_send(ac_lsbus *n) {
    const int bus = bus_index(n);
    ac_ls_fmu *b = &n->fmus[bus];
    int order[MAX_TERMS], m = 0;
    for (int k = 0; k < b->n_terms; k++)
        if (b->terms[k].seq) {
            int j = m++;
            for (; j > 0 && b->terms[order[j - 1]].seq > b->terms[k].seq; j--)
                order[j] = order[j - 1];
            order[j] = k;
        }
    fmi3ValueReference clocks[MAX_TERMS], vrs[MAX_TERMS];
    size_t sizes[MAX_TERMS];
    fmi3Binary data[MAX_TERMS];
    for (int j = 0; j < m; j++) {
        const ac_ls_terminal *q = &b->terms[order[j]];
        clocks[j] = q->rx_clock;
        vrs[j] = q->rx_data;
        sizes[j] = q->len;
        data[j] = q->buf;
    }
    TRY(fresh_event(n, bus));
    TRY(set_clocks(n, bus, clocks, (size_t)m));
    CALL(n, bus, "fmi3SetBinary", b->setBinary(b->instance, vrs, (size_t)m, sizes, data, (size_t)m));
    for (int j = 0; j < m; j++) {
        b->terms[order[j]].len = 0;
        b->terms[order[j]].seq = 0;
    }
    return bus_settle(n);
}

/* --- the nodes --- */

/* Network._node_event: one Event Mode of node i: its Float64 inputs (inputs), its
 * clocks (the Tx clock if ticking, the Rx clock if data arrived), Rx_Data, a triggered
 * output Tx clock read (fmi3GetClock), Tx_Data of an active Tx clock copied into its bus
 * terminal's batch while the clock is active, then fmi3UpdateDiscreteStates while it asks
 * (FMI 3.0.2, 2.2.8 "Getting and Setting Variable Values", 2.3: the update ends the
 * activation) */
static int node_event(ac_lsbus *n, int i, int ticking, int inputs) {
    ac_ls_fmu *f = &n->fmus[i];
    ac_ls_terminal *q = &f->terms[0];
    const int rx = q->seq != 0;      /* pending.pop((f, terminal)) */
    q->seq = 0;
    TRY(fresh_event(n, i));
    for (int j = 0; inputs && j < n->n_inputs; j++)
        if (n->inputs[j].node == i)
            CALL(n, i, "fmi3SetFloat64", f->setFloat64(f->instance, &n->inputs[j].vr, 1, &n->inputs[j].value, 1));
    fmi3ValueReference clocks[2];
    size_t nc = 0;
    if (ticking)
        clocks[nc++] = q->tx_clock;
    if (rx)
        clocks[nc++] = q->rx_clock;
    TRY(set_clocks(n, i, clocks, nc));
    if (rx) {
        const size_t size = q->len;
        const fmi3Binary data = q->buf;
        CALL(n, i, "fmi3SetBinary", f->setBinary(f->instance, &q->rx_data, 1, &size, &data, 1));
        q->len = 0;
    }
    int sending = ticking;
    if (q->tx_output) {              /* fmi-ls-bus 1.0, "Triggered Tx Clocks" */
        fmi3Clock active = fmi3ClockInactive;
        CALL(n, i, "fmi3GetClock", f->getClock(f->instance, &q->tx_clock, 1, &active));
        sending = sending || active;
    }
    if (sending) {
        size_t size = 0;
        fmi3Binary data = NULL;
        CALL(n, i, "fmi3GetBinary", f->getBinary(f->instance, &q->tx_data, 1, &size, &data, 1));
        if (size && !data)           /* the FMU's own error: refused, never read */
            return refuse(n, i, "fmi3GetBinary gave a NULL value of size > 0");
        /* zero-size Tx_Data: no Rx clock (4____network_abstraction.adoc); copied before the update */
        if (size && q->peer >= 0)
            TRY(append(n, bus_index(n), &n->fmus[bus_index(n)].terms[q->peer], data, size));
    }
    return settle(n, i);
}

/* Network._instant: every event at n->t, in the order of lsbus.py's docstring */
static int instant(ac_lsbus *n) {
    const int bus = bus_index(n);
    n->instants++;
    TRY(bus_due(n));                                  /* 1. the bus's operations due now */
    for (int i = 0; i < n->n_nodes; i++) {            /* 2. the nodes in their order */
        ac_ls_fmu *f = &n->fmus[i];
        const int ticking = ticks_at(&f->terms[0], n->t0, n->t);
        /* FMI 3.0.2, 4.2, fmi3EnterEventMode: after eventHandlingNeeded or at its nextEventTime */
        const int woke = f->flagged || f->next_event <= n->t + EPS;
        f->flagged = 0;
        if (!ticking && !f->terms[0].seq && !woke && f->mode != AC_LS_EVENT)
            continue;
        TRY(node_event(n, i, ticking, ticking || woke || f->mode == AC_LS_EVENT));
    }
    int batch = 0;                                    /* 3. the instant's Tx_Data to the bus */
    for (int k = 0; k < n->fmus[bus].n_terms; k++)
        batch |= n->fmus[bus].terms[k].seq != 0;
    if (batch)
        TRY(bus_send(n));
    int it;                                           /* 4. what the bus answered, to its nodes */
    for (it = 0; it < MAX_ITERATIONS; it++) {
        int first = -1;
        for (int i = 0; i < n->n_nodes; i++)
            if (n->fmus[i].terms[0].seq && (first < 0 || n->fmus[i].terms[0].seq < n->fmus[first].terms[0].seq))
                first = i;
        if (first < 0)
            break;
        TRY(node_event(n, first, 0, 0));
    }
    if (it == MAX_ITERATIONS) {
        char m[sizeof n->message];
        snprintf(m, sizeof m, "t = %.17g: the nodes keep sending in the same instant (%d rounds)", n->t,
                 MAX_ITERATIONS);
        return refuse(n, -1, m);
    }
    if (n->fmus[bus].mode == AC_LS_EVENT)
        TRY(bus_settle(n));
    return 0;
}

/* Network._next_point: the next bus communication point (a periodic Tx tick, a countdown
 * tick of the bus, the bus's nextEventTime), at most stop */
static double next_point(const ac_lsbus *n, double stop) {
    double t_next = stop;
    for (int i = 0; i < n->n_nodes; i++)
        for (int k = 0; k < n->fmus[i].n_terms; k++) {
            const ac_ls_terminal *q = &n->fmus[i].terms[k];
            if (q->period > 0.0) {
                const double tk = next_tick(q, n->t0, n->t);
                t_next = tk < t_next ? tk : t_next;
            }
            /* a triggered output Tx clock's next tick, announced as nextEventTime */
            const double te = n->fmus[i].next_event;
            if (q->tx_output && te > n->t + EPS && te < t_next)
                t_next = te;
        }
    const ac_ls_fmu *b = &n->fmus[bus_index(n)];
    if (b->next_event > n->t + EPS && b->next_event < t_next)
        t_next = b->next_event;
    for (int k = 0; k < b->n_terms; k++)
        if (b->terms[k].tick_seq && b->terms[k].tick > n->t + EPS && b->terms[k].tick < t_next)
            t_next = b->terms[k].tick;
    return t_next;
}

/* Network._step_all: every FMU out of Event Mode, then each fmi3DoStep to t_next */
static int step_all(ac_lsbus *n, double t_next) {
    const int all = n->n_nodes + 1;
    for (int i = 0; i < all; i++)
        TRY(leave_event_mode(n, i));
    for (int i = 0; i < all; i++) {
        ac_ls_fmu *f = &n->fmus[i];
        fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
        fmi3Float64 last = n->t;
        CALL(n, i, "fmi3DoStep",
             f->doStep(f->instance, n->t, t_next - n->t, fmi3True, &event, &terminate, &early, &last));
        if (terminate)
            return refuse(n, i, "asked to terminate the simulation");
        if (i == bus_index(n) && event)
            n->bus_flagged = 1;
        else if (event)
            f->flagged = 1;
    }
    n->t = t_next;
    return 0;
}

/* Network.advance(t_end): the instant now, then the steps to t_end cut at the bus
 * communication points, each with its instant; t_end's own is the next tick's */
static int advance(ac_lsbus *n, double t_end) {
    for (;;) {
        TRY(instant(n));
        TRY(step_all(n, next_point(n, t_end)));
        if (n->t >= t_end - EPS)
            return 0;
    }
}

AC_EXPORT int artibus_lsbus_tick(ac_lsbus *n, double t) {
    n->ticks++;
    for (int j = 0; j < n->n_inputs; j++) {           /* LsBusSteering.tick: the values of the tick */
        ac_ls_input *in = &n->inputs[j];
        if (in->src)
            in->value = *in->src;
        else {
            ac_ls_fmu *s = &n->fmus[in->src_node];
            CALL(n, in->src_node, "fmi3GetFloat64", s->getFloat64(s->instance, &in->src_vr, 1, &in->value, 1));
        }
    }
    TRY(advance(n, t + n->period));
    for (int j = 0; j < n->n_outputs; j++) {          /* the outputs onto the plant's inputs */
        ac_ls_output *o = &n->outputs[j];
        ac_ls_fmu *f = &n->fmus[o->node];
        CALL(n, o->node, "fmi3GetFloat64", f->getFloat64(f->instance, &o->vr, 1, o->dst, 1));
    }
    return 0;
}

AC_EXPORT int artibus_lsbus_set_clocks(ac_lsbus *n, int fmu, const fmi3ValueReference *vrs, size_t nvr) {
    if (fmu < 0 || fmu > n->n_nodes || nvr > 2 * MAX_TERMS)
        return refuse(n, -1, "no such FMU, or too many clocks");
    return set_clocks(n, fmu, vrs, nvr);
}
