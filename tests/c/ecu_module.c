/* ecu_module: the module ECU (src/models/SteeringECU/ecu.c) and the steering
 * actuators (src/models/SteeringActuator/actuator.c) with their shared stale
 * detection and fallback (src/models/common/can_fallback.c), built alone as
 * on an ECU: C99, <math.h>, no FMI headers, static objects, a 10 ms loop.
 * Checks: the two module ECUs together command exactly what TrainGuidance's
 * and ForceMinimization's algorithms command for the whole bus; a message
 * that stops is stale in the nStale-th cycle without a new counter, the
 * outputs hold for tHold, then ramp to 0 at rampRate (the cycle counts
 * worked out here from the parameters), only messages the module uses count,
 * recovery after nRecover fresh cycles with a slew back; a driving direction
 * neither forwards nor backwards is a fallback; backwards (the A6 end
 * leads) the ECUs of modules 1 and 2 command exactly what TrainGuidance and
 * ForceMinimization with backwards = true command (A6's angle as gamma1,
 * -v, the hinges through leading_hinges.h), module 3 steers nothing, and the
 * tractor ECU (module 1) decides the direction from v with its hysteresis; the actuator's lag and rate limit
 * against their closed forms; bad parameters named; never a NaN. Run by
 * ctest; exit status 1 on any failure. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ecu.h"
#include "actuator.h"

static int checks = 0, failures = 0;
#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

#define TS 0.01
/* the 36 m bus (ssp/parameters/Bus36m.ssv), the FMUs' defaults */
static const TgParams TG = { .l1 = 5.9, .lg1 = 3.15, .l2 = 9.05, .lg2 = 3.15, .l3 = 9.05,
                             .S4 = 14.0, .S6 = 36.0, .Ts = TS, .gamma4Max = 0.75, .gamma6Max = 0.75 };
static const FmParams FM = { .l1 = 5.9, .lg1 = 3.15, .l2 = 9.05, .lA3 = 3.15, .lg2 = 3.15,
                             .l3 = 9.05, .lA5 = 3.15, .gamma3Max = 0.75, .gamma5Max = 0.75 };

static SteeringEcu ecu1, ecu2, ecu3;
static TgGuidance tg;
static FmSteering fm;
static SteeringAct act;

static EcuParams params(int module) {
    EcuParams p = { .module = module, .tg = TG, .fm = FM, .nStale = 3, .nRecover = 5,
                    .tHold = 0.2, .rampRate = 0.1, .vDir = 0.05 };
    return p;
}

/* a drive: steering into a 17.5 m-ish circle and out, articulation following */
static EcuInputs drive(int k) {
    const double t = k * TS;
    EcuInputs in;
    memset(&in, 0, sizeof in);
    in.gamma1 = 0.35 * sin(0.2 * t) * (t < 30 ? 1.0 : 0.0);
    in.v = 3.0 + 0.5 * sin(0.1 * t);
    in.dPsi1 = 0.4 * sin(0.2 * t - 0.5);
    in.dPsi2 = 0.3 * sin(0.2 * t - 1.0);
    for (int i = 0; i < ECU_NMSG; i++) in.alive[i] = (double)(k % 16);
    return in;
}

static void same_algorithm_as_the_controllers(void) {
    EcuParams p2 = params(2), p3 = params(3);
    EcuInputs in = drive(0);
    CHECK(ecu_setup(&ecu2, &p2, &in) == 0 && ecu_setup(&ecu3, &p3, &in) == 0, "setup");
    tg_setup(&tg, &TG);
    fm_setup(&fm, &FM);
    tg_reset(&tg, in.gamma1);
    int mismatch = 0, moved = 0;
    for (int k = 1; k < 4000; k++) {
        in = drive(k);
        ecu_sample(&ecu2, &in);
        ecu_sample(&ecu3, &in);
        /* the direct benches: TrainGuidance, then ForceMinimization on its outputs */
        tg_sample(&tg, in.gamma1, in.v);
        fm_sample(&fm, in.gamma1, in.dPsi1, in.dPsi2, tg.gamma4, tg.gamma6);
        if (ecu2.cf.out[0] != fm.gamma3 || ecu2.cf.out[1] != tg.gamma4 ||
            ecu3.cf.out[0] != fm.gamma5 || ecu3.cf.out[1] != tg.gamma6 ||
            ecu2.cf.mode != CF_NORMAL || ecu3.cf.mode != CF_NORMAL || ecu2.stale || ecu3.stale)
            mismatch++;
        if (fabs(ecu3.cf.out[1]) > 0.05) moved = 1;
    }
    CHECK(mismatch == 0, "%d cycles where the module ECUs differ from the controllers' algorithms", mismatch);
    CHECK(moved, "the drive did not steer: the comparison cannot fail");
}

