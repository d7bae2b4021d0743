"""The match environments (issue 41): MatchEnv (PettingZoo ParallelEnv) and ScriptedOpponentsEnv."""

import math
import re
import shutil
import warnings
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test, state_test
from pettingzoo.utils.conversions import parallel_to_aec

from aibo_sim.envs.match import BALL_PROGRESS_REWARD, FALL_PENALTY, MatchEnv, ScriptedOpponentsEnv
from aibo_sim.ers7 import JOINT_INDEX
from aibo_sim.team import RobotSpec, TeamError

MATCH_VS_SCRIPTED = "aibo_sim/MatchVsScripted-v0"
STRIKERS = [RobotSpec("red", 4), RobotSpec("blue", 4)]  # kickoff poses, facing each other across the centre
SMALL = {"camera_layer": "L", "camera_profile": "ideal"}


def hold(env: MatchEnv, agent: str) -> np.ndarray:
    """The action that keeps ``agent``'s targets where they are."""
    targets = env.robot(agent).servos.target[[JOINT_INDEX[name] for name in env.actuated_joints]]
    return env.targets_to_action(agent, targets)


def knock_over(robot) -> None:
    """Lay the robot on its side (90 degrees of roll), a little above the ground."""
    model, data = robot.model, robot.data
    root = model.jnt_qposadr[model.body_jntadr[model.body(robot.prefix + "body").id]]
    data.qpos[root + 2] += 0.05
    data.qpos[root + 3 : root + 7] = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    mujoco.mj_forward(model, data)


def team_pixels(image: np.ndarray, team: str) -> int:
    """Pixels of the team's uniform colour (dark blue, near black as the real ones read, or red; not
    the sky-blue goal nor the orange ball)."""
    r, g, b = (image[..., i].astype(int) for i in range(3))
    if team == "blue":
        return int(((b > 2 * g) & (b > 2 * r) & (b >= 4)).sum())
    return int(((r > 3 * g) & (r > 3 * b) & (r > 60)).sum())


