/* ecu_damping: seed 001's articulation damping algorithms (DampingController's
 * damping.c, SwayBaseline's baseline.c) built alone, as for an ECU: C99,
 * <math.h> only, no FMI headers, static objects, no heap. Checks against
 * numbers derived here by other routes: the bilinear step response in closed
 * form, the exact model's steady articulation from the circle geometry of the
 * kinematic bus, the torque formulas of eqs. 5.3-5.5 and 6.1.3 written out, and
 * that bad input gives finite requests within [pctFloor, pctMax].
 *
 * usage: ecu_damping   (exit status 0 when every check passes) */
#include <math.h>
#include <stdio.h>

#include "damping.h"
#include "baseline.h"

#define PI 3.14159265358979323846

static int checks = 0, failures = 0;
#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

static int close_to(double a, double b, double rel, double abs_) {
    return fabs(a - b) <= rel * (fabs(a) + fabs(b)) + abs_;
}

static DcController dc;     /* static: nothing on the heap */
static SbBaseline sb;

/* the thesis's bus (seed 001, Tables 3.1, 5.1, 5.3) */
static DcParams scania(int option) {
    DcParams p;
    int i;
    p.f1 = 1.944; p.b1 = 3.306; p.b11 = 5.128; p.f2 = 4.777; p.b2 = 0.163;
    p.m2 = 8556; p.Crear = 1375760; p.option = option;
    p.K1 = 0.130; p.K2 = 0.565; p.K3 = 0.605; p.Krev = 80.0;
    p.exactRef = 0; p.nKc = 1;
    for (i = 0; i < DC_MAX_KC; i++) { p.KcSpeed[i] = 5.0 * i; p.KcGain[i] = 1.0; }
    p.pctMax = 34; p.pctFloor = 3.5; p.pctAtMmax = 50; p.vMin = 1.0; p.Ts = 0.02;
    return p;
}

static DcInputs at(double Lambda, double LambdaDot, double v, double delta) {
    DcInputs in;
    in.Lambda = Lambda; in.LambdaDot = LambdaDot; in.v = v; in.v2 = v; in.delta = delta;
    in.Mmax = 2.4e4; in.pctExternal = 0;
    return in;
}

static void reference_model(void) {
    const double l1 = 5.25, l2 = 4.94, e = 5.128 - 3.306, a = 1 / l1 + e / (l1 * l2), T = 0.02;
    const double speeds[] = { 50 / 3.6, 100 / 3.6 };
    DcParams p = scania(0);
    unsigned s;
    int k;
    for (s = 0; s < 2; s++) {
        /* step of delta at sample 1: the bilinear recursion in closed form,
           Lambda_k = K - (K - beta) rho^(k-1), K = a l2, rho = (2 - pT)/(2 + pT),
           beta = v a T/(2 + pT) (delta_0 = 0, delta_k = 1 from k = 1) */
        const double v = speeds[s], pp = v / l2, rho = (2 - pp * T) / (2 + pp * T);
        const double beta = v * a * T / (2 + pp * T), K = a * l2;
        DcInputs in = at(0, 0, v, 0);
        CHECK(dc_setup(&dc, &p) == 0, "setup refused");
        dc_reset(&dc, &in);
        in.delta = 1.0;
        for (k = 1; k <= 300; k++) {
            const double expect = K - (K - beta) * pow(rho, k - 1);
            dc_sample(&dc, &in);
            CHECK(close_to(dc.LambdaRef, expect, 1e-12, 1e-14), "v = %g, k = %d: LambdaRef %.15g, "
                  "closed form %.15g", v, k, dc.LambdaRef, expect);
            CHECK(close_to(dc.LambdaDotRef, -pp * expect + v * a, 1e-10, 1e-12), "LambdaDotRef, k = %d", k);
        }
        CHECK(close_to(dc.LambdaRef, 1.288, 1e-3, 0), "kinematic DC gain a l2 = 1.288: %g", dc.LambdaRef);
    }

    /* exact eq. 2.3 in a steady turn: the articulation of the kinematic bus on
       its circle. The front section turns about the point on its rear axle
       line at R1 = l1/tan(delta); the hinge, e behind that axle, is at
       Rh = hypot(R1, e); the rear axle, l2 behind the hinge, rolls on the
       circle whose radius is perpendicular to the rear section:
       Lambda = atan(e/R1) + asin(l2/Rh). */
    p.exactRef = 1;
    for (k = 0; k < 4; k++) {
        const double delta = 0.05 + 0.1 * k, R1 = l1 / tan(delta), Rh = hypot(R1, e);
        const double expect = atan(e / R1) + asin(l2 / Rh);
        DcInputs in = at(0, 0, 10.0, 0);
        int i;
        CHECK(dc_setup(&dc, &p) == 0, "setup refused");
        dc_reset(&dc, &in);
        in.delta = delta;
        for (i = 0; i < 2000; i++) dc_sample(&dc, &in);
        CHECK(close_to(dc.LambdaRef, expect, 1e-9, 0), "delta = %g: exact steady Lambda %.12g, circle %.12g",
              delta, dc.LambdaRef, expect);
        CHECK(fabs(dc.LambdaDotRef) < 1e-9, "steady LambdaDotRef %g", dc.LambdaDotRef);
    }
}

