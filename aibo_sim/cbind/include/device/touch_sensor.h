/* Touch sensors (paws, chin, head, back): 1.0 when pressed beyond the threshold, else 0.0. */
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
