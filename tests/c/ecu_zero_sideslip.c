/* ecu_zero_sideslip: the zero-side-slip steering law (src/models/
 * ZeroSideslipSteering/zero_sideslip.c) built alone, as for an ECU: C99,
 * <math.h> only, no FMI headers, no heap. Checks the gain against the
 * textbook two-axle (4WS) closed form written out here, eq. 3's linear
 * distribution, and that bad input gives finite, limited commands.
 *
 * usage: ecu_zero_sideslip   (exit status 0 when every check passes) */
#include <math.h>
#include <stdio.h>

#include "zero_sideslip.h"

static int checks = 0, failures = 0;
#define CHECK(cond, ...) do { checks++; if (!(cond)) { failures++; \
    printf("FAIL %s:%d: ", __FILE__, __LINE__); printf(__VA_ARGS__); printf("\n"); } } while (0)

static int close_to(double a, double b, double rel) {
    return fabs(a - b) <= rel * (fabs(a) + fabs(b)) + 1e-15;
}

static ZsVehicle bus(void) {          /* the FMU's default vehicle (15 m, three axles) */
    ZsVehicle v = { 3, { 0, 5.40, -1.55, -3.05 }, { 0, -4.0e5, -6.0e5, -3.8e5 },
                    { 0, 700, 1300, 600 }, { 0, 1, 0, 1 }, 23400, { 0, 0.8727, 0.35, 0.35 } };
    return v;
}

