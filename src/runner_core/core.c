/* The runner's stepping core, the one stepping loop: see core.h and
 * docs/developer/stepping-core.md. Compiled with -ffp-contract=off: factor * out +
 * offset stays a multiply and an add, as SSP 1.0's LinearTransformation is written
 * (and as Python computes it, in the tests' closed forms), never a fused multiply-add. */
#define _POSIX_C_SOURCE 200809L
#include "core.h"

#include <math.h>
#include <string.h>
#include <time.h>


static double now(void) {                     /* time.perf_counter(): CLOCK_MONOTONIC */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The FMUs' time is taken with the time-stamp counter (a few ns a read; the
 * monotonic clock's ~30 ns, four reads per unit and step, were a third of the
 * core's own time) and turned into seconds at the end of each
 * artibus_core_run by the counter's rate over the call against the clock. */
static unsigned long long stamp(void) {
#if defined(__x86_64__) || defined(__i386__)
    return __builtin_ia32_rdtsc();
#else
    return (unsigned long long)(1e9 * now());
#endif
}

/* the counter's rate over a call that began at (now(), stamp()) = (m0, c0):
 * seconds per count, to turn the FMUs' counts into seconds */
static double seconds_per_count(double m0, unsigned long long c0) {
    const double dm = now() - m0;
    const unsigned long long dc = stamp() - c0;
    return dc ? dm / (double)dc : 0.0;
}

unsigned long long artibus_stamp(void) {      /* lsbus.c's timing of the network's FMU calls */
    return stamp();
}

static void record(ac_sim *sim, long row, double t) {   /* row `row` of the result table at t */
    double *r = sim->table + (size_t)row * (size_t)sim->n_cols;
    r[0] = t;
    for (int i = 0; i < sim->n_runs; i++) {  /* runs of consecutive outputs: a copy each */
        const ac_rec_run *q = &sim->runs[i];
        for (int c = 0; c < q->n; c++)
            r[q->col + c] = q->src[c];
    }
}

static void propagate(ac_unit *u) {           /* the unit's inputs from its sources, then its C stimuli */
    for (int s = 0; s < u->n_sources; s++) {
        const ac_source *q = &u->sources[s];
        *q->dst = q->factor * *q->src + q->offset;
    }
    for (int s = 0; s < u->n_stimuli; s++) {
        const ac_stimulus *q = &u->stimuli[s];
        *q->dst = (q->has_base ? q->base : *q->dst) + (*q->value - q->minus);
    }
}

/* the Python callback for unit j (what: an AC_HOOK_*), if the unit has it: AC_OK or AC_HOOK */
static int hook(ac_sim *sim, int what, int j, long k, double t) {
    if (j >= 0 && !(sim->units[j].hooks & what))
        return AC_OK;
    return sim->hook(what, j, k, t) < 0 ? AC_HOOK : AC_OK;
}

/* the unit's inputs: the sources and C stimuli, then what Python adds (AC_HOOK_PROPAGATE) */
static int propagate_unit(ac_sim *sim, int j, long k, double t) {
    propagate(&sim->units[j]);
    return sim->units[j].hooks & AC_HOOK_PROPAGATE ? hook(sim, AC_HOOK_PROPAGATE, j, k, t) : AC_OK;
}

static int inputs_changed(const ac_unit *u) { /* set them only when the FMU does not hold them already */
    if (!u->n_in)
        return 0;
    if (!u->has_written)
        return 1;
    for (size_t i = 0; i < u->n_in; i++) {   /* memcmp(in, written) != 0, a few doubles: no call */
        unsigned long long a, b;
        memcpy(&a, &u->inp[i], sizeof a);
        memcpy(&b, &u->written[i], sizeof b);
        if (a != b)
            return 1;
    }
    return 0;
}

/* the unit's calls, FMI 2.0 or 3.0 (core.h) */
static fmi2Status set_inputs(ac_unit *u) {
    if (u->fmi == 3)
        return (fmi2Status)u->setFloat64(u->component, (const fmi3ValueReference *)u->in_vrs, u->n_in,
                                         u->inp, u->n_in);
    return u->setReal(u->component, u->in_vrs, u->n_in, u->inp);
}

static fmi2Status get_outputs(ac_unit *u) {
    if (u->fmi == 3)
        return (fmi2Status)u->getFloat64(u->component, (const fmi3ValueReference *)u->out_vrs, u->n_out,
                                         u->out, u->n_out);
    return u->getReal(u->component, u->out_vrs, u->n_out, u->out);
}

/* one step; 1 in *end when the FMU ends the simulation: FMI 3.0's terminateSimulation
 * (FMI 2.0's fmi2Discard with fmi2Terminated is Python's to ask, after AC_DO_STEP) */
static fmi2Status do_step(ac_unit *u, double t, int *end) {
    *end = 0;
    if (u->fmi == 3) {
        fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
        fmi3Float64 last = t;
        const fmi3Status st = u->doStep3(u->component, t, u->step, fmi3True, &event, &terminate, &early, &last);
        u->terminate = terminate ? 1 : 0;
        u->last_successful_time = last;
        *end = u->terminate;
        return (fmi2Status)st;
    }
    return u->doStep(u->component, t, u->step, fmi2True);
}

/* After a step that returned st (or asked to end, FMI 3.0): did the FMU end the simulation?
 * FMI 3.0: terminateSimulation (FMI 3.0 4.2.1); FMI 2.0: fmi2Discard with fmi2Terminated true
 * (FMI 2.0 4.2.3), its fmi2LastSuccessfulTime, NaN when it gives none. An FMU that cannot
 * say (its status functions fail or are missing) has not ended it. Sets u->terminate and
 * u->last_successful_time. */
static int unit_ended(ac_unit *u, fmi2Status st) {
    if (u->fmi == 3)
        return u->terminate;
    fmi2Boolean terminated = fmi2False;
    if (st != fmi2Discard || !u->getBooleanStatus
        || u->getBooleanStatus(u->component, fmi2Terminated, &terminated) != fmi2OK || !terminated)
        return 0;
    fmi2Real last = NAN;
    if (!u->getRealStatus || u->getRealStatus(u->component, fmi2LastSuccessfulTime, &last) != fmi2OK)
        last = NAN;
    u->terminate = 1;
    u->last_successful_time = last;
    return 1;
}

/* Where the step the plan does in base step [t, t + h] starts: at t + h - step when the plan
 * steps the unit in the last base step of its period (early 0); a sampled unit whose output the
 * bench's stated timing makes visible earlier is stepped `early` base steps before that, its
 * step still from its period's start (artibus.runner.plan: the sampled outputs' timing, issue 44) */
static double step_start(const ac_unit *u, double t, double h) {
    return t + h * (1 + u->early) - u->step;
}

/* its inputs set (write: they changed), then its step from t and its outputs read
 * (step: the plan steps it right after, as Gauss-Seidel's propagate, write,
 * step of one unit does): the FMU's calls within one pair of stamps, its
 * time. Returns AC_OK or the function that failed, its status in *st. */
static int call_unit(ac_unit *u, int write, int step, double t, fmi2Status *st) {
    const unsigned long long w = stamp();
    if (write) {
        *st = set_inputs(u);
        if (*st > fmi2Warning) {
            u->ticks += stamp() - w;
            return AC_SET_REAL;
        }
    }
    int failed = AC_OK;
    if (step) {
        int end;
        *st = do_step(u, t, &end);
        if (*st > fmi2Warning || end)
            failed = AC_DO_STEP;
        else if (u->n_out) {
            *st = get_outputs(u);
            if (*st > fmi2Warning)
                failed = AC_GET_REAL;
        }
    }
    u->ticks += stamp() - w;
    if (write) {                             /* the FMU holds them now */
        memcpy(u->written, u->inp, u->n_in * sizeof(double));
        u->has_written = 1;
    }
    return failed;
}

static void no_failure(ac_sim *sim) {       /* no failure yet (fail() fills these) */
    sim->ended_unit = -1;
    sim->fail_unit = -1;
    sim->fail_function = AC_OK;
    sim->fail_status = 0;
    sim->fail_k = -1;
}

static int fail(ac_sim *sim, int unit, int function, fmi2Status st, long k) {
    sim->fail_unit = unit;
    sim->fail_function = function;
    sim->fail_status = (int)st;
    sim->fail_k = k;
    return function;
}

/* --- the CAN network's tick (artibus.can.Network.tick, see core.h) ----------------- */

static unsigned char crc8h2f[256];           /* can._CRC8H2F */
static int crc8h2f_made;

static void make_crc8h2f(void) {
    for (int i = 0; i < 256; i++) {
        unsigned c = (unsigned)i;
        for (int b = 0; b < 8; b++)
            c = (c & 0x80) ? ((c << 1) ^ 0x2F) & 0xFF : (c << 1) & 0xFF;
        crc8h2f[i] = (unsigned char)c;
    }
    crc8h2f_made = 1;
}

/* The codec's functions are static, called directly (inlined) in the tick;
 * the exported artibus_can_* below are for the tests. */
static unsigned e2e_crc(const unsigned char *data, int dlc, unsigned data_id) {
    if (!crc8h2f_made)                       /* can.e2e_crc */
        make_crc8h2f();
    unsigned crc = 0xFF;
    for (int i = 1; i < dlc; i++)
        crc = crc8h2f[crc ^ data[i]];
    return crc8h2f[(crc ^ data_id) & 0xFF] ^ 0xFF;
}

/* frame_bits' two loops over the frame's bits a byte at a time: the CRC-15
 * register (polynomial 0x4599, most significant bit first) after 8 more bits,
 * and the stuffing run's state after 8 more bits. A run's state: 0..7 =
 * 4 * (the last bit) + (equal bits in a row - 1), 8 = none yet (the start). */
static unsigned short crc15_byte[256];
static unsigned char stuff_next[9][256], stuff_count[9][256];
static unsigned char stuff_count7[9][128];   /* the stuff bits among 7 bits (the CRC's last) */
static int can_tables_made;

static int stuff_step(int state, int b, int *stuffed) {      /* can.frame_bits' loop, one bit */
    if (state < 8 && (state >> 2) == b) {
        const int run = (state & 3) + 2;
        if (run == 5) {                      /* a complement bit; it starts the next run */
            ++*stuffed;
            return 4 * !b;
        }
        return 4 * b + run - 1;
    }
    return 4 * b;
}

static void make_can_tables(void) {
    for (int i = 0; i < 256; i++) {
        unsigned crc = (unsigned)i << 7;
        for (int k = 0; k < 8; k++)
            crc = (crc & 0x4000) ? ((crc << 1) & 0x7FFF) ^ 0x4599 : (crc << 1) & 0x7FFF;
        crc15_byte[i] = (unsigned short)crc;
        for (int st = 0; st < 9; st++) {
            int state = st, stuffed = 0;
            for (int k = 7; k >= 0; k--)
                state = stuff_step(state, (i >> k) & 1, &stuffed);
            stuff_next[st][i] = (unsigned char)state;
            stuff_count[st][i] = (unsigned char)stuffed;
            if (i < 128) {
                state = st, stuffed = 0;
                for (int k = 6; k >= 0; k--)
                    state = stuff_step(state, (i >> k) & 1, &stuffed);
                stuff_count7[st][i] = (unsigned char)stuffed;
            }
        }
    }
    can_tables_made = 1;
}

#if defined(__GNUC__)
/* the tables made when the library is loaded, before any thread can use them
 * (a sweep's threads run cores at once); elsewhere at the first use */
__attribute__((constructor)) static void make_tables(void) {
    make_crc8h2f();
    make_can_tables();
}
#endif

static unsigned crc15_bit(unsigned crc, unsigned bit) {
    return (bit ^ (crc >> 14)) ? ((crc << 1) & 0x7FFF) ^ 0x4599 : (crc << 1) & 0x7FFF;
}

/* can.frame_bits in two parts. The frame's head, the same in every frame of a
 * message: SOF 0, ID, RTR 0, IDE 0, r0 0, DLC: 3 bits (SOF, ID10, ID9), then two
 * whole bytes (ID8..ID1; ID0, RTR, IDE, r0, DLC): the CRC-15 register
 * (polynomial 0x4599, ISO 11898-1), the stuffing run's state and the stuff
 * bits after it. */
static void frame_head(unsigned id, int dlc, unsigned *crc, int *state, int *stuffed) {
    if (!can_tables_made)
        make_can_tables();
    const int head[3] = {0, (int)(id >> 10) & 1, (int)(id >> 9) & 1};
    const unsigned char bytes[2] = {(unsigned char)((id >> 1) & 0xFF),
                                    (unsigned char)(((id & 1) << 7) | ((unsigned)dlc & 0xF))};
    unsigned c = 0;
    int st = 8, n = 0;
    for (int i = 0; i < 3; i++) {
        c = crc15_bit(c, (unsigned)head[i]);
        st = stuff_step(st, head[i], &n);
    }
    for (int b = 0; b < 2; b++) {
        c = ((c << 8) & 0x7FFF) ^ crc15_byte[((c >> 7) ^ bytes[b]) & 0xFF];
        n += stuff_count[st][bytes[b]];
        st = stuff_next[st][bytes[b]];
    }
    *crc = c, *state = st, *stuffed = n;
}

/* ... then the data bytes, and the CRC's 15 bits (stuffed too): its first 8 as
 * a byte, its last 7 */
static int frame_bits_after(unsigned crc, int state, int stuffed, const unsigned char *data, int dlc) {
    for (int b = 0; b < dlc; b++) {
        crc = ((crc << 8) & 0x7FFF) ^ crc15_byte[((crc >> 7) ^ data[b]) & 0xFF];
        stuffed += stuff_count[state][data[b]];
        state = stuff_next[state][data[b]];
    }
    stuffed += stuff_count[state][crc >> 7];
    state = stuff_next[state][crc >> 7];
    stuffed += stuff_count7[state][crc & 0x7F];
    return 19 + 8 * dlc + 15 + stuffed + 10 + 3;
}

AC_EXPORT int artibus_can_frame_bits(unsigned id, const unsigned char *data, int dlc) {
    unsigned crc;                            /* can.frame_bits, the same count */
    int state, stuffed;
    frame_head(id, dlc, &crc, &state, &stuffed);
    return frame_bits_after(crc, state, stuffed, data, dlc);
}

/* the raw bits' place in the frame: bit i of the raw value (0 = least significant) */
static int bit_place(const ac_can_signal *s, int i) {
    if (!s->big_endian)
        return s->start + i;                 /* little-endian: byte p / 8, bit p % 8 */
    /* big-endian (cantools.utils.start_bit): the most significant bit at network bit
     * q0 = 8 (start / 8) + 7 - start % 8, then on in network order (bit 7 of byte 0 first) */
    const int q = 8 * (s->start / 8) + (7 - s->start % 8) + (s->length - 1 - i);
    return 8 * (q / 8) + (7 - q % 8);
}

static double round_half_even(double x) {   /* Python's round(x): rint without libm */
    const double two52 = 4503599627370496.0; /* 2^52: from here on every double is an integer */
    if (!(fabs(x) < two52))
        return x;
    return x < 0 ? -((-x + two52) - two52) : (x + two52) - two52;
}

static int encode_signal(const ac_can_signal *s, double v, unsigned char *data, int dlc) {
    /* cantools: raw = round((v - offset) / scale), half to even (Python's round);
     * bitstruct refuses a raw value its bits cannot hold (OverflowError) */
    const double r = round_half_even((v - s->offset) / s->scale);
    if (!isfinite(r) || fabs(r) > 9.0e15)
        return 1;
    const long long raw = (long long)r;
    const long long span = 1LL << s->length;
    if (s->is_signed ? (raw < -span / 2 || raw > span / 2 - 1) : (raw < 0 || raw > span - 1))
        return 1;
    const unsigned long long u = (unsigned long long)raw;
    if (!s->big_endian) {                    /* bits start .. start + length - 1 of the frame read little-endian */
        if (s->start < 0 || s->start + s->length > 8 * dlc)
            return 1;
        const unsigned long long w = (u & ((1ULL << s->length) - 1)) << s->start;
        for (int b = s->start / 8; b <= (s->start + s->length - 1) / 8; b++)
            data[b] |= (unsigned char)(w >> (8 * b));
        return 0;
    }
    for (int i = 0; i < s->length; i++) {
        const int p = bit_place(s, i);
        if (p < 0 || p >= 8 * dlc)
            return 1;
        if ((u >> i) & 1)
            data[p / 8] |= (unsigned char)(1u << (p % 8));
    }
    return 0;
}

static double decode_signal(const ac_can_signal *s, const unsigned char *data) {
    unsigned long long u = 0;
    if (!s->big_endian) {
        for (int b = s->start / 8; b <= (s->start + s->length - 1) / 8; b++)
            u |= (unsigned long long)data[b] << (8 * b);
        u = (u >> s->start) & ((1ULL << s->length) - 1);
    } else {
        for (int i = 0; i < s->length; i++) {
            const int p = bit_place(s, i);
            u |= (unsigned long long)((data[p / 8] >> (p % 8)) & 1) << i;
        }
    }
    long long raw = (long long)u;
    if (s->is_signed && (u >> (s->length - 1)) & 1)
        raw -= 1LL << s->length;
    if (s->integer)                          /* cantools: raw * scale + offset, in integers */
        return (double)(raw * s->iscale + s->ioffset);
    return (double)raw * s->scale + s->offset;
}

AC_EXPORT unsigned artibus_can_e2e_crc(const unsigned char *data, int dlc, unsigned data_id) {
    return e2e_crc(data, dlc, data_id);
}

AC_EXPORT int artibus_can_encode(const ac_can_signal *s, double v, unsigned char *data, int dlc) {
    return encode_signal(s, v, data, dlc);
}

AC_EXPORT double artibus_can_decode(const ac_can_signal *s, const unsigned char *data) {
    return decode_signal(s, data);
}

static long floordiv(long a, long b) {       /* Python's a // b */
    if (b == 1)
        return a;
    long q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0)))
        q--;
    return q;
}

