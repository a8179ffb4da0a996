/* The 9 x 17 fan grid on ten PCA9685 I2C PWM boards (addresses and bus in chair_config.h). */
#pragma once

#include <stdint.h>

void output_fans_begin(void);
/* Take AH_N_FANS levels (row-major, 0..255); the bus writes happen in output_fans_service(). */
void output_fans_set(const uint8_t *levels);
/* Call every loop pass: writes at most one pending chunk (a few hundred microseconds of I2C). */
void output_fans_service(void);
