/* The runner's stepping core (issues 13, 37): the one stepping loop of every
 * bench (artibus.runner.Simulation.run), in C, called with ctypes.
 *
 * Python sets the bench up, puts its FMUs into Initialization Mode, builds the
 * plan below and calls artibus_core_settle() (the initialisation's fixed point)
 * and artibus_core_run() for a range of base steps; the core calls the FMUs'
 * fmi2SetReal/fmi2DoStep/fmi2GetReal through their function pointers, on value
 * buffers Python allocated, and calls back into Python (ac_hook) for what runs
 * there. Plain C11, no Python headers, no heap use: every array is Python's (see
 * src/artibus/runner/core.py, _CoreStepper).
 *
 * A unit is an FMI 2.0 or an FMI 3.0 instance (ac_unit.fmi): FMI 3.0's
 * fmi3SetFloat64/fmi3DoStep/fmi3GetFloat64 take the same values in the same
 * order (nValues = nValueReferences: every variable the core reads or sets is
 * a scalar Float64, FMI 3.0 2.2.6.2), and fmi3DoStep says through its
 * out-arguments what FMI 2.0 says through fmi2Discard and fmi2GetBooleanStatus:
 * terminateSimulation ends the run (FMI 3.0 4.2.1). fmi3Status has fmi2Status's
 * values for OK .. Fatal (FMI 3.0 2.2.3), so one status type serves both.
 */
#ifndef ARTIBUS_RUNNER_CORE_H
#define ARTIBUS_RUNNER_CORE_H

#include <stddef.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"
#include "lsbus.h"

/* The structs below and lsbus.h's are the one declaration of the core's data:
 * their layout is generated into the library (gen_layout.py: artibus_core_layout,
 * each field's kind, offset and size), and Python's ctypes structures are built
 * from it (artibus.runner.layout). A field added here needs no change elsewhere
 * but its use. */

/* one connection into a unit's input: *dst = factor * *src + offset */
typedef struct {
    double *dst;                    /* the input's place in the unit's input buffer */
    const double *src;              /* the output's place in the source unit's output buffer */
    double factor, offset;
} ac_source;

/* an FMI-LS-BUS network's output onto a unit's input (the stimulus of
 * artibus.runner.lsbus_bench: f(t) = *value - minus, added to base or, has_base 0,
 * to the input's connection): *dst = (has_base ? base : *dst) + (*value - minus) */
typedef struct {
    double *dst;
    const double *value;            /* the network's output as of its last tick (lsbus.h) */
    double base, minus;
    int has_base;
} ac_stimulus;

/* A callback into Python (artibus.runner.core._Hooks) for what the core does not do in C:
 * a unit's Integer, Boolean, String and Enumeration variables (read with FMPy's calls) and
 * its stimuli (Python functions of time: artibus bode's sine, an LS-BUS network's outputs
 * in its Python master), and a network that ticks in Python (CAN with faults, a tamper
 * function or a real interface; an FMI-LS-BUS network the C master does not run). The
 * core calls it where the one stepping loop needs it (what, below; unit -1: the network's),
 * k the base step (-1 in the initialisation), t the time. Returns 0 (AC_HOOK_SETTLED: the
 * unit's typed inputs unchanged since AC_HOOK_SNAPSHOT), 1 (AC_HOOK_SETTLED: changed), or
 * -1: Python keeps the exception (an FMU call that failed, Ctrl-C) and the core stops with
 * AC_HOOK. */
typedef int ac_hook(int what, int unit, long k, double t);
enum {
    AC_HOOK_PROPAGATE = 1,          /* after the unit's sources: its typed sources, its stimuli */
    AC_HOOK_READ = 2,               /* after its fmi2GetReal: its typed outputs */
    AC_HOOK_WRITE = 4,              /* after its fmi2SetReal, before its step: its typed inputs */
    AC_HOOK_TICK = 8,               /* the network's tick k (unit -1), before the base step's operations */
    AC_HOOK_SETTLE = 16,            /* the network's settle in the initialisation (unit -1) */
    AC_HOOK_SNAPSHOT = 32,          /* a round of the initialisation begins: the typed inputs kept */
    AC_HOOK_SETTLED = 64            /* a round ends: are the unit's typed inputs the same? */
};

