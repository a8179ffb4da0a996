/* Fans through PCA9685 boards: fan i is channel i % 16 of board i / 16 (board 0 at
 * BOARD_FAN_FIRST_ADDR). Each fan's MOSFET gate takes the 12-bit PWM. Levels are written in
 * chunks of four channels (17 bytes, well inside the Wire buffer) so no loop pass blocks for
 * long; all fans off (safe state, STOP) is one ALL_LED_OFF write per board. A board that does
 * not answer is skipped from then on, so a partly built grid still works. */
#include "output_fans.h"

#include <Arduino.h>
#include <Wire.h>

#include "chair_config.h"

#define PCA_MODE1 0x00
#define PCA_MODE2 0x01
#define PCA_LED0_ON_L 0x06
#define PCA_ALL_LED_OFF_H 0xFD
#define PCA_PRE_SCALE 0xFE
#define PCA_MODE1_AI 0x20
#define PCA_MODE1_SLEEP 0x10
#define PCA_MODE1_RESTART 0x80
#define PCA_MODE2_OUTDRV 0x04
#define PCA_FULL 0x10 /* bit 4 of LEDn_ON_H / LEDn_OFF_H: full on / full off */

#define CHANNELS_PER_BOARD 16
#define CHUNK 4
#define CHUNKS_PER_BOARD (CHANNELS_PER_BOARD / CHUNK)
#define N_CHUNKS (BOARD_FAN_BOARDS * CHUNKS_PER_BOARD)

#if BOARD_FAN_BOARDS * CHANNELS_PER_BOARD < AH_N_FANS
#error "not enough PCA9685 channels for the fan grid"
#endif

static uint8_t levels[BOARD_FAN_BOARDS * CHANNELS_PER_BOARD];
static bool chunk_dirty[N_CHUNKS];
static bool board_all_off[BOARD_FAN_BOARDS];
static bool board_present[BOARD_FAN_BOARDS];
static unsigned next_chunk;

static bool write_reg(uint8_t addr, uint8_t reg, uint8_t value)
{
    Wire.beginTransmission(addr);
    Wire.write(reg);
    Wire.write(value);
    return Wire.endTransmission() == 0;
}

void output_fans_begin(void)
{
    const uint8_t prescale = (uint8_t)(25000000L / (4096L * BOARD_FAN_PWM_HZ) - 1); /* 25 MHz oscillator */
    Wire.begin();
    Wire.setClock(BOARD_FAN_I2C_HZ);
    for (unsigned b = 0; b < BOARD_FAN_BOARDS; b++) {
        uint8_t addr = (uint8_t)(BOARD_FAN_FIRST_ADDR + b);
        board_present[b] = write_reg(addr, PCA_MODE1, PCA_MODE1_SLEEP) && write_reg(addr, PCA_PRE_SCALE, prescale) &&
                           write_reg(addr, PCA_MODE1, PCA_MODE1_AI);
        if (!board_present[b]) continue;
        delayMicroseconds(500); /* oscillator start-up before RESTART */
        write_reg(addr, PCA_MODE1, PCA_MODE1_AI | PCA_MODE1_RESTART);
        write_reg(addr, PCA_MODE2, PCA_MODE2_OUTDRV);
        write_reg(addr, PCA_ALL_LED_OFF_H, PCA_FULL);
    }
}

void output_fans_set(const uint8_t *src)
{
    for (unsigned b = 0; b < BOARD_FAN_BOARDS; b++) {
        bool any_on = false;
        for (unsigned ch = 0; ch < CHANNELS_PER_BOARD; ch++) {
            unsigned i = b * CHANNELS_PER_BOARD + ch;
            uint8_t v = i < AH_N_FANS ? src[i] : 0;
            if (v != levels[i]) chunk_dirty[i / CHUNK] = true;
            levels[i] = v;
            any_on = any_on || v != 0;
        }
        if (!any_on) { /* one register write turns the whole board off */
            board_all_off[b] = true;
            for (unsigned k = 0; k < CHUNKS_PER_BOARD; k++) chunk_dirty[b * CHUNKS_PER_BOARD + k] = false;
        }
    }
}

static void write_chunk(unsigned k)
{
    unsigned b = k / CHUNKS_PER_BOARD, first = k * CHUNK;
    Wire.beginTransmission((uint8_t)(BOARD_FAN_FIRST_ADDR + b));
    Wire.write((uint8_t)(PCA_LED0_ON_L + 4 * (first % CHANNELS_PER_BOARD)));
    for (unsigned ch = 0; ch < CHUNK; ch++) {
        uint8_t v = levels[first + ch];
        uint16_t off = (uint16_t)(((uint32_t)v * 4095u) / 255u);
        Wire.write(0x00);                         /* ON_L */
        Wire.write(v == 255 ? PCA_FULL : 0x00);   /* ON_H: full on */
        Wire.write((uint8_t)(off & 0xFF));        /* OFF_L */
        Wire.write(v == 0 ? PCA_FULL : (v == 255 ? 0x00 : (uint8_t)(off >> 8))); /* OFF_H: full off */
    }
    Wire.endTransmission();
}

void output_fans_service(void)
{
    for (unsigned b = 0; b < BOARD_FAN_BOARDS; b++) {
        if (board_all_off[b]) {
            board_all_off[b] = false;
            if (board_present[b]) {
                write_reg((uint8_t)(BOARD_FAN_FIRST_ADDR + b), PCA_ALL_LED_OFF_H, PCA_FULL);
                return;
            }
        }
    }
    for (unsigned n = 0; n < N_CHUNKS; n++) {
        unsigned k = (next_chunk + n) % N_CHUNKS;
        if (!chunk_dirty[k]) continue;
        chunk_dirty[k] = false;
        next_chunk = (k + 1) % N_CHUNKS;
        if (board_present[k / CHUNKS_PER_BOARD]) write_chunk(k);
        return;
    }
}
