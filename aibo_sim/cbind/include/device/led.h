/* LEDs: 0 off, 1 on, 2..255 a Sony intensity. */
#ifndef AIBO_SIM_DEVICE_LED_H
#define AIBO_SIM_DEVICE_LED_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void led_set(DeviceTag led, int value);

#ifdef __cplusplus
}
#endif

#endif
