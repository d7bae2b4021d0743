/*
 * WebotsApi.cc: the Webots Aibo API of the <device/...> headers (aibo_sim/cbind/include/device), over
 * the wrapper object (Controller.h says what each part does on the robot). Values and errors are
 * aibo_sim's Python API's (aibo_sim/controller.py).
 */
#include <stdarg.h>
#include <stdio.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OSyslog.h>
#include <device/accelerometer.h>
#include <device/camera.h>
#include <device/distance_sensor.h>
#include <device/led.h>
#include <device/mtn.h>
#include <device/robot.h>
#include <device/servo.h>
#include <device/touch_sensor.h>
#include "Controller.h"
#include "Ers7Table.h"

using wrapper::Robot;

namespace {

Robot& Api() { return Controller::Instance().GetRobot(); }

}  // namespace

/* ------------------------------------------------------------------ robot */

void robot_live(void (*reset)(void)) {
    if (reset != 0) reset();
}

void robot_die(void (*exit_fn)(void)) { Controller::Instance().Die(exit_fn); }

void robot_run(int (*run)(int)) { Controller::Instance().Run(run); }

int robot_step(int ms) {
    wrapper::Fail("robot_step(%d): not on the robot: an OPEN-R object cannot wait for time to pass inside a call "
                  "(the robot's next data comes only after it returns); call robot_run(run) instead, whose run "
                  "function the wrapper calls at each step", ms);
}

DeviceTag robot_get_device(const char* name) { return (DeviceTag)Api().GetDevice(name); }

double robot_get_time(void) { return Api().TimeMs() / 1000.0; }

const char* robot_get_name(void) {
    static char design[orobotdesignNAME_MAX + 1];
    if (OPENR::GetRobotDesign(design) != oSUCCESS) return "ERS-7";
    return design;
}

int robot_get_mode(void) { return 1; }  /* Webots 5: cross-compiled, on the robot */

double robot_get_basic_time_step(void) { return wrapper::FRAME_MS; }

int robot_get_synchronization(void) { return 0; }  /* the robot's time goes on while the controller computes */

void robot_keyboard_enable(unsigned short ms) {
    if (ms == 0) wrapper::Fail("robot_keyboard_enable: sampling period must be a positive whole number of ms, not 0");
}

void robot_keyboard_disable(void) {}

int robot_keyboard_get_key(void) { return 0; }  /* the robot has no keyboard */

void robot_console_printf(const char* format, ...) {
    char text[4096];
    va_list arguments;
    va_start(arguments, format);
    vsnprintf(text, sizeof text, format, arguments);
    va_end(arguments);
    OSYSPRINT(("%s", text));
}

/* ------------------------------------------------------------------ servos */

void servo_enable_position(DeviceTag servo, unsigned short ms) { Api().Enable(servo, Robot::SERVO, ms); }
void servo_disable_position(DeviceTag servo) { Api().Disable(servo, Robot::SERVO); }
double servo_get_position(DeviceTag servo) { return Api().Value(servo, Robot::SERVO, 0); }
void servo_set_position(DeviceTag servo, double radians) { Api().SetPosition(servo, radians); }
void servo_set_velocity(DeviceTag servo, double rad_per_s) { Api().SetVelocity(servo, rad_per_s); }
void servo_set_acceleration(DeviceTag servo, double rad_per_s2) { Api().SetAcceleration(servo, rad_per_s2); }
void servo_set_control_p(DeviceTag servo, double p) { Controller::Instance().SetControlP(servo, p); }
void servo_enable_motor_force_feedback(DeviceTag servo, unsigned short ms) { Api().EnableForceFeedback(servo, ms); }
void servo_disable_motor_force_feedback(DeviceTag servo) { Api().DisableForceFeedback(servo); }
/* The torque from the joint's PWM duty (the robot reports no torque; the duty is its share of it). */
double servo_get_motor_force_feedback(DeviceTag servo) { return Api().ForceFeedback(servo); }

