"""Keeps the ball centred in the camera image by moving the head (the body stands still)."""

from ball_vision import find_ball, pixel_angles

from aibo_sim.controller import *  # noqa: F403

TIME_STEP = 32
GAIN = 0.6  # fraction of the angular error corrected each step
HEAD_TILT_LOW = -0.26  # rad: below this the neck tilts instead of the head

camera = neck = pan = tilt = None


def init():
    global camera, neck, pan, tilt
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    neck = robot_get_device("PRM:/r1/c1-Joint2:11")
    pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    tilt = robot_get_device("PRM:/r1/c1/c2/c3-Joint2:13")
    camera_enable(camera, TIME_STEP)
    for servo in (neck, pan, tilt):
        servo_enable_position(servo, TIME_STEP)


def track(ball):
    """Turn the head by a fraction of the ball's angular offset; returns the head pan."""
    w, h = camera_get_width(camera), camera_get_height(camera)
    left, up = pixel_angles(ball[0], ball[1], w, h, camera_get_fov(camera))
    servo_set_position(pan, servo_get_position(pan) + GAIN * left)
    head_tilt = servo_get_position(tilt) + GAIN * up
    if head_tilt < HEAD_TILT_LOW:
        servo_set_position(neck, servo_get_position(neck) + head_tilt - HEAD_TILT_LOW)
        head_tilt = HEAD_TILT_LOW
    servo_set_position(tilt, head_tilt)
    return servo_get_position(pan)


def run(ms):
    if ms:  # the first call comes before any sample
        ball = find_ball(camera_get_image(camera), camera_get_width(camera), camera_get_height(camera))
        if ball is not None:
            track(ball)
    return TIME_STEP


if __name__ == "__main__":
    robot_live(init)
    robot_run(run)
