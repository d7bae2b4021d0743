"""The benchmark's controller (twin of sweep/sweep.c): sweeps the head, reads its position, the
IR distance and the camera image every 32 ms step, and keeps the image's mean brightness."""

import math

from aibo_sim.controller import *  # noqa: F403

STEP = 32
pan = camera = ir = None
brightness = reach = 0.0


def reset():
    global pan, camera, ir
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    ir = robot_get_device("PRM:/r1/c1/c2/c3/p1-Sensor:p1")
    servo_enable_position(pan, STEP)
    camera_enable(camera, STEP)
    distance_sensor_enable(ir, STEP)


def run(ms):
    global brightness, reach
    if ms:
        image = camera_get_image(camera)
        brightness = float(image.mean())
        reach = distance_sensor_get_value(ir) + servo_get_position(pan)
    servo_set_position(pan, 0.8 * math.sin(robot_get_time()))
    return STEP


robot_live(reset)
robot_run(run)
