"""The OPEN-R runtime's sensor vector values (aibo_sim.openr.sensor_values, compiled) are the
simulator's readings to the bit, and the host protocol's answers split into frames."""

import struct

import numpy as np
import pytest

from aibo_sim import ers7
from aibo_sim.openr.host import SensorFrame
from aibo_sim.sim import Simulation
from openr_bridge import host_protocol


def test_distances_and_accelerations_are_the_simulators_to_the_bit():
    """SensorFrame.at computes Simulation.distances_mm (with the same noise draws) and
    Simulation.acceleration itself: the same doubles, frame after frame, as the head moves
    (near and far readings, out of range, clamped)."""
    sim = Simulation(seed=11)
    try:
        frame = SensorFrame(sim)
        distances = [i for i, (_, kind) in enumerate(frame.entries) if kind == host_protocol.SENSOR_KINDS["DISTANCE"]]
        accelerations = [
            i for i, (_, kind) in enumerate(frame.entries) if kind == host_protocol.SENSOR_KINDS["ACCELERATION"]
        ]
        rng = np.random.default_rng(0)
        heads = [ers7.JOINT_INDEX[name] for name in ("neck_tilt", "head_pan", "head_tilt")]
        seen = set()
        for tick in range(240):
            if tick % 20 == 0:
                for joint in heads:
                    sim.servos.set_target(joint, rng.uniform(sim.servos.low[joint], sim.servos.high[joint]))
            state = sim.rng.bit_generator.state
            frame.at(tick)
            after = sim.rng.bit_generator.state
            sim.rng.bit_generator.state = state
            expected = np.array(sim.distances_mm()) * 1e3
            assert sim.rng.bit_generator.state == after  # the same draws, no more, no fewer
            silent = frame._silent[tick % 2]
            measured = frame._raw[distances, 0]
            assert np.array_equal(measured[~silent], expected[~silent])
            signs = np.array(ers7.OPENR_ACCELERATION_SIGNS)
            assert np.array_equal(frame._raw[accelerations, 0], signs * (sim.acceleration() * 1e6))
            seen.update(np.round(expected[~silent] / 1e3, 3).tolist())
            sim.step_frame()
        assert len(seen) > 100  # readings of all sorts were compared
    finally:
        sim.close()


def test_a_standing_robot_reads_its_switches_and_its_accelerometer_as_a_real_one():
    """Model Information 3.2.4: the paw and chin switches return oswitchON / oswitchOFF in both
    OSensorValue fields (signal was always 0). The accelerometer's a1 is backward and a3 down
    (Tekkotsu's ERS7Info): a standing robot read a3 = +1 g, upside down."""
    sim = Simulation()
    try:
        frame = SensorFrame(sim)
        switches = [i for i, (_, kind) in enumerate(frame.entries) if kind == host_protocol.SENSOR_KINDS["SWITCH"]]
        for _ in range(60):  # the robot settles onto its paws
            sim.step_frame()
        frame.at(60)
        values = frame._raw[switches, :2]
        assert np.array_equal(values[:, 0], values[:, 1]) and values[:, 0].sum() == 4, values  # the paws pressed
        # Standing: a3 (down) reads -1 g, a1 (backward) a little above 0: the body pitched 1 deg nose down
        # (Tekkotsu: "positive for faceplant")
        accelerations = [
            i for i, (_, kind) in enumerate(frame.entries) if kind == host_protocol.SENSOR_KINDS["ACCELERATION"]
        ]
        a1, a2, a3 = frame._raw[accelerations, 0] / 1e6
        assert a3 == pytest.approx(-9.81, abs=0.1) and 0 < a1 < 0.5 and abs(a2) < 0.05, (a1, a2, a3)
    finally:
        sim.close()


def test_a_frame_done_splits_into_the_frame_and_its_foretold_frames():
    def record(kind, payload=b""):
        return struct.pack("<2I", host_protocol.RECORDS[kind], len(payload)) + payload

    joint = record("JOINT", struct.pack("<2i", 3, 1000))
    led = record("LED", struct.pack("<3i", 40, 255, 0))
    assert host_protocol.split_frames(b"") == [b""]
    assert host_protocol.split_frames(joint + led) == [joint + led]
    next_frame = record("NEXT_FRAME")
    assert host_protocol.split_frames(joint + next_frame + next_frame + led + joint) == [joint, b"", led + joint]