/* The robot's servos have no torque limit to set: the call is checked, and said once. */
void servo_set_motor_force(DeviceTag servo, double newton_metres) {
    static bool said = false;
    Api().CheckedNumber(servo, Robot::SERVO, "motor force", newton_metres);
    if (!said) OSYSPRINT(("servo_set_motor_force: the robot's servos have no force limit (ignored)\n"));
    said = true;
}

/* ------------------------------------------------------------------ camera */

void camera_enable(DeviceTag camera, unsigned short ms) { Api().Enable(camera, Robot::CAMERA, ms); }
void camera_disable(DeviceTag camera) { Api().Disable(camera, Robot::CAMERA); }
unsigned char* camera_get_image(DeviceTag camera) { return Api().CameraImage(camera); }
int camera_save_image(DeviceTag camera, const char* filename, int quality) {
    return Api().CameraSaveImage(camera, filename, quality);
}
unsigned short camera_get_width(DeviceTag camera) { return (unsigned short)Api().CameraWidth(camera); }
unsigned short camera_get_height(DeviceTag camera) { return (unsigned short)Api().CameraHeight(camera); }

float camera_get_fov(DeviceTag camera) {
    Api().DeviceLocator(camera, Robot::CAMERA);
    return (float)ers7::FIELD_OF_VIEW;
}

void camera_set_white_balance(DeviceTag camera, int value) {
    Controller::Instance().CameraControl(camera, "camera_set_white_balance", value);
}

void camera_set_gain(DeviceTag camera, int value) {
    Controller::Instance().CameraControl(camera, "camera_set_gain", value);
}

void camera_set_shutter_speed(DeviceTag camera, int value) {
    Controller::Instance().CameraControl(camera, "camera_set_shutter_speed", value);
}

/* ------------------------------------------------------------------ sensors, LEDs */

void distance_sensor_enable(DeviceTag sensor, unsigned short ms) { Api().Enable(sensor, Robot::DISTANCE, ms); }
void distance_sensor_disable(DeviceTag sensor) { Api().Disable(sensor, Robot::DISTANCE); }
double distance_sensor_get_value(DeviceTag sensor) { return Api().Value(sensor, Robot::DISTANCE, 0); }

void touch_sensor_enable(DeviceTag sensor, unsigned short ms) { Api().Enable(sensor, Robot::TOUCH, ms); }
void touch_sensor_disable(DeviceTag sensor) { Api().Disable(sensor, Robot::TOUCH); }
double touch_sensor_get_value(DeviceTag sensor) { return Api().Value(sensor, Robot::TOUCH, 0); }

void accelerometer_enable(DeviceTag sensor, unsigned short ms) { Api().Enable(sensor, Robot::ACCELEROMETER, ms); }
void accelerometer_disable(DeviceTag sensor) { Api().Disable(sensor, Robot::ACCELEROMETER); }

const float* accelerometer_get_values(DeviceTag sensor) {
    static float values[3];
    for (int axis = 0; axis < 3; axis++) values[axis] = (float)Api().Value(sensor, Robot::ACCELEROMETER, axis);
    return values;
}

void led_set(DeviceTag led, int value) { Api().SetLed(led, value); }

/* ------------------------------------------------------------------ MTN */

MTN* mtn_new(const char* filename) { return Api().NewMotion(filename); }

void mtn_delete(MTN* mtn) {
    if (mtn == 0) return;
    Api().StopMotion(mtn);
    delete mtn;
}

void mtn_play(MTN* mtn) { Api().PlayMotion(mtn); }
int mtn_is_over(MTN* mtn) { return Api().IsOver(mtn); }
int mtn_get_length(MTN* mtn) { return (int)Api().CheckMotion(mtn, "mtn_get_length")->motion.LengthMs(); }
int mtn_get_time(MTN* mtn) { return (int)Api().MotionTime(mtn); }
const char* mtn_get_name(MTN* mtn) { return Api().CheckMotion(mtn, "mtn_get_name")->motion.name.c_str(); }

void mtn_fprint(FILE* file, MTN* mtn) {
    fprintf(file, "%s\n", wrapper::FormatMotionInfo(Api().CheckMotion(mtn, "mtn_fprint")->motion).c_str());
}

const char* mtn_get_error(void) { return Api().MotionError(); }
