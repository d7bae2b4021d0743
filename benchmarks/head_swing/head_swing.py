"""The benchmark's Python controller: what benchmarks/head_swing/HeadSwing does, through the Webots-era
API: the head pan at 60 sin(2 pi t / 4 s) degrees, a set-point every 8 ms frame, the head's
angle read every 32 ms and the camera's image at every camera frame."""

import math

from aibo_sim.controller import *  # noqa: F403

camera = pan = None
frame = 0


def init():
    global camera, pan
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    camera_enable(camera, 32)
    servo_enable_position(pan, 32)


def run(ms):
    global frame
    if ms and frame % 4 == 0:
        servo_get_position(pan)
        camera_get_image(camera)
    servo_set_position(pan, math.radians(60 * math.sin(2 * math.pi * frame * 0.008 / 4)))
    frame += 1
    return 8


if __name__ == "__main__":
    robot_live(init)
    robot_run(run)
