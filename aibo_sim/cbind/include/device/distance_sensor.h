/* Infrared distance sensors: millimetres. */
#ifndef AIBO_SIM_DEVICE_DISTANCE_SENSOR_H
#define AIBO_SIM_DEVICE_DISTANCE_SENSOR_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void distance_sensor_enable(DeviceTag sensor, unsigned short ms);
void distance_sensor_disable(DeviceTag sensor);
double distance_sensor_get_value(DeviceTag sensor);

#ifdef __cplusplus
}
#endif

#endif
