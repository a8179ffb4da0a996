/* Incremental, non-blocking frame parser (PacketSerial style): feed it whatever bytes arrived;
 * every complete frame, valid or not, reaches the handler with its status. A frame is decoded
 * into a message only after its length and CRC check out, so a corrupt or truncated frame is
 * dropped whole and counted, never half-delivered. Memory is one encoded frame (AH_MAX_ENCODED
 * bytes); COBS is decoded in place. */
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "proto_wire.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Called once per complete frame: st == AH_OK with the decoded message, or an error with msg NULL. */
typedef void (*ah_msg_handler)(void *ctx, ah_status_t st, const ah_msg_t *msg);

typedef struct {
    uint32_t packets_ok;
    uint32_t crc_errors;
    uint32_t length_errors;
    uint32_t overflows;
    uint32_t version_errors;
    uint32_t type_errors;
} ah_rx_counters_t;

typedef struct {
    uint8_t buf[AH_MAX_ENCODED]; /* encoded bytes of the frame being received */
    uint16_t n;
    uint8_t overflowed;          /* discarding until the next delimiter */
    ah_rx_counters_t cnt;
    ah_msg_handler on_msg;
    void *ctx;
} ah_parser_t;

void ah_parser_init(ah_parser_t *p, ah_msg_handler on_msg, void *ctx);

/* Feed one byte. Returns AH_PENDING while a frame is incomplete (and for empty frames, i.e.
 * repeated delimiters), AH_OK with *msg filled when a valid frame ended, or the error that
 * dropped it. Counts the result; does not call the handler. */
ah_status_t ah_parser_feed(ah_parser_t *p, uint8_t byte, ah_msg_t *msg);

/* Feed n bytes and call the handler for every frame they complete. Never blocks. */
void ah_parser_update(ah_parser_t *p, const uint8_t *data, size_t n);

#ifdef __cplusplus
}
#endif
