/* Teensy 3.2 firmware: USB serial in, the portable core in the middle, PWM/I2C out.
 *
 * loop() never blocks: it hands whatever bytes arrived to chair_update() with millis(), drives
 * the outputs when the core reports a change, and writes at most one chunk of fan levels. The
 * core owns the protocol (firmware/PROTOCOL.md), the watchdog and the temperature limits. */
#include <Arduino.h>

#include "chair_config.h"
#include "chair_core.h"
#include "output_actuators.h"
#include "output_fans.h"
#include "output_temp.h"

static chair_t chair;

static size_t usb_write(void *ctx, const uint8_t *data, size_t n)
{
    (void)ctx;
    if (!Serial.dtr()) return 0; /* no host has the port open: drop the reply, never wait */
    /* Teensy 3's usb_serial_write() returns 0 on success and -1 after a transmit timeout (it
     * then stops waiting on later calls until the host reads again); it does not return a count.
     * availableForWrite() only reports the current 64-byte packet, so it cannot gate a frame. */
    if (usb_serial_write(data, (uint32_t)n) != 0) return 0;
    usb_serial_flush_output(); /* send now rather than after the 5 ms flush timer */
    return n;
}

static void apply_all(const chair_t *c)
{
    output_actuators_set(c->out.motors);
    output_fans_set(c->out.fans);
    output_temp_set(c->out.temp_setpoint_cc);
    digitalWrite(BOARD_LED_PIN, (c->flags & AH_FLAG_SAFE) ? LOW : HIGH);
}

static void on_event(void *ctx, chair_event_t ev, int status, const chair_t *c)
{
    (void)ctx;
    (void)status;
    switch (ev) {
    case CHAIR_EV_FRAME:
    case CHAIR_EV_SAFE:
    case CHAIR_EV_STOP:
        apply_all(c);
        break;
    case CHAIR_EV_TEMP:
        output_temp_set(c->out.temp_setpoint_cc);
        break;
    default:
        break;
    }
}

void setup()
{
    chair_io_t io;
    pinMode(BOARD_LED_PIN, OUTPUT);
    output_actuators_begin();
    output_temp_begin();
    output_fans_begin();
    Serial.begin(115200); /* USB CDC: the baud rate is ignored */
    io.write = usb_write;
    io.event = on_event;
    io.ctx = nullptr;
    chair_init(&chair, &io, millis());
    apply_all(&chair);
}

void loop()
{
    uint8_t buf[64];
    int n = usb_serial_read(buf, sizeof buf); /* what has arrived, up to 64 bytes; never waits */
    chair_update(&chair, buf, n > 0 ? (size_t)n : 0u, millis());
    output_fans_service();
}
