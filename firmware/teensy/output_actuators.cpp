/* ERM motors: one PWM pin each, 8-bit, 20 kHz (above hearing). An ERM needs a minimum duty to
 * start spinning, so a non-zero level 1..255 maps linearly onto BOARD_MOTOR_MIN_DUTY..255 and 0
 * stays 0 (off). */
#include "output_actuators.h"

#include <Arduino.h>

#include "chair_config.h"

static const uint8_t motor_pins[AH_N_MOTORS] = BOARD_MOTOR_PINS;

static uint8_t motor_duty(uint8_t level)
{
    if (level == 0) return 0;
    return (uint8_t)(BOARD_MOTOR_MIN_DUTY + ((uint16_t)level * (255u - BOARD_MOTOR_MIN_DUTY)) / 255u);
}

void output_actuators_begin(void)
{
    analogWriteResolution(8);
    for (unsigned i = 0; i < AH_N_MOTORS; i++) {
        pinMode(motor_pins[i], OUTPUT);
        analogWriteFrequency(motor_pins[i], BOARD_MOTOR_PWM_HZ);
        analogWrite(motor_pins[i], 0);
    }
}

void output_actuators_set(const uint8_t *levels)
{
    for (unsigned i = 0; i < AH_N_MOTORS; i++) analogWrite(motor_pins[i], motor_duty(levels[i]));
}
