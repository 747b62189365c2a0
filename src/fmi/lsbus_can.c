/* FMI-LS-BUS 1.0 CAN bus operations: reading and writing (lsbus_can.h).
 * Every operation's layout is the table of its section in fmi-ls-bus v1.0.0
 * docs/4_4_1_can.adoc ("Operations"); the header and the Format Error are in
 * docs/4____network_abstraction.adoc ("Operations", "Format Error"). */
#include "lsbus_can.h"

#include <string.h>

const char *lsbus_result_name(LsBusResult r) {
    switch (r) {
    case LSBUS_OK:          return "ok";
    case LSBUS_END:         return "end of buffer";
    case LSBUS_E_FULL:      return "buffer full";
    case LSBUS_E_ARGUMENT:  return "argument out of range";
    case LSBUS_E_TRUNCATED: return "truncated operation";
    case LSBUS_E_LENGTH:    return "wrong length";
    case LSBUS_E_UNKNOWN_OP: return "unknown operation";
    case LSBUS_E_VALUE:     return "argument out of its defined values";
    }
    return "unknown result";
}

const char *lsbus_op_name(uint32_t op) {
    switch (op) {
    case LSBUS_OP_FORMAT_ERROR:         return "Format Error";
    case LSBUS_CAN_OP_TRANSMIT:         return "CAN Transmit";
    case LSBUS_CAN_OP_FD_TRANSMIT:      return "CAN FD Transmit";
    case LSBUS_CAN_OP_XL_TRANSMIT:      return "CAN XL Transmit";
    case LSBUS_CAN_OP_CONFIRM:          return "Confirm";
    case LSBUS_CAN_OP_ARBITRATION_LOST: return "Arbitration Lost";
    case LSBUS_CAN_OP_BUS_ERROR:        return "Bus Error";
    case LSBUS_CAN_OP_CONFIGURATION:    return "Configuration";
    case LSBUS_CAN_OP_STATUS:           return "Status";
    case LSBUS_CAN_OP_WAKEUP:           return "Wakeup";
    }
    return "unknown";
}

/* ---- reading ------------------------------------------------------------------- */

static int is_bool(uint8_t b) { return b == LSBUS_FALSE || b == LSBUS_TRUE; }

/* the data lengths a CAN FD frame can have (ISO 11898-1: DLC 0-8, then 9-15
   as 12, 16, 20, 24, 32, 48, 64 bytes); LS-BUS's Data includes the padding */
static int fd_length_ok(uint16_t dl) {
    return dl <= 8 || dl == 12 || dl == 16 || dl == 20 || dl == 24 || dl == 32 ||
           dl == 48 || dl == 64;
}

/* the identifier fits its format: 11 bits (Ide FALSE) or 29 bits (Ide TRUE) */
static int id_ok(uint32_t id, uint8_t ide) {
    return id <= (ide == LSBUS_TRUE ? 0x1FFFFFFFu : 0x7FFu);
}

