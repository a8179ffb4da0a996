/* Wire format of the chair protocol; see proto_wire.h and firmware/PROTOCOL.md. */
#include "proto_wire.h"

#include <string.h>

/* ---- little-endian field access, one field at a time -------------------------------------- */
typedef struct {
    uint8_t *buf;
    size_t pos;
} ah_writer_t;

static void put_u8(ah_writer_t *w, uint8_t v) { w->buf[w->pos++] = v; }

static void put_u16(ah_writer_t *w, uint16_t v)
{
    put_u8(w, (uint8_t)(v & 0xFFu));
    put_u8(w, (uint8_t)(v >> 8));
}

static void put_i16(ah_writer_t *w, int16_t v) { put_u16(w, (uint16_t)v); }

static void put_u32(ah_writer_t *w, uint32_t v)
{
    put_u16(w, (uint16_t)(v & 0xFFFFu));
    put_u16(w, (uint16_t)(v >> 16));
}

static void put_bytes(ah_writer_t *w, const uint8_t *src, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) put_u8(w, src[i]);
}

typedef struct {
    const uint8_t *buf;
    size_t pos;
} ah_reader_t;

static uint8_t get_u8(ah_reader_t *r) { return r->buf[r->pos++]; }

static uint16_t get_u16(ah_reader_t *r)
{
    uint16_t lo = get_u8(r);
    uint16_t hi = get_u8(r);
    return (uint16_t)(lo | (uint16_t)(hi << 8));
}

static int16_t get_i16(ah_reader_t *r)
{
    uint16_t u = get_u16(r);
    return (u >= 0x8000u) ? (int16_t)((int32_t)u - 65536) : (int16_t)u;
}

static uint32_t get_u32(ah_reader_t *r)
{
    uint32_t lo = get_u16(r);
    uint32_t hi = get_u16(r);
    return lo | (hi << 16);
}

static void get_bytes(ah_reader_t *r, uint8_t *dst, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) dst[i] = get_u8(r);
}

/* ---- CRC-16/CCITT-FALSE, a nibble at a time (32-byte table) ------------------------------- */
static const uint16_t crc_nibble[16] = {
    0x0000u, 0x1021u, 0x2042u, 0x3063u, 0x4084u, 0x50A5u, 0x60C6u, 0x70E7u,
    0x8108u, 0x9129u, 0xA14Au, 0xB16Bu, 0xC18Cu, 0xD1ADu, 0xE1CEu, 0xF1EFu,
};

uint16_t ah_crc16(const uint8_t *data, size_t n)
{
    uint16_t crc = 0xFFFFu;
    size_t i;
    for (i = 0; i < n; i++) {
        uint8_t b = data[i];
        crc = (uint16_t)((uint16_t)(crc << 4) ^ crc_nibble[((crc >> 12) ^ (b >> 4)) & 0x0Fu]);
        crc = (uint16_t)((uint16_t)(crc << 4) ^ crc_nibble[((crc >> 12) ^ (b & 0x0Fu)) & 0x0Fu]);
    }
    return crc;
}

/* ---- COBS ---------------------------------------------------------------------------------- */
size_t ah_cobs_encode(const uint8_t *src, size_t n, uint8_t *dst, size_t cap)
{
    size_t i, o = 0, code_pos;
    uint8_t code = 1;
    if (cap == 0) return 0;
    code_pos = o++;
    for (i = 0; i < n; i++) {
        if (src[i] == 0) {
            dst[code_pos] = code;
            if (o >= cap) return 0;
            code_pos = o++;
            code = 1;
        } else {
            if (o >= cap) return 0;
            dst[o++] = src[i];
            code++;
            if (code == 0xFFu && i + 1 < n) { /* a full run; start the next only if bytes remain */
                dst[code_pos] = code;
                if (o >= cap) return 0;
                code_pos = o++;
                code = 1;
            }
        }
    }
    dst[code_pos] = code;
    return o;
}