/* Network._deliver's end: the signals decoded into the receivers' inputs */
static void decode_into(const ac_can_message *m, const unsigned char *d) {
    for (int j = 0; j < m->n_signals; j++) {
        const ac_can_signal *s = &m->signals[j];
        const double v = decode_signal(s, d);
        for (int r = 0; r < s->n_receivers; r++)
            *s->receivers[r].dst = s->receivers[r].factor * v;
    }
}

/* Network._encode: message m's frame from its senders' outputs with the alive
 * counter into d (8 bytes), byte 0 left for the E2E CRC; 1 when a value is
 * outside its signal's range or its raw bits */
static int encode_frame(const ac_can_message *m, int counter, unsigned char *d) {
    memcpy(d, m->fixed, 8);
    for (int j = 0; j < m->n_signals; j++) {
        const ac_can_signal *s = &m->signals[j];
        if (!s->src)                         /* the AliveCounter: the network fills it */
            continue;
        const double v = s->factor * *s->src;
        if (!(isfinite(v) && s->minimum <= v && v <= s->maximum))
            return 1;
        if (encode_signal(s, v, d, m->dlc))
            return 1;
    }
    d[1] |= (unsigned char)counter;          /* AliveCounter: bits 8-11 */
    return 0;
}

/* The frame's E2E CRC into d[0] and its bits on the wire (can.frame_bits), both
 * functions of bytes 1..dlc-1 alone: a frame repeats every 16 cycles while its
 * signals hold, so the last frame of each counter value is kept with them (as
 * can.frame_bits' lru_cache; the bytes after dlc are 0) */
