/* The chair's portable core: applies FRAMEs from the parser to the output state, answers HELLO
 * and STATUS requests, and keeps the chair safe (watchdog, temperature clamp and slew limit).
 * No Arduino header, no heap, no clock of its own: the platform passes millis() in, feeds the
 * received bytes and drives its outputs from chair_t.out when an event says they changed.
 * Protocol: firmware/PROTOCOL.md. */
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "chair_config.h"
#include "proto_parser.h"
#include "proto_wire.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    CHAIR_EV_FRAME = 1, /* a FRAME was applied: motors, fans and temperature target changed */
    CHAIR_EV_SAFE = 2,  /* the watchdog put the outputs in the safe state */
    CHAIR_EV_STOP = 3,  /* STOP put the outputs in the safe state */
    CHAIR_EV_TEMP = 4,  /* the slew-limited temperature setpoint moved (at most once per update) */
    CHAIR_EV_RX_ERROR = 5, /* a frame was dropped; the status says why */
    CHAIR_EV_HELLO = 6  /* the host said HELLO; sequence tracking restarts */
} chair_event_t;

struct chair_s;

typedef struct {
    /* Send bytes to the host; returns how many were taken. A short write counts as tx_dropped. */
    size_t (*write)(void *ctx, const uint8_t *data, size_t n);
    /* Optional: told about every state change (drive the outputs, log). status is an ah_status_t. */
    void (*event)(void *ctx, chair_event_t ev, int status, const struct chair_s *c);
    void *ctx;
} chair_io_t;

typedef struct {
    uint8_t motors[AH_N_MOTORS]; /* A1..A9 duty, 0..255 */
    uint8_t fans[AH_N_FANS];     /* row-major 9 x 17, 0..255 */
    int16_t temp_target_cc;      /* clamped target from the last FRAME, neutral in safe state */
    int16_t temp_setpoint_cc;    /* what the temperature element is driven to (slew limited) */
} chair_outputs_t;

typedef struct {
    uint32_t frames_ok;
    uint32_t stale_frames;
    uint32_t seq_gaps;
    uint32_t late_frames;
    uint32_t watchdog_trips;
    uint32_t tx_dropped;
} chair_counters_t;

typedef struct chair_s {
    ah_parser_t parser;
    chair_outputs_t out;
    chair_counters_t cnt;
    chair_io_t io;
    uint32_t boot_ms;
    uint32_t now_ms;
    uint32_t last_update_ms;
    uint32_t last_frame_ms;
    int32_t temp_milli;  /* setpoint in 1/1000 centi-degree, for an exact integer slew */
    uint32_t last_tick;
    uint16_t last_seq;
    uint8_t seq_valid;
    uint8_t flags;       /* AH_FLAG_* */
    uint8_t safe_reason; /* AH_SAFE_* */
} chair_t;

/* Start in the safe state (outputs off, temperature at neutral) at time now_ms. */
void chair_init(chair_t *c, const chair_io_t *io, uint32_t now_ms);

/* Call often (every loop pass, at least every millisecond or two) with the bytes that arrived
 * since the last call (n may be 0) and the current millis(). Advances the temperature slew,
 * runs the watchdog, then parses the bytes and applies every complete valid frame. */
void chair_update(chair_t *c, const uint8_t *rx, size_t n, uint32_t now_ms);

/* Clamp a temperature target to [AH_TEMP_MIN_CC, AH_TEMP_MAX_CC]. */
int16_t chair_clamp_temp(int16_t temp_cc);

/* Open-loop drive for the temperature element, -255 (full cooling) .. +255 (full heating):
 * linear in the setpoint's distance from neutral, full scale at the range's end. */
int16_t chair_temp_drive(int16_t setpoint_cc);

void chair_hello(const chair_t *c, ah_hello_t *h);
void chair_status(const chair_t *c, ah_status_msg_t *s);

#ifdef __cplusplus
}
#endif
