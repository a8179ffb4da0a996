/* Incremental frame parser; see proto_parser.h. */
#include "proto_parser.h"

void ah_parser_init(ah_parser_t *p, ah_msg_handler on_msg, void *ctx)
{
    p->n = 0;
    p->overflowed = 0;
    p->cnt.packets_ok = 0;
    p->cnt.crc_errors = 0;
    p->cnt.length_errors = 0;
    p->cnt.overflows = 0;
    p->cnt.version_errors = 0;
    p->cnt.type_errors = 0;
    p->on_msg = on_msg;
    p->ctx = ctx;
}

static void count(ah_parser_t *p, ah_status_t st)
{
    switch (st) {
    case AH_OK: p->cnt.packets_ok++; break;
    case AH_ERR_CRC: p->cnt.crc_errors++; break;
    case AH_ERR_LENGTH: p->cnt.length_errors++; break;
    case AH_ERR_OVERFLOW: p->cnt.overflows++; break;
    case AH_ERR_VERSION: p->cnt.version_errors++; break;
    case AH_ERR_TYPE: p->cnt.type_errors++; break;
    default: break;
    }
}

static ah_status_t end_of_frame(ah_parser_t *p, ah_msg_t *msg)
{
    size_t n = 0;
    ah_status_t st;
    if (p->overflowed) {
        p->overflowed = 0;
        p->n = 0;
        return AH_ERR_OVERFLOW;
    }
    if (p->n == 0) return AH_PENDING; /* empty frame: a delimiter used to resynchronise */
    st = ah_cobs_decode_inplace(p->buf, p->n, &n);
    p->n = 0;
    if (st != AH_OK) return st;
    return ah_decode_packet(p->buf, n, msg);
}

ah_status_t ah_parser_feed(ah_parser_t *p, uint8_t byte, ah_msg_t *msg)
{
    ah_status_t st;
    if (byte == 0x00u) {
        st = end_of_frame(p, msg);
        count(p, st);
        return st;
    }
    if (p->overflowed) return AH_PENDING;
    if (p->n >= AH_MAX_ENCODED) { /* longer than any valid frame: drop it whole */
        p->overflowed = 1;
        p->n = 0;
        return AH_PENDING;
    }
    p->buf[p->n++] = byte;
    return AH_PENDING;
}

void ah_parser_update(ah_parser_t *p, const uint8_t *data, size_t n)
{
    size_t i;
    ah_msg_t msg;
    for (i = 0; i < n; i++) {
        ah_status_t st = ah_parser_feed(p, data[i], &msg);
        if (st == AH_PENDING) continue;
        if (p->on_msg != 0) p->on_msg(p->ctx, st, st == AH_OK ? &msg : 0);
    }
}