/* the arguments of a whole operation p[0, len), header already in op */
static LsBusResult decode(const uint8_t *p, uint32_t len, LsBusCanOp *op) {
    const uint8_t *a = p + LSBUS_HEADER_SIZE;    /* the arguments */
    switch (op->op) {
    case LSBUS_OP_FORMAT_ERROR:
        if (len < LSBUS_FORMAT_ERROR_SIZE) return LSBUS_E_LENGTH;
        op->dataLength = lsbus_get_u16(a);
        if (len != (uint32_t)LSBUS_FORMAT_ERROR_SIZE + op->dataLength) return LSBUS_E_LENGTH;
        op->data = a + 2;
        return LSBUS_OK;
    case LSBUS_CAN_OP_TRANSMIT:
        if (len < LSBUS_CAN_TRANSMIT_SIZE) return LSBUS_E_LENGTH;
        op->id = lsbus_get_u32(a);
        op->ide = a[4];
        op->rtr = a[5];
        op->dataLength = lsbus_get_u16(a + 6);
        if (len != (uint32_t)LSBUS_CAN_TRANSMIT_SIZE + op->dataLength) return LSBUS_E_LENGTH;
        op->data = a + 8;
        if (!is_bool(op->ide) || !is_bool(op->rtr) || !id_ok(op->id, op->ide) ||
            op->dataLength > LSBUS_CAN_MAX_DATA)
            return LSBUS_E_VALUE;
        return LSBUS_OK;
    case LSBUS_CAN_OP_FD_TRANSMIT:
        if (len < LSBUS_CAN_FD_TRANSMIT_SIZE) return LSBUS_E_LENGTH;
        op->id = lsbus_get_u32(a);
        op->ide = a[4];
        op->brs = a[5];
        op->esi = a[6];
        op->dataLength = lsbus_get_u16(a + 7);
        if (len != (uint32_t)LSBUS_CAN_FD_TRANSMIT_SIZE + op->dataLength) return LSBUS_E_LENGTH;
        op->data = a + 9;
        if (!is_bool(op->ide) || !is_bool(op->brs) || !is_bool(op->esi) ||
            !id_ok(op->id, op->ide) || !fd_length_ok(op->dataLength))
            return LSBUS_E_VALUE;
        return LSBUS_OK;
    case LSBUS_CAN_OP_XL_TRANSMIT:
        if (len < LSBUS_CAN_XL_TRANSMIT_SIZE) return LSBUS_E_LENGTH;
        op->id = lsbus_get_u32(a);
        op->ide = a[4];
        op->sec = a[5];
        op->sdt = a[6];
        op->vcid = a[7];
        op->af = lsbus_get_u32(a + 8);
        op->dataLength = lsbus_get_u16(a + 12);
        if (len != (uint32_t)LSBUS_CAN_XL_TRANSMIT_SIZE + op->dataLength) return LSBUS_E_LENGTH;
        op->data = a + 14;
        if (!is_bool(op->ide) || !is_bool(op->sec) || !id_ok(op->id, op->ide) ||
            op->dataLength < 1 || op->dataLength > LSBUS_CAN_XL_MAX_DATA)
            return LSBUS_E_VALUE;
        return LSBUS_OK;
    case LSBUS_CAN_OP_CONFIRM:
    case LSBUS_CAN_OP_ARBITRATION_LOST:
        if (len != LSBUS_CAN_CONFIRM_SIZE) return LSBUS_E_LENGTH;
        op->id = lsbus_get_u32(a);
        return LSBUS_OK;
    case LSBUS_CAN_OP_BUS_ERROR:
        if (len != LSBUS_CAN_BUS_ERROR_SIZE) return LSBUS_E_LENGTH;
        op->id = lsbus_get_u32(a);
        op->errorCode = a[4];
        op->errorFlag = a[5];
        op->isSender = a[6];
        if (op->errorCode < LSBUS_CAN_BIT_ERROR || op->errorCode > LSBUS_CAN_BROKEN_ERROR_FRAME ||
            (op->errorFlag != LSBUS_CAN_PRIMARY_ERROR_FLAG &&
             op->errorFlag != LSBUS_CAN_SECONDARY_ERROR_FLAG) || !is_bool(op->isSender))
            return LSBUS_E_VALUE;
        return LSBUS_OK;
    case LSBUS_CAN_OP_CONFIGURATION:
        if (len < LSBUS_CAN_CONFIGURATION_SIZE) return LSBUS_E_LENGTH;
        op->parameterType = a[0];
        switch (op->parameterType) {
        case LSBUS_CAN_CONFIG_CAN_BAUDRATE:
        case LSBUS_CAN_CONFIG_CAN_FD_BAUDRATE:
        case LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE:
            if (len != LSBUS_CAN_CONFIGURATION_SIZE + 4) return LSBUS_E_LENGTH;
            op->baudrate = lsbus_get_u32(a + 1);
            return op->baudrate > 0 ? LSBUS_OK : LSBUS_E_VALUE;
        case LSBUS_CAN_CONFIG_ARBITRATION_LOST_BEHAVIOR:
            if (len != LSBUS_CAN_CONFIGURATION_SIZE + 1) return LSBUS_E_LENGTH;
            op->arbitrationLostBehavior = a[1];
            return (op->arbitrationLostBehavior == LSBUS_CAN_BUFFER_AND_RETRANSMIT ||
                    op->arbitrationLostBehavior == LSBUS_CAN_DISCARD_AND_NOTIFY)
                       ? LSBUS_OK : LSBUS_E_VALUE;
        }
        return LSBUS_E_VALUE;
    case LSBUS_CAN_OP_STATUS:
        if (len != LSBUS_CAN_STATUS_SIZE) return LSBUS_E_LENGTH;
        op->status = a[0];
        return (op->status >= LSBUS_CAN_ERROR_ACTIVE && op->status <= LSBUS_CAN_BUS_OFF)
                   ? LSBUS_OK : LSBUS_E_VALUE;
    case LSBUS_CAN_OP_WAKEUP:
        return len == LSBUS_CAN_WAKEUP_SIZE ? LSBUS_OK : LSBUS_E_LENGTH;
    }
    return LSBUS_E_UNKNOWN_OP;
}

