/* The LS-BUS CAN codec (src/fmi/lsbus_can.c) against byte strings written by hand
 * from the tables of fmi-ls-bus v1.0.0 docs/4_4_1_can.adoc ("Operations") and
 * docs/4____network_abstraction.adoc (header: OP Code u32, Length u32 = total
 * bytes, little-endian). Plain C99 without FMI headers; run by ctest, also under
 * ASan/UBSan (every cut of a buffer is read, and nothing may read past its end). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsbus_can.h"

static int failures = 0;
#define CHECK(cond) do { if (!(cond)) { printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond); failures++; } } while (0)

/* a buffer read into ops[]: the results in res[], the number of calls until END */
static int read_all(const uint8_t *buf, size_t size, LsBusCanOp ops[], LsBusResult res[], int max) {
    size_t pos = 0;
    int n = 0;
    for (;;) {
        LsBusCanOp op;
        LsBusResult r = lsbus_can_read(buf, size, &pos, &op);
        if (r == LSBUS_END) return n;
        if (n >= max) return -1;
        ops[n] = op;
        res[n] = r;
        n++;
        if (pos > size) return -2;
    }
}

static void test_transmit_bytes(void) {
    /* CAN Transmit, ID 0x123 standard, no RTR, 2 bytes AB CD: Length = 16 + 2 */
    static const uint8_t expected[] = {
        0x10, 0, 0, 0,  18, 0, 0, 0,  0x23, 0x01, 0, 0,  0x00,  0x00,  2, 0,  0xAB, 0xCD};
    uint8_t mem[64];
    LsBusBuffer b;
    lsbus_buffer_init(&b, mem, sizeof mem);
    const uint8_t data[] = {0xAB, 0xCD};
    CHECK(lsbus_can_append_transmit(&b, 0x123, LSBUS_FALSE, LSBUS_FALSE, data, 2) == LSBUS_OK);
    CHECK(b.size == sizeof expected);
    CHECK(memcmp(mem, expected, sizeof expected) == 0);

    LsBusCanOp op;
    size_t pos = 0;
    CHECK(lsbus_can_read(expected, sizeof expected, &pos, &op) == LSBUS_OK);
    CHECK(op.op == 0x10 && op.length == 18 && op.id == 0x123 && op.ide == 0 && op.rtr == 0);
    CHECK(op.dataLength == 2 && op.data == expected + 16 && op.data[1] == 0xCD);
    CHECK(pos == sizeof expected);
    CHECK(lsbus_can_read(expected, sizeof expected, &pos, &op) == LSBUS_END);
}

static void test_each_operation_bytes(void) {
    uint8_t mem[256];
    LsBusBuffer b;
    lsbus_buffer_init(&b, mem, sizeof mem);
    CHECK(lsbus_can_append_confirm(&b, 0x7FF) == LSBUS_OK);
    CHECK(lsbus_can_append_arbitration_lost(&b, 0x101) == LSBUS_OK);
    CHECK(lsbus_can_append_bus_error(&b, 0x55, LSBUS_CAN_CRC_ERROR, LSBUS_CAN_PRIMARY_ERROR_FLAG,
                                     LSBUS_TRUE) == LSBUS_OK);
    CHECK(lsbus_can_append_config_baudrate(&b, LSBUS_CAN_CONFIG_CAN_BAUDRATE, 500000) == LSBUS_OK);
    CHECK(lsbus_can_append_config_arbitration_lost(&b, LSBUS_CAN_DISCARD_AND_NOTIFY) == LSBUS_OK);
    CHECK(lsbus_can_append_status(&b, LSBUS_CAN_BUS_OFF) == LSBUS_OK);
    CHECK(lsbus_can_append_wakeup(&b) == LSBUS_OK);
    static const uint8_t bad[] = {0x99, 0, 0, 0, 8, 0, 0, 0};
    CHECK(lsbus_append_format_error(&b, bad, sizeof bad) == LSBUS_OK);
    static const uint8_t expected[] = {
        0x20, 0, 0, 0, 12, 0, 0, 0, 0xFF, 0x07, 0, 0,                  /* Confirm */
        0x30, 0, 0, 0, 12, 0, 0, 0, 0x01, 0x01, 0, 0,                  /* Arbitration Lost */
        0x31, 0, 0, 0, 15, 0, 0, 0, 0x55, 0, 0, 0, 0x04, 0x01, 0x01,   /* Bus Error */
        0x40, 0, 0, 0, 13, 0, 0, 0, 0x01, 0x20, 0xA1, 0x07, 0x00,      /* 500000 = 0x7A120 */
        0x40, 0, 0, 0, 10, 0, 0, 0, 0x04, 0x02,                        /* arbitration lost */
        0x41, 0, 0, 0, 9, 0, 0, 0, 0x03,                               /* Status BUS_OFF */
        0x42, 0, 0, 0, 8, 0, 0, 0,                                     /* Wakeup */
        0x01, 0, 0, 0, 18, 0, 0, 0, 8, 0, 0x99, 0, 0, 0, 8, 0, 0, 0};  /* Format Error */
    CHECK(b.size == sizeof expected);
    CHECK(memcmp(mem, expected, sizeof expected) == 0);

    LsBusCanOp ops[16];
    LsBusResult res[16];
    int n = read_all(expected, sizeof expected, ops, res, 16);
    CHECK(n == 8);
    for (int i = 0; i < n; i++) CHECK(res[i] == LSBUS_OK);
    if (n != 8) return;
    CHECK(ops[0].op == LSBUS_CAN_OP_CONFIRM && ops[0].id == 0x7FF);
    CHECK(ops[1].op == LSBUS_CAN_OP_ARBITRATION_LOST && ops[1].id == 0x101);
    CHECK(ops[2].op == LSBUS_CAN_OP_BUS_ERROR && ops[2].id == 0x55 && ops[2].errorCode == 4 &&
          ops[2].errorFlag == 1 && ops[2].isSender == 1);
    CHECK(ops[3].parameterType == 1 && ops[3].baudrate == 500000);
    CHECK(ops[4].parameterType == 4 && ops[4].arbitrationLostBehavior == 2);
    CHECK(ops[5].op == LSBUS_CAN_OP_STATUS && ops[5].status == 3);
    CHECK(ops[6].op == LSBUS_CAN_OP_WAKEUP && ops[6].length == 8);
    CHECK(ops[7].op == LSBUS_OP_FORMAT_ERROR && ops[7].dataLength == 8 &&
          memcmp(ops[7].data, bad, 8) == 0);
}

