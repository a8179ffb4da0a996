/* The chair's portable core; see chair_core.h. */
#include "chair_core.h"

#include <string.h>

static void emit(chair_t *c, chair_event_t ev, ah_status_t st)
{
    if (c->io.event != 0) c->io.event(c->io.ctx, ev, (int)st, c);
}

static void send_msg(chair_t *c, const ah_msg_t *msg)
{
    uint8_t wire[AH_MAX_ENCODED + 1u];
    size_t n = ah_encode_msg(msg, wire, sizeof wire);
    if (n == 0 || c->io.write == 0 || c->io.write(c->io.ctx, wire, n) < n) c->cnt.tx_dropped++;
}

static void send_hello(chair_t *c)
{
    ah_msg_t msg;
    msg.type = AH_MSG_HELLO;
    chair_hello(c, &msg.u.hello);
    send_msg(c, &msg);
}

static void send_status(chair_t *c)
{
    ah_msg_t msg;
    msg.type = AH_MSG_STATUS;
    chair_status(c, &msg.u.status);
    send_msg(c, &msg);
}

int16_t chair_clamp_temp(int16_t temp_cc)
{
    if (temp_cc < AH_TEMP_MIN_CC) return (int16_t)AH_TEMP_MIN_CC;
    if (temp_cc > AH_TEMP_MAX_CC) return (int16_t)AH_TEMP_MAX_CC;
    return temp_cc;
}

int16_t chair_temp_drive(int16_t setpoint_cc)
{
    int32_t d = (int32_t)chair_clamp_temp(setpoint_cc) - AH_TEMP_NEUTRAL_CC;
    int32_t span = d >= 0 ? (AH_TEMP_MAX_CC - AH_TEMP_NEUTRAL_CC) : (AH_TEMP_NEUTRAL_CC - AH_TEMP_MIN_CC);
    if (span <= 0 || d == 0) return 0;
    return (int16_t)(d * 255 / span);
}

static void enter_safe(chair_t *c, uint8_t reason)
{
    memset(c->out.motors, 0, sizeof c->out.motors);
    memset(c->out.fans, 0, sizeof c->out.fans);
    c->out.temp_target_cc = (int16_t)AH_TEMP_NEUTRAL_CC;
    c->flags = (uint8_t)((c->flags | AH_FLAG_SAFE) & ~AH_FLAG_STOPPED);
    if (reason == AH_SAFE_STOP) c->flags |= AH_FLAG_STOPPED;
    c->safe_reason = reason;
    c->seq_valid = 0; /* the next stream may start at any sequence number */
}

static int16_t milli_to_cc(int32_t milli)
{
    return (int16_t)(milli >= 0 ? (milli + 500) / 1000 : -((-milli + 500) / 1000));
}

static void slew_temperature(chair_t *c, uint32_t dt_ms)
{
    int32_t target = (int32_t)c->out.temp_target_cc * 1000;
    int32_t step;
    int16_t before = c->out.temp_setpoint_cc;
    if (dt_ms > AH_MAX_STEP_MS) dt_ms = AH_MAX_STEP_MS;
    step = (int32_t)AH_TEMP_RATE_CC_PER_S * (int32_t)dt_ms; /* (cC/s) * ms = 1/1000 cC */
    if (c->temp_milli < target) {
        c->temp_milli = (target - c->temp_milli > step) ? c->temp_milli + step : target;
    } else if (c->temp_milli > target) {
        c->temp_milli = (c->temp_milli - target > step) ? c->temp_milli - step : target;
    }
    c->out.temp_setpoint_cc = milli_to_cc(c->temp_milli);
    if (c->temp_milli != target) c->flags |= AH_FLAG_RAMPING;
    else c->flags &= (uint8_t)~AH_FLAG_RAMPING;
    if (c->out.temp_setpoint_cc != before) emit(c, CHAIR_EV_TEMP, AH_OK);
}

static void apply_frame(chair_t *c, const ah_frame_t *f)
{
    if (c->seq_valid) {
        uint16_t d = (uint16_t)(f->seq - c->last_seq); /* serial-number arithmetic, RFC 1982 */
        if (d == 0 || d >= 0x8000u) {
            c->cnt.stale_frames++;
            emit(c, CHAIR_EV_RX_ERROR, AH_ERR_STALE);
            return;
        }
        if (d > 1u) c->cnt.seq_gaps += (uint32_t)(d - 1u);
    }
    if (!(c->flags & AH_FLAG_SAFE) && (uint32_t)(c->now_ms - c->last_frame_ms) > AH_LATE_MS) c->cnt.late_frames++;
    /* The frame was fully decoded and checked before this point; apply it all at once. */
    memcpy(c->out.motors, f->motors, sizeof c->out.motors);
    memcpy(c->out.fans, f->fans, sizeof c->out.fans);
    c->out.temp_target_cc = chair_clamp_temp(f->temp_cc);
    c->last_tick = f->tick;
    c->last_seq = f->seq;
    c->seq_valid = 1;
    c->last_frame_ms = c->now_ms;
    c->flags = (uint8_t)((c->flags & ~(AH_FLAG_SAFE | AH_FLAG_STOPPED)) | AH_FLAG_HAS_TICK);
    c->safe_reason = AH_SAFE_NONE;
    c->cnt.frames_ok++;
    emit(c, CHAIR_EV_FRAME, AH_OK);
}