ah_status_t ah_cobs_decode_inplace(uint8_t *buf, size_t n, size_t *out_n)
{
    size_t i = 0, o = 0; /* o <= i - 1 at every write: decoding in place never overtakes reading */
    while (i < n) {
        uint8_t code = buf[i++];
        uint8_t k;
        if (code == 0) return AH_ERR_LENGTH;
        for (k = 1; k < code; k++) {
            uint8_t b;
            if (i >= n) return AH_ERR_LENGTH; /* the run claims bytes the frame does not have */
            b = buf[i++];
            if (b == 0) return AH_ERR_LENGTH;
            buf[o++] = b;
        }
        if (code != 0xFFu && i < n) buf[o++] = 0;
    }
    *out_n = o;
    return AH_OK;
}

/* ---- messages ------------------------------------------------------------------------------ */
int ah_payload_len(uint8_t type)
{
    switch (type) {
    case AH_MSG_HELLO_REQ:
    case AH_MSG_STATUS_REQ:
    case AH_MSG_STOP:
        return 0;
    case AH_MSG_HELLO:
        return (int)AH_PAYLOAD_HELLO;
    case AH_MSG_STATUS:
        return (int)AH_PAYLOAD_STATUS;
    case AH_MSG_FRAME:
        return (int)AH_PAYLOAD_FRAME;
    default:
        return -1;
    }
}

static void write_payload(const ah_msg_t *msg, ah_writer_t *w)
{
    switch (msg->type) {
    case AH_MSG_FRAME: {
        const ah_frame_t *f = &msg->u.frame;
        put_u32(w, f->tick);
        put_u16(w, f->seq);
        put_bytes(w, f->motors, AH_N_MOTORS);
        put_i16(w, f->temp_cc);
        put_bytes(w, f->fans, AH_N_FANS);
        break;
    }
    case AH_MSG_HELLO: {
        const ah_hello_t *h = &msg->u.hello;
        put_u8(w, h->protocol_version);
        put_u8(w, h->fw_major);
        put_u8(w, h->fw_minor);
        put_u8(w, h->fw_patch);
        put_u8(w, h->n_actuators);
        put_u8(w, h->fan_rows);
        put_u8(w, h->fan_cols);
        put_i16(w, h->temp_min_cc);
        put_i16(w, h->temp_max_cc);
        put_i16(w, h->temp_neutral_cc);
        put_u16(w, h->temp_rate_cc_per_s);
        put_u16(w, h->watchdog_ms);
        put_u16(w, h->tick_ms);
        put_u16(w, h->max_packet);
        put_bytes(w, (const uint8_t *)h->name, AH_NAME_LEN);
        break;
    }
    case AH_MSG_STATUS: {
        const ah_status_msg_t *s = &msg->u.status;
        put_u32(w, s->uptime_ms);
        put_u32(w, s->frames_ok);
        put_u32(w, s->packets_ok);
        put_u32(w, s->crc_errors);
        put_u32(w, s->length_errors);
        put_u32(w, s->overflows);
        put_u32(w, s->version_errors);
        put_u32(w, s->type_errors);
        put_u32(w, s->stale_frames);
        put_u32(w, s->seq_gaps);
        put_u32(w, s->late_frames);
        put_u32(w, s->watchdog_trips);
        put_u32(w, s->tx_dropped);
        put_u32(w, s->last_tick);
        put_u16(w, s->last_seq);
        put_u8(w, s->flags);
        put_u8(w, s->safe_reason);
        put_i16(w, s->temp_target_cc);
        put_i16(w, s->temp_setpoint_cc);
        break;
    }
    default:
        break; /* HELLO_REQ, STATUS_REQ, STOP: no payload */
    }
}