int main(void) {
    ZsGains g;
    ZsMemory mem;
    double delta[ZS_MAX_AXLES + 1], K[ZS_MAX_AXLES + 1];

    /* 1. two axles, unsprung masses 0: the textbook zero-side-slip 4WS ratio
          delta_2/delta_1 = -(b - m a u^2/(C_2 L)) / (a + m b u^2/(C_1 L)),
          C_i = -k_i > 0, a and b the distances of the axles from the CG */
    const double a = 1.3, b = 1.5, L = a + b, m = 1500, C1 = 8e4, C2 = 9e4;
    ZsVehicle car = { 2, { 0, a, -b }, { 0, -C1, -C2 }, { 0, 0, 0 }, { 0, 1, 1 }, m,
                      { 0, 0.6, 0.6 } };
    CHECK(zs_prepare(&car, &g, NULL) == ZS_OK, "two-axle car refused");
    for (double u = 0; u <= 60; u += 2.5) {
        const double textbook = -(b - m * a * u * u / (C2 * L)) / (a + m * b * u * u / (C1 * L));
        CHECK(close_to(zs_gain(&g, u), textbook, 1e-13), "u = %g: K = %.17g, textbook %.17g",
              u, zs_gain(&g, u), textbook);
    }
    CHECK(g.uPole < 0, "a pole for the car: %g", g.uPole);

    /* 2. four axles, all steered: eq. 3, delta_i linear in l_i between 1 and 4 */
    ZsVehicle crane = { 4, { 0, 3.0, 1.5, -1.0, -2.5 }, { 0, -3e5, -3e5, -3e5, -3e5 },
                        { 0, 800, 800, 800, 800 }, { 0, 1, 1, 1, 1 }, 30000,
                        { 0, 1.0, 1.0, 1.0, 1.0 } };
    CHECK(zs_prepare(&crane, &g, NULL) == ZS_OK, "crane refused");
    zs_reset(&mem);
    for (double u = 0; u <= 30; u += 5) {
        const unsigned f = zs_step(&g, &mem, 0.05, u, delta, K);
        CHECK(f == 0, "u = %g: flags %u", u, f);
        for (int i = 2; i <= 3; i++) {
            const double s = (3.0 - crane.l[i]) / (3.0 - (-2.5));
            CHECK(close_to(delta[i], (1 - s) * delta[1] + s * delta[4], 1e-12),
                  "eq. 3 at axle %d, u = %g", i, u);
        }
        CHECK(close_to(delta[4], zs_gain(&g, u) * 0.05, 1e-14), "delta_4 = K delta_1");
        CHECK(delta[5] == 0 && delta[6] == 0 && K[1] == 1.0, "axles beyond n");
    }

    /* 3. the bus: a fixed middle axle gets 0, bad input stays finite and limited */
    ZsVehicle v = bus();
    CHECK(zs_prepare(&v, &g, NULL) == ZS_OK && g.rear == 3, "bus refused");
    zs_reset(&mem);
    CHECK(zs_step(&g, &mem, 0.02, 10.0, delta, K) == 0, "plain step flagged");
    CHECK(delta[2] == 0.0 && K[2] == 0.0, "fixed axle steered");
    const double held = delta[3];
    CHECK(zs_step(&g, &mem, NAN, 10.0, delta, K) & ZS_INPUT_NOT_FINITE, "NaN delta1 not flagged");
    CHECK(delta[3] == held && isfinite(delta[1]), "NaN delta1: command not held");
    unsigned f = zs_step(&g, &mem, 0.02, NAN, delta, K);
    CHECK((f & ZS_INPUT_NOT_FINITE) && close_to(delta[3], held, 1e-15), "NaN u: last speed not used");
    f = zs_step(&g, &mem, 0.02, INFINITY, delta, K);
    CHECK(f & ZS_INPUT_NOT_FINITE, "Inf u not flagged");
    f = zs_step(&g, &mem, 0.02, -3.0, delta, K);
    CHECK((f & ZS_REVERSING) && close_to(delta[3], zs_gain(&g, 0) * 0.02, 1e-14), "u < 0: not K(0)");
    f = zs_step(&g, &mem, 0.02, 0.0, delta, K);
    CHECK(f == 0 && isfinite(delta[3]), "standstill flagged or not finite");
    f = zs_step(&g, &mem, 1e300, 1e300, delta, K);
    CHECK((f & ZS_SATURATED) && delta[1] == 0.8727 && fabs(delta[3]) == 0.35, "huge input not limited");
    f = zs_step(&g, &mem, -INFINITY, 5.0, delta, K);
    CHECK(f & ZS_INPUT_NOT_FINITE, "-Inf delta1 not flagged");
    for (int i = 0; i <= ZS_MAX_AXLES; i++) CHECK(isfinite(delta[i]) && isfinite(K[i]), "not finite");

    /* 4. a vehicle whose K(u) has a pole: at the pole the command is finite and limited */
    ZsVehicle p = { 3, { 0, 2.0, -3.0, -4.5 }, { 0, -4e5, -2e6, -6e5 }, { 0, 0, 0, 0 },
                    { 0, 1, 0, 1 }, 20000, { 0, 0.8, 0.3, 0.3 } };
    CHECK(zs_prepare(&p, &g, NULL) == ZS_OK, "pole vehicle refused");
    if (g.uPole > 0) {
        zs_reset(&mem);
        f = zs_step(&g, &mem, 0.01, g.uPole, delta, K);
        CHECK(f & ZS_NEAR_POLE, "pole at u = %g not flagged (flags %u)", g.uPole, f);
        for (int i = 1; i <= 3; i++)
            CHECK(isfinite(delta[i]) && fabs(delta[i]) <= p.deltaMax[i], "axle %d at the pole", i);
    } else {
        CHECK(0, "the pole vehicle has no pole (uPole = %g)", g.uPole);
    }

    /* 5. refused vehicles */
    ZsVehicle w = bus();
    w.steerable[3] = 0;
    CHECK(zs_prepare(&w, &g, NULL) == ZS_NO_REAR_AXLE, "no rear axle accepted");
    w = bus();
    w.l[3] = 0.0;
    int axle = 0;
    CHECK(zs_prepare(&w, &g, &axle) == ZS_NOT_ORDERED && axle == 3, "unordered axles accepted");
    w = bus();
    w.k[2] = 1e5;
    CHECK(zs_prepare(&w, &g, &axle) == ZS_BAD_PARAMETER && axle == 2, "k > 0 accepted");
    w = bus();
    w.steerable[1] = 0;
    CHECK(zs_prepare(&w, &g, NULL) == ZS_FRONT_NOT_STEERABLE, "fixed front axle accepted");

    printf("%d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
