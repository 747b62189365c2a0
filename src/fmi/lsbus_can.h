/* FMI-LS-BUS 1.0 CAN bus operations in a Binary buffer (Rx_Data / Tx_Data):
 * append an operation to a buffer, and walk a buffer operation by operation.
 * Plain C99, no FMI types: used by the bus simulation FMU (CanBus) and the
 * network FMUs alike, and by a test built without any FMI header.
 *
 * The wire format (fmi-ls-bus v1.0.0, docs/4____network_abstraction.adoc,
 * "Operations"): every operation is
 *     OP Code (4 bytes) | Length (4 bytes) | arguments
 * numbers little-endian, Length the operation's total size in bytes, its header
 * included (Transmit: 16 + Data Length = 4 + 4 + ID 4 + Ide 1 + Rtr 1 + DL 2);
 * a buffer holds 0..n operations back to back, and an empty one has size 0.
 * The CAN operations and their codes: docs/4_4_1_can.adoc, "Operations"; the
 * Format Error (0x01, any bus): docs/4____network_abstraction.adoc, "Format Error".
 *
 * Reading never goes past the end of the buffer: a truncated or malformed
 * operation gives an error code (LsBusResult) and the bytes of the operation,
 * so that the reader can answer with a Format Error carrying them.
 */
#ifndef ARTIBUS_LSBUS_CAN_H
#define ARTIBUS_LSBUS_CAN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- codes of the standard ------------------------------------------------ */

/* operation codes (4_4_1_can.adoc, "Operations"; Format Error: 4____network_abstraction.adoc) */
enum {
    LSBUS_OP_FORMAT_ERROR          = 0x01,
    LSBUS_CAN_OP_TRANSMIT          = 0x10,
    LSBUS_CAN_OP_FD_TRANSMIT       = 0x11,
    LSBUS_CAN_OP_XL_TRANSMIT       = 0x12,
    LSBUS_CAN_OP_CONFIRM           = 0x20,
    LSBUS_CAN_OP_ARBITRATION_LOST  = 0x30,
    LSBUS_CAN_OP_BUS_ERROR         = 0x31,
    LSBUS_CAN_OP_CONFIGURATION     = 0x40,
    LSBUS_CAN_OP_STATUS            = 0x41,
    LSBUS_CAN_OP_WAKEUP            = 0x42
};

/* the fixed part of each operation, header included: Length = size + data */
enum {
    LSBUS_HEADER_SIZE              = 8,   /* OP Code + Length */
    LSBUS_FORMAT_ERROR_SIZE        = 10,  /* + Data Length 2, then Data */
    LSBUS_CAN_TRANSMIT_SIZE        = 16,  /* + ID 4, Ide 1, Rtr 1, Data Length 2, then Data */
    LSBUS_CAN_FD_TRANSMIT_SIZE     = 17,  /* + ID 4, Ide, Brs, Esi 1 each, Data Length 2 */
    LSBUS_CAN_XL_TRANSMIT_SIZE     = 22,  /* + ID 4, Ide, Sec, SDT, VCID 1 each, AF 4, DL 2 */
    LSBUS_CAN_CONFIRM_SIZE         = 12,  /* + ID 4 */
    LSBUS_CAN_ARBITRATION_LOST_SIZE = 12, /* + ID 4 */
    LSBUS_CAN_BUS_ERROR_SIZE       = 15,  /* + ID 4, Error Code 1, Error Flag 1, Is Sender 1 */
    LSBUS_CAN_CONFIGURATION_SIZE   = 9,   /* + Parameter Type 1, then the parameter */
    LSBUS_CAN_STATUS_SIZE          = 9,   /* + Status 1 */
    LSBUS_CAN_WAKEUP_SIZE          = 8
};

/* the largest Data of a frame: CAN 8, CAN FD 64, CAN XL 2048 bytes (ISO 11898-1) */
enum { LSBUS_CAN_MAX_DATA = 8, LSBUS_CAN_FD_MAX_DATA = 64, LSBUS_CAN_XL_MAX_DATA = 2048 };