/* one message stops at cycle k0: detection, hold, ramp, safe; then it resumes */
static void stale_hold_ramp_recover(int module, int msg, int expectFallback) {
    SteeringEcu *e = module == 2 ? &ecu2 : &ecu3;
    EcuParams p = params(module);
    EcuInputs in = drive(0);
    ecu_setup(e, &p, &in);
    const int k0 = 1000, kBack = 1600;
    double frozen = 0, held[2] = { 0, 0 };
    int kDetect = -1, kRamp = -1, kSafe = -1, kRecover = -1, kRejoined = -1, rampOk = 1, holdOk = 1;
    double prev[2] = { 0, 0 };
    for (int k = 1; k < 2200; k++) {
        in = drive(k);
        if (k == k0) frozen = in.alive[msg];
        if (k >= k0 && k < kBack) in.alive[msg] = frozen;     /* no new frame from k0 + 1 on */
        prev[0] = e->cf.out[0];
        prev[1] = e->cf.out[1];
        ecu_sample(e, &in);
        if (kDetect < 0 && e->cf.mode != CF_NORMAL) {
            kDetect = k;
            held[0] = prev[0];
            held[1] = prev[1];
        }
        if (kDetect > 0 && kRamp < 0 && e->cf.mode == CF_HOLD &&
            (e->cf.out[0] != held[0] || e->cf.out[1] != held[1])) holdOk = 0;
        if (kDetect > 0 && kRamp < 0 && e->cf.mode == CF_RAMP) kRamp = k;
        if (e->cf.mode == CF_RAMP || (e->cf.mode == CF_SAFE && kSafe < 0)) {
            for (int j = 0; j < 2; j++) {       /* |out| falls by rampRate Ts per cycle, or to 0 */
                const double want = fabs(prev[j]) > 0.1 * TS ? fabs(prev[j]) - 0.1 * TS : 0.0;
                if (fabs(fabs(e->cf.out[j]) - want) > 1e-12 || e->cf.out[j] * prev[j] < 0) rampOk = 0;
            }
        }
        if (kSafe < 0 && e->cf.mode == CF_SAFE) kSafe = k;
        if (kSafe > 0 && kRecover < 0 && e->cf.mode == CF_NORMAL) kRecover = k;
        if (kRecover > 0 && kRejoined < 0 && e->cf.out[0] == e->calc[0] && e->cf.out[1] == e->calc[1])
            kRejoined = k;
    }
    if (!expectFallback) {
        CHECK(kDetect < 0, "module %d: message %d is not used, yet fallback at cycle %d", module, msg, kDetect);
        return;
    }
    /* frames stop after k0: cycles k0+1, k0+2, k0+3 bring none, stale in the 3rd (nStale = 3) */
    CHECK(kDetect == k0 + 3, "module %d, message %d: fallback at cycle %d, expected %d", module, msg, kDetect, k0 + 3);
    CHECK(holdOk, "outputs moved while holding");
    /* hold: ceil(0.2 / 0.01) = 20 cycles from the detection on, the ramp in the 21st */
    CHECK(kRamp == kDetect + 20, "ramp at cycle %d, expected %d", kRamp, kDetect + 20);
    CHECK(rampOk, "ramp not at rampRate toward 0");
    const double big = fmax(fabs(held[0]), fabs(held[1]));
    const int nRamp = (int)ceil(big / (0.1 * TS) - 1e-9);
    CHECK(kSafe == kRamp + nRamp - 1, "safe at cycle %d, expected %d (|held| = %g rad)", kSafe, kRamp + nRamp - 1, big);
    CHECK(big > 0.05, "the held angle %g is too small for the ramp to be seen", big);
    /* frames again from kBack: 5 fresh cycles kBack..kBack+4, normal in the 5th */
    CHECK(kRecover == kBack + 4, "recovered at cycle %d, expected %d", kRecover, kBack + 4);
    CHECK(kRejoined > kRecover, "no slew back to the computed angles (rejoined at %d)", kRejoined);
    CHECK(e->stale == 0 && e->cf.mode == CF_NORMAL, "not back to normal");
}