static void torques(void) {
    const double l2 = 4.94, Crear = 1375760, v = 100 / 3.6;
    int option;
    for (option = 1; option <= 4; option++) {
        DcParams p = scania(option);
        DcInputs in = at(0, 0, v, 0);
        double eL, eLd, T1, T2, T, pct;
        CHECK(dc_setup(&dc, &p) == 0, "setup refused");
        dc_reset(&dc, &in);                     /* LambdaRef = 0, delta 0: the reference stays 0 */
        in.Lambda = 0.01;
        in.LambdaDot = 0.02;                    /* moving in the direction of both errors */
        dc_sample(&dc, &in);
        eL = in.Lambda - dc.LambdaRef;
        eLd = in.LambdaDot - dc.LambdaDotRef;
        CHECK(eL == dc.eLambda && eLd == dc.eLambdaDot, "errors");
        T1 = 0.130 * Crear * l2 * eL;
        T2 = 0.565 * Crear * l2 * l2 * eLd / v;
        T = option == 1 ? T1 : option == 2 ? T2 : option == 3 ? 0.605 * (T1 + T2) : 80.0 * 8556 * eLd;
        CHECK(close_to(dc.T, T, 1e-13, 0), "option %d: T = %.15g, formula %.15g", option, dc.T, T);
        pct = 50 * fabs(T) / 2.4e4;
        pct = pct > 34 ? 34 : pct < 3.5 ? 3.5 : pct;
        CHECK(close_to(dc.pct, pct, 1e-13, 0), "option %d: pct = %g, expected %g", option, dc.pct, pct);
        CHECK(dc.T * in.LambdaDot > 0 && dc.active == (pct > 3.5), "option %d: gate", option);

        /* errors against the motion (measured rate below the reference's, or the angle
           on the other side): no request */
        dc_reset(&dc, &in);
        in.Lambda = -0.01;
        in.LambdaDot = 0.02;
        in.delta = 0.05;                        /* LambdaDotRef about v a delta = 0.36 rad/s */
        dc_sample(&dc, &in);
        CHECK(dc.eLambda < 0 && dc.eLambdaDot < 0, "option %d: errors %g %g", option, dc.eLambda,
              dc.eLambdaDot);
        CHECK(dc.T == 0 && dc.pct == 3.5 && dc.active == 0, "option %d: gate open against the "
              "motion: T = %g, pct = %g", option, dc.T, dc.pct);
        in.LambdaDot = -0.02;                   /* now the motion is with the errors */
        dc_sample(&dc, &in);
        CHECK(dc.T < 0 && dc.pct > 3.5, "option %d: gate closed with the motion: T = %g", option, dc.T);
    }
    /* option 3: torques added before the gate, they may cancel */
    {
        DcParams p = scania(3);
        DcInputs in = at(0, 0, v, 0);
        const double eL = 0.01, eLd = -0.130 * Crear * l2 * eL / (0.565 * Crear * l2 * l2 / v);
        dc_setup(&dc, &p);
        dc_reset(&dc, &in);
        in.Lambda = eL;
        in.LambdaDot = eLd;
        dc_sample(&dc, &in);
        CHECK(fabs(dc.T) < 1e-6 * 0.130 * Crear * l2 * eL && dc.pct == 3.5, "option 3: T1 + T2 = 0, T = %g",
              dc.T);
    }
    /* torque to pct through Mmax, cap, floor, and a damper without torque */
    {
        DcParams p = scania(4);
        DcInputs in = at(0, 0, v, 0);
        dc_setup(&dc, &p);
        dc_reset(&dc, &in);
        in.LambdaDot = 0.01;                                   /* T = 80 * 8556 * 0.01 = 6844.8 N m */
        in.Mmax = 2e4;
        dc_sample(&dc, &in);
        CHECK(close_to(dc.pct, 50 * 6844.8 / 2e4, 1e-12, 0), "pct %g", dc.pct);
        in.Mmax = 5e3;
        CHECK((dc_sample(&dc, &in) & DC_FAULT_LIMIT) && dc.pct == 34, "cap: %g", dc.pct);
        in.Mmax = 0;
        CHECK((dc_sample(&dc, &in) & DC_FAULT_MMAX) && dc.pct == 34, "Mmax 0: %g", dc.pct);
        in.Mmax = 1e9;
        dc_sample(&dc, &in);
        CHECK(dc.pct == 3.5 && dc.active == 0 && dc.T > 0, "floor: %g", dc.pct);
    }
    /* option 0: the floor only; option 5: pass-through within [floor, pctMax] */
    {
        DcParams p = scania(0);
        DcInputs in = at(0.1, 0.3, v, 0);
        dc_setup(&dc, &p);
        dc_reset(&dc, &in);
        in.Lambda = 0.2;
        dc_sample(&dc, &in);
        CHECK(dc.pct == 3.5 && dc.T == 0 && dc.active == 0, "option 0");
        p = scania(5);
        dc_setup(&dc, &p);
        dc_reset(&dc, &in);
        in.pctExternal = 20;
        dc_sample(&dc, &in);
        CHECK(dc.pct == 20 && dc.active == 1, "option 5: %g", dc.pct);
        in.pctExternal = 45;
        dc_sample(&dc, &in);
        CHECK(dc.pct == 34, "option 5 cap: %g", dc.pct);
        in.pctExternal = 1;
        dc_sample(&dc, &in);
        CHECK(dc.pct == 3.5 && dc.active == 0, "option 5 floor: %g", dc.pct);
    }
}

