/* Every API function, its results written to tour.txt: the twin of api_tour.py. */
#include <stdio.h>
#include <device/accelerometer.h>
#include <device/camera.h>
#include <device/distance_sensor.h>
#include <device/led.h>
#include <device/mtn.h>
#include <device/robot.h>
#include <device/servo.h>
#include <device/touch_sensor.h>

static FILE *out;
static DeviceTag pan, camera, near_ir, paw, accelerometer, led;
static MTN *walk;

static void reset(void) {
    out = fopen("tour.txt", "w");
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12");
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    near_ir = robot_get_device("PRM:/r1/c1/c2/c3/p1-Sensor:p1");
    paw = robot_get_device("PRM:/r2/c1/c2/c3/c4-Sensor:24");
    accelerometer = robot_get_device("PRM:/a1-Sensor:a1");
    led = robot_get_device("PRM:/r1/c1/c2/c3/l1-LED2:l1");
    fprintf(out, "name %s tags %d %d %d %d %d %d\n", robot_get_name(), pan, camera, near_ir, paw, accelerometer, led);
    robot_keyboard_enable(64);
    fprintf(out, "mode %d key %d step %g synchronized %d\n", robot_get_mode(), robot_keyboard_get_key(),
            robot_get_basic_time_step(), robot_get_synchronization());
    fprintf(out, "keys %d %d %d\n", ROBOT_KEYBOARD_UP, ROBOT_KEYBOARD_SHIFT | 'A', ROBOT_KEYBOARD_KEY);
    robot_keyboard_disable();
    servo_enable_position(pan, 32);
    servo_enable_motor_force_feedback(pan, 64);
    camera_enable(camera, 32);
    distance_sensor_enable(near_ir, 32);
    touch_sensor_enable(paw, 32);
    accelerometer_enable(accelerometer, 32);
    servo_set_velocity(pan, 2.0);
    servo_set_acceleration(pan, 20.0);
    servo_set_motor_force(pan, 2.5);
    servo_set_control_p(pan, 1.5);
    servo_set_position(pan, 0.4);
    camera_set_white_balance(camera, CAMERA_WB_INDOOR);
    camera_set_gain(camera, CAMERA_GAIN_HIGH);
    camera_set_shutter_speed(camera, CAMERA_SHUTTER_FAST);
    led_set(led, 1);
    MTN *missing = mtn_new("no_such_motion.mtn");
    fprintf(out, "missing %d error %s\n", missing == NULL, mtn_get_error());
    walk = mtn_new("walkfwd.mtn"); /* WALKFWD.MTN, found ignoring case */
    fprintf(out, "walk %s length %d over %d\n", mtn_get_name(walk), mtn_get_length(walk), mtn_is_over(walk));
    mtn_fprint(out, walk);
    mtn_play(walk);
}

static void bye(void) {
    mtn_delete(walk);
    fprintf(out, "die at %.3f\n", robot_get_time());
    fclose(out);
}

static int run(int ms) {
    static int calls;
    if (ms == 0) return 64;
    unsigned char *image = camera_get_image(camera);
    int w = camera_get_width(camera), h = camera_get_height(camera);
    long sum = 0;
    for (int k = 0; k < w * h * 3; k++) sum += image[k];
    const float *a = accelerometer_get_values(accelerometer);
    fprintf(out, "t %.3f ms %d pan %.9f torque %.9f ir %.6f paw %.1f acc %.3f %.3f %.3f image %dx%d fov %.6f sum %ld rgb %d %d %d grey %d mtn %d %d\n",
            robot_get_time(), ms, servo_get_position(pan), servo_get_motor_force_feedback(pan),
            distance_sensor_get_value(near_ir),
            touch_sensor_get_value(paw), accelerometer_value_x(a), accelerometer_value_y(a), accelerometer_value_z(a),
            w, h, camera_get_fov(camera), sum, camera_image_get_red(image, w, 10, 20),
            camera_image_get_green(image, w, 10, 20), camera_image_get_blue(image, w, 10, 20),
            camera_image_get_grey(image, w, 10, 20), mtn_get_time(walk), mtn_is_over(walk));
    robot_console_printf("step %d\n", ++calls);
    if (calls == 3) {
        int png = camera_save_image(camera, "tour.png", 0);
        fprintf(out, "saved %d %d\n", png, camera_save_image(camera, "tour.jpg", 75));
        servo_disable_position(pan);
        servo_disable_motor_force_feedback(pan);
        camera_disable(camera);
        distance_sensor_disable(near_ir);
        touch_sensor_disable(paw);
        accelerometer_disable(accelerometer);
        servo_enable_position(pan, 32);
        servo_enable_motor_force_feedback(pan, 32);
        camera_enable(camera, 32);
        distance_sensor_enable(near_ir, 32);
        touch_sensor_enable(paw, 32);
        accelerometer_enable(accelerometer, 32);
        led_set(led, 0);
        return 32;
    }
    return 64;
}

int main(void) {
    robot_live(reset);
    robot_die(bye);
    robot_run(run);
    return 0;
}
