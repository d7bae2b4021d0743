/* The accelerometer: m/s^2, body axes x forward, y left, z up. */
#ifndef AIBO_SIM_DEVICE_ACCELEROMETER_H
#define AIBO_SIM_DEVICE_ACCELEROMETER_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void accelerometer_enable(DeviceTag sensor, unsigned short ms);
void accelerometer_disable(DeviceTag sensor);
/* x, y, z; valid until the next call. */
const float *accelerometer_get_values(DeviceTag sensor);

#define accelerometer_value_x(values) ((values)[0])
#define accelerometer_value_y(values) ((values)[1])
#define accelerometer_value_z(values) ((values)[2])

#ifdef __cplusplus
}
#endif

#endif