def test_parallel_api_test_and_the_state_test_pass():
    """state_test warned (an error here) of state_space's infinite bounds."""
    env, other = MatchEnv(STRIKERS, **SMALL), MatchEnv(STRIKERS, **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(env, num_cycles=12)
        state_test(parallel_to_aec(other), other, num_cycles=12)
    assert np.isfinite(env.state_space.low).all() and np.isfinite(env.state_space.high).all()
    env.close()
    other.close()


def test_four_against_four_at_kickoff():
    env = MatchEnv()
    assert env.metadata["name"] == "aibo_sim_match_v0"
    assert env.possible_agents == [f"{team}_{n}" for team in ("red", "blue") for n in range(1, 5)]
    observations, infos = env.reset(seed=0)
    assert env.agents == env.possible_agents and observations.keys() == infos.keys() == set(env.agents)
    for _ in range(2):
        observations, rewards, terminations, truncations, infos = env.step(
            {agent: env.action_space(agent).sample() for agent in env.agents}
        )
    for agent in env.possible_agents:
        assert env.observation_space(agent).contains(observations[agent]), agent
        assert observations[agent]["image"].shape == (160, 208, 3)
        assert not terminations[agent] and not truncations[agent]
        team, number = agent.split("_")
        assert infos[agent]["team"] == team and infos[agent]["number"] == int(number)
        assert (infos[agent]["position"][0] < 0) == (team == "red")  # red in the -X half
    assert rewards["red_1"] == rewards["red_4"] == -rewards["blue_2"]
    assert env.state().shape == env.state_space.shape
    env.close()


def test_same_seed_same_observations_and_other_seed_other_images():
    def run(env, seed):
        for agent in env.possible_agents:
            env.action_space(agent).seed(seed)
        steps = [env.reset(seed=seed)[0]]
        for _ in range(2):
            steps.append(env.step({agent: env.action_space(agent).sample() for agent in env.agents})[0])
        return steps

    options = {"camera_layer": "M", "randomize": {"lighting": 0.3, "ball_start": 0.2, "camera_robot": 1.0}}
    env, fresh = MatchEnv(STRIKERS, **options), MatchEnv(STRIKERS, **options)
    first, again, elsewhere, other = run(env, 5), run(env, 5), run(fresh, 5), run(env, 6)
    for run_ in (again, elsewhere):
        for obs_1, obs_2 in zip(first, run_, strict=True):
            for agent in obs_1:
                for key in obs_1[agent]:
                    assert np.array_equal(obs_1[agent][key], obs_2[agent][key]), (agent, key)
    assert not np.array_equal(first[-1]["red_4"]["image"], other[-1]["red_4"]["image"])
    assert env.camera_robots["red_4"] != env.camera_robots["blue_4"]  # each camera drew its own deviation
    env.close()
    fresh.close()


def test_each_agent_sees_through_its_own_camera():
    # red_4 looks at blue_4's left flank, blue_4 (turned to +Y) at red_3's right flank.
    robots = [
        RobotSpec("red", 4, (-0.45, 0.0, 0.0)),
        RobotSpec("blue", 4, (0.0, 0.0, 90.0)),
        RobotSpec("red", 3, (0.0, 0.45, 0.0)),
    ]
    env = MatchEnv(robots, camera_profile="ideal")
    observations, _ = env.reset(seed=0, options={"ball": (2.0, -1.5)})
    red_view, blue_view = observations["red_4"]["image"], observations["blue_4"]["image"]
    assert not np.array_equal(red_view, blue_view)
    assert team_pixels(red_view, "blue") > 1000 and team_pixels(red_view, "red") == 0
    assert team_pixels(blue_view, "red") > 1000 and team_pixels(blue_view, "blue") == 0
    visible = {agent: env.image_position(agent, env.robot("blue_4").body_pose()[0])[1] for agent in env.agents}
    assert visible == {"red_4": True, "blue_4": False, "red_3": False}
    env.close()


def test_ball_moved_towards_the_blue_goal_rewards_red_and_costs_blue():
    env = MatchEnv(STRIKERS, camera=None)
    env.reset(seed=0, options={"ball": (0.0, 1.0)})
    sim = env.robot("red_4")
    for x, sign in ((0.5, 1), (-0.3, -1)):  # towards +X, the blue (sky-blue) goal, then back past the centre
        before = float(sim.ball_position()[0])
        sim.place_ball(x, 1.0)
        _, rewards, *_ = env.step({agent: hold(env, agent) for agent in env.agents})
        expected = BALL_PROGRESS_REWARD * (float(sim.ball_position()[0]) - before)
        assert rewards["red_4"] == pytest.approx(expected) and np.sign(rewards["red_4"]) == sign
        assert rewards["blue_4"] == pytest.approx(-expected)
        assert abs(expected) > 0.9 * BALL_PROGRESS_REWARD * abs(x - before)
    env.close()


def test_a_fallen_agent_is_terminated_and_its_robot_holds_its_targets():
    env = MatchEnv(STRIKERS, camera=None)
    env.reset(seed=0, options={"ball": (0.0, 1.5)})
    knock_over(env.robot("red_4"))
    actions = {agent: hold(env, agent) for agent in env.agents}
    _, rewards, terminations, truncations, infos = env.step(actions)
    assert terminations == {"red_4": True, "blue_4": False} and not any(truncations.values())
    assert infos["red_4"]["fallen"] and rewards["red_4"] == pytest.approx(-FALL_PENALTY, abs=0.05)
    assert env.agents == ["blue_4"]
    targets = env.robot("red_4").servos.target.copy()
    with pytest.raises(ValueError, match="'red_4', which is done"):
        env.step(actions)
    observations, *_ = env.step({"blue_4": actions["blue_4"]})
    assert observations.keys() == {"blue_4"} and np.array_equal(env.robot("red_4").servos.target, targets)
    env.close()


def test_truncation_ends_every_agent_and_step_then_needs_a_reset():
    env = MatchEnv(STRIKERS, camera=None, max_cycles=2)
    env.reset(seed=0)
    assert not any(env.step({})[3].values())  # an agent without an action holds its targets
    *_, truncations, _ = env.step({})
    assert truncations == {"red_4": True, "blue_4": True} and env.agents == []
    with pytest.raises(gym.error.ResetNeeded):
        env.step({})
    env.close()
    with pytest.raises(gym.error.ClosedEnvironmentError):
        env.reset(seed=0)


def test_a_refused_step_or_reset_changes_nothing():
    env = MatchEnv(STRIKERS, camera=None)
    try:
        env.reset(seed=0)
        env.step({})
        red = env.robots["red_4"]
        targets, time_ms = red.servos.target.copy(), env.sim.time_ms
        # blue's action is refused, naming blue: red's is not given either
        with pytest.raises(ValueError, match=r"^blue_4's action\[0\] \(lf_j1\) is nan: actions must be finite$"):
            env.step({"red_4": np.ones(15, np.float32), "blue_4": np.full(15, np.nan, np.float32)})
        assert np.array_equal(red.servos.target, targets)
        for ball, message in (
            ((math.nan, 0.0), "x = nan must be a finite number"),
            ((1, 2, 3), "want two numbers"),
            ({"x": 0.3, "y": 0.2}, "want two numbers"),  # a bare KeyError: 0 before
        ):
            with pytest.raises(ValueError, match=message):
                env.reset(options={"ball": ball})
            assert env.sim.time_ms == time_ms and env.agents == ["red_4", "blue_4"]  # the match goes on
        qpos = env.sim.data.qpos.copy()
        blue = env.robots["blue_4"]  # the ball at its front left leg's knee, as run and dump refuse it
        x, y = blue.data.xpos[blue.model.body(blue.prefix + "lf_j3").id][:2]
        with pytest.raises(ValueError, match=rf"the ball at {x:g}, {y:g} would overlap blue 4 by \d+\.\d cm$"):
            env.reset(options={"ball": (x, y)})
        with pytest.raises(ValueError, match=r"the ball at 3.5, 0 lies off the carpet \(\|x\| <= 3 m\) of the default"):
            env.reset(options={"ball": (3.5, 0.0)})  # behind the goal's wall
        assert np.array_equal(env.sim.data.qpos, qpos) and env.sim.time_ms == time_ms
    finally:
        env.close()


def test_a_randomised_ball_start_is_never_inside_a_robot():
    """The ball drawn inside a robot was kicked out at 0.8 m/s, a reward to both teams before any
    action (seed 64 of the default match with ball_start 0.3: 3.6 cm into blue 4)."""
    env = MatchEnv(camera=None, randomize={"ball_start": 0.3})
    try:
        for seed in range(60, 70):
            env.reset(seed=seed)
            assert not [pair for pair in env.sim.overlaps(0.001) if "the ball" in pair[:2]], seed
            assert np.abs(env.sim.ball_position()[:2]).max() <= 0.3
    finally:
        env.close()


def test_a_match_whose_robot_stands_on_the_centre_spot_is_refused_when_made():
    """The ball starts there: reset drew its start again for ever (ball_start 0 draws the spot)."""
    with pytest.raises(ValueError, match=r"^the ball on the centre spot would overlap red 1 by \d+\.\d cm"):
        MatchEnv([RobotSpec("red", 1, (0.05, 0.05, 0.0)), RobotSpec("blue", 1)], camera=None)


def test_robots_from_a_team_file_and_bad_arguments(tmp_path):
    path = tmp_path / "robots.toml"
    path.write_text('[[robot]]\nteam = "blue"\nnumber = 2\n\n[[robot]]\nteam = "red"\nnumber = 1\n')
    env = MatchEnv(str(path), camera=None)
    assert env.possible_agents == ["blue_2", "red_1"]
    assert env.observation_space("red_1") is env.observation_space("red_1") is not env.observation_space("blue_2")
    env.close()
    for bad, match in (
        ({"robots": [RobotSpec(None, 1)]}, "needs a team"),
        ({"robots": STRIKERS, "scripted": {"red_2": None}}, "no robot 'red_2'"),
        ({"robots": STRIKERS, "max_cycles": 0}, "max_cycles"),
        ({"robots": STRIKERS, "camera": "bgr"}, "camera must be"),
        ({"robots": STRIKERS, "randomize": {"lighting": 2}}, "at most 1"),
    ):
        with pytest.raises(ValueError, match=match):
            MatchEnv(**bad)
    with pytest.raises(ValueError, match="learner 'red_3'"):
        ScriptedOpponentsEnv(learner="red_3", robots=STRIKERS)
    with pytest.raises(
        TypeError, match=r"^scripted\['blue_4'\] is 3, not a factory called with the robot's Simulation"
    ):
        MatchEnv(STRIKERS, scripted={"blue_4": 3})


def test_render_shows_the_field():
    env = MatchEnv(STRIKERS, camera=None, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (360, 480, 3) and frame.dtype == np.uint8 and frame.std() > 10
    env.close()


class Holder:
    """A scripted policy that keeps its robot's targets."""

    def __init__(self, robot):
        self.robot = robot

    def reset(self):
        pass

    def plan(self, frames):
        return np.tile(self.robot.servos.target, (frames, 1))


def test_scripted_robots_step_frame_by_frame_with_the_same_physics():
    """With a script the joint frames of a step run one by one (the script sets targets every 8 ms);
    a script that holds gives bit for bit the world of an agent given no action."""
    robots = [*STRIKERS, RobotSpec("blue", 1)]
    plain, scripted = (
        MatchEnv(robots, camera_layer="M"),
        MatchEnv(robots, camera_layer="M", scripted={"blue_1": Holder}),
    )
    assert scripted.possible_agents == ["red_4", "blue_4"]
    rng = np.random.default_rng(0)
    plain.reset(seed=4)
    scripted.reset(seed=4)
    for _ in range(3):
        actions = {agent: rng.uniform(-1, 1, 15).astype(np.float32) for agent in scripted.agents}
        observed, seen = plain.step(actions)[0], scripted.step(actions)[0]
        assert np.array_equal(plain.sim.data.qpos, scripted.sim.data.qpos)
        assert all(np.array_equal(observed[a][k], seen[a][k]) for a in seen for k in seen[a])
    plain.close()
    scripted.close()


def test_scripted_opponents_env_passes_check_env():
    env = gym.make(MATCH_VS_SCRIPTED, **SMALL).unwrapped  # with a spec: check_env tries render_mode="rgb_array" too
    assert isinstance(env, ScriptedOpponentsEnv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env)
    assert env.observation_space is env.match.observation_space("red_4") and env.match.possible_agents == ["red_4"]
    env.close()


@pytest.mark.parametrize("seed", [None, 7])
def test_a_refused_reset_of_the_scripted_opponents_env_changes_nothing(seed):
    """It drew from its generator (or took the new seed) before the match refused the ball."""
    envs = [gym.make(MATCH_VS_SCRIPTED, camera=None).unwrapped for _ in range(2)]
    for env in envs:
        env.reset(seed=0)
    with pytest.raises(ValueError, match="off the carpet"):
        envs[0].reset(seed=seed, options={"ball": (50.0, 0.0)})
    observations = [env.reset()[0] for env in envs]
    for env in envs:
        env.close()
    assert all(np.array_equal(observations[0][key], observations[1][key]) for key in observations[0])


def test_scripted_robots_chase_the_ball():
    env = gym.make(MATCH_VS_SCRIPTED, camera=None)
    assert env.spec.max_episode_steps == 900
    _, info = env.reset(seed=0)
    match = env.unwrapped.match
    ball = info["ball_position"][:2]

    def distance(name):
        return float(np.linalg.norm(match.robot(name).body_pose()[0][:2] - ball))

    start = {name: distance(name) for name in ("red_2", "blue_3", "blue_4")}
    keeper = match.robot("blue_1").body_pose()[0][:2].copy()
    action = hold(match, "red_4")
    for _ in range(90):  # 3 s
        _, reward, terminated, truncated, info = env.step(action)
    assert not terminated and not truncated and np.isfinite(reward)
    for name, before in start.items():
        assert distance(name) < before - 0.1, name  # walked at the ball (~0.1 m/s)
    assert np.linalg.norm(match.robot("blue_1").body_pose()[0][:2] - keeper) < 0.1  # the goalkeeper stays
    assert not any(match.robot(name).fallen() for name in match.robots)
    env.close()


def test_robots_inside_each_other_or_with_a_malformed_pose_are_refused_as_run_refuses_them(tmp_path):
    robots = tmp_path / "robots.toml"
    robots.write_text(
        '[[robot]]\nteam = "red"\nnumber = 2\npose = [0.5, 0.5, 0]\n\n'
        '[[robot]]\nteam = "blue"\nnumber = 2\npose = [0.71, 0.5, 180]\n'
    )
    with pytest.raises(ValueError, match=r"robots\.toml:1: red 2 starts inside blue 2 \(\d+\.\d cm deep\)$"):
        MatchEnv(robots=str(robots), camera=None)
    for pose in [(0, 0), ("a", 0, 0), (0, 0, 0, 0)]:
        with pytest.raises(TeamError, match=r"robot 1 \(red 4\): pose must be 3 numbers \[x, y, yaw\]"):
            MatchEnv(robots=[RobotSpec("red", 4, pose)], camera=None)


def test_a_ball_option_in_a_scene_without_a_ball_is_refused_as_run_refuses_it(tmp_path):
    """It was dropped without a word (info's ball_position None), where run --ball is refused."""
    models = Path(__file__).resolve().parents[1] / "models"
    shutil.copy(models / "ers7.xml", tmp_path)
    scene = tmp_path / "noball.xml"
    scene.write_text(re.sub(r'<body name="ball".*?</body>', "", (models / "scene.xml").read_text(), flags=re.S))
    env = MatchEnv(STRIKERS, camera=None, scene=str(scene))
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match=r"this scene has no body named 'ball' to place$"):
            env.reset(options={"ball": (0.3, 0.2)})
    finally:
        env.close()
