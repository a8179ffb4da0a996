/* Every constant of the chair firmware, in one place. The wire format itself is specified in
 * firmware/PROTOCOL.md; the sizes below follow from it and must not be changed without bumping
 * AH_PROTOCOL_VERSION. The device limits (temperature range, rate, watchdog) may be overridden
 * per build with -D flags (platformio.ini build_flags or CFLAGS). */
#pragma once

/* ---- protocol (PROTOCOL.md) ---------------------------------------------------------------- */
#define AH_PROTOCOL_VERSION 1u

#define AH_MSG_HELLO_REQ  0x01u /* host -> chair: empty; resets sequence tracking, chair answers HELLO */
#define AH_MSG_HELLO      0x02u /* chair -> host: capabilities */
#define AH_MSG_STATUS_REQ 0x03u /* host -> chair: empty; chair answers STATUS */
#define AH_MSG_STATUS     0x04u /* chair -> host: counters and state */
#define AH_MSG_FRAME      0x10u /* host -> chair: one 100 ms tick of outputs */
#define AH_MSG_STOP       0x11u /* host -> chair: empty; all outputs off now, chair answers STATUS */

#define AH_N_MOTORS   9u   /* A1..A9 */
#define AH_FAN_ROWS   9u
#define AH_FAN_COLS   17u
#define AH_N_FANS     (AH_FAN_ROWS * AH_FAN_COLS) /* 153, row-major, row 0 = top */
#define AH_NAME_LEN   16u  /* HELLO device name, ASCII, zero padded */

#define AH_HEADER_LEN 4u   /* version u8, type u8, payload length u16 */
#define AH_CRC_LEN    2u   /* CRC-16/CCITT-FALSE, little-endian */
#define AH_PAYLOAD_HELLO  37u
#define AH_PAYLOAD_STATUS 64u
#define AH_PAYLOAD_FRAME  (4u + 2u + AH_N_MOTORS + 2u + AH_N_FANS) /* 170 */
#define AH_MAX_PAYLOAD    AH_PAYLOAD_FRAME
#define AH_MAX_PACKET     (AH_HEADER_LEN + AH_MAX_PAYLOAD + AH_CRC_LEN) /* 176 */
/* COBS adds one code byte per started run of 254 bytes: the longest valid encoded frame. */
#define AH_MAX_ENCODED    (AH_MAX_PACKET + (AH_MAX_PACKET + 253u) / 254u) /* 177 */

/* ---- firmware identity ---------------------------------------------------------------------- */
#define AH_FW_MAJOR 0u
#define AH_FW_MINOR 1u
#define AH_FW_PATCH 0u
#ifndef AH_DEVICE_NAME
#define AH_DEVICE_NAME "autohaptics"
#endif

/* ---- device limits ------------------------------------------------------------------------- */
#define AH_TICK_MS 100u /* the host sends one FRAME per tick */
#ifndef AH_WATCHDOG_MS
#define AH_WATCHDOG_MS 300u /* no valid FRAME for this long -> safe state */
#endif
#ifndef AH_LATE_MS
#define AH_LATE_MS 150u /* a FRAME this long after the previous one counts as late */
#endif
#ifndef AH_TEMP_MIN_CC
#define AH_TEMP_MIN_CC 1800 /* centi-degrees C */
#endif
#ifndef AH_TEMP_MAX_CC
#define AH_TEMP_MAX_CC 4000
#endif
#ifndef AH_TEMP_NEUTRAL_CC
#define AH_TEMP_NEUTRAL_CC 3300 /* skin-neutral; the target in safe state */
#endif
#ifndef AH_TEMP_RATE_CC_PER_S
#define AH_TEMP_RATE_CC_PER_S 100 /* setpoint slew limit: 1.00 C per second */
#endif
#define AH_MAX_STEP_MS 60000u /* longer gaps between updates are treated as this long */

#if AH_TEMP_MIN_CC > AH_TEMP_NEUTRAL_CC || AH_TEMP_NEUTRAL_CC > AH_TEMP_MAX_CC
#error "AH_TEMP_MIN_CC <= AH_TEMP_NEUTRAL_CC <= AH_TEMP_MAX_CC must hold"
#endif
#if AH_TEMP_RATE_CC_PER_S < 1 || AH_TEMP_RATE_CC_PER_S > 10000
#error "AH_TEMP_RATE_CC_PER_S must lie in 1..10000"
#endif

/* ---- board: the Teensy 3.2 layer in teensy/ (unused by the portable core) ----------------- */
/* ERM motors A1..A9 through logic-level MOSFETs (or a ULN2803-style driver), PWM at 20 kHz. */
#define BOARD_MOTOR_PINS {3, 4, 5, 6, 9, 10, 20, 21, 22}
#define BOARD_MOTOR_PWM_HZ 20000
#define BOARD_MOTOR_MIN_DUTY 60 /* ERMs do not start below ~25 % duty: 1..255 maps onto 60..255 */
/* Temperature element: a Peltier on an H-bridge (PWM magnitude + direction), open loop. */
#define BOARD_TEMP_PWM_PIN 23
#define BOARD_TEMP_DIR_PIN 2 /* HIGH = heat, LOW = cool */
/* Fans: 153 channels on ten PCA9685 16-channel PWM boards on I2C (SDA 18, SCL 19). */
#define BOARD_FAN_I2C_HZ 400000
#define BOARD_FAN_FIRST_ADDR 0x40
#define BOARD_FAN_BOARDS 10
#define BOARD_FAN_PWM_HZ 1000
#define BOARD_LED_PIN 13 /* on while frames are applied, off in the safe state */