static void on_msg(void *ctx, ah_status_t st, const ah_msg_t *msg)
{
    chair_t *c = (chair_t *)ctx;
    if (st != AH_OK) {
        emit(c, CHAIR_EV_RX_ERROR, st);
        return;
    }
    switch (msg->type) {
    case AH_MSG_FRAME:
        apply_frame(c, &msg->u.frame);
        break;
    case AH_MSG_STOP:
        enter_safe(c, AH_SAFE_STOP);
        emit(c, CHAIR_EV_STOP, AH_OK);
        send_status(c);
        break;
    case AH_MSG_HELLO_REQ:
        c->seq_valid = 0;
        emit(c, CHAIR_EV_HELLO, AH_OK);
        send_hello(c);
        break;
    case AH_MSG_STATUS_REQ:
        send_status(c);
        break;
    default: /* a valid packet the chair does not accept (HELLO, STATUS) */
        c->parser.cnt.type_errors++;
        emit(c, CHAIR_EV_RX_ERROR, AH_ERR_TYPE);
        break;
    }
}

void chair_init(chair_t *c, const chair_io_t *io, uint32_t now_ms)
{
    memset(c, 0, sizeof *c);
    c->io = *io;
    ah_parser_init(&c->parser, on_msg, c);
    c->boot_ms = now_ms;
    c->now_ms = now_ms;
    c->last_update_ms = now_ms;
    c->last_frame_ms = now_ms;
    c->temp_milli = (int32_t)AH_TEMP_NEUTRAL_CC * 1000;
    c->out.temp_setpoint_cc = (int16_t)AH_TEMP_NEUTRAL_CC;
    enter_safe(c, AH_SAFE_BOOT);
}

void chair_update(chair_t *c, const uint8_t *rx, size_t n, uint32_t now_ms)
{
    uint32_t dt = (uint32_t)(now_ms - c->last_update_ms); /* unsigned: millis() wrap-around is fine */
    c->now_ms = now_ms;
    c->last_update_ms = now_ms;
    if (dt > 0) slew_temperature(c, dt); /* the time since the last update ran under the old target */
    if (!(c->flags & AH_FLAG_SAFE) && (uint32_t)(now_ms - c->last_frame_ms) >= AH_WATCHDOG_MS) {
        enter_safe(c, AH_SAFE_WATCHDOG);
        c->cnt.watchdog_trips++;
        emit(c, CHAIR_EV_SAFE, AH_OK);
        send_status(c);
    }
    if (n > 0) ah_parser_update(&c->parser, rx, n);
}

void chair_hello(const chair_t *c, ah_hello_t *h)
{
    static const char name[] = AH_DEVICE_NAME;
    size_t i;
    (void)c;
    h->protocol_version = (uint8_t)AH_PROTOCOL_VERSION;
    h->fw_major = (uint8_t)AH_FW_MAJOR;
    h->fw_minor = (uint8_t)AH_FW_MINOR;
    h->fw_patch = (uint8_t)AH_FW_PATCH;
    h->n_actuators = (uint8_t)AH_N_MOTORS;
    h->fan_rows = (uint8_t)AH_FAN_ROWS;
    h->fan_cols = (uint8_t)AH_FAN_COLS;
    h->temp_min_cc = (int16_t)AH_TEMP_MIN_CC;
    h->temp_max_cc = (int16_t)AH_TEMP_MAX_CC;
    h->temp_neutral_cc = (int16_t)AH_TEMP_NEUTRAL_CC;
    h->temp_rate_cc_per_s = (uint16_t)AH_TEMP_RATE_CC_PER_S;
    h->watchdog_ms = (uint16_t)AH_WATCHDOG_MS;
    h->tick_ms = (uint16_t)AH_TICK_MS;
    h->max_packet = (uint16_t)AH_MAX_PACKET;
    for (i = 0; i < AH_NAME_LEN; i++) h->name[i] = (i < sizeof name - 1u) ? name[i] : '\0';
}

void chair_status(const chair_t *c, ah_status_msg_t *s)
{
    s->uptime_ms = (uint32_t)(c->now_ms - c->boot_ms);
    s->frames_ok = c->cnt.frames_ok;
    s->packets_ok = c->parser.cnt.packets_ok;
    s->crc_errors = c->parser.cnt.crc_errors;
    s->length_errors = c->parser.cnt.length_errors;
    s->overflows = c->parser.cnt.overflows;
    s->version_errors = c->parser.cnt.version_errors;
    s->type_errors = c->parser.cnt.type_errors;
    s->stale_frames = c->cnt.stale_frames;
    s->seq_gaps = c->cnt.seq_gaps;
    s->late_frames = c->cnt.late_frames;
    s->watchdog_trips = c->cnt.watchdog_trips;
    s->tx_dropped = c->cnt.tx_dropped;
    s->last_tick = c->last_tick;
    s->last_seq = c->last_seq;
    s->flags = c->flags;
    s->safe_reason = c->safe_reason;
    s->temp_target_cc = c->out.temp_target_cc;
    s->temp_setpoint_cc = c->out.temp_setpoint_cc;
}
