/////////////////////////////////////////////////////////////////
// Base Webots controller for Aibo robots.
// Cognition for Robotic Research group (C4R2). Jaume I University.
// 03/2007
//
// The report's Annex I as printed, with (aibo-sim):
// - the include lines pointed at the Webots-era headers (<device/...>, which `aibo-sim run`
//   puts on the include path);
// - the output path made relative: image.raw lands in the run's --out folder;
// - its outright bugs fixed: `using namespace std` for ofstream; run() allocated three
//   IMAGE_SIZE buffers on every call and never freed them (now one set, kept); run() opened
//   image.raw on every call, truncating it during the walk (now only to write an image);
//   run() fell off its end without returning the next step while the motion played (now it
//   returns SIMULATION_STEP on every path); die() had a stray closing brace.
// It plays Sony's wwfwd.mtn, which aibo-sim does not ship: put WWFWD.MTN (Webots'
// data/mtn/ers7/ has it) in this folder; mtn_new finds it ignoring case, as the memory stick
// did. Without it, mtn_new returns NULL and the first mtn_is_over ends the run with
// "MTN is NULL: mtn_new failed (File not found: wwfwd.mtn)".
/////////////////////////////////////////////////////////////////

// Includes ///////////////////////////////////////////////////////////////////
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
#include <fstream>
#include <device/robot.h>
#include <device/servo.h>
#include <device/led.h>
#include <device/distance_sensor.h>
#include <device/touch_sensor.h>
#include <device/camera.h>
#include <device/mtn.h>

using namespace std;

//Constants ///////////////////////////////////////////////////////////////////
#define SIMULATION_STEP 16
#define IMAGE_SIZE 208*160
#define MTN_REPLAY 15

// Webots compilation.
// #define MTN_PATH "../data/mtn/ers7/"
// #define MTN_FILE "../data/mtn/ers7/wwfwd.mtn"

// Aibo compilation.
#define MTN_PATH "/ms/open-r/mw/data/p/"
#define MTN_FILE "/ms/open-r/mw/data/p/wwfwd.mtn"

// Static variables ///////////////////////////////////////////////////////////////////
static MTN *mtn;
static DeviceTag camera,
    head_distance_near,
    head_distance_far,
    chest_distance_sensor,
    touch_sensor_fore_l,
    touch_sensor_fore_r,
    touch_sensor_hind_l,
    touch_sensor_hind_r,
    head_pan,
    joint[15];
static unsigned char ychannel[IMAGE_SIZE], uchannel[IMAGE_SIZE], vchannel[IMAGE_SIZE];

