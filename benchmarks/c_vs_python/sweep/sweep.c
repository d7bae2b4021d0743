/* The benchmark's controller (twin of sweep.py): sweeps the head, reads its position, the IR
 * distance and the camera image every 32 ms step, and keeps the image's mean brightness. */
#include <math.h>
#include <device/camera.h>
#include <device/distance_sensor.h>
#include <device/robot.h>
#include <device/servo.h>

#define STEP 32

static DeviceTag pan, camera, ir;
static double brightness, reach;

static void reset(void) {
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12");
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    ir = robot_get_device("PRM:/r1/c1/c2/c3/p1-Sensor:p1");
    servo_enable_position(pan, STEP);
    camera_enable(camera, STEP);
    distance_sensor_enable(ir, STEP);
}

static int run(int ms) {
    if (ms) {
        unsigned char *image = camera_get_image(camera);
        int size = camera_get_width(camera) * camera_get_height(camera) * 3;
        long sum = 0;
        for (int k = 0; k < size; k++) sum += image[k];
        brightness = (double)sum / size;
        reach = distance_sensor_get_value(ir) + servo_get_position(pan);
    }
    servo_set_position(pan, 0.8 * sin(robot_get_time()));
    return STEP;
}

int main(void) {
    robot_live(reset);
    robot_run(run);
    return 0;
}
