/* Smallest complete program around the core, for measuring its flash and RAM on Cortex-M4
 * (`make size`). Bytes come from and go to volatile registers so nothing is optimised away;
 * this image is linked to be measured, not flashed (the Teensy build is teensy/main.cpp). */
#include <stdint.h>

#include "chair_core.h"

volatile uint8_t size_rx_data;
volatile uint8_t size_rx_ready;
volatile uint8_t size_tx_data;
volatile uint32_t size_millis;
volatile uint8_t size_outputs[AH_N_MOTORS + AH_N_FANS];

static chair_t chair;

static size_t size_write(void *ctx, const uint8_t *data, size_t n)
{
    size_t i;
    (void)ctx;
    for (i = 0; i < n; i++) size_tx_data = data[i];
    return n;
}

static void size_event(void *ctx, chair_event_t ev, int status, const chair_t *c)
{
    unsigned i;
    (void)ctx;
    (void)ev;
    (void)status;
    for (i = 0; i < AH_N_MOTORS; i++) size_outputs[i] = c->out.motors[i];
    for (i = 0; i < AH_N_FANS; i++) size_outputs[AH_N_MOTORS + i] = c->out.fans[i];
    (void)chair_temp_drive(c->out.temp_setpoint_cc);
}

int main(void)
{
    chair_io_t io;
    io.write = size_write;
    io.event = size_event;
    io.ctx = 0;
    chair_init(&chair, &io, size_millis);
    for (;;) {
        uint8_t b[1];
        size_t n = 0;
        if (size_rx_ready) {
            b[0] = size_rx_data;
            n = 1;
        }
        chair_update(&chair, b, n, size_millis);
    }
}