LsBusResult lsbus_can_read(const uint8_t *buf, size_t size, size_t *pos, LsBusCanOp *op) {
    memset(op, 0, sizeof *op);
    if (*pos >= size) {
        *pos = size;
        return LSBUS_END;
    }
    const size_t left = size - *pos;
    const uint8_t *p = buf + *pos;
    op->raw = p;
    op->rawSize = left;
    if (left < LSBUS_HEADER_SIZE) {
        *pos = size;
        return LSBUS_E_TRUNCATED;
    }
    op->op = lsbus_get_u32(p);
    op->length = lsbus_get_u32(p + 4);
    if (op->length < LSBUS_HEADER_SIZE || op->length > left) {
        *pos = size;
        return LSBUS_E_TRUNCATED;
    }
    /* from here on the operation lies inside the buffer: skip it whatever it holds */
    op->rawSize = op->length;
    *pos += op->length;
    return decode(p, op->length, op);
}

/* ---- writing ------------------------------------------------------------------- */

void lsbus_buffer_init(LsBusBuffer *b, uint8_t *mem, size_t capacity) {
    b->data = mem;
    b->size = 0;
    b->capacity = capacity;
}

void lsbus_buffer_clear(LsBusBuffer *b) { b->size = 0; }

static void put_u16(uint8_t *p, uint16_t x) {
    p[0] = (uint8_t)x;
    p[1] = (uint8_t)(x >> 8);
}

static void put_u32(uint8_t *p, uint32_t x) {
    p[0] = (uint8_t)x;
    p[1] = (uint8_t)(x >> 8);
    p[2] = (uint8_t)(x >> 16);
    p[3] = (uint8_t)(x >> 24);
}

/* room for an operation of len bytes: its start with the header written, or NULL */
static uint8_t *reserve(LsBusBuffer *b, uint32_t op, size_t len) {
    if (b->size > b->capacity || len > b->capacity - b->size) return NULL;
    uint8_t *p = b->data + b->size;
    put_u32(p, op);
    put_u32(p + 4, (uint32_t)len);
    b->size += len;
    return p;
}

LsBusResult lsbus_can_append_transmit(LsBusBuffer *b, uint32_t id, uint8_t ide, uint8_t rtr,
                                      const uint8_t *data, uint16_t dataLength) {
    if (!is_bool(ide) || !is_bool(rtr) || !id_ok(id, ide) || dataLength > LSBUS_CAN_MAX_DATA ||
        (dataLength > 0 && data == NULL))
        return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_CAN_OP_TRANSMIT, (size_t)LSBUS_CAN_TRANSMIT_SIZE + dataLength);
    if (!p) return LSBUS_E_FULL;
    put_u32(p + 8, id);
    p[12] = ide;
    p[13] = rtr;
    put_u16(p + 14, dataLength);
    if (dataLength > 0) memcpy(p + 16, data, dataLength);
    return LSBUS_OK;
}