static int crc_and_bits(ac_can_message *m, unsigned char *d) {
    unsigned long long key = 0;
    for (int b = 1; b < 8; b++)
        key |= (unsigned long long)d[b] << (8 * b);
    const int slot = d[1] & 0x0F;            /* its counter */
    if (m->seen_bits[slot] && m->seen[slot] == key) {
        d[0] = m->seen_crc[slot];
        return m->seen_bits[slot];
    }
    d[0] = (unsigned char)e2e_crc(d, m->dlc, m->data_id);
    m->seen[slot] = key;
    m->seen_crc[slot] = d[0];
    m->seen_bits[slot] = frame_bits_after(m->head_crc, m->head_state, m->head_stuffed, d, m->dlc);
    return m->seen_bits[slot];
}

/* Network._deliver: the receivers' E2E check, then the signals decoded into
 * their inputs. Its CRC check (e2e_crc(data, data_id) != data[0]: rejected,
 * "crc") is not redone: the core runs only without faults and tamper, so the
 * frame read here is the one encode_frame made this tick, whose byte 0 is
 * that CRC over the same bytes; the check always passes and rejected_crc
 * stays 0, as Python counts it. The counter checks may reject (a reference
 * counter from before this run), so they stay. */
static void deliver(ac_can_message *m, const unsigned char *d, long tick) {
    const int counter = d[1] & 0x0F;
    if (m->last_counter >= 0) {
        const int delta = ((counter - m->last_counter) % 16 + 16) % 16;
        long allowed = floordiv(tick - m->good_tick, m->ratio);
        allowed = allowed < 1 ? 1 : allowed > 15 ? 15 : allowed;
        if (delta == 0) {
            m->rejected++;
            m->rejected_repeated++;
            return;
        }
        if (delta > allowed) {
            m->rejected++;
            m->rejected_sequence++;
            m->last_counter = counter;
            return;
        }
    }
    m->last_counter = counter;
    m->good_tick = tick;
    decode_into(m, d);
}