static void read_payload(ah_reader_t *r, ah_msg_t *msg)
{
    switch (msg->type) {
    case AH_MSG_FRAME: {
        ah_frame_t *f = &msg->u.frame;
        f->tick = get_u32(r);
        f->seq = get_u16(r);
        get_bytes(r, f->motors, AH_N_MOTORS);
        f->temp_cc = get_i16(r);
        get_bytes(r, f->fans, AH_N_FANS);
        break;
    }
    case AH_MSG_HELLO: {
        ah_hello_t *h = &msg->u.hello;
        h->protocol_version = get_u8(r);
        h->fw_major = get_u8(r);
        h->fw_minor = get_u8(r);
        h->fw_patch = get_u8(r);
        h->n_actuators = get_u8(r);
        h->fan_rows = get_u8(r);
        h->fan_cols = get_u8(r);
        h->temp_min_cc = get_i16(r);
        h->temp_max_cc = get_i16(r);
        h->temp_neutral_cc = get_i16(r);
        h->temp_rate_cc_per_s = get_u16(r);
        h->watchdog_ms = get_u16(r);
        h->tick_ms = get_u16(r);
        h->max_packet = get_u16(r);
        get_bytes(r, (uint8_t *)h->name, AH_NAME_LEN);
        break;
    }
    case AH_MSG_STATUS: {
        ah_status_msg_t *s = &msg->u.status;
        s->uptime_ms = get_u32(r);
        s->frames_ok = get_u32(r);
        s->packets_ok = get_u32(r);
        s->crc_errors = get_u32(r);
        s->length_errors = get_u32(r);
        s->overflows = get_u32(r);
        s->version_errors = get_u32(r);
        s->type_errors = get_u32(r);
        s->stale_frames = get_u32(r);
        s->seq_gaps = get_u32(r);
        s->late_frames = get_u32(r);
        s->watchdog_trips = get_u32(r);
        s->tx_dropped = get_u32(r);
        s->last_tick = get_u32(r);
        s->last_seq = get_u16(r);
        s->flags = get_u8(r);
        s->safe_reason = get_u8(r);
        s->temp_target_cc = get_i16(r);
        s->temp_setpoint_cc = get_i16(r);
        break;
    }
    default:
        break;
    }
}

ah_status_t ah_decode_packet(const uint8_t *pkt, size_t n, ah_msg_t *msg)
{
    size_t len;
    uint16_t crc;
    int expected;
    ah_reader_t r;
    if (n < AH_HEADER_LEN + AH_CRC_LEN) return AH_ERR_LENGTH;
    msg->type = pkt[1];
    len = (size_t)pkt[2] | ((size_t)pkt[3] << 8);
    if (len != n - AH_HEADER_LEN - AH_CRC_LEN) return AH_ERR_LENGTH; /* truncated or run together */
    crc = (uint16_t)(pkt[n - 2] | (uint16_t)(pkt[n - 1] << 8));
    if (crc != ah_crc16(pkt, n - AH_CRC_LEN)) return AH_ERR_CRC;
    if (pkt[0] != AH_PROTOCOL_VERSION) return AH_ERR_VERSION;
    expected = ah_payload_len(pkt[1]);
    if (expected < 0) return AH_ERR_TYPE;
    if (len != (size_t)expected) return AH_ERR_LENGTH;
    r.buf = pkt + AH_HEADER_LEN;
    r.pos = 0;
    read_payload(&r, msg);
    return AH_OK;
}

size_t ah_encode_msg(const ah_msg_t *msg, uint8_t *out, size_t cap)
{
    uint8_t pkt[AH_MAX_PACKET];
    ah_writer_t w;
    int plen = ah_payload_len(msg->type);
    size_t n;
    uint16_t crc;
    if (plen < 0) return 0;
    w.buf = pkt;
    w.pos = 0;
    put_u8(&w, (uint8_t)AH_PROTOCOL_VERSION);
    put_u8(&w, msg->type);
    put_u16(&w, (uint16_t)plen);
    write_payload(msg, &w);
    crc = ah_crc16(pkt, w.pos);
    put_u16(&w, crc);
    if (cap < 1) return 0;
    n = ah_cobs_encode(pkt, w.pos, out, cap - 1);
    if (n == 0) return 0;
    out[n] = 0x00u;
    return n + 1;
}

const char *ah_status_name(ah_status_t st)
{
    switch (st) {
    case AH_PENDING: return "pending";
    case AH_OK: return "ok";
    case AH_ERR_CRC: return "crc_error";
    case AH_ERR_LENGTH: return "length_error";
    case AH_ERR_OVERFLOW: return "overflow";
    case AH_ERR_VERSION: return "version_error";
    case AH_ERR_TYPE: return "type_error";
    case AH_ERR_STALE: return "stale";
    default: return "unknown";
    }
}
