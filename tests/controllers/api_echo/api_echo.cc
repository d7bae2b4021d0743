// Every API function called from C++, each result written as the controller received it:
// echo.txt ("name argument value": the tag, the step, the name asked for, "mtn" for the motion,
// 0 for none; doubles to 17 digits), images.bin (the images' bytes), fprint.txt (mtn_fprint)
// and pixels.txt (the pixel macros at (10, 20)). tests/test_c_controller.py checks them
// against what the Python API returned in the same run.
#include <stdio.h>
#include <device/accelerometer.h>
#include <device/camera.h>
#include <device/distance_sensor.h>
#include <device/led.h>
#include <device/mtn.h>
#include <device/robot.h>
#include <device/servo.h>
#include <device/touch_sensor.h>

static FILE *out, *images, *pixels;
static DeviceTag pan, camera, ir, paw, acc, led;
static MTN *walk;

static void put_int(const char *name, const char *arg, long value) { fprintf(out, "%s %s %ld\n", name, arg, value); }
static void put_tag_int(const char *name, int arg, long value) { fprintf(out, "%s %d %ld\n", name, arg, value); }
static void put_double(const char *name, int arg, double value) { fprintf(out, "%s %d %.17g\n", name, arg, value); }
static void put_text(const char *name, const char *arg, const char *value) {
    fprintf(out, "%s %s %s\n", name, arg, value ? value : "");
}

static DeviceTag device(const char *name) {
    DeviceTag tag = robot_get_device(name);
    put_int("robot_get_device", name, tag);
    return tag;
}

static void reset(void) {
    out = fopen("echo.txt", "w");
    images = fopen("images.bin", "wb");
    pixels = fopen("pixels.txt", "w");
    FILE *fprint = fopen("fprint.txt", "w");
    pan = device("PRM:/r1/c1/c2-Joint2:12");
    camera = device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    ir = device("PRM:/r1/c1/c2/c3/p1-Sensor:p1");
    paw = device("PRM:/r2/c1/c2/c3/c4-Sensor:24");
    acc = device("PRM:/a1-Sensor:a1");
    led = device("PRM:/r1/c1/c2/c3/l1-LED2:l1");
    put_text("robot_get_name", "0", robot_get_name());
    robot_keyboard_enable(64);
    put_int("robot_get_mode", "0", robot_get_mode());
    put_double("robot_get_basic_time_step", 0, robot_get_basic_time_step());
    put_int("robot_get_synchronization", "0", robot_get_synchronization());
    put_int("robot_keyboard_get_key", "0", robot_keyboard_get_key());
    robot_keyboard_disable();
    servo_enable_position(pan, 32);
    servo_enable_motor_force_feedback(pan, 32);
    camera_enable(camera, 32);
    distance_sensor_enable(ir, 32);
    touch_sensor_enable(paw, 32);
    accelerometer_enable(acc, 32);
    servo_set_velocity(pan, 3.0);
    servo_set_acceleration(pan, 30.0);
    servo_set_motor_force(pan, 2.0);
    servo_set_control_p(pan, 2.0);
    servo_set_position(pan, -0.3);
    camera_set_white_balance(camera, CAMERA_WB_OUTDOOR);
    camera_set_gain(camera, CAMERA_GAIN_LOW);
    camera_set_shutter_speed(camera, CAMERA_SHUTTER_SLOW);
    led_set(led, 1);
    robot_console_printf("echo %s %d\n", "starts", 1);
    put_int("mtn_new", "missing.mtn", mtn_new("missing.mtn") != NULL);
    put_text("mtn_get_error", "0", mtn_get_error());
    walk = mtn_new("WalkFwd.mtn");
    put_int("mtn_new", "WalkFwd.mtn", walk != NULL);
    put_text("mtn_get_error", "0", mtn_get_error());
    put_text("mtn_get_name", "mtn", mtn_get_name(walk));
    put_int("mtn_get_length", "mtn", mtn_get_length(walk));
    mtn_fprint(fprint, walk);
    fclose(fprint);
    mtn_play(walk);
}

static void sample(void) {
    put_double("robot_get_time", 0, robot_get_time());
    put_double("servo_get_position", pan, servo_get_position(pan));
    put_double("servo_get_motor_force_feedback", pan, servo_get_motor_force_feedback(pan));
    put_double("distance_sensor_get_value", ir, distance_sensor_get_value(ir));
    put_double("touch_sensor_get_value", paw, touch_sensor_get_value(paw));
    const float *a = accelerometer_get_values(acc);
    fprintf(out, "accelerometer_get_values %d %.9g %.9g %.9g\n", acc, accelerometer_value_x(a),
            accelerometer_value_y(a), accelerometer_value_z(a));
    unsigned char *image = camera_get_image(camera);
    fprintf(out, "camera_get_image %d \n", camera);
    int w = camera_get_width(camera), h = camera_get_height(camera);
    put_tag_int("camera_get_width", camera, w);
    put_tag_int("camera_get_height", camera, h);
    put_double("camera_get_fov", camera, camera_get_fov(camera));
    put_tag_int("camera_save_image", camera, camera_save_image(camera, "echo.png", 0));
    fwrite(image, 1, (size_t)w * h * 3, images);
    fprintf(pixels, "%d %d %d %d %d\n", camera_image_get_red(image, w, 10, 20), camera_image_get_green(image, w, 10, 20),
            camera_image_get_blue(image, w, 10, 20), camera_image_get_grey(image, w, 10, 20),
            camera_image_get_gray(image, w, 10, 20));
    put_int("mtn_get_time", "mtn", mtn_get_time(walk));
    put_int("mtn_is_over", "mtn", mtn_is_over(walk));
}

static void bye(void) {
    put_double("robot_get_time", 0, robot_get_time());
    fclose(out);
    fclose(images);
    fclose(pixels);
}

int main() {
    robot_live(reset);
    robot_die(bye);
    for (int k = 0; k < 4; k++) {
        int ms = k == 2 ? 32 : 64;
        put_tag_int("robot_step", ms, robot_step(ms));
        sample();
        if (k == 1) {
            servo_disable_position(pan);
            servo_disable_motor_force_feedback(pan);
            camera_disable(camera);
            distance_sensor_disable(ir);
            touch_sensor_disable(paw);
            accelerometer_disable(acc);
            servo_enable_position(pan, 32);
            servo_enable_motor_force_feedback(pan, 32);
            camera_enable(camera, 32);
            distance_sensor_enable(ir, 32);
            touch_sensor_enable(paw, 32);
            accelerometer_enable(acc, 32);
            led_set(led, 0);
        }
    }
    mtn_delete(walk);
    return 0;
}