// Init function ///////////////////////////////////////////////////////////////////////////////////////////////////////////////////
static void init(void) {
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    head_distance_near = robot_get_device("PRM:/r1/c1/c2/c3/p1-Sensor:p1");
    head_distance_far = robot_get_device("PRM:/r1/c1/c2/c3/p2-Sensor:p2");
    chest_distance_sensor = robot_get_device("PRM:/p1-Sensor:p1");
    touch_sensor_fore_l = robot_get_device("PRM:/r2/c1/c2/c3/c4-Sensor:24");
    touch_sensor_hind_l = robot_get_device("PRM:/r3/c1/c2/c3/c4-Sensor:34");
    touch_sensor_fore_r = robot_get_device("PRM:/r4/c1/c2/c3/c4-Sensor:44");
    touch_sensor_hind_r = robot_get_device("PRM:/r5/c1/c2/c3/c4-Sensor:54");

    joint[0] = robot_get_device("PRM:/r2/c1-Joint2:21"); // LFLJ1 joint
    joint[1] = robot_get_device("PRM:/r2/c1/c2-Joint2:22"); // LFLJ2 joint
    joint[2] = robot_get_device("PRM:/r2/c1/c2/c3-Joint2:23"); // LFLJ3 joint
    joint[3] = robot_get_device("PRM:/r3/c1-Joint2:31"); // LRLJ1 joint
    joint[4] = robot_get_device("PRM:/r3/c1/c2-Joint2:32"); // LRLJ2 joint
    joint[5] = robot_get_device("PRM:/r3/c1/c2/c3-Joint2:33"); // LRLJ3 joint
    joint[6] = robot_get_device("PRM:/r4/c1-Joint2:41"); // RFLJ1 joint
    joint[7] = robot_get_device("PRM:/r4/c1/c2-Joint2:42"); // RFLJ2 joint
    joint[8] = robot_get_device("PRM:/r4/c1/c2/c3-Joint2:43"); // RFLJ3 joint
    joint[9] = robot_get_device("PRM:/r5/c1-Joint2:51"); // RRLJ1 joint
    joint[10] = robot_get_device("PRM:/r5/c1/c2-Joint2:52"); // RRLJ2 joint
    joint[11] = robot_get_device("PRM:/r5/c1/c2/c3-Joint2:53"); // RRLJ3 joint
    joint[12] = robot_get_device("PRM:/r1/c1-Joint2:11"); // Neck Tilt1 joint
    joint[13] = robot_get_device("PRM:/r1/c1/c2-Joint2:12"); // Neck Pan joint
    joint[14] = robot_get_device("PRM:/r1/c1/c2/c3-Joint2:13"); // Neck Tilt2 joint

    // Enabling sensors.
    camera_enable(camera,SIMULATION_STEP);
    distance_sensor_enable(head_distance_near,SIMULATION_STEP);
    distance_sensor_enable(head_distance_far,SIMULATION_STEP);
    distance_sensor_enable(chest_distance_sensor,SIMULATION_STEP);
    touch_sensor_enable(touch_sensor_fore_l,SIMULATION_STEP);
    touch_sensor_enable(touch_sensor_hind_l,SIMULATION_STEP);
    touch_sensor_enable(touch_sensor_fore_r,SIMULATION_STEP);
    touch_sensor_enable(touch_sensor_hind_r,SIMULATION_STEP);

    // Setting velocity and acceleration of the joints.
    for (int i = 0; i < 15; i++) {
        servo_set_velocity(joint[i], 2.498);
        servo_set_acceleration(joint[i], 2.498);
        servo_enable_position(joint[i], SIMULATION_STEP);
    }

    // Creating the mtn movement.
    mtn = mtn_new("wwfwd.mtn");
}

// Die function ///////////////////////////////////////////////////////////////////////////////////////////////////////////////////
static void die(void) {
    // Deleting the mtn data.
    if( mtn ) mtn_delete(mtn);
}

// Run function ////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////
static int run (int ms) {
    static int loop=0;
    unsigned char *image;
    unsigned char r,g,b;
    int h,w, aux;

    if ((mtn_is_over(mtn)) && (loop<MTN_REPLAY)){
        // Play mtn until enough loops
        mtn_play(mtn);
        loop++;
    }

    else if ((mtn_is_over(mtn)) && (loop==MTN_REPLAY)) {
        ofstream is("image.raw");
        image = camera_get_image(camera);
        w = camera_get_width(camera);
        h = camera_get_height(camera);
        aux = 0;
        for (int j = 0; j< h; j++) {
            for (int i = 0; i < w; i++) {

                r = camera_image_get_red(image,w,i,j);
                g = camera_image_get_green(image,w,i,j);
                b = camera_image_get_blue(image,w,i,j);
                ychannel[aux] = (unsigned char)(0.299 * r + 0.587 * g + 0.114 * b);
                uchannel[aux] = (unsigned char)(0.492 * (b - ychannel[aux]) + 128);
                vchannel[aux] = (unsigned char)(0.5 * (r -ychannel[aux]) + 128);
                is.put(ychannel[aux]);
                is.put(uchannel[aux]);
                is.put(vchannel[aux]);
                aux++;
            }
        }
    }
    return SIMULATION_STEP;
}

// main function ////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////////
int main() {
    robot_live(init);
    robot_die(die);
    robot_run(run);
    return 0;
}
