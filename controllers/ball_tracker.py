"""Keeps the ball centred in the camera image by moving the head (the body stands still)."""

from ball_vision import find_ball, pixel_angles

from aibo_sim.controller import *  # noqa: F403

TIME_STEP = 32
GAIN = 0.6  # fraction of the angular error corrected each step

camera = pan = tilt = None


def init():
    global camera, pan, tilt
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    tilt = robot_get_device("PRM:/r1/c1/c2/c3-Joint2:13")
    camera_enable(camera, TIME_STEP)
    for servo in (pan, tilt):
        servo_enable_position(servo, TIME_STEP)


def run(ms):
    if ms == 0:  # first call: nothing sampled yet
        return TIME_STEP
    w, h = camera_get_width(camera), camera_get_height(camera)
    ball = find_ball(camera_get_image(camera), w, h)
    if ball is not None:
        left, up = pixel_angles(*ball, w, h, camera_get_fov(camera))
        servo_set_position(pan, servo_get_position(pan) + GAIN * left)
        servo_set_position(tilt, servo_get_position(tilt) + GAIN * up)
    return TIME_STEP


if __name__ == "__main__":
    robot_live(init)
    robot_run(run)
