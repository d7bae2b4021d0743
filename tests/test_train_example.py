"""The training example's evaluation and learning-curve plot (training itself needs
stable-baselines3 and minutes: the README has its measured result)."""

import sys

import cv2
import gymnasium as gym
import numpy as np
import pytest

import aibo_sim  # noqa: F401  (registers the environments)
from aibo_sim.envs import train_example
from aibo_sim.envs.train_example import EVAL_SEED, evaluate, hold_still, plot_learning_curve
from aibo_sim.ers7 import JOINT_INDEX


def test_evaluation_replays_the_same_episodes_for_every_policy():
    env = gym.make("aibo_sim/HeadTrackBall-v0", camera_layer="L", max_episode_steps=30)
    still = evaluate(env, lambda obs: np.zeros(3, np.float32), 2)
    again = evaluate(env, lambda obs: np.zeros(3, np.float32), 2)
    randomly = evaluate(env, lambda obs: env.action_space.sample(), 2)
    held = evaluate(env, hold_still(env), 2)
    start = env.unwrapped.sim.servos.target[[JOINT_INDEX[n] for n in env.unwrapped.actuated_joints]].copy()
    env.close()
    assert still == again and len(still) == 2 and still != randomly  # seeds EVAL_SEED, EVAL_SEED + 1
    assert all(0 <= total <= 30 for total in still + randomly + held) and held not in (still, randomly)
    assert np.allclose(start, [np.radians(-30), 0, np.radians(15)], atol=1e-6)  # held at the keyframe's targets
    assert EVAL_SEED == 10_000


@pytest.mark.slow
def test_learning_curve_is_a_png_with_the_policies_levels(tmp_path):
    path = tmp_path / "curve.png"
    steps = np.arange(1, 51) * 300.0
    levels = {"random": 43.7, "holding still": 89.0, "trained": 141.3}
    plot_learning_curve(str(path), steps, np.linspace(40, 140, 50), levels)
    image = cv2.imread(str(path))
    assert image.shape == (480, 800, 3)
    red, orange, green, mean_blue = [40, 39, 214], [14, 127, 255], [44, 160, 44], [180, 119, 31]  # tab: in BGR
    for colour, least in ((red, 500), (orange, 500), (green, 500), (mean_blue, 100)):
        assert (image == colour).all(axis=2).sum() > least, colour
    with pytest.raises(OSError, match="cannot write .*folder.png: No such file"):
        plot_learning_curve(str(tmp_path / "no" / "such" / "folder.png"), steps, steps, {"random": 0.0})


def test_learning_curve_without_matplotlib_says_what_to_install(tmp_path, monkeypatch):
    for name in [name for name in sys.modules if name.split(".")[0] == "matplotlib"] + ["matplotlib"]:
        monkeypatch.setitem(sys.modules, name, None)  # its imports then fail
    with pytest.raises(ImportError, match=r"pip install 'aibo-sim\[plot\]'"):
        plot_learning_curve(str(tmp_path / "curve.png"), np.zeros(0), np.zeros(0), {"random": 0.0})


@pytest.mark.parametrize("option, value", [("--envs", "0"), ("--steps", "-5"), ("--episodes", "0"), ("--envs", "x")])
def test_counts_that_are_not_at_least_one_are_refused_before_training(capsys, option, value):
    """--envs 0 was SubprocVecEnv's bare ValueError; --steps -5 'trained -5 steps'; --episodes 0 nan."""
    with pytest.raises(SystemExit) as refused:
        train_example.main([option, value])
    assert refused.value.code == 2
    assert f"argument {option}: {value!r} is not a whole number of at least 1" in capsys.readouterr().err
