/* artibus's LS-BUS CAN codec (src/fmi/lsbus_can.c) against the FMI-LS-BUS 1.0 C
 * headers of the Modelica Association (fmi3LsBusCan.h, fmi3LsBusUtilCan.h; BSD-2-Clause,
 * from the crate fmi-sys 0.6.0 on crates.io: scripts/fetch_lsbus_headers.sh), built by
 * tests/test_lsbus_official_headers.py with the sanitizers when the compiler has them.
 *
 *   lsbus_official_test            every CAN operation (fmi-ls-bus v1.0.0 4_4_1_can.adoc,
 *                                  "Operations"; Format Error: 4____network_abstraction.adoc)
 *                                  built with the standard's FMI3_LS_BUS_CAN_CREATE_OP_*
 *                                  macros and read with our lsbus_can_read (fields equal the
 *                                  macro's arguments); built with our lsbus_can_append_* and
 *                                  read with the standard's FMI3_LS_BUS_READ_NEXT_OPERATION
 *                                  into its packed structs (fields equal ours); both byte
 *                                  strings equal; both writers refuse a buffer one byte short.
 *   lsbus_official_test FILE...    each file one Binary buffer (a Tx_Data from a run): walked
 *                                  with the standard's FMI3_LS_BUS_READ_NEXT_OPERATION_DIRECT
 *                                  and our reader side by side; one line per operation printed
 *                                  from the standard's structs ("<file> <op> <fields>"), for
 *                                  the pytest to compare with what the DBC says.
 * Exit status: 0 when every check held, 1 otherwise (each failure printed). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3LsBusUtilCan.h"
#include "lsbus_can.h"

static int failures = 0, checks = 0;
#define CHECK(cond) do { checks++; if (!(cond)) { \
    printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond); failures++; } } while (0)

/* ---- the two codecs on one operation --------------------------------------------- */

/* buffer std[0, n) (built by the standard's macro) read by our codec: one operation, OK */
static LsBusCanOp ours_read_one(const uint8_t *buf, size_t n) {
    LsBusCanOp op;
    size_t pos = 0;
    LsBusResult r = lsbus_can_read(buf, n, &pos, &op);
    if (r != LSBUS_OK) printf("  our reader: %s on op 0x%x\n", lsbus_result_name(r), op.op);
    CHECK(r == LSBUS_OK);
    CHECK(pos == n);
    LsBusCanOp end;
    CHECK(lsbus_can_read(buf, n, &pos, &end) == LSBUS_END);
    return op;
}

/* our buffer read by the standard's reader (FMI3_LS_BUS_BUFFER_WRITE, then
   FMI3_LS_BUS_READ_NEXT_OPERATION): the one operation, NULL if it found none */
static fmi3LsBusOperationHeader *std_read_one(fmi3LsBusUtilBufferInfo *info, const uint8_t *buf, size_t n) {
    fmi3LsBusOperationHeader *h = NULL, *extra = NULL;
    FMI3_LS_BUS_BUFFER_WRITE(info, buf, n);
    CHECK(info->status == fmi3True);
    /* the macro is a bare `cond ? ... : ...` (no outer parentheses): negated, it must be
       parenthesised, or the `!` binds to its condition alone */
    if (!(FMI3_LS_BUS_READ_NEXT_OPERATION(info, h))) {
        CHECK(!"the standard's reader found no operation");
        return NULL;
    }
    CHECK(!(FMI3_LS_BUS_READ_NEXT_OPERATION(info, extra)));
    CHECK(h->length == n);
    return h;
}

/* the standard's bytes std[0, sn) and ours b: equal, byte for byte */
static void same_bytes(const char *what, const uint8_t *std, size_t sn, const LsBusBuffer *b) {
    int same = sn == b->size && memcmp(std, b->data, sn) == 0;
    if (!same) {
        printf("  %s: standard %zu bytes, ours %zu:\n   ", what, sn, b->size);
        for (size_t i = 0; i < sn; i++) printf(" %02x", std[i]);
        printf("\n   ");
        for (size_t i = 0; i < b->size; i++) printf(" %02x", b->data[i]);
        printf("\n");
    }
    CHECK(same);
}