/* boolean arguments (4____network_abstraction.adoc, "Basic Type Definitions") */
enum { LSBUS_FALSE = 0x00, LSBUS_TRUE = 0x01 };

/* Bus Error: Error Code and Error Flag (4_4_1_can.adoc, "Bus Error") */
enum {
    LSBUS_CAN_BIT_ERROR            = 0x01,
    LSBUS_CAN_BIT_STUFFING_ERROR   = 0x02,
    LSBUS_CAN_FORM_ERROR           = 0x03,
    LSBUS_CAN_CRC_ERROR            = 0x04,
    LSBUS_CAN_ACK_ERROR            = 0x05,
    LSBUS_CAN_BROKEN_ERROR_FRAME   = 0x06
};
enum { LSBUS_CAN_PRIMARY_ERROR_FLAG = 0x01, LSBUS_CAN_SECONDARY_ERROR_FLAG = 0x02 };

/* Configuration: Parameter Type, and the Arbitration Lost Behavior values
   (4_4_1_can.adoc, "Configuration") */
enum {
    LSBUS_CAN_CONFIG_CAN_BAUDRATE              = 0x01,   /* u32 bit/s */
    LSBUS_CAN_CONFIG_CAN_FD_BAUDRATE           = 0x02,   /* u32 bit/s */
    LSBUS_CAN_CONFIG_CAN_XL_BAUDRATE           = 0x03,   /* u32 bit/s */
    LSBUS_CAN_CONFIG_ARBITRATION_LOST_BEHAVIOR = 0x04    /* u8, below */
};
enum { LSBUS_CAN_BUFFER_AND_RETRANSMIT = 0x01, LSBUS_CAN_DISCARD_AND_NOTIFY = 0x02 };

/* Status (4_4_1_can.adoc, "Status") */
enum { LSBUS_CAN_ERROR_ACTIVE = 0x01, LSBUS_CAN_ERROR_PASSIVE = 0x02, LSBUS_CAN_BUS_OFF = 0x03 };

/* ---- results ---------------------------------------------------------------- */

typedef enum {
    LSBUS_OK = 0,          /* an operation appended, or read into *op */
    LSBUS_END,             /* the buffer has no more operations */
    LSBUS_E_FULL,          /* append: the operation does not fit; the buffer is unchanged */
    LSBUS_E_ARGUMENT,      /* append: an argument outside what the standard allows
                              (Data Length above the format's, a NULL data pointer) */
    LSBUS_E_TRUNCATED,     /* read: fewer bytes left than a header, or than its Length */
    LSBUS_E_LENGTH,        /* read: Length does not match the operation (Transmit: 16 + DL) */
    LSBUS_E_UNKNOWN_OP,    /* read: an OP Code this standard does not define for CAN */
    LSBUS_E_VALUE          /* read: an argument outside its defined values (a boolean
                              not 0/1, Data Length above the format's, an unknown
                              Parameter Type, Error Code, Error Flag or Status) */
} LsBusResult;

/* a short text for a result ("truncated operation", ...) */
const char *lsbus_result_name(LsBusResult r);
/* the name of an OP Code ("CAN Transmit", ...), "unknown" if none */
const char *lsbus_op_name(uint32_t op);

/* ---- one operation, decoded ------------------------------------------------------ */

/* The arguments of every operation in one plain struct; an operation uses
   those its table lists, the rest are zero. data points into the buffer read. */
