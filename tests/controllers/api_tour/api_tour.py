"""Every API function, its results written to tour.txt: the twin of api_tour.c."""

import numpy as np

from aibo_sim.controller import *  # noqa: F403

out = pan = camera = near_ir = paw = accelerometer = led = walk = None
calls = 0


def reset():
    global out, pan, camera, near_ir, paw, accelerometer, led, walk
    out = open("tour.txt", "w")
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    near_ir = robot_get_device("PRM:/r1/c1/c2/c3/p1-Sensor:p1")
    paw = robot_get_device("PRM:/r2/c1/c2/c3/c4-Sensor:24")
    accelerometer = robot_get_device("PRM:/a1-Sensor:a1")
    led = robot_get_device("PRM:/r1/c1/c2/c3/l1-LED2:l1")
    out.write(f"name {robot_get_name()} tags {pan} {camera} {near_ir} {paw} {accelerometer} {led}\n")
    robot_keyboard_enable(64)
    out.write(
        f"mode {robot_get_mode()} key {robot_keyboard_get_key()} step {robot_get_basic_time_step():g} "
        f"synchronized {robot_get_synchronization()}\n"
    )
    out.write(f"keys {ROBOT_KEYBOARD_UP} {ROBOT_KEYBOARD_SHIFT | ord('A')} {ROBOT_KEYBOARD_KEY}\n")
    robot_keyboard_disable()
    servo_enable_position(pan, 32)
    servo_enable_motor_force_feedback(pan, 64)
    camera_enable(camera, 32)
    distance_sensor_enable(near_ir, 32)
    touch_sensor_enable(paw, 32)
    accelerometer_enable(accelerometer, 32)
    servo_set_velocity(pan, 2.0)
    servo_set_acceleration(pan, 20.0)
    servo_set_motor_force(pan, 2.5)
    servo_set_control_p(pan, 1.5)
    servo_set_position(pan, 0.4)
    camera_set_white_balance(camera, CAMERA_WB_INDOOR)
    camera_set_gain(camera, CAMERA_GAIN_HIGH)
    camera_set_shutter_speed(camera, CAMERA_SHUTTER_FAST)
    led_set(led, 1)
    missing = mtn_new("no_such_motion.mtn")
    out.write(f"missing {int(missing is None)} error {mtn_get_error()}\n")
    walk = mtn_new("walkfwd.mtn")
    out.write(f"walk {mtn_get_name(walk)} length {mtn_get_length(walk)} over {int(mtn_is_over(walk))}\n")
    mtn_fprint(out, walk)
    mtn_play(walk)


def bye():
    mtn_delete(walk)
    out.write(f"die at {robot_get_time():.3f}\n")
    out.close()


def run(ms):
    global calls
    if ms == 0:
        return 64
    image = camera_get_image(camera)
    w, h = camera_get_width(camera), camera_get_height(camera)
    a = [float(np.float32(v)) for v in accelerometer_get_values(accelerometer)]  # C: const float *
    out.write(
        f"t {robot_get_time():.3f} ms {ms} pan {servo_get_position(pan):.9f} "
        f"torque {servo_get_motor_force_feedback(pan):.9f} "
        f"ir {distance_sensor_get_value(near_ir):.6f} paw {touch_sensor_get_value(paw):.1f} "
        f"acc {accelerometer_value_x(a):.3f} {accelerometer_value_y(a):.3f} {accelerometer_value_z(a):.3f} "
        f"image {w}x{h} fov {float(np.float32(camera_get_fov(camera))):.6f} sum {int(image.astype(int).sum())} "
        f"rgb {camera_image_get_red(image, w, 10, 20)} {camera_image_get_green(image, w, 10, 20)} "
        f"{camera_image_get_blue(image, w, 10, 20)} grey {camera_image_get_grey(image, w, 10, 20)} "
        f"mtn {mtn_get_time(walk)} {int(mtn_is_over(walk))}\n"
    )
    calls += 1
    robot_console_printf("step %d\n", calls)
    if calls == 3:
        out.write(f"saved {camera_save_image(camera, 'tour.png', 0)} {camera_save_image(camera, 'tour.jpg', 75)}\n")
        servo_disable_position(pan)
        servo_disable_motor_force_feedback(pan)
        camera_disable(camera)
        distance_sensor_disable(near_ir)
        touch_sensor_disable(paw)
        accelerometer_disable(accelerometer)
        servo_enable_position(pan, 32)
        servo_enable_motor_force_feedback(pan, 32)
        camera_enable(camera, 32)
        distance_sensor_enable(near_ir, 32)
        touch_sensor_enable(paw, 32)
        accelerometer_enable(accelerometer, 32)
        led_set(led, 0)
        return 32
    return 64


robot_live(reset)
robot_die(bye)
robot_run(run)