/* Network.tick(tick, t) without faults: returns -1, or the index of the message
 * whose frame could not be encoded */
static int can_tick(ac_can *c, long tick, double t) {
    unsigned char frames[64][8];
    int due[64], bits_of[64];
    long busy = 0;
    for (int i = 0; i < c->n_messages; i++) {
        ac_can_message *m = &c->messages[i];
        due[i] = m->ratio == 1 || tick % m->ratio == 0;
        if (!due[i])
            continue;
        unsigned char *d = frames[i];       /* Network._produce, ._encode */
        m->produced++;
        const int counter = m->counter;
        m->counter = (m->counter + 1) % 16;
        if (encode_frame(m, counter, d))
            return i;
        bits_of[i] = crc_and_bits(m, d);
    }
    for (int i = 0; i < c->n_messages; i++) {   /* on the wire in identifier order */
        if (!due[i])
            continue;
        ac_can_message *m = &c->messages[i];
        const int bits = bits_of[i];
        busy += bits;
        const long end = busy - 3;           /* end of its EOF */
        if (end > m->end_bits)
            m->end_bits = end;
        m->sent++;
        m->bits += bits;
        if (c->frames < c->frame_cap) {
            c->frame_tick[c->frames] = tick;
            c->frame_stamp[c->frames] = t + (double)end * c->tau;
            unsigned char *f = c->frame_data + 16 * (size_t)c->frames;
            memset(f, 0, 16);
            f[0] = (unsigned char)(m->id & 0xFF);
            f[1] = (unsigned char)(m->id >> 8);
            f[4] = (unsigned char)m->dlc;
            memcpy(f + 8, frames[i], (size_t)m->dlc);
        }
        c->frames++;
    }
    for (int i = 0; i < c->n_messages; i++) {   /* the receivers read their buffers */
        ac_can_message *m = &c->messages[i];
        if (due[i])
            deliver(m, frames[i], tick);
        m->since[c->ticks] = (double)floordiv(tick - m->good_tick, m->ratio);
    }
    c->ticks++;
    return -1;
}