enum { CAP = 4096 };
static uint8_t std_mem[CAP], our_mem[CAP], read_mem[CAP];

/* each operation: the standard's macro into std_mem (info s), ours into our_mem (b) */
#define BEGIN(s, b) do { FMI3_LS_BUS_BUFFER_INFO_INIT(&(s), std_mem, CAP); \
    lsbus_buffer_init(&(b), our_mem, CAP); } while (0)
#define STD_LEN(s) ((size_t)FMI3_LS_BUS_BUFFER_LENGTH(&(s)))

static void test_can_transmit(uint32_t id, uint8_t ide, uint8_t rtr, const uint8_t *data, uint16_t dl) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&s, id, ide, rtr, dl, data);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_TRANSMIT && op.length == 16u + dl);
    CHECK(op.id == id && op.ide == ide && op.rtr == rtr && op.dataLength == dl);
    CHECK(dl == 0 || memcmp(op.data, data, dl) == 0);

    CHECK(lsbus_can_append_transmit(&b, id, ide, rtr, data, dl) == LSBUS_OK);
    same_bytes("CAN Transmit", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    const fmi3LsBusCanOperationCanTransmit *t = (const fmi3LsBusCanOperationCanTransmit *)h;
    CHECK(h->opCode == FMI3_LS_BUS_CAN_OP_CAN_TRANSMIT);
    CHECK(t->id == id && t->ide == ide && t->rtr == rtr && t->dataLength == dl);
    CHECK(dl == 0 || memcmp(t->data, data, dl) == 0);
}

/* CAN FD and CAN XL: our codec reads them (a bus simulation must accept every frame
   format on its bus); it writes only classic CAN, the DBC's frames being 8 bytes */
static void test_can_fd_transmit(uint32_t id, uint8_t ide, uint8_t brs, uint8_t esi,
                                 const uint8_t *data, uint16_t dl) {
    fmi3LsBusUtilBufferInfo s;
    FMI3_LS_BUS_BUFFER_INFO_INIT(&s, std_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_FD_TRANSMIT(&s, id, ide, brs, esi, dl, data);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_FD_TRANSMIT && op.length == 17u + dl);
    CHECK(op.id == id && op.ide == ide && op.brs == brs && op.esi == esi && op.dataLength == dl);
    CHECK(dl == 0 || memcmp(op.data, data, dl) == 0);
}

static void test_can_xl_transmit(uint32_t id, uint8_t ide, uint8_t sec, uint8_t sdt, uint8_t vcid,
                                 uint32_t af, const uint8_t *data, uint16_t dl) {
    fmi3LsBusUtilBufferInfo s;
    FMI3_LS_BUS_BUFFER_INFO_INIT(&s, std_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_XL_TRANSMIT(&s, id, ide, sec, sdt, vcid, af, dl, data);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_XL_TRANSMIT && op.length == 22u + dl);
    CHECK(op.id == id && op.ide == ide && op.sec == sec && op.sdt == sdt && op.vcid == vcid);
    CHECK(op.af == af && op.dataLength == dl && memcmp(op.data, data, dl) == 0);
}

/* Confirm and Arbitration Lost: the same layout, ID only */
static void test_id_only(uint32_t code, uint32_t id) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    if (code == LSBUS_CAN_OP_CONFIRM) {
        FMI3_LS_BUS_CAN_CREATE_OP_CONFIRM(&s, id);
        CHECK(lsbus_can_append_confirm(&b, id) == LSBUS_OK);
    } else {
        FMI3_LS_BUS_CAN_CREATE_OP_ARBITRATION_LOST(&s, id);
        CHECK(lsbus_can_append_arbitration_lost(&b, id) == LSBUS_OK);
    }
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == code && op.length == 12 && op.id == id);
    same_bytes(lsbus_op_name(code), std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    CHECK(h->opCode == code);
    /* Confirm and Arbitration Lost are the same struct (header, id) in the standard */
    CHECK(((const fmi3LsBusCanOperationConfirm *)h)->id == id);
    CHECK(((const fmi3LsBusCanOperationArbitrationLost *)h)->id == id);
}