static void direction_and_no_check(void) {
    EcuParams p = params(2);
    EcuInputs in = drive(0);
    ecu_setup(&ecu2, &p, &in);
    for (int k = 1; k < 50; k++) {
        in = drive(k);
        in.direction = k >= 10 ? 1.0 : 0.0;
        ecu_sample(&ecu2, &in);
    }
    CHECK(ecu2.cf.mode == CF_NORMAL && !(ecu2.fault & ECU_FAULT_DIRECTION) && ecu2.direction == 1,
          "backwards is a fallback (mode %d, fault %u)", ecu2.cf.mode, ecu2.fault);
    for (int k = 50; k < 60; k++) {
        in = drive(k);
        in.direction = 2.0;                       /* J1939 error */
        ecu_sample(&ecu2, &in);
    }
    CHECK(ecu2.cf.mode != CF_NORMAL && (ecu2.fault & ECU_FAULT_DIRECTION), "direction 'error' is not a fallback");
    p.nStale = 0;                                 /* direct connections: counters never change */
    in = drive(0);
    ecu_setup(&ecu2, &p, &in);
    for (int k = 1; k < 500; k++) {
        in = drive(k);
        for (int i = 0; i < ECU_NMSG; i++) in.alive[i] = 0;
        ecu_sample(&ecu2, &in);
    }
    CHECK(ecu2.cf.mode == CF_NORMAL && ecu2.stale == 0 && ecu2.cf.out[1] == ecu2.calc[1], "nStale = 0 checks");
}

static void bad_input_and_parameters(void) {
    EcuParams p = params(3);
    EcuInputs in = drive(0);
    ecu_setup(&ecu3, &p, &in);
    for (int k = 1; k < 300; k++) {
        in = drive(k);
        if (k % 3 == 0) { in.gamma1 = NAN; in.dPsi2 = INFINITY; in.v = -1; }
        if (k % 7 == 0) in.alive[0] = NAN;
        ecu_sample(&ecu3, &in);
        CHECK(isfinite(ecu3.cf.out[0]) && isfinite(ecu3.cf.out[1]) && fabs(ecu3.cf.out[0]) <= 0.75 &&
              fabs(ecu3.cf.out[1]) <= 0.75, "cycle %d: output %g, %g", k, ecu3.cf.out[0], ecu3.cf.out[1]);
    }
    p.module = 4;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu3, &p, &in)), "module") == 0, "module 4 accepted");
    p = params(2); p.nRecover = 0;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu3, &p, &in)), "nRecover") == 0, "nRecover 0 accepted");
    p = params(2); p.rampRate = 0;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu3, &p, &in)), "rampRate") == 0, "rampRate 0 accepted");
    p = params(2); p.tg.S6 = -1;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu3, &p, &in)), "S6") == 0, "S6 < 0 accepted");
    p = params(2); p.fm.lA5 = 0;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu3, &p, &in)), "lA5") == 0, "lA5 = 0 accepted");
    const ActParams ap = { .Tact = -1, .nStale = 3, .nRecover = 5, .tHold = 0.2, .rampRate = 0.1, .Ts = TS };
    const double z[2] = { 0, 0 };
    CHECK(strcmp(act_param_name(act_setup(&act, &ap, z, 0)), "Tact") == 0, "Tact < 0 accepted");
    const ActParams aq = { .nStale = 3, .nRecover = 5, .tHold = 0.2, .rampRate = 0.1, .Ts = 0 };
    CHECK(strcmp(act_param_name(act_setup(&act, &aq, z, 0)), "Ts") == 0, "Ts = 0 accepted");
}