/* Network.settle: each message's frame from its senders' outputs with its
 * next counter (not advanced), delivered to its receivers as the first frame
 * they see (no reference counter: the CRC always fits, so it is accepted);
 * then the receivers' E2E state reset (no reference counter, the frame
 * counting as the cycle before tick 0). Nothing is sent or counted. */
AC_EXPORT int artibus_core_can_settle(ac_can *c) {
    for (int i = 0; i < c->n_messages; i++) {
        ac_can_message *m = &c->messages[i];
        unsigned char d[8];
        if (encode_frame(m, m->counter, d))
            return i;
        d[0] = (unsigned char)e2e_crc(d, m->dlc, m->data_id);
        decode_into(m, d);
        m->last_counter = -1;
        m->good_tick = -(long)m->ratio;
    }
    return -1;
}

AC_EXPORT void artibus_core_record_start(ac_sim *sim) { record(sim, 0, sim->start); }

/* fmi2GetReal of its outputs, its time in ticks; then its typed outputs (Python) */
static int read_unit(ac_sim *sim, int j, long k, double t, fmi2Status *st) {
    ac_unit *u = &sim->units[j];
    if (u->n_out) {
        const unsigned long long w = stamp();
        *st = get_outputs(u);
        u->ticks += stamp() - w;
        if (*st > fmi2Warning)
            return AC_GET_REAL;
    }
    return hook(sim, AC_HOOK_READ, j, k, t);
}