typedef struct {
    void *component;                /* fmi2Component or fmi3Instance */
    int fmi;                        /* 2: the fmi2 functions below are called, 3: the fmi3 ones */
    fmi2DoStepTYPE *doStep;
    fmi2GetRealTYPE *getReal;
    fmi2SetRealTYPE *setReal;
    fmi3DoStepTYPE *doStep3;
    fmi3GetFloat64TYPE *getFloat64;
    fmi3SetFloat64TYPE *setFloat64;
    double step;                    /* its communication step (s) */
    size_t n_out, n_in;
    const fmi2ValueReference *out_vrs;
    double *out;                    /* n_out: read by fmi2GetReal after each of its steps */
    const fmi2ValueReference *in_vrs;
    double *inp;                    /* n_in: its inputs */
    double *written;                /* n_in: the input values last set */
    int has_written;                /* 0: never set, the next write sets them */
    int n_sources;
    const ac_source *sources;
    double wall;                    /* seconds inside fmi2DoStep, fmi2GetReal, fmi2SetReal, accumulated */
    unsigned long long ticks;       /* the same in the processor's time-stamp counter, within one call */
    int terminate;                  /* FMI 3.0: its last fmi3DoStep's terminateSimulation */
    double last_successful_time;    /* FMI 3.0: its last fmi3DoStep's lastSuccessfulTime */
    int n_stimuli;                  /* applied after its sources */
    const ac_stimulus *stimuli;
    int hooks;                      /* AC_HOOK_PROPAGATE | _READ | _WRITE | _SNAPSHOT: what ac_sim.hook does for it */
    /* FMI 2.0: fmi2DoStep's fmi2Discard ends the run when fmi2Terminated is true (FMI 2.0 4.2.3) */
    fmi2GetBooleanStatusTYPE *getBooleanStatus;
    fmi2GetRealStatusTYPE *getRealStatus;
    int early;                      /* base steps before its period's end in which the plan steps it
                                     * (a sampled unit's stated timing: artibus.runner.plan); 0: the last */
} ac_unit;

/* what the plan does with a unit */
enum { AC_PROPAGATE = 0, AC_WRITE = 1, AC_STEP = 2 };

/* which functions failed (ac_sim.fail_function); AC_CAN: a frame could not be
 * encoded (a value outside its signal's range or its raw bits): fail_unit is
 * then the message's index, Python's encoder says why (artibus.can) */
/* AC_DO_STEP: fmi2DoStep/fmi3DoStep returned fmi2Discard or worse, or fmi3DoStep
 * asked to terminate the simulation (ac_unit.terminate) */
/* AC_LSBUS: the FMI-LS-BUS network's tick failed (ac_lsbus's fail_* and message say why) */
/* AC_HOOK: the Python callback failed (it keeps the exception); AC_ENDED: not a failure, an FMU
 * ended the simulation (fail_unit: which, its ac_unit.last_successful_time, NaN: none
 * given) in base step fail_k, which the others finished and which was recorded */
enum { AC_OK = 0, AC_DO_STEP = 1, AC_GET_REAL = 2, AC_SET_REAL = 3, AC_CAN = 4, AC_LSBUS = 7, AC_HOOK = 8,
       AC_ENDED = 9 };

/* --- the CAN network's tick (artibus.can.Network.tick without faults, log,
 * tamper or a real interface): the frames due at a tick in identifier order,
 * each signal encoded as cantools encodes it (strict), the alive counter and
 * the AUTOSAR E2E profile-2 CRC, the receivers' E2E check and cantools'
 * decode into their inputs; counts, bits (stuffing counted) and the cycles
 * since the last accepted frame per tick. */