typedef struct {
    uint32_t op;              /* OP Code */
    uint32_t length;          /* Length: total bytes, header included */
    uint32_t id;              /* Transmit, Confirm, Arbitration Lost, Bus Error */
    uint8_t ide, rtr;         /* Transmit (Ide also FD/XL): LSBUS_TRUE/FALSE */
    uint8_t brs, esi;         /* CAN FD Transmit */
    uint8_t sec, sdt, vcid;   /* CAN XL Transmit */
    uint32_t af;              /* CAN XL Transmit: acceptance field */
    uint16_t dataLength;      /* Transmit (all three), Format Error: bytes of data */
    const uint8_t *data;
    uint8_t errorCode, errorFlag, isSender;   /* Bus Error */
    uint8_t parameterType;    /* Configuration */
    uint32_t baudrate;        /* Configuration CAN/CAN FD/CAN XL baud rate, bit/s */
    uint8_t arbitrationLostBehavior;          /* Configuration */
    uint8_t status;           /* Status */
    /* the operation's bytes as read (also after an error: what a Format Error
       carries back; for a truncated one, the rest of the buffer) */
    const uint8_t *raw;
    size_t rawSize;
} LsBusCanOp;

/* ---- reading ------------------------------------------------------------------- */

/* Reads the operation at buf[*pos] (0 <= *pos <= size) into *op.
 *   LSBUS_OK: *op holds it, *pos is past it.
 *   LSBUS_END: *pos == size, nothing read.
 *   LSBUS_E_LENGTH, _UNKNOWN_OP, _VALUE: the operation's Length fits in the
 *     buffer, so *pos is past it and the next call reads the one after it;
 *     op->op, op->length, op->raw and op->rawSize describe the bad one.
 *   LSBUS_E_TRUNCATED: Length is below a header or beyond the end: nothing
 *     after it can be trusted, *pos is set to size; op->raw is the rest.
 * Never reads outside buf[0, size). An unknown OP Code is reported as such, so
 * that a reader that tolerates it (the standard lets a network FMU ignore
 * operations it does not use) skips it by its Length. */
LsBusResult lsbus_can_read(const uint8_t *buf, size_t size, size_t *pos, LsBusCanOp *op);

/* ---- writing ------------------------------------------------------------------- */

/* A buffer being written: capacity bytes at data, size of them used. */
typedef struct {
    uint8_t *data;
    size_t size;
    size_t capacity;
} LsBusBuffer;

/* an empty buffer over mem[capacity] */
void lsbus_buffer_init(LsBusBuffer *b, uint8_t *mem, size_t capacity);
/* size back to 0 (nothing to send) */
void lsbus_buffer_clear(LsBusBuffer *b);

/* Append one operation; LSBUS_E_FULL (buffer unchanged) if it does not fit,
   LSBUS_E_ARGUMENT if an argument is outside the standard's values. */
LsBusResult lsbus_can_append_transmit(LsBusBuffer *b, uint32_t id, uint8_t ide, uint8_t rtr,
                                      const uint8_t *data, uint16_t dataLength);
LsBusResult lsbus_can_append_confirm(LsBusBuffer *b, uint32_t id);
LsBusResult lsbus_can_append_arbitration_lost(LsBusBuffer *b, uint32_t id);
LsBusResult lsbus_can_append_bus_error(LsBusBuffer *b, uint32_t id, uint8_t errorCode,
                                       uint8_t errorFlag, uint8_t isSender);
/* parameterType LSBUS_CAN_CONFIG_CAN_BAUDRATE, _FD_ or _XL_: baud rate in bit/s */
LsBusResult lsbus_can_append_config_baudrate(LsBusBuffer *b, uint8_t parameterType,
                                             uint32_t baudrate);
LsBusResult lsbus_can_append_config_arbitration_lost(LsBusBuffer *b, uint8_t behavior);
LsBusResult lsbus_can_append_status(LsBusBuffer *b, uint8_t status);
LsBusResult lsbus_can_append_wakeup(LsBusBuffer *b);
/* a Format Error carrying the bad operation's bytes (at most 65535 of them:
   Data Length is 2 bytes; a longer one is cut there) */
LsBusResult lsbus_append_format_error(LsBusBuffer *b, const uint8_t *data, size_t dataLength);

/* the CAN frame of an operation read as plain values: little-endian helpers,
   for the codec and its users */
static inline uint32_t lsbus_get_u32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint16_t lsbus_get_u16(const uint8_t *p) {
    return (uint16_t)(p[0] | p[1] << 8);
}

#ifdef __cplusplus
}
#endif

#endif
