"""Walks to the ball: the head tracks it, the legs turn towards it and walk until it is close."""

import ball_tracker
from ball_vision import find_ball

from aibo_sim.controller import *  # noqa: F403

TIME_STEP = 32
TURN_PAN = 0.35  # rad: turn instead of walking when the head looks further aside
CLOSE_PIXELS = 2500  # the ball fills this many pixels of the 208 x 160 image when it is ~25 cm away

walk = turn_left = turn_right = None
reached = False


def init():
    global walk, turn_left, turn_right
    ball_tracker.init()
    walk, turn_left, turn_right = (mtn_new(name) for name in ("WALKFWD.MTN", "TURNL.MTN", "TURNR.MTN"))


def run(ms):
    global reached
    if not ms or reached:
        return TIME_STEP
    camera = ball_tracker.camera
    ball = find_ball(camera_get_image(camera), camera_get_width(camera), camera_get_height(camera))
    pan = ball_tracker.track(ball) if ball is not None else None
    if ball is not None and ball[2] >= CLOSE_PIXELS:
        reached = True
        robot_console_printf("reached the ball at t = %.2f s\n", robot_get_time())
    elif all(mtn_is_over(m) for m in (walk, turn_left, turn_right)):
        if pan is None or pan > TURN_PAN:
            mtn_play(turn_left)  # search to the left, or turn towards the ball
        elif pan < -TURN_PAN:
            mtn_play(turn_right)
        else:
            mtn_play(walk)
    return TIME_STEP


if __name__ == "__main__":
    robot_live(init)
    robot_run(run)