static void actuator(void) {
    /* pass-through, then silent ECU: same timing as the ECU's fallback */
    ActParams p = { .nStale = 3, .nRecover = 5, .tHold = 0.2, .rampRate = 0.1, .Ts = TS };
    double cmd[2] = { 0.2, -0.3 };
    act_setup(&act, &p, cmd, 0);
    int pass = 1, kDetect = -1, kSafe = -1;
    for (int k = 1; k < 800; k++) {
        if (k < 300) {                    /* from 300 on no new frame: the inputs keep the last one's values */
            cmd[0] = 0.2 * cos(0.01 * k);
            cmd[1] = -0.3 * cos(0.013 * k);
        }
        const double alive = k < 300 ? (double)(k % 16) : (double)(299 % 16);
        act_sample(&act, cmd, alive);
        if (k < 300 && (act.delta[0] != cmd[0] || act.delta[1] != cmd[1])) pass = 0;
        if (kDetect < 0 && act.cf.mode != CF_NORMAL) kDetect = k;
        if (kSafe < 0 && act.cf.mode == CF_SAFE) kSafe = k;
    }
    CHECK(pass, "default actuator is not a pass-through");
    CHECK(kDetect == 302, "actuator fallback at cycle %d, expected 302", kDetect);
    /* held at the set-points of cycle 299 (|A4-side| = 0.3 cos(3.887) = 0.2204), 20 cycles, then 0.1 rad/s */
    const double held = fabs(-0.3 * cos(0.013 * 299));
    const int nRamp = (int)ceil(held / (0.1 * TS) - 1e-9);
    CHECK(kSafe == kDetect + 20 + nRamp - 1, "actuator safe at cycle %d, expected %d", kSafe, kDetect + 20 + nRamp - 1);
    CHECK(act.delta[0] == 0 && act.delta[1] == 0 && act.stale == 1, "actuator not straight at the end");

    /* first-order lag: a step of the set-point, y_k = c (1 - exp(-k Ts / Tact)) */
    p.Tact = 0.15;
    double c0[2] = { 0, 0 };
    act_setup(&act, &p, c0, 0);
    double c[2] = { 0.1, -0.1 }, err = 0;
    for (int k = 1; k <= 100; k++) {
        act_sample(&act, c, (double)(k % 16));
        err = fmax(err, fabs(act.delta[0] - 0.1 * (1 - exp(-k * TS / 0.15))));
    }
    CHECK(err < 1e-12, "first-order lag off its closed form by %g", err);
    /* rate limit: a step of 0.1 rad at 0.5 rad/s takes 0.2 s = 20 cycles, linearly */
    p.Tact = 0;
    p.rateMax = 0.5;
    act_setup(&act, &p, c0, 0);
    err = 0;
    for (int k = 1; k <= 30; k++) {
        act_sample(&act, c, (double)(k % 16));
        err = fmax(err, fabs(act.delta[0] - fmin(0.1, 0.5 * TS * k)));
    }
    CHECK(err < 1e-12, "rate limit off the ramp by %g", err);
}

/* backwards: the A6 end leads; the drive's gamma1 is A6's angle, its speed
   negative (module 1's, backwards), the hinges as measured */
static EcuInputs drive_back(int k) {
    EcuInputs in = drive(k);
    in.gammaA6 = in.gamma1;
    in.gamma1 = 0.1;                              /* A1's angle: not the leading one backwards */
    in.v = -in.v;
    in.direction = 1.0;
    return in;
}

