/* Touch sensors: 0 or 1 (paws, chin), pressure for the head and back. */
#ifndef AIBO_SIM_DEVICE_TOUCH_SENSOR_H
#define AIBO_SIM_DEVICE_TOUCH_SENSOR_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void touch_sensor_enable(DeviceTag sensor, unsigned short ms);
void touch_sensor_disable(DeviceTag sensor);
double touch_sensor_get_value(DeviceTag sensor);

#ifdef __cplusplus
}
#endif

#endif
