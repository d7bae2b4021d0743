/* Servos: radians, rad/s, rad/s^2, N m. */
#ifndef AIBO_SIM_DEVICE_SERVO_H
#define AIBO_SIM_DEVICE_SERVO_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void servo_enable_position(DeviceTag servo, unsigned short ms);
void servo_disable_position(DeviceTag servo);
double servo_get_position(DeviceTag servo);
void servo_set_position(DeviceTag servo, double radians);
void servo_set_velocity(DeviceTag servo, double rad_per_s);
void servo_set_acceleration(DeviceTag servo, double rad_per_s2);  /* -1: unlimited */
void servo_set_motor_force(DeviceTag servo, double newton_metres);
void servo_set_control_p(DeviceTag servo, double p);
void servo_enable_motor_force_feedback(DeviceTag servo, unsigned short ms);
void servo_disable_motor_force_feedback(DeviceTag servo);
double servo_get_motor_force_feedback(DeviceTag servo);  /* the motor's torque, N m, signed along the joint */

#ifdef __cplusplus
}
#endif

#endif
