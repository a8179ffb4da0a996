/* The nine ERM vibration motors A1..A9 on PWM pins (pin map in chair_config.h). */
#pragma once

#include <stdint.h>

void output_actuators_begin(void);
void output_actuators_set(const uint8_t *levels); /* AH_N_MOTORS levels, 0..255 */