static void kc_table(void) {
    DcParams p = scania(2);
    p.nKc = 3;
    p.KcSpeed[0] = 10; p.KcSpeed[1] = 20; p.KcSpeed[2] = 30;
    p.KcGain[0] = 1.0; p.KcGain[1] = 0.8; p.KcGain[2] = 0.5;
    CHECK(dc_kc(&p, 0) == 1.0 && dc_kc(&p, 10) == 1.0, "below the table");
    CHECK(close_to(dc_kc(&p, 15), 0.9, 1e-15, 0) && close_to(dc_kc(&p, 27.5), 0.575, 1e-15, 0), "inside");
    CHECK(dc_kc(&p, 30) == 0.5 && dc_kc(&p, 99) == 0.5, "above the table");
    p.KcSpeed[2] = 20;
    CHECK(dc_setup(&dc, &p) == -11, "KcSpeed not increasing accepted");
    p = scania(2);
    p.pctFloor = 40;
    CHECK(dc_setup(&dc, &p) == -14, "pctFloor > pctMax accepted");
    p = scania(2);
    p.pctMax = 60;
    CHECK(dc_setup(&dc, &p) == -13, "pctMax > 50 accepted");
    p = scania(2);
    p.f2 = -0.2;
    CHECK(dc_setup(&dc, &p) == -2, "l2 <= 0 accepted");
}

static void bad_input(void) {
    DcParams p = scania(2);
    DcInputs in = at(0.05, 0.1, 20, 0.05);
    const double speeds[] = { 0.5, 0.0, -3.0, -1e-300 };
    unsigned i, f;
    double held;
    dc_setup(&dc, &p);
    dc_reset(&dc, &in);
    for (i = 0; i < 20; i++) dc_sample(&dc, &in);
    held = dc.pct;
    in.Lambda = NAN;
    CHECK((dc_sample(&dc, &in) & DC_FAULT_NAN) && dc.pct == held, "NaN: not held");
    in.Lambda = 0.05;
    for (i = 0; i < 4; i++) {                       /* slow, standing, reversing */
        in.v = in.v2 = speeds[i];
        in.LambdaDot = 0.4;
        in.delta = 0.3;
        f = dc_sample(&dc, &in);
        CHECK((f & DC_FAULT_SLOW) && (speeds[i] < 0 ? (f & DC_FAULT_REVERSE) != 0 : (f & DC_FAULT_REVERSE) == 0),
              "v = %g: flags %u", speeds[i], f);
        CHECK(dc.pct == 3.5 && dc.T == 0 && dc.LambdaRef == in.Lambda && dc.LambdaDotRef == in.LambdaDot &&
              dc.eLambda == 0 && dc.eLambdaDot == 0 && isfinite(dc.Kc), "v = %g: not held at the floor", speeds[i]);
    }
    in.v = in.v2 = 20;                              /* back above vMin: from the measured state */
    in.v2 = 0.0;
    f = dc_sample(&dc, &in);
    CHECK((f & DC_FAULT_V2) && isfinite(dc.pct) && dc.pct >= 3.5 && dc.pct <= 34, "v2 = 0: %u %g", f, dc.pct);
    in.v2 = 20;
    in.Lambda = 1e6;                                /* absurd but finite */
    in.LambdaDot = 1e6;
    dc_sample(&dc, &in);
    CHECK(isfinite(dc.T) && dc.pct == 34, "huge error: %g", dc.pct);
    p.exactRef = 1;
    dc_setup(&dc, &p);
    dc_reset(&dc, &in);
    in.delta = 1e3;
    in.v = 1e3;
    for (i = 0; i < 10; i++) dc_sample(&dc, &in);
    CHECK(isfinite(dc.LambdaRef) && isfinite(dc.LambdaDotRef) && dc.pct >= 3.5 && dc.pct <= 34,
          "exact model, absurd input: %g %g", dc.LambdaRef, dc.pct);
}