static void test_bus_error(uint32_t id, uint8_t code, uint8_t flag, uint8_t isSender) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_BUS_ERROR(&s, id, code, flag, isSender);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_BUS_ERROR && op.length == 15 && op.id == id);
    CHECK(op.errorCode == code && op.errorFlag == flag && op.isSender == isSender);
    CHECK(lsbus_can_append_bus_error(&b, id, code, flag, isSender) == LSBUS_OK);
    same_bytes("Bus Error", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    const fmi3LsBusCanOperationBusError *e = (const fmi3LsBusCanOperationBusError *)h;
    CHECK(h->opCode == FMI3_LS_BUS_CAN_OP_BUS_ERROR);
    CHECK(e->id == id && e->errorCode == code && e->errorFlag == flag && e->isSender == isSender);
}

/* Configuration: a baud rate (CAN, CAN FD, CAN XL) or the arbitration lost behaviour */
static void test_configuration_baudrate(uint8_t kind, uint32_t baud) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    if (kind == LSBUS_CAN_CONFIG_CAN_BAUDRATE) FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_BAUDRATE(&s, baud);
    if (kind == LSBUS_CAN_CONFIG_CAN_FD_BAUDRATE) FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_FD_BAUDRATE(&s, baud);
    if (kind == LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE) FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_XL_BAUDRATE(&s, baud);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_CONFIGURATION && op.length == 13);
    CHECK(op.parameterType == kind && op.baudrate == baud);
    CHECK(lsbus_can_append_config_baudrate(&b, kind, baud) == LSBUS_OK);
    same_bytes("Configuration (baud rate)", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    const fmi3LsBusCanOperationConfiguration *c = (const fmi3LsBusCanOperationConfiguration *)h;
    CHECK(h->opCode == FMI3_LS_BUS_CAN_OP_CONFIGURATION);
    CHECK(c->parameterType == kind && c->baudrate == baud);
}

static void test_configuration_arbitration_lost(uint8_t behavior) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_ARBITRATION_LOST_BEHAVIOR(&s, behavior);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_CONFIGURATION && op.length == 10);
    CHECK(op.parameterType == LSBUS_CAN_CONFIG_ARBITRATION_LOST_BEHAVIOR);
    CHECK(op.arbitrationLostBehavior == behavior);
    CHECK(lsbus_can_append_config_arbitration_lost(&b, behavior) == LSBUS_OK);
    same_bytes("Configuration (arbitration lost behaviour)", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    const fmi3LsBusCanOperationConfiguration *c = (const fmi3LsBusCanOperationConfiguration *)h;
    CHECK(c->parameterType == FMI3_LS_BUS_CAN_CONFIG_PARAM_TYPE_ARBITRATION_LOST_BEHAVIOR);
    CHECK(c->arbitrationLostBehavior == behavior);
}

static void test_status(uint8_t status) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_STATUS(&s, status);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_STATUS && op.length == 9 && op.status == status);
    CHECK(lsbus_can_append_status(&b, status) == LSBUS_OK);
    same_bytes("Status", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    CHECK(h->opCode == FMI3_LS_BUS_CAN_OP_STATUS);
    CHECK(((const fmi3LsBusCanOperationStatus *)h)->status == status);
}

static void test_wakeup(void) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CAN_CREATE_OP_WAKEUP(&s);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_CAN_OP_WAKEUP && op.length == 8);
    CHECK(lsbus_can_append_wakeup(&b) == LSBUS_OK);
    same_bytes("Wakeup", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (h) CHECK(h->opCode == FMI3_LS_BUS_CAN_OP_WAKEUP && h->length == 8);
}

