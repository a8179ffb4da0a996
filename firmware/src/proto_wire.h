/* The chair wire protocol: framing (COBS, 0x00 delimiter), CRC-16/CCITT-FALSE, and the messages.
 * The frame diagram and every field are specified in firmware/PROTOCOL.md (the one place); this
 * header mirrors it. Fields are written and read one by one, little-endian, never by copying a
 * struct, so the layout does not depend on the compiler. Portable C99: no heap, no VLAs. */
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "chair_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Result of decoding a frame. Negative values are errors; each has a counter in STATUS. */
typedef enum {
    AH_PENDING = 1,         /* parser: no complete frame yet */
    AH_OK = 0,
    AH_ERR_CRC = -1,        /* CRC mismatch */
    AH_ERR_LENGTH = -2,     /* too short, COBS run past the end, length field or payload size wrong */
    AH_ERR_OVERFLOW = -3,   /* more than AH_MAX_ENCODED bytes before a delimiter */
    AH_ERR_VERSION = -4,    /* version byte is not AH_PROTOCOL_VERSION */
    AH_ERR_TYPE = -5,       /* unknown message type, or one not meant for this receiver */
    AH_ERR_STALE = -6       /* FRAME sequence number not newer than the last applied one */
} ah_status_t;

typedef struct {
    uint32_t tick;                /* timeline tick index (100 ms each) */
    uint16_t seq;                 /* per-FRAME sequence number, wraps */
    uint8_t motors[AH_N_MOTORS];  /* A1..A9 intensity, 0..255 */
    int16_t temp_cc;              /* temperature target, centi-degrees C */
    uint8_t fans[AH_N_FANS];      /* fan level 0..255, row-major 9 x 17, row 0 = top */
} ah_frame_t;

typedef struct {
    uint8_t protocol_version;
    uint8_t fw_major, fw_minor, fw_patch;
    uint8_t n_actuators, fan_rows, fan_cols;
    int16_t temp_min_cc, temp_max_cc, temp_neutral_cc;
    uint16_t temp_rate_cc_per_s;
    uint16_t watchdog_ms;
    uint16_t tick_ms;
    uint16_t max_packet;
    char name[AH_NAME_LEN];       /* ASCII, zero padded, not necessarily zero terminated */
} ah_hello_t;

/* Flags in STATUS. */
#define AH_FLAG_SAFE     0x01u /* outputs are in the safe state (off, temperature to neutral) */
#define AH_FLAG_STOPPED  0x02u /* the safe state was commanded by STOP */
#define AH_FLAG_RAMPING  0x04u /* the temperature setpoint is still moving towards the target */
#define AH_FLAG_HAS_TICK 0x08u /* a FRAME was applied since boot: last_tick is meaningful */

/* Why the chair is in the safe state. */
#define AH_SAFE_NONE     0u
#define AH_SAFE_BOOT     1u
#define AH_SAFE_WATCHDOG 2u
#define AH_SAFE_STOP     3u

typedef struct {
    uint32_t uptime_ms;
    uint32_t frames_ok;        /* FRAMEs applied */
    uint32_t packets_ok;       /* valid packets of any type */
    uint32_t crc_errors;
    uint32_t length_errors;
    uint32_t overflows;
    uint32_t version_errors;
    uint32_t type_errors;
    uint32_t stale_frames;     /* dropped: out of order or duplicate */
    uint32_t seq_gaps;         /* FRAMEs missing, by sequence number */
    uint32_t late_frames;      /* arrived more than AH_LATE_MS after the previous FRAME */
    uint32_t watchdog_trips;
    uint32_t tx_dropped;       /* replies the chair could not send (output buffer full) */
    uint32_t last_tick;
    uint16_t last_seq;
    uint8_t flags;             /* AH_FLAG_* */
    uint8_t safe_reason;       /* AH_SAFE_* */
    int16_t temp_target_cc;
    int16_t temp_setpoint_cc;
} ah_status_msg_t;

typedef struct {
    uint8_t type; /* AH_MSG_*; HELLO_REQ, STATUS_REQ and STOP carry no payload */
    union {
        ah_frame_t frame;
        ah_hello_t hello;
        ah_status_msg_t status;
    } u;
} ah_msg_t;

/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor ("123456789" -> 0x29B1). */
uint16_t ah_crc16(const uint8_t *data, size_t n);

/* COBS-encode n bytes into dst (capacity cap), without the trailing 0x00. Returns the encoded
 * length, or 0 when it does not fit. */
size_t ah_cobs_encode(const uint8_t *src, size_t n, uint8_t *dst, size_t cap);

/* COBS-decode n bytes (no delimiter) in place; the decoded length goes to *out_n.
 * AH_ERR_LENGTH when a run points past the end or a zero byte appears inside the frame. */
ah_status_t ah_cobs_decode_inplace(uint8_t *buf, size_t n, size_t *out_n);

/* Payload length that message type `type` must carry, or -1 for an unknown type. */
int ah_payload_len(uint8_t type);

/* Decode and validate one packet (COBS already removed): length, CRC, version, type, payload
 * size, in that order. On AH_OK the message is in *msg; otherwise *msg is untouched except
 * msg->type, which holds the header's type byte when one was present. */
ah_status_t ah_decode_packet(const uint8_t *pkt, size_t n, ah_msg_t *msg);

/* Encode a message as wire bytes: COBS(packet) followed by the 0x00 delimiter.
 * Returns the number of bytes written to out, or 0 when cap is too small or the type unknown.
 * AH_MAX_ENCODED + 1 bytes always suffice. */
size_t ah_encode_msg(const ah_msg_t *msg, uint8_t *out, size_t cap);

/* Short name of a status ("ok", "crc_error", ...), for logs. */
const char *ah_status_name(ah_status_t st);

#ifdef __cplusplus
}
#endif