typedef struct {
    double *dst;                    /* the receiver's input */
    double factor;                  /* DBC unit -> the input's unit */
} ac_can_receiver;

typedef struct {
    const double *src;              /* the sender's output (NULL: the AliveCounter, filled by the network) */
    double factor;                  /* the output's unit -> the DBC unit */
    double minimum, maximum;        /* the signal's range */
    double scale, offset;           /* cantools' conversion: raw = round((v - offset) / scale) */
    int integer;                    /* 1: an integer conversion (decoded raw * iscale + ioffset exactly) */
    long long iscale, ioffset;
    int start, length, big_endian, is_signed;
    int n_receivers;
    const ac_can_receiver *receivers;
} ac_can_signal;

typedef struct {
    unsigned id;                    /* 11-bit identifier */
    int dlc;                        /* data bytes, 2..8 */
    int ratio;                      /* cycle time / tick */
    unsigned data_id;               /* E2E data ID */
    unsigned char fixed[8];         /* the signals no connection feeds, packed (cantools) */
    int n_signals;
    const ac_can_signal *signals;
    /* state, as artibus.can.network._Message's */
    int counter;                    /* next counter to send */
    int last_counter;               /* the receivers' reference counter, -1: none */
    long good_tick;                 /* tick of the last accepted frame */
    long produced, sent, rejected, rejected_crc, rejected_repeated, rejected_sequence;
    long long bits;
    long long end_bits;             /* the longest (busy - 3) bits at the end of one of its frames, -1: none */
    double *since;                  /* per tick: cycles since the last accepted frame */
    /* its frames' first 19 bits (SOF .. DLC), the same in every frame: the CRC-15
     * register, the stuffing run's state and the stuff bits after them (the core
     * sets them at each artibus_core_run) */
    unsigned head_crc;
    int head_state, head_stuffed;
    /* the last frame of each counter value (bytes 1..7 as bits 8..63) with its E2E
     * CRC and its bits on the wire; seen_bits 0: none yet */
    unsigned long long seen[16];
    int seen_bits[16];
    unsigned char seen_crc[16];
} ac_can_message;

typedef struct {
    int n_messages;
    ac_can_message *messages;       /* in identifier order */
    int ratio;                      /* base steps per tick */
    double tau;                     /* 1 / bit rate (s) */
    long ticks, frames;
    /* every frame, if frame_cap > 0: its tick, stamp (s) and 16 bytes: id (4, little-endian), dlc (4), data (8) */
    long frame_cap;
    long *frame_tick;
    double *frame_stamp;
    unsigned char *frame_data;
    /* the network's own time: its ticks within one artibus_core_run in the
     * time-stamp counter (stamps), then added in seconds (wall) at its end */
    unsigned long long stamps;
    double wall;
} ac_can;

/* recording: n consecutive outputs from src into the row's columns col .. col + n - 1 */
typedef struct {
    const double *src;
    int col, n;
} ac_rec_run;

typedef struct {
    int n_units;
    ac_unit *units;
    /* the plan: base step k does ops op_start[k % period] .. op_start[k % period + 1] - 1,
     * each (op_kind[i], op_unit[i]) */
    int period;
    const int *op_start;            /* period + 1 */
    const int *op_kind;
    const int *op_unit;
    double start, h;                /* t = start + k * h */
    ac_can *can;                    /* NULL: no CAN network */
    /* recording: row r of table (n_cols doubles, row-major) is the time in column 0,
     * then each run's outputs in its columns (the columns of no run: not written) */
    int n_cols;                     /* the row's length */
    int n_runs;
    const ac_rec_run *runs;
    double *table;                  /* (steps + 1) * n_cols */
    /* on failure */
    int fail_unit, fail_function, fail_status;
    long fail_k;                    /* the base step that failed */
    double wall;                    /* seconds inside artibus_core_run, added (the FMUs' and the network's too) */
    ac_lsbus *lsbus;                /* NULL: no FMI-LS-BUS network; else ticked every lsbus->ratio base steps */
    ac_hook *hook;                  /* NULL: none needed (no unit's hooks, no hook_ratio) */
    int hook_ratio;                 /* base steps per tick of a network in Python (AC_HOOK_TICK), 0: none */
    int ended_unit;                 /* a failure after an FMU ended the run in the same base step: that FMU, else -1 */
} ac_sim;