static SbParams acs5(void) {
    SbParams p;
    int i;
    p.nGround = 3;
    p.groundSpeed[0] = 0; p.groundSpeed[1] = 100 / 3.6; p.groundSpeed[2] = 130 / 3.6;
    p.groundPct[0] = 3.5; p.groundPct[1] = 13.5; p.groundPct[2] = 16.5;
    for (i = 3; i < SB_MAX_GROUND; i++) { p.groundSpeed[i] = 40 + 5 * i; p.groundPct[i] = 16.5; }
    p.vSSC = 60 / 3.6; p.LambdaDotSSC = 0.12; p.tHold = 1.5; p.pctSSC = 34;
    p.LambdaEP0 = 44 * PI / 180; p.LambdaEP1 = 50 * PI / 180; p.pctEP = 34; p.pctMax = 34; p.Ts = 0.01;
    return p;
}

static void baseline(void) {
    SbParams p = acs5();
    int k, on = -1, off = -1;
    CHECK(sb_setup(&sb, &p) == 0, "baseline refused");
    sb_sample(&sb, 100 / 3.6, 0, 0);
    CHECK(close_to(sb.pct, 13.5, 1e-14, 0) && sb.ssc == 0, "ground at 100 km/h: %g", sb.pct);
    sb_sample(&sb, 50 / 3.6, 0, 0);
    CHECK(close_to(sb.pct, 8.5, 1e-14, 0), "ground at 50 km/h: %g", sb.pct);
    sb_sample(&sb, 60, 0, 0);
    CHECK(sb.pct == 16.5, "ground above the table: %g", sb.pct);
    /* SSC: |LambdaDot| above its threshold from sample 100 to 149 at 100 km/h;
       on at 100, off 1.5 s (150 samples) after the condition last held (149) */
    CHECK(sb_setup(&sb, &p) == 0, "baseline refused");
    for (k = 0; k < 600; k++) {
        const double rate = (k >= 100 && k < 150) ? (k % 2 ? 0.2 : -0.2) : 0.05;
        sb_sample(&sb, 100 / 3.6, 0, rate);
        if (sb.ssc != 0 && on < 0) on = k;
        if (on >= 0 && sb.ssc == 0 && off < 0) off = k;
        if (sb.ssc != 0) CHECK(sb.pct == 34, "SSC level %g", sb.pct);
    }
    CHECK(on == 100 && off == 149 + 150, "SSC on at sample %d, off at %d", on, off);
    /* below vSSC it stays off */
    CHECK(sb_setup(&sb, &p) == 0, "baseline refused");
    sb_sample(&sb, 59 / 3.6, 0, 1.0);
    CHECK(sb.ssc == 0 && close_to(sb.pct, 3.5 + 5.9, 1e-12, 0), "SSC below vSSC");
    /* end protection: half-way at 47 deg, full at 50 deg, then the cap */
    sb_sample(&sb, 0, 47 * PI / 180, 0);
    CHECK(close_to(sb.pct, 17, 1e-12, 0) && sb.ep == 1, "EP at 47 deg: %g", sb.pct);
    sb_sample(&sb, 0, -52 * PI / 180, 0);
    CHECK(sb.pct == 34, "EP beyond 50 deg: %g", sb.pct);
    p.pctMax = 20;
    CHECK(sb_setup(&sb, &p) == 0, "baseline refused");
    sb_sample(&sb, 0, 52 * PI / 180, 0);
    CHECK(sb.pct == 20, "cap: %g", sb.pct);
    CHECK(sb_sample(&sb, NAN, 0, 0) == SB_FAULT_NAN && sb.pct == 20, "NaN not held");
    CHECK((sb_sample(&sb, -5, 0, 0) & SB_FAULT_REVERSE) && sb.pct == 3.5, "reversing");
    p.LambdaEP1 = p.LambdaEP0;
    CHECK(sb_setup(&sb, &p) == -9, "LambdaEP1 = LambdaEP0 accepted");
}

int main(void) {
    reference_model();
    torques();
    kc_table();
    bad_input();
    baseline();
    printf("ecu_damping: %d checks, %d failures\n", checks, failures);
    return failures ? 1 : 0;
}