static void test_format_error(const uint8_t *data, uint16_t dl) {
    fmi3LsBusUtilBufferInfo s, r;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_BUFFER_INFO_INIT(&r, read_mem, CAP);
    FMI3_LS_BUS_CREATE_OP_FORMAT_ERROR(&s, dl, data);
    CHECK(s.status == fmi3True);
    LsBusCanOp op = ours_read_one(std_mem, STD_LEN(s));
    CHECK(op.op == LSBUS_OP_FORMAT_ERROR && op.length == 10u + dl && op.dataLength == dl);
    CHECK(memcmp(op.data, data, dl) == 0);
    CHECK(lsbus_append_format_error(&b, data, dl) == LSBUS_OK);
    same_bytes("Format Error", std_mem, STD_LEN(s), &b);
    fmi3LsBusOperationHeader *h = std_read_one(&r, b.data, b.size);
    if (!h) return;
    const fmi3LsBusOperationFormatError *f = (const fmi3LsBusOperationFormatError *)h;
    CHECK(h->opCode == FMI3_LS_BUS_OP_FORMAT_ERROR && f->dataLength == dl);
    CHECK(memcmp(f->data, data, dl) == 0);
}

/* a whole Tx_Data as a node sends it at its first tick (Configuration, then the
   Transmits) and a bus simulation answers (Confirm, Arbitration Lost, Bus Error):
   one buffer, both writers, the same bytes; both readers agree operation by operation */
static void test_one_buffer_of_many(void) {
    static const uint8_t d8[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
    fmi3LsBusUtilBufferInfo s;
    LsBusBuffer b;
    BEGIN(s, b);
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_BAUDRATE(&s, 500000);
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_ARBITRATION_LOST_BEHAVIOR(
        &s, FMI3_LS_BUS_CAN_CONFIG_PARAM_ARBITRATION_LOST_BEHAVIOR_BUFFER_AND_RETRANSMIT);
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&s, 0x100, FMI3_LS_BUS_FALSE, FMI3_LS_BUS_FALSE, 8, d8);
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&s, 0x1ABCDEF, FMI3_LS_BUS_TRUE, FMI3_LS_BUS_FALSE, 3, d8);
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIRM(&s, 0x100);
    FMI3_LS_BUS_CAN_CREATE_OP_ARBITRATION_LOST(&s, 0x101);
    FMI3_LS_BUS_CAN_CREATE_OP_BUS_ERROR(&s, 0x102, FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_CRC_ERROR,
                                        FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_FLAG_PRIMARY_ERROR_FLAG,
                                        FMI3_LS_BUS_FALSE);
    FMI3_LS_BUS_CAN_CREATE_OP_STATUS(&s, FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_ERROR_ACTIVE);
    FMI3_LS_BUS_CAN_CREATE_OP_WAKEUP(&s);
    CHECK(s.status == fmi3True);
    CHECK(lsbus_can_append_config_baudrate(&b, LSBUS_CAN_CONFIG_CAN_BAUDRATE, 500000) == LSBUS_OK);
    CHECK(lsbus_can_append_config_arbitration_lost(&b, LSBUS_CAN_BUFFER_AND_RETRANSMIT) == LSBUS_OK);
    CHECK(lsbus_can_append_transmit(&b, 0x100, LSBUS_FALSE, LSBUS_FALSE, d8, 8) == LSBUS_OK);
    CHECK(lsbus_can_append_transmit(&b, 0x1ABCDEF, LSBUS_TRUE, LSBUS_FALSE, d8, 3) == LSBUS_OK);
    CHECK(lsbus_can_append_confirm(&b, 0x100) == LSBUS_OK);
    CHECK(lsbus_can_append_arbitration_lost(&b, 0x101) == LSBUS_OK);
    CHECK(lsbus_can_append_bus_error(&b, 0x102, LSBUS_CAN_CRC_ERROR, LSBUS_CAN_PRIMARY_ERROR_FLAG,
                                     LSBUS_FALSE) == LSBUS_OK);
    CHECK(lsbus_can_append_status(&b, LSBUS_CAN_ERROR_ACTIVE) == LSBUS_OK);
    CHECK(lsbus_can_append_wakeup(&b) == LSBUS_OK);
    same_bytes("a buffer of nine operations", std_mem, STD_LEN(s), &b);

    static const uint32_t codes[] = {0x40, 0x40, 0x10, 0x10, 0x20, 0x30, 0x31, 0x41, 0x42};
    size_t pos = 0, n = 0, direct = 0;
    fmi3LsBusOperationHeader *h;
    while (FMI3_LS_BUS_READ_NEXT_OPERATION_DIRECT(std_mem, STD_LEN(s), direct, h)) {
        LsBusCanOp op;
        CHECK(lsbus_can_read(our_mem, b.size, &pos, &op) == LSBUS_OK);
        CHECK(n < 9 && h->opCode == codes[n] && op.op == codes[n]);
        CHECK(h->length == op.length && pos == direct);
        n++;
    }
    CHECK(n == 9 && direct == STD_LEN(s));
}