static void backwards_same_algorithm_as_the_controllers(void) {
    EcuParams p1 = params(1), p2 = params(2), p3 = params(3);
    EcuInputs in = drive_back(0);
    CHECK(ecu_setup(&ecu1, &p1, &in) == 0 && ecu_setup(&ecu2, &p2, &in) == 0 && ecu_setup(&ecu3, &p3, &in) == 0,
          "setup backwards");
    CHECK(ecu1.direction == 1 && ecu2.direction == 1 && ecu3.direction == 1, "not backwards from the start");
    tg_setup(&tg, &TG);
    fm_setup(&fm, &FM);
    tg_reset(&tg, in.gammaA6);
    int mismatch = 0, moved = 0;
    for (int k = 1; k < 4000; k++) {
        in = drive_back(k);
        ecu_sample(&ecu1, &in);
        ecu_sample(&ecu2, &in);
        ecu_sample(&ecu3, &in);
        /* Bus36m_Circle_Backwards: TrainGuidance and ForceMinimization with backwards = true:
           gamma1 = A6's angle, v = the leading module's speed, hinges -dPsi2, -dPsi1 */
        tg_sample(&tg, in.gammaA6, -in.v);
        fm_sample(&fm, in.gammaA6, -in.dPsi2, -in.dPsi1, tg.gamma4, tg.gamma6);
        if (ecu2.cf.out[0] != tg.gamma4 || ecu2.cf.out[1] != fm.gamma3 ||      /* A3, A4 */
            ecu1.cf.out[0] != tg.gamma6 || ecu1.cf.out[1] != fm.gamma5 ||      /* A1, A2 */
            ecu3.cf.out[0] != 0.0 || ecu3.cf.out[1] != 0.0 ||                  /* A5 rigid, A6 the driver's */
            ecu1.cf.mode || ecu2.cf.mode || ecu3.cf.mode || ecu1.stale || ecu2.stale || ecu3.stale)
            mismatch++;
        if (fabs(ecu1.cf.out[0]) > 0.05) moved = 1;
    }
    CHECK(mismatch == 0, "%d cycles where the module ECUs differ from the controllers' backwards algorithms", mismatch);
    CHECK(moved, "the backwards drive did not steer A1: the comparison cannot fail");
    /* backwards, module 2 watches A6 and G2, not A1; module 1 not its own TractorECU_State */
    CHECK(ecu2.used == (1u << ECU_MSG_A6 | 1u << ECU_MSG_G1 | 1u << ECU_MSG_G2 | 1u << ECU_MSG_STATE) &&
          ecu3.used == 0 && ecu1.used == (ecu2.used & ~(1u << ECU_MSG_STATE)), "used masks backwards %u %u %u", ecu1.used, ecu2.used, ecu3.used);
}

/* the tractor ECU decides the direction from its speed: backwards below -vDir,
   forwards above vDir, unchanged in between */
static void tractor_direction_hysteresis(void) {
    EcuParams p1 = params(1);
    EcuInputs in = drive(0);
    in.v = 0.0;
    ecu_setup(&ecu1, &p1, &in);
    CHECK(ecu1.direction == 0, "standing start not forwards");
    const double v[] = { 0.04, -0.04, -0.06, -0.01, 0.03, 0.051, -0.049 };
    const int want[] = { 0, 0, 1, 1, 1, 0, 0 };
    for (int i = 0; i < 7; i++) {
        in.v = v[i];
        in.direction = 3.0;                       /* module 1 ignores what it receives */
        ecu_sample(&ecu1, &in);
        CHECK(ecu1.direction == want[i], "v = %g: direction %d, expected %d", v[i], ecu1.direction, want[i]);
    }
    p1.vDir = -1;
    CHECK(strcmp(ecu_param_name(ecu_setup(&ecu1, &p1, &in)), "vDir") == 0, "vDir -1 accepted");
}

int main(void) {
    backwards_same_algorithm_as_the_controllers();
    tractor_direction_hysteresis();
    same_algorithm_as_the_controllers();
    stale_hold_ramp_recover(2, ECU_MSG_A1, 1);
    stale_hold_ramp_recover(2, ECU_MSG_G1, 1);
    stale_hold_ramp_recover(2, ECU_MSG_STATE, 1);
    stale_hold_ramp_recover(2, ECU_MSG_G2, 0);      /* module 2 does not use hinge G2 */
    stale_hold_ramp_recover(3, ECU_MSG_G2, 1);
    stale_hold_ramp_recover(3, ECU_MSG_A1, 1);
    direction_and_no_check();
    bad_input_and_parameters();
    actuator();
    printf("ecu_module: %d checks, %d failures\n", checks, failures);
    return failures ? 1 : 0;
}