/* its Real inputs when they changed, then its typed ones (Python) */
static int write_unit(ac_sim *sim, int j, long k, double t, fmi2Status *st) {
    ac_unit *u = &sim->units[j];
    int failed = AC_OK;
    if (inputs_changed(u) && (failed = call_unit(u, 1, 0, 0.0, st)))
        return failed;
    return hook(sim, AC_HOOK_WRITE, j, k, t);
}

static int settled(double b, double x) {     /* |b - x| <= 1e-12 + 1e-12 |x|, NaN never, inf only on itself */
    const double tol = 1e-12;
    return b == x || (isfinite(x) && fabs(b - x) <= tol + tol * fabs(x));
}

/* every input within tolerance of its value at the round's start (before), the typed ones the same */
static int round_settled(ac_sim *sim, const double *before, int *done) {
    size_t at = 0;
    *done = 1;
    for (int j = 0; j < sim->n_units && *done; j++) {
        const ac_unit *u = &sim->units[j];
        for (size_t i = 0; i < u->n_in && *done; i++)
            *done = settled(before[at + i], u->inp[i]);
        at += u->n_in;
    }
    if (*done && sim->hook) {
        const int r = sim->hook(AC_HOOK_SETTLED, -1, -1, 0.0);
        if (r < 0)
            return AC_HOOK;
        *done = r == 0;
    }
    return AC_OK;
}

/* one round's first half: each unit of the order read, its inputs propagated
 * (Gauss-Seidel: its own, if it has sources; Jacobi: every unit's) */
static int settle_reads(ac_sim *sim, ac_settle *z, double t0) {
    fmi2Status st = fmi2OK;
    int failed;
    for (int o = 0; o < z->n_order; o++) {
        const int j = z->order[o];
        const ac_unit *u = &sim->units[j];
        if ((failed = read_unit(sim, j, -1, t0, &st)))
            return fail(sim, j, failed, st, -1);
        if (!z->gauss_seidel) {              /* self._propagate(None, start) */
            for (int q = 0; q < sim->n_units; q++)
                if ((failed = propagate_unit(sim, q, -1, t0)))
                    return fail(sim, q, failed, st, -1);
        } else if (u->n_sources || u->n_stimuli || (u->hooks & AC_HOOK_PROPAGATE)) {
            if ((failed = propagate_unit(sim, j, -1, t0)))
                return fail(sim, j, failed, st, -1);
        }
    }
    return AC_OK;
}

/* the round's second half: the network settled, each unit of the order propagated and
 * written, every unit read */
static int settle_writes(ac_sim *sim, ac_settle *z, double t0) {
    fmi2Status st = fmi2OK;
    int failed;
    if (z->can) {                            /* the C CAN network's settle */
        const int bad = artibus_core_can_settle(z->can);
        if (bad >= 0)
            return fail(sim, bad, AC_CAN, fmi2OK, -1);
        z->can_settles++;
    } else if (z->hook_settle && sim->hook(AC_HOOK_SETTLE, -1, -1, t0) < 0) {
        return fail(sim, -1, AC_HOOK, fmi2OK, -1);
    }
    for (int o = 0; o < z->n_order; o++) {
        const int j = z->order[o];
        const ac_unit *u = &sim->units[j];
        if ((u->n_sources || u->n_stimuli || (u->hooks & AC_HOOK_PROPAGATE))
            && (failed = propagate_unit(sim, j, -1, t0)))
            return fail(sim, j, failed, st, -1);
        if ((failed = write_unit(sim, j, -1, t0, &st)))
            return fail(sim, j, failed, st, -1);
    }
    for (int j = 0; j < sim->n_units; j++)
        if ((failed = read_unit(sim, j, -1, t0, &st)))
            return fail(sim, j, failed, st, -1);
    return AC_OK;
}

