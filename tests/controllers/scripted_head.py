"""Test controller: open-loop head and leg motion, logging joints and taking pictures."""

import math

from aibo_sim.controller import *  # noqa: F403

STEP = 16
LOCATORS = ["PRM:/r1/c1/c2-Joint2:12", "PRM:/r1/c1/c2/c3-Joint2:13", "PRM:/r2/c1-Joint2:21", "PRM:/r4/c1-Joint2:41"]


def init():
    global camera, servos, log
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    camera_enable(camera, STEP)
    servos = [robot_get_device(name) for name in LOCATORS]
    for tag in servos:
        servo_enable_position(tag, STEP)
    log = open("joints.txt", "w")


def run(ms):
    t = robot_get_time()
    if ms:
        log.write(" ".join(f"{servo_get_position(tag):.12f}" for tag in servos) + "\n")
        image = camera_get_image(camera)
        log.write(f"pixel {camera_image_get_red(image, 208, 104, 80)}\n")
    servo_set_position(servos[0], 0.6 * math.sin(2 * t))
    servo_set_position(servos[1], 0.2 * math.sin(3 * t))
    servo_set_position(servos[2], 0.3 * math.sin(4 * t))
    servo_set_position(servos[3], -0.3 * math.sin(4 * t))
    return STEP


def die():
    log.close()


if __name__ == "__main__":
    robot_live(init)
    robot_die(die)
    robot_run(run)
