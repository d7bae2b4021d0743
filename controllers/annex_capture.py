"""Annex I of the report (Peris, Grande, Escrig 2008), ported from C to the same API in Python.

Plays the forward walk MTN_REPLAY times, then captures the camera image and writes
``image.raw``: for each pixel, row-major, the bytes Y, U, V computed with the Annex's own
formulas (U from blue, V from red, C casts: truncation toward zero).

Changes from the C original, all fixes of outright bugs:
- ``run`` allocated three IMAGE_SIZE buffers on every call and never freed them (leak):
  they are gone (numpy arrays are made when an image is converted);
- ``run`` opened ``image.raw`` with ``ofstream`` on every call, truncating it during the
  walk: the file is now opened only to write an image;
- ``run`` fell off its end without returning the next step while the motion played
  (undefined behaviour in C): it returns SIMULATION_STEP on every path;
- ``die`` had a stray closing brace.
The motion file is this project's own forward walk (Sony's wwfwd.mtn is not shipped), and
the file path is relative to the run's output folder instead of /ms/open-r/mw/data/p/.
"""

from aibo_sim.controller import *  # noqa: F403
from aibo_sim.dump import annex_yuv  # the Annex's three formulas, shared with `aibo-sim dump`

SIMULATION_STEP = 16
MTN_REPLAY = 15
MTN_FILE = "WALKFWD.MTN"
IMAGE_FILE = "image.raw"

mtn = None
camera = None
loop = 0


def init():
    global mtn, camera
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
    sensors = [
        robot_get_device(name)
        for name in ("PRM:/r1/c1/c2/c3/p1-Sensor:p1", "PRM:/r1/c1/c2/c3/p2-Sensor:p2", "PRM:/p1-Sensor:p1")
    ]
    touch = [robot_get_device(f"PRM:/r{leg}/c1/c2/c3/c4-Sensor:{leg}4") for leg in (2, 3, 4, 5)]
    joints = [
        robot_get_device(f"PRM:/r{leg}/c1{part}-Joint2:{leg}{j}")
        for leg in (2, 3, 4, 5)
        for j, part in ((1, ""), (2, "/c2"), (3, "/c2/c3"))
    ]
    joints += [
        robot_get_device(name)
        for name in ("PRM:/r1/c1-Joint2:11", "PRM:/r1/c1/c2-Joint2:12", "PRM:/r1/c1/c2/c3-Joint2:13")
    ]

    camera_enable(camera, SIMULATION_STEP)
    for tag in sensors:
        distance_sensor_enable(tag, SIMULATION_STEP)
    for tag in touch:
        touch_sensor_enable(tag, SIMULATION_STEP)
    for tag in joints:
        servo_set_velocity(tag, 2.498)
        servo_set_acceleration(tag, 2.498)
        servo_enable_position(tag, SIMULATION_STEP)
    mtn = mtn_new(MTN_FILE)


def die():
    if mtn is not None:
        mtn_delete(mtn)


def run(ms):
    global loop
    if mtn_is_over(mtn) and loop < MTN_REPLAY:
        mtn_play(mtn)  # play the motion until enough loops
        loop += 1
    elif mtn_is_over(mtn) and loop == MTN_REPLAY:
        image = camera_get_image(camera)
        w = camera_get_width(camera)
        h = camera_get_height(camera)
        with open(IMAGE_FILE, "wb") as raw:
            raw.write(annex_yuv(image.reshape(h, w, 3)).tobytes())
    return SIMULATION_STEP


if __name__ == "__main__":
    robot_live(init)
    robot_die(die)
    robot_run(run)