/* a buffer one byte too short for an operation: the standard's writer sets status
   false and leaves it, ours answers LSBUS_E_FULL and leaves it; one byte more, both fit */
static void test_full_buffer(void) {
    static const uint8_t d8[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    for (size_t cap = 23; cap <= 24; cap++) {
        fmi3LsBusUtilBufferInfo s;
        LsBusBuffer b;
        FMI3_LS_BUS_BUFFER_INFO_INIT(&s, std_mem, cap);
        lsbus_buffer_init(&b, our_mem, cap);
        FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&s, 0x10, FMI3_LS_BUS_FALSE, FMI3_LS_BUS_FALSE, 8, d8);
        LsBusResult r = lsbus_can_append_transmit(&b, 0x10, LSBUS_FALSE, LSBUS_FALSE, d8, 8);
        CHECK((s.status == fmi3True) == (cap == 24) && (r == LSBUS_OK) == (cap == 24));
        CHECK((size_t)FMI3_LS_BUS_BUFFER_LENGTH(&s) == b.size && b.size == (cap == 24 ? 24u : 0u));
    }
}

static int run_operations(void) {
    static uint8_t big[2048];
    for (size_t i = 0; i < sizeof big; i++) big[i] = (uint8_t)(i * 7 + 3);
    /* the official macros memcpy(Data, DataLength) even for 0 bytes: a NULL Data
       there is undefined (C11 7.24.1), so an empty frame is given a real pointer */
    for (uint16_t dl = 0; dl <= 8; dl++) test_can_transmit(0x123, LSBUS_FALSE, LSBUS_FALSE, big, dl);
    test_can_transmit(0x000, LSBUS_FALSE, LSBUS_FALSE, big, 8);
    test_can_transmit(0x7FF, LSBUS_FALSE, LSBUS_TRUE, big, 0);              /* a remote frame */
    test_can_transmit(0x1FFFFFFF, LSBUS_TRUE, LSBUS_FALSE, big, 8);         /* 29-bit identifier */
    static const uint16_t fd_lengths[] = {0, 1, 8, 12, 16, 20, 24, 32, 48, 64};
    for (size_t i = 0; i < sizeof fd_lengths / sizeof fd_lengths[0]; i++)
        test_can_fd_transmit(0x456, LSBUS_FALSE, LSBUS_TRUE, LSBUS_FALSE, big, fd_lengths[i]);
    test_can_fd_transmit(0x1234567, LSBUS_TRUE, LSBUS_FALSE, LSBUS_TRUE, big, 64);
    test_can_xl_transmit(0x7FF, LSBUS_FALSE, LSBUS_TRUE, 0x03, 0x55, 0xDEADBEEF, big, 1);
    test_can_xl_transmit(0x1FFFFFFF, LSBUS_TRUE, LSBUS_FALSE, 0x00, 0x00, 0x00000001, big, 2048);
    test_id_only(LSBUS_CAN_OP_CONFIRM, 0x7FF);
    test_id_only(LSBUS_CAN_OP_CONFIRM, 0x1FFFFFFF);
    test_id_only(LSBUS_CAN_OP_ARBITRATION_LOST, 0x101);
    for (uint8_t code = LSBUS_CAN_BIT_ERROR; code <= LSBUS_CAN_BROKEN_ERROR_FRAME; code++) {
        test_bus_error(0x2A0, code, LSBUS_CAN_PRIMARY_ERROR_FLAG, LSBUS_TRUE);
        test_bus_error(0x2A0, code, LSBUS_CAN_SECONDARY_ERROR_FLAG, LSBUS_FALSE);
    }
    test_configuration_baudrate(LSBUS_CAN_CONFIG_CAN_BAUDRATE, 500000);
    test_configuration_baudrate(LSBUS_CAN_CONFIG_CAN_BAUDRATE, 125000);
    test_configuration_baudrate(LSBUS_CAN_CONFIG_CAN_FD_BAUDRATE, 2000000);
    test_configuration_baudrate(LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE, 10000000);
    test_configuration_arbitration_lost(LSBUS_CAN_BUFFER_AND_RETRANSMIT);
    test_configuration_arbitration_lost(LSBUS_CAN_DISCARD_AND_NOTIFY);
    test_status(LSBUS_CAN_ERROR_ACTIVE);
    test_status(LSBUS_CAN_ERROR_PASSIVE);
    test_status(LSBUS_CAN_BUS_OFF);
    test_wakeup();
    test_format_error(big, 0);
    test_format_error(big, 24);
    test_one_buffer_of_many();
    test_full_buffer();

    /* the standard's constants are ours */
    CHECK(FMI3_LS_BUS_OP_FORMAT_ERROR == LSBUS_OP_FORMAT_ERROR);
    CHECK(FMI3_LS_BUS_CAN_OP_CAN_TRANSMIT == LSBUS_CAN_OP_TRANSMIT);
    CHECK(FMI3_LS_BUS_CAN_OP_CANFD_TRANSMIT == LSBUS_CAN_OP_FD_TRANSMIT);
    CHECK(FMI3_LS_BUS_CAN_OP_CANXL_TRANSMIT == LSBUS_CAN_OP_XL_TRANSMIT);
    CHECK(FMI3_LS_BUS_CAN_OP_CONFIRM == LSBUS_CAN_OP_CONFIRM);
    CHECK(FMI3_LS_BUS_CAN_OP_ARBITRATION_LOST == LSBUS_CAN_OP_ARBITRATION_LOST);
    CHECK(FMI3_LS_BUS_CAN_OP_BUS_ERROR == LSBUS_CAN_OP_BUS_ERROR);
    CHECK(FMI3_LS_BUS_CAN_OP_CONFIGURATION == LSBUS_CAN_OP_CONFIGURATION);
    CHECK(FMI3_LS_BUS_CAN_OP_STATUS == LSBUS_CAN_OP_STATUS);
    CHECK(FMI3_LS_BUS_CAN_OP_WAKEUP == LSBUS_CAN_OP_WAKEUP);
    CHECK(FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_BIT_ERROR == LSBUS_CAN_BIT_ERROR);
    CHECK(FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_BROKEN_ERROR_FRAME == LSBUS_CAN_BROKEN_ERROR_FRAME);
    CHECK(FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_FLAG_SECONDARY_ERROR_FLAG == LSBUS_CAN_SECONDARY_ERROR_FLAG);
    CHECK(FMI3_LS_BUS_CAN_CONFIG_PARAM_TYPE_CANXL_BAUDRATE == LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE);
    CHECK(FMI3_LS_BUS_CAN_CONFIG_PARAM_ARBITRATION_LOST_BEHAVIOR_DISCARD_AND_NOTIFY == LSBUS_CAN_DISCARD_AND_NOTIFY);
    CHECK(FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_BUS_OFF == LSBUS_CAN_BUS_OFF);
    printf("operations: %d checks, %d failed\n", checks, failures);
    return failures ? 1 : 0;
}

