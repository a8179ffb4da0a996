/* The temperature element: a Peltier module on an H-bridge (PWM + direction), open loop. */
#pragma once

#include <stdint.h>

void output_temp_begin(void);
void output_temp_set(int16_t setpoint_cc); /* slew-limited setpoint from the core, centi-degrees C */
