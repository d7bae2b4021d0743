"""The sensor vector's values of one frame, compiled with numba (``SensorFrame.at``: a frame's
thirty-odd values in one call, where numpy takes a call per operation and Python a few
microseconds a value).

Rows follow ``SensorFrame.entries``: the joints (angle, -, duty, command), the distance sensors
(mm, signal), the accelerometer's three axes (one primitive each; ``ers7.OPENR_ACCELERATION_SIGNS``),
the touch sensors and switches,
the wireless LAN switch. Values are rounded to OPEN-R's integer units once: micro-radians,
micrometres, micrometres per second squared; the duty in ``ers7.PWM_DUTY_FULL_SCALE``ths of the
motor's full force.

The distances and accelerations are ``Simulation.distances_mm`` and ``Simulation.acceleration``
computed here, operation for operation in the same order and in doubles (numba, like Python,
neither reorders nor fuses them), from the same noise draws: the same values to the bit
(tests/test_openr_sensor_values.py holds them to it).
"""

import numpy as np

from ..ers7 import PWM_DUTY_FULL_SCALE
from ..jit import compiled


@compiled(nogil=True)
def fill(
    qpos,
    actuator_force,
    command,
    sensordata,
    noise,
    silent,
    qpos_adr,
    force_index,
    joints,
    max_force,
    distance_adr,
    distance_ranges,
    ir_noise,
    accel_adr,
    accel_signs,
    accel_range,
    touch_adr,
    switch,
    threshold,
    touch_ad_per_newton,
    touch_ad_max,
    raw,
    values,
):
    """Write a frame's values into ``raw`` (floats; a silent head distance sensor keeps its last
    value there) and, rounded half to even, into the int32 ``values``. ``noise``: one standard
    normal draw per distance sensor, in order (``Simulation.distances_mm``'s)."""
    n = joints.shape[0]
    for k in range(n):
        duty = actuator_force[force_index[k]] / max_force[k]
        raw[k, 0] = qpos[qpos_adr[k]] * 1e6
        raw[k, 2] = min(max(duty, -1.0), 1.0) * PWM_DUTY_FULL_SCALE
        raw[k, 3] = command[joints[k]] * 1e6
    row = n
    for k in range(distance_adr.shape[0]):
        if silent[k]:
            raw[row, 1] = 0.0  # not this head sensor's turn: its last value stays, no signal
        else:
            # Simulation.distances_mm: clamped to the range, 10 % noise mid-range (IR_NOISE)
            low, high = distance_ranges[k, 0], distance_ranges[k, 1]
            reading = sensordata[distance_adr[k]]
            mm = high if reading < 0 else min(max(reading * 1000, low), high)  # < 0: no hit
            mm = mm * (1 + ir_noise * (1 - abs(2 * (mm - low) / (high - low) - 1)) * noise[k])
            raw[row, 0] = mm * 1e3
            raw[row, 1] = min(mm, 65535.0)
        row += 1
    for axis in range(3):  # the accelerometer's three primitives, one axis each (within +-2 g), as Sony's signs
        raw[row, 0] = accel_signs[axis] * min(max(sensordata[accel_adr + axis], -accel_range), accel_range) * 1e6
        row += 1
    for k in range(touch_adr.shape[0]):
        force = sensordata[touch_adr[k]]
        if switch[k]:
            raw[row, 0] = raw[row, 1] = 1.0 if force > threshold[k] else 0.0  # both: Model Information 3.2.4
        else:
            raw[row, 0] = raw[row, 1] = min(touch_ad_max, force * touch_ad_per_newton)
        row += 1
    for r in range(raw.shape[0]):
        for c in range(raw.shape[1]):
            values[r, c] = np.int32(np.rint(raw[r, c]))