/* ---- a buffer from a run, read by the standard's macros --------------------------- */

static void print_hex(const uint8_t *p, size_t n) {
    for (size_t i = 0; i < n; i++) printf("%02x", p[i]);
}

static int parse_file(const char *path) {
    static uint8_t buf[1 << 16];
    FILE *f = fopen(path, "rb");
    if (!f) {
        printf("FAIL %s: cannot open\n", path);
        return 1;
    }
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    size_t direct = 0, pos = 0;
    fmi3LsBusOperationHeader *h;
    while (FMI3_LS_BUS_READ_NEXT_OPERATION_DIRECT(buf, n, direct, h)) {
        LsBusCanOp op;
        LsBusResult r = lsbus_can_read(buf, n, &pos, &op);
        CHECK(r == LSBUS_OK && op.op == h->opCode && op.length == h->length && pos == direct);
        printf("%s ", path);
        switch (h->opCode) {
        case FMI3_LS_BUS_CAN_OP_CAN_TRANSMIT: {
            const fmi3LsBusCanOperationCanTransmit *t = (const fmi3LsBusCanOperationCanTransmit *)h;
            CHECK(h->length == 16u + t->dataLength);
            CHECK(op.id == t->id && op.dataLength == t->dataLength && memcmp(op.data, t->data, t->dataLength) == 0);
            printf("Transmit id=%u ide=%u rtr=%u dl=%u data=", t->id, t->ide, t->rtr, t->dataLength);
            print_hex(t->data, t->dataLength);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CONFIRM:
            printf("Confirm id=%u", ((const fmi3LsBusCanOperationConfirm *)h)->id);
            CHECK(op.id == ((const fmi3LsBusCanOperationConfirm *)h)->id);
            break;
        case FMI3_LS_BUS_CAN_OP_ARBITRATION_LOST:
            printf("ArbitrationLost id=%u", ((const fmi3LsBusCanOperationArbitrationLost *)h)->id);
            CHECK(op.id == ((const fmi3LsBusCanOperationArbitrationLost *)h)->id);
            break;
        case FMI3_LS_BUS_CAN_OP_BUS_ERROR: {
            const fmi3LsBusCanOperationBusError *e = (const fmi3LsBusCanOperationBusError *)h;
            printf("BusError id=%u code=%u flag=%u sender=%u", e->id, e->errorCode, e->errorFlag, e->isSender);
            CHECK(op.id == e->id && op.errorCode == e->errorCode && op.isSender == e->isSender);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CONFIGURATION: {
            const fmi3LsBusCanOperationConfiguration *c = (const fmi3LsBusCanOperationConfiguration *)h;
            if (c->parameterType == FMI3_LS_BUS_CAN_CONFIG_PARAM_TYPE_ARBITRATION_LOST_BEHAVIOR) {
                printf("Configuration type=%u behavior=%u", c->parameterType, c->arbitrationLostBehavior);
                CHECK(op.arbitrationLostBehavior == c->arbitrationLostBehavior);
            } else {
                printf("Configuration type=%u baudrate=%u", c->parameterType, c->baudrate);
                CHECK(op.baudrate == c->baudrate);
            }
            break;
        }
        case FMI3_LS_BUS_CAN_OP_STATUS:
            printf("Status status=%u", ((const fmi3LsBusCanOperationStatus *)h)->status);
            break;
        case FMI3_LS_BUS_CAN_OP_WAKEUP:
            printf("Wakeup");
            break;
        case FMI3_LS_BUS_OP_FORMAT_ERROR:
            printf("FormatError dl=%u data=", ((const fmi3LsBusOperationFormatError *)h)->dataLength);
            print_hex(((const fmi3LsBusOperationFormatError *)h)->data,
                      ((const fmi3LsBusOperationFormatError *)h)->dataLength);
            break;
        default:
            printf("unknown op=0x%x length=%u", h->opCode, h->length);
        }
        printf("\n");
    }
    /* the standard's reader stops where the buffer ends, nothing left over */
    CHECK(direct == n);
    return failures ? 1 : 0;
}

int main(int argc, char **argv) {
    if (argc == 1) return run_operations();
    int rc = 0;
    for (int i = 1; i < argc; i++) rc |= parse_file(argv[i]);
    if (rc) printf("parse: %d checks, %d failed\n", checks, failures);
    return rc;
}