/* every prefix of a valid two-operation buffer: whole operations read, the cut
   one TRUNCATED with the rest as its bytes, nothing read past the end (the
   prefix is copied into a heap block of exactly its size, so ASan sees it) */
static void test_truncation(void) {
    uint8_t mem[64];
    LsBusBuffer b;
    lsbus_buffer_init(&b, mem, sizeof mem);
    const uint8_t d[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    CHECK(lsbus_can_append_transmit(&b, 0x10, 0, 0, d, 8) == LSBUS_OK);   /* 24 bytes */
    CHECK(lsbus_can_append_confirm(&b, 0x11) == LSBUS_OK);                /* 12 bytes */
    CHECK(b.size == 36);
    for (size_t cut = 0; cut <= b.size; cut++) {
        uint8_t *p = malloc(cut ? cut : 1);
        memcpy(p, mem, cut);
        LsBusCanOp ops[4];
        LsBusResult res[4];
        int n = read_all(p, cut, ops, res, 4);
        int whole = (cut >= 24) + (cut == 36);
        int partial = cut != 0 && cut != 24 && cut != 36;
        CHECK(n == whole + partial);
        for (int i = 0; i < whole && i < n; i++) CHECK(res[i] == LSBUS_OK);
        if (partial && n == whole + 1) {
            CHECK(res[whole] == LSBUS_E_TRUNCATED);
            CHECK(ops[whole].rawSize == cut - (whole ? 24 : 0));
        }
        free(p);
    }
}

static void test_malformed(void) {
    LsBusCanOp op;
    size_t pos;
    /* Transmit whose Length says 17 but DL says 2 (16 + 2 = 18): wrong length,
       skipped by its Length so that the Confirm after it is still read */
    static const uint8_t wrongLen[] = {
        0x10, 0, 0, 0, 17, 0, 0, 0, 0x23, 0x01, 0, 0, 0, 0, 2, 0, 0xAB,
        0x20, 0, 0, 0, 12, 0, 0, 0, 0x05, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(wrongLen, sizeof wrongLen, &pos, &op) == LSBUS_E_LENGTH);
    CHECK(pos == 17 && op.raw == wrongLen && op.rawSize == 17);
    CHECK(lsbus_can_read(wrongLen, sizeof wrongLen, &pos, &op) == LSBUS_OK && op.id == 5);
    /* Length below the fixed part of a Transmit */
    static const uint8_t shortTx[] = {0x10, 0, 0, 0, 12, 0, 0, 0, 1, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(shortTx, sizeof shortTx, &pos, &op) == LSBUS_E_LENGTH);
    /* Length beyond the buffer, and below a header: truncated, the rest skipped */
    static const uint8_t beyond[] = {0x20, 0, 0, 0, 200, 0, 0, 0, 1, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(beyond, sizeof beyond, &pos, &op) == LSBUS_E_TRUNCATED);
    CHECK(pos == sizeof beyond);
    static const uint8_t below[] = {0x20, 0, 0, 0, 4, 0, 0, 0, 1, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(below, sizeof below, &pos, &op) == LSBUS_E_TRUNCATED);
    /* a huge Length (0xFFFFFFFF) must not wrap */
    static const uint8_t huge[] = {0x10, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF};
    pos = 0;
    CHECK(lsbus_can_read(huge, sizeof huge, &pos, &op) == LSBUS_E_TRUNCATED);
    /* an unknown OP Code of a valid Length: reported, skipped */
    static const uint8_t unknown[] = {0x77, 0, 0, 0, 9, 0, 0, 0, 0x00,
                                      0x42, 0, 0, 0, 8, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(unknown, sizeof unknown, &pos, &op) == LSBUS_E_UNKNOWN_OP);
    CHECK(op.op == 0x77 && pos == 9);
    CHECK(lsbus_can_read(unknown, sizeof unknown, &pos, &op) == LSBUS_OK);
    CHECK(op.op == LSBUS_CAN_OP_WAKEUP);
    /* arguments outside their values: DL 9 on classic CAN, Ide 2, an 11-bit ID
       above 0x7FF, error code 7, status 4, an unknown configuration kind */
    uint8_t dl9[16 + 9] = {0x10, 0, 0, 0, 25, 0, 0, 0, 1, 0, 0, 0, 0, 0, 9, 0};
    pos = 0;
    CHECK(lsbus_can_read(dl9, sizeof dl9, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t ide2[] = {0x10, 0, 0, 0, 16, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(ide2, sizeof ide2, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t id800[] = {0x10, 0, 0, 0, 16, 0, 0, 0, 0x00, 0x08, 0, 0, 0, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(id800, sizeof id800, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t ext800[] = {0x10, 0, 0, 0, 16, 0, 0, 0, 0x00, 0x08, 0, 0, 1, 0, 0, 0};
    pos = 0;
    CHECK(lsbus_can_read(ext800, sizeof ext800, &pos, &op) == LSBUS_OK && op.ide == 1);
    static const uint8_t err7[] = {0x31, 0, 0, 0, 15, 0, 0, 0, 1, 0, 0, 0, 7, 1, 0};
    pos = 0;
    CHECK(lsbus_can_read(err7, sizeof err7, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t st4[] = {0x41, 0, 0, 0, 9, 0, 0, 0, 4};
    pos = 0;
    CHECK(lsbus_can_read(st4, sizeof st4, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t cfg9[] = {0x40, 0, 0, 0, 9, 0, 0, 0, 9};
    pos = 0;
    CHECK(lsbus_can_read(cfg9, sizeof cfg9, &pos, &op) == LSBUS_E_VALUE);
    static const uint8_t cfgShort[] = {0x40, 0, 0, 0, 10, 0, 0, 0, 1, 0};
    pos = 0;
    CHECK(lsbus_can_read(cfgShort, sizeof cfgShort, &pos, &op) == LSBUS_E_LENGTH);
    /* an empty buffer: nothing, at once */
    pos = 0;
    CHECK(lsbus_can_read(NULL, 0, &pos, &op) == LSBUS_END);
}

static void test_append_limits(void) {
    uint8_t mem[30];
    LsBusBuffer b;
    lsbus_buffer_init(&b, mem, sizeof mem);
    const uint8_t d[8] = {0};
    CHECK(lsbus_can_append_transmit(&b, 1, 0, 0, d, 8) == LSBUS_OK);       /* 24 of 30 */
    CHECK(lsbus_can_append_confirm(&b, 1) == LSBUS_E_FULL);                /* 12 more */
    CHECK(b.size == 24);
    CHECK(lsbus_can_append_wakeup(&b) == LSBUS_E_FULL);                    /* 8 more */
    CHECK(lsbus_can_append_transmit(&b, 1, 0, 0, d, 9) == LSBUS_E_ARGUMENT);
    CHECK(lsbus_can_append_transmit(&b, 0x800, 0, 0, d, 0) == LSBUS_E_ARGUMENT);
    CHECK(lsbus_can_append_transmit(&b, 1, 0, 0, NULL, 1) == LSBUS_E_ARGUMENT);
    CHECK(lsbus_can_append_bus_error(&b, 1, 0, 1, 0) == LSBUS_E_ARGUMENT);
    CHECK(lsbus_can_append_status(&b, 0) == LSBUS_E_ARGUMENT);
    CHECK(lsbus_can_append_config_baudrate(&b, 4, 500000) == LSBUS_E_ARGUMENT);
    CHECK(b.size == 24);
    lsbus_buffer_clear(&b);
    CHECK(b.size == 0);
    CHECK(strcmp(lsbus_op_name(0x10), "CAN Transmit") == 0);
    CHECK(strcmp(lsbus_op_name(0x99), "unknown") == 0);
}

int main(void) {
    test_transmit_bytes();
    test_each_operation_bytes();
    test_truncation();
    test_malformed();
    test_append_limits();
    if (failures) {
        printf("lsbus_can_test: %d failed\n", failures);
        return 1;
    }
    printf("lsbus_can_test: all checks passed\n");
    return 0;
}