static int settle_rounds(ac_sim *sim, ac_settle *z) {
    const double t0 = sim->start;
    int failed;
    double *before = z->before;
    for (int it = 0; it < z->max_iter; it++) {
        z->rounds = it + 1;
        size_t at = 0;                       /* before = the watched units' inputs */
        for (int j = 0; j < sim->n_units; j++) {
            const ac_unit *u = &sim->units[j];
            if (u->n_in)
                memcpy(before + at, u->inp, u->n_in * sizeof(double));
            at += u->n_in;
        }
        if (sim->hook && sim->hook(AC_HOOK_SNAPSHOT, -1, -1, t0) < 0)
            return fail(sim, -1, AC_HOOK, fmi2OK, -1);
        if ((failed = settle_reads(sim, z, t0)) || (failed = settle_writes(sim, z, t0)))
            return failed;
        int done;
        if ((failed = round_settled(sim, before, &done)))
            return fail(sim, -1, failed, fmi2OK, -1);
        if (done)
            return AC_OK;
    }
    return AC_UNSETTLED;
}

/* the initialisation's end: each unit fmi2/fmi3ExitInitializationMode, then read */
static int exit_initialization(ac_sim *sim, ac_settle *z) {
    fmi2Status st = fmi2OK;
    int failed;
    for (int j = 0; j < sim->n_units; j++) {
        ac_unit *u = &sim->units[j];
        const unsigned long long w = stamp();
        st = u->fmi == 3 ? (fmi2Status)z->exit_init[j].fmi3(u->component) : z->exit_init[j].fmi2(u->component);
        u->ticks += stamp() - w;
        if (st > fmi2Warning)
            return fail(sim, j, AC_EXIT_INIT, st, -1);
        if ((failed = read_unit(sim, j, -1, sim->start, &st)))
            return fail(sim, j, failed, st, -1);
    }
    return AC_OK;
}

AC_EXPORT int artibus_core_settle(ac_sim *sim, ac_settle *z) {
    const double m0 = now();
    const unsigned long long c0 = stamp();
    no_failure(sim);
    z->rounds = 0;
    z->can_settles = 0;
    for (int j = 0; j < sim->n_units; j++) {
        sim->units[j].ticks = 0;
        sim->units[j].has_written = 0;       /* every connected input is set at least once */
    }
    int result = settle_rounds(sim, z);
    if (result == AC_OK && z->exit_init)
        result = exit_initialization(sim, z);
    const double second = seconds_per_count(m0, c0);
    unsigned long long ticks = 0;
    for (int j = 0; j < sim->n_units; j++) {
        ticks += sim->units[j].ticks;
        sim->units[j].ticks = 0;
    }
    z->fmu_wall += (double)ticks * second;
    return result;
}

static int run_steps(ac_sim *sim, long k0, long k1);

AC_EXPORT int artibus_core_run(ac_sim *sim, long k0, long k1) {
    const double m0 = now();
    const unsigned long long c0 = stamp();
    for (int j = 0; j < sim->n_units; j++)
        sim->units[j].ticks = 0;
    for (int i = 0; sim->can && i < sim->can->n_messages; i++) {
        ac_can_message *m = &sim->can->messages[i];
        frame_head(m->id, m->dlc, &m->head_crc, &m->head_state, &m->head_stuffed);
    }
    if (sim->can)
        sim->can->stamps = 0;
    if (sim->lsbus)
        sim->lsbus->stamps = sim->lsbus->fmu_stamps = 0;
    const int result = run_steps(sim, k0, k1);
    const double second = seconds_per_count(m0, c0);
    for (int j = 0; j < sim->n_units; j++) {
        sim->units[j].wall += (double)sim->units[j].ticks * second;
        sim->units[j].ticks = 0;
    }
    if (sim->can) {
        sim->can->wall += (double)sim->can->stamps * second;
        sim->can->stamps = 0;
    }
    if (sim->lsbus) {
        sim->lsbus->wall += (double)sim->lsbus->stamps * second;
        sim->lsbus->fmu_wall += (double)sim->lsbus->fmu_stamps * second;
        sim->lsbus->stamps = sim->lsbus->fmu_stamps = 0;
    }
    sim->wall += now() - m0;
    return result;
}

/* the networks' ticks at base step k, before its operations: self.can.tick(k // can_ratio, t) */
static int tick_networks(ac_sim *sim, long k, double t) {
    if (sim->can && (sim->can->ratio == 1 || k % sim->can->ratio == 0)) {
        const unsigned long long w = stamp();
        const int bad = can_tick(sim->can, k / sim->can->ratio, t);
        sim->can->stamps += stamp() - w;
        if (bad >= 0)
            return fail(sim, bad, AC_CAN, fmi2OK, k);
    }
    if (sim->lsbus && (sim->lsbus->ratio == 1 || k % sim->lsbus->ratio == 0)) {   /* LsBusSteering.tick */
        const unsigned long long w = stamp();
        const int bad = artibus_lsbus_tick(sim->lsbus, t);
        sim->lsbus->stamps += stamp() - w;
        if (bad)
            return fail(sim, -1, AC_LSBUS, fmi2OK, k);
    }
    if (sim->hook_ratio && k % sim->hook_ratio == 0 && sim->hook(AC_HOOK_TICK, -1, k / sim->hook_ratio, t) < 0)
        return fail(sim, -1, AC_HOOK, fmi2OK, k);
    return AC_OK;
}