static LsBusResult append_id(LsBusBuffer *b, uint32_t op, uint32_t id) {
    uint8_t *p = reserve(b, op, LSBUS_CAN_CONFIRM_SIZE);
    if (!p) return LSBUS_E_FULL;
    put_u32(p + 8, id);
    return LSBUS_OK;
}

LsBusResult lsbus_can_append_confirm(LsBusBuffer *b, uint32_t id) {
    return append_id(b, LSBUS_CAN_OP_CONFIRM, id);
}

LsBusResult lsbus_can_append_arbitration_lost(LsBusBuffer *b, uint32_t id) {
    return append_id(b, LSBUS_CAN_OP_ARBITRATION_LOST, id);
}

LsBusResult lsbus_can_append_bus_error(LsBusBuffer *b, uint32_t id, uint8_t errorCode,
                                       uint8_t errorFlag, uint8_t isSender) {
    if (errorCode < LSBUS_CAN_BIT_ERROR || errorCode > LSBUS_CAN_BROKEN_ERROR_FRAME ||
        (errorFlag != LSBUS_CAN_PRIMARY_ERROR_FLAG && errorFlag != LSBUS_CAN_SECONDARY_ERROR_FLAG) ||
        !is_bool(isSender))
        return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_CAN_OP_BUS_ERROR, LSBUS_CAN_BUS_ERROR_SIZE);
    if (!p) return LSBUS_E_FULL;
    put_u32(p + 8, id);
    p[12] = errorCode;
    p[13] = errorFlag;
    p[14] = isSender;
    return LSBUS_OK;
}

LsBusResult lsbus_can_append_config_baudrate(LsBusBuffer *b, uint8_t parameterType,
                                             uint32_t baudrate) {
    if ((parameterType != LSBUS_CAN_CONFIG_CAN_BAUDRATE &&
         parameterType != LSBUS_CAN_CONFIG_CAN_FD_BAUDRATE &&
         parameterType != LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE) || baudrate == 0)
        return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_CAN_OP_CONFIGURATION, LSBUS_CAN_CONFIGURATION_SIZE + 4);
    if (!p) return LSBUS_E_FULL;
    p[8] = parameterType;
    put_u32(p + 9, baudrate);
    return LSBUS_OK;
}

LsBusResult lsbus_can_append_config_arbitration_lost(LsBusBuffer *b, uint8_t behavior) {
    if (behavior != LSBUS_CAN_BUFFER_AND_RETRANSMIT && behavior != LSBUS_CAN_DISCARD_AND_NOTIFY)
        return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_CAN_OP_CONFIGURATION, LSBUS_CAN_CONFIGURATION_SIZE + 1);
    if (!p) return LSBUS_E_FULL;
    p[8] = LSBUS_CAN_CONFIG_ARBITRATION_LOST_BEHAVIOR;
    p[9] = behavior;
    return LSBUS_OK;
}

LsBusResult lsbus_can_append_status(LsBusBuffer *b, uint8_t status) {
    if (status < LSBUS_CAN_ERROR_ACTIVE || status > LSBUS_CAN_BUS_OFF) return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_CAN_OP_STATUS, LSBUS_CAN_STATUS_SIZE);
    if (!p) return LSBUS_E_FULL;
    p[8] = status;
    return LSBUS_OK;
}

LsBusResult lsbus_can_append_wakeup(LsBusBuffer *b) {
    return reserve(b, LSBUS_CAN_OP_WAKEUP, LSBUS_CAN_WAKEUP_SIZE) ? LSBUS_OK : LSBUS_E_FULL;
}

LsBusResult lsbus_append_format_error(LsBusBuffer *b, const uint8_t *data, size_t dataLength) {
    if (dataLength > 0xFFFF) dataLength = 0xFFFF;
    if (dataLength > 0 && data == NULL) return LSBUS_E_ARGUMENT;
    uint8_t *p = reserve(b, LSBUS_OP_FORMAT_ERROR, LSBUS_FORMAT_ERROR_SIZE + dataLength);
    if (!p) return LSBUS_E_FULL;
    put_u16(p + 8, (uint16_t)dataLength);
    if (dataLength > 0) memmove(p + 10, data, dataLength);
    return LSBUS_OK;
}
