/* Keeps the ball centred in the camera image by moving the head (the body stands still):
 * controllers/ball_tracker.py in C, the same algorithm and numbers. One difference comes from
 * the API itself: camera_get_fov is a float in C (0.993092 to float precision), a double in
 * Python, so the angles differ from the Python controller's in their last digits. */
#include <device/camera.h>
#include <device/robot.h>
#include <device/servo.h>

#include "ball_vision.h"

#define TIME_STEP 32
#define GAIN 0.6             /* fraction of the angular error corrected each step */
#define HEAD_TILT_LOW -0.26  /* rad: below this the neck tilts instead of the head */

static DeviceTag camera, neck, pan, tilt;

static void init(void) {
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    neck = robot_get_device("PRM:/r1/c1-Joint2:11");
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12");
    tilt = robot_get_device("PRM:/r1/c1/c2/c3-Joint2:13");
    camera_enable(camera, TIME_STEP);
    DeviceTag servos[3] = {neck, pan, tilt};
    for (int i = 0; i < 3; i++) servo_enable_position(servos[i], TIME_STEP);
}

/* Turn the head by a fraction of the ball's angular offset; returns the head pan. */
static double track(double x, double y) {
    double left, up;
    pixel_angles(x, y, camera_get_width(camera), camera_get_height(camera), camera_get_fov(camera), &left, &up);
    servo_set_position(pan, servo_get_position(pan) + GAIN * left);
    double head_tilt = servo_get_position(tilt) + GAIN * up;
    if (head_tilt < HEAD_TILT_LOW) {
        servo_set_position(neck, servo_get_position(neck) + head_tilt - HEAD_TILT_LOW);
        head_tilt = HEAD_TILT_LOW;
    }
    servo_set_position(tilt, head_tilt);
    return servo_get_position(pan);
}

static int run(int ms) {
    if (ms) { /* the first call comes before any sample */
        double x, y;
        int count;
        if (find_ball(camera_get_image(camera), camera_get_width(camera), camera_get_height(camera), &x, &y, &count)) {
            track(x, y);
        }
    }
    return TIME_STEP;
}

int main(void) {
    robot_live(init);
    robot_run(run);
    return 0;
}