/* The codec alone (tests against cantools): a frame's data from raw signal
 * values; a signal's value from a frame; the bits of a frame on the wire. */
int artibus_can_encode(const ac_can_signal *s, double v, unsigned char *data, int dlc);
double artibus_can_decode(const ac_can_signal *s, const unsigned char *data);
int artibus_can_frame_bits(unsigned id, const unsigned char *data, int dlc);
unsigned artibus_can_e2e_crc(const unsigned char *data, int dlc, unsigned data_id);

/* artibus.can.Network.settle on the network's messages (their counter in):
 * each frame encoded from its senders' outputs and decoded into its
 * receivers' inputs, their E2E state reset (last_counter -1, good_tick
 * -ratio). Returns -1, or the index of the message whose frame could not be
 * encoded (Python's encoder says why); the messages before it are done. */
int artibus_core_can_settle(ac_can *c);

/* The initialisation's fixed point of the connected inputs (between
 * the parameters and fmi2ExitInitializationMode), on the units' buffers:
 * up to max_iter rounds of: each unit of order[0..n_order-1] read
 * (fmi2GetReal) and its inputs propagated (Gauss-Seidel: its own, if it has
 * sources; Jacobi: every unit's), the network settled (can: NULL, none), each
 * unit of the order propagated and written (fmi2SetReal when its inputs
 * changed; has_written 0 on entry: every input set once), every unit read;
 * done when each input is within 1e-12 + 1e-12 |x| of its value before the
 * round (_settled). Then, if exit_init is given, each unit in turn
 * (units[0..n_units-1]) fmi2ExitInitializationMode and read. */
typedef union {                     /* a unit's exit, as its fmi */
    fmi2ExitInitializationModeTYPE *fmi2;
    fmi3ExitInitializationModeTYPE *fmi3;
} ac_exit_init;

typedef struct {
    const int *order;               /* n_order unit indices: Gauss-Seidel's order (Simulation.order) */
    int n_order;
    int gauss_seidel;               /* 0: Jacobi */
    int max_iter;                   /* MAX_INIT_ITERATIONS */
    ac_can *can;                    /* NULL: no network in C */
    int hook_settle;                /* 1: the network settles in Python (AC_HOOK_SETTLE) */
    double *before;                 /* scratch: the units' n_in summed */
    const ac_exit_init *exit_init;  /* n_units, or NULL: Python exits */
    /* results */
    double fmu_wall;                /* seconds inside fmi2GetReal/fmi2SetReal (time-stamp counter), added */
    int rounds;                     /* rounds begun */
    long can_settles;               /* the network's settles done */
} ac_settle;

enum { AC_UNSETTLED = 5, AC_EXIT_INIT = 6 };

/* Returns AC_OK, the failing function (ac_sim's fail_unit, fail_status set;
 * AC_CAN: fail_unit the message whose frame could not be encoded), or
 * AC_UNSETTLED (max_iter rounds done). */
int artibus_core_settle(ac_sim *sim, ac_settle *st);

/* Record row 0 at t = start (after the initialisation). */
void artibus_core_record_start(ac_sim *sim);

/* Base steps k0 .. k1 - 1, each recorded into row k + 1. Returns 0, or the
 * failing function (AC_DO_STEP, ...) with fail_unit/fail_status/fail_k set:
 * rows 0 .. fail_k are then filled; AC_ENDED: rows 0 .. fail_k + 1. */
int artibus_core_run(ac_sim *sim, long k0, long k1);

#endif
