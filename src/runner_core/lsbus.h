/* The importer side of FMI-LS-BUS 1.0 in the stepping core (issue 24): the
 * network of an artibus.runner.lsbus_bench bench (FMI 3.0 Co-Simulation node
 * FMUs with Event Mode on a bus simulation FMU such as CanBus) ticked by the
 * core at each network period, as artibus.runner.lsbus.Network.advance does it:
 * the same calls, in the same order, on the same instances (FMPy's, set up in
 * Python), so that the results are the Python master's bit for bit. See
 * lsbus.py's module docstring for the order within an instant and lsbus.c for
 * the sections of the standards each step follows.
 *
 * Plain C11, no heap use: every array is Python's (artibus.runner.lsbus_core).
 */
#ifndef ARTIBUS_RUNNER_LSBUS_H
#define ARTIBUS_RUNNER_LSBUS_H

#include <stddef.h>

#include "fmi3FunctionTypes.h"

/* the stepping core's exported functions (core.c and lsbus.c; core.h includes this header) */
#if defined(__GNUC__)
#define AC_EXPORT __attribute__((visibility("default")))
#else
#define AC_EXPORT
#endif

/* where an FMU is (lsbus.Fmu.mode): in Event Mode before fmi3UpdateDiscreteStates,
 * after it ('need' says whether it asked for a further iteration), in Step Mode */
enum { AC_LS_EVENT = 0, AC_LS_UPDATED = 1, AC_LS_STEP = 2 };

/* one bus terminal (lsbus.Terminal): its four members and, for a node, its
 * time-based Tx clock's period and shift (period 0: none, e.g. the bus's
 * countdown clocks) */
typedef struct {
    fmi3ValueReference rx_data, tx_data, rx_clock, tx_clock;
    double period, shift;
    int countdown;                  /* 1: the Tx clock is a countdown clock (read with fmi3GetIntervalDecimal) */
    int tx_output;                  /* 1: the Tx clock is a triggered output clock (read with fmi3GetClock) */
    int peer;                       /* a node's terminal: its bus terminal's index; a bus terminal: its node's, -1 none */
    /* a bus countdown tick announced (Network.bus_ticks): its time and its place in the
     * dict's insertion order (seq 0: none) */
    double tick;
    long tick_seq;
    /* the data routed to this terminal in the instant (a node's Rx_Data: Network's pending;
     * a bus terminal's NodeK.Rx_Data: the batch), in the dict's insertion order (seq 0: none) */
    unsigned char *buf;
    size_t len, cap;
    long seq;
} ac_ls_terminal;

/* one FMI 3.0 instance (lsbus.Fmu) and its functions */
typedef struct {
    fmi3Instance instance;
    fmi3EnterEventModeTYPE *enterEventMode;
    fmi3EnterStepModeTYPE *enterStepMode;
    fmi3UpdateDiscreteStatesTYPE *updateDiscreteStates;
    fmi3SetClockTYPE *setClock;
    fmi3SetBinaryTYPE *setBinary;
    fmi3GetBinaryTYPE *getBinary;
    fmi3GetClockTYPE *getClock;
    fmi3GetIntervalDecimalTYPE *getIntervalDecimal;
    fmi3SetFloat64TYPE *setFloat64;
    fmi3GetFloat64TYPE *getFloat64;
    fmi3DoStepTYPE *doStep;
    int n_terms;
    ac_ls_terminal *terms;
    int mode, need;
    double next_event;              /* nextEventTime of its last update, INFINITY: none */
    long n_events;                  /* Event Mode entries (fmi3EnterEventMode) */
    int flagged;                    /* a node's last fmi3DoStep returned eventHandlingNeeded */
} ac_ls_fmu;

/* an input set at the node's Tx ticks: the plant's output (src), or, src NULL, another
 * node's Float64 read at the tick */
typedef struct {
    int node;
    fmi3ValueReference vr;
    const double *src;
    int src_node;
    fmi3ValueReference src_vr;
    double value;                   /* as of the tick */
} ac_ls_input;

/* an output read after the network's steps of a tick, into *dst (the plant's stimulus) */
typedef struct {
    int node;
    fmi3ValueReference vr;
    double *dst;
} ac_ls_output;

typedef struct {
    int n_nodes;
    ac_ls_fmu *fmus;                /* n_nodes + 1: the nodes in their order within an instant, then the bus */
    int ratio;                      /* base steps per tick */
    double period;                  /* s */
    double t0, t;                   /* the network's start and its time */
    int n_inputs, n_outputs;
    ac_ls_input *inputs;
    ac_ls_output *outputs;
    int bus_flagged;                /* the bus's last fmi3DoStep asked for an event */
    long seq;                       /* the last insertion number given out */
    long ticks, instants;
    /* the frames on the wire (Network.wire_frames): each CAN Transmit a bus terminal's
     * Tx_Data delivers, once per instant; its data in pool from frame_at */
    long frame_cap, frames;
    double *frame_t;
    unsigned *frame_id;
    int *frame_ide, *frame_dl;
    long *frame_at;
    unsigned char *pool;
    long pool_cap, pool_used;
    /* on failure: the FMU (n_nodes: the bus), the function, its status, and why */
    int fail_fmu, fail_status;
    char fail_function[48];
    char message[512];
    unsigned long long stamps;      /* its time within one artibus_core_run (time-stamp counter) */
    double wall;                    /* seconds, added at the end of each artibus_core_run */
    int timed;                      /* 1: time the FMUs' calls (benchmarks/suite.py; two stamps a call) */
    unsigned long long fmu_stamps;  /* of which inside the FMUs' calls (CALL), within one run */
    double fmu_wall;                /* seconds, as wall */
} ac_lsbus;

/* the stepping core's time-stamp counter (core.c: a few ns a read) */
unsigned long long artibus_stamp(void);

/* One tick at t (artibus.runner.lsbus_bench.LsBusSteering.tick): the inputs read,
 * Network.advance(t + period), the outputs read. Returns 0, or 1 with fail_* and
 * message set (an FMU's call failed: fail_function; the master refused: message). */
int artibus_lsbus_tick(ac_lsbus *n, double t);

/* lsbus.Fmu.set_clocks on fmus[fmu], the standard's order checked (tests): 0 or 1, as above */
int artibus_lsbus_set_clocks(ac_lsbus *n, int fmu, const fmi3ValueReference *vrs, size_t nvr);

#endif