/* op i of the plan at base step k (t its start): AC_OK or the function that failed, with
 * *st; *skip 1 when it did the next op too (a write and the step right after it) */
static int do_op(ac_sim *sim, int i, int end, long k, double t, fmi2Status *st, int *skip) {
    const double h = sim->h;
    const int j = sim->op_unit[i];
    ac_unit *u = &sim->units[j];
    const int step = sim->op_kind[i] == AC_WRITE && i + 1 < end && sim->op_kind[i + 1] == AC_STEP
                     && sim->op_unit[i + 1] == j;
    int failed = AC_OK;
    *skip = 0;
    switch (sim->op_kind[i]) {
    case AC_PROPAGATE:
        return propagate_unit(sim, j, k, t);
    case AC_WRITE:                                   /* its inputs set, and its step if next */
        if (u->hooks & AC_HOOK_WRITE) {              /* (its typed inputs between the two) */
            if ((failed = write_unit(sim, j, k, t, st)) || !step)
                return failed;
            *skip = 1;
            failed = call_unit(u, 0, 1, step_start(u, t, h), st);
        } else {
            const int write = inputs_changed(u);
            *skip = step;
            if (write || step)
                failed = call_unit(u, write, step, step_start(u, t, h), st);
        }
        break;
    default:                                         /* its step from t + h - u.step */
        failed = call_unit(u, 0, 1, step_start(u, t, h), st);
        break;
    }
    if ((u->hooks & AC_HOOK_READ) && !failed && (step || sim->op_kind[i] == AC_STEP))
        failed = hook(sim, AC_HOOK_READ, j, k, t);   /* its typed outputs */
    return failed;
}

/* The rest of base step k after the unit of op i ended the simulation:
 * its outputs read (getters are allowed after fmi2Discard: its values at its last successful
 * time), then the ops the plan has after it, so that every unit ends the step at t + h; a unit
 * that ends the simulation there too is read as well. AC_OK, or a failure (ended_unit set). */
static int finish_step(ac_sim *sim, int i, int end, long k, double t) {
    fmi2Status st = fmi2OK;
    int failed;
    const int ended = sim->op_unit[i];
    sim->ended_unit = ended;
    if ((failed = read_unit(sim, ended, k, t, &st)))
        return fail(sim, ended, failed, st, k);
    for (i++; i < end; i++) {
        const int j = sim->op_unit[i];
        ac_unit *u = &sim->units[j];
        if (sim->op_kind[i] == AC_PROPAGATE)
            failed = propagate_unit(sim, j, k, t);
        else if (sim->op_kind[i] == AC_WRITE)
            failed = write_unit(sim, j, k, t, &st);
        else if ((failed = call_unit(u, 0, 1, step_start(u, t, sim->h), &st)) == AC_DO_STEP && unit_ended(u, st))
            failed = read_unit(sim, j, k, t, &st);
        else if (!failed)
            failed = hook(sim, AC_HOOK_READ, j, k, t);
        if (failed)
            return fail(sim, j, failed, st, k);
    }
    sim->ended_unit = -1;
    return AC_OK;
}

static int run_steps(ac_sim *sim, long k0, long k1) {
    const double h = sim->h;
    no_failure(sim);
    for (long k = k0; k < k1; k++) {
        const double t = sim->start + (double)k * h;         /* t = start + k * h */
        const int p = (int)(k % sim->period);
        int failed = tick_networks(sim, k, t);
        if (failed)
            return failed;
        const int end = sim->op_start[p + 1];
        for (int i = sim->op_start[p]; i < end; i++) {
            fmi2Status st = fmi2OK;
            int skip;
            failed = do_op(sim, i, end, k, t, &st, &skip);
            i += skip;
            if (failed == AC_DO_STEP && unit_ended(&sim->units[sim->op_unit[i]], st)) {
                const int j = sim->op_unit[i];               /* the FMU's own end: a normal end */
                if ((failed = finish_step(sim, i, end, k, t)))
                    return failed;
                record(sim, k + 1, sim->start + (double)(k + 1) * h);
                return fail(sim, j, AC_ENDED, st, k);
            }
            if (failed)
                return fail(sim, sim->op_unit[i], failed, st, k);
        }
        record(sim, k + 1, sim->start + (double)(k + 1) * h);   /* t = start + (k + 1) * h */
    }
    return AC_OK;
}
