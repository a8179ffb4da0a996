/* Open-loop temperature drive: no sensor and no PID. The core's chair_temp_drive() maps the
 * setpoint's distance from neutral linearly onto -255..+255 (full cooling .. full heating at the
 * range's ends); the sign picks the H-bridge direction, the magnitude is the PWM duty. Calibrate
 * AH_TEMP_* in chair_config.h so that full duty reaches the range's end on your element; the
 * core's clamp and slew limit are the safety, not this mapping. */
#include "output_temp.h"

#include <Arduino.h>

#include "chair_config.h"
#include "chair_core.h"

void output_temp_begin(void)
{
    pinMode(BOARD_TEMP_DIR_PIN, OUTPUT);
    pinMode(BOARD_TEMP_PWM_PIN, OUTPUT);
    digitalWrite(BOARD_TEMP_DIR_PIN, HIGH);
    analogWrite(BOARD_TEMP_PWM_PIN, 0);
}

void output_temp_set(int16_t setpoint_cc)
{
    int16_t drive = chair_temp_drive(setpoint_cc);
    digitalWrite(BOARD_TEMP_DIR_PIN, drive >= 0 ? HIGH : LOW);
    analogWrite(BOARD_TEMP_PWM_PIN, drive >= 0 ? drive : -drive);
}
