"""A match on the field: ERS-7s of the red and the blue team, each with its own camera.

``MatchEnv`` is a PettingZoo ``ParallelEnv`` (the multi-agent standard): every robot an agent,
named ``red_1`` .. ``blue_4`` (team, player number), each observing through its own head camera
and acting on its own joints as the single-robot environments do (``aibo_sim.envs.base``).
``ScriptedOpponentsEnv`` (``gymnasium.make("aibo_sim/MatchVsScripted-v0")``) is the Gymnasium
view of one robot of such a match, every other robot driven by a scripted ``BallChaser``::

    from aibo_sim.envs.match import MatchEnv

    env = MatchEnv(camera_layer="L")  # 4 against 4 at the kickoff poses
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)
    env.close()

One step is one frame of the head cameras at 30 fps (4 or 5 joint frames of 8 ms), as in the
single-robot environments; every live agent's camera frame is made, together (``World.frames``: in
parallel threads with a software OpenGL), so a step of 8 agents costs about 8 camera frames of a
match (their times in docs/benchmarks.md).
"""

from __future__ import annotations

import copy
import functools
import math
import numbers
from collections.abc import Callable, Mapping

import gymnasium as gym
import mujoco
import numpy as np
import pettingzoo
from gymnasium.utils import seeding

import openr_bridge

from ..camera import CameraSettings, RobotColour
from ..camera.backends import OpenRCamera
from ..config import CameraConfig
from ..ers7 import DISTANCE_SENSORS, JOINT_INDEX, JOINTS, TOUCH_SENSORS, joint_indices
from ..motions import BLEND_MS
from ..mtn import MotionPlayer, read_mtn
from ..placement import ball_start_problem, place_match
from ..render import Renderer
from ..robot import short_repr
from ..sim import (
    ACCEL_RANGE,
    FRAME_MS,
    Simulation,
    models_dir,
    placement_values,
)
from ..team import PLAYERS_PER_TEAM, TEAMS, RobotSpec, check_robots
from .base import HEAD_JOINTS, LAYERS, LEG_JOINTS, RENDER_SIZE, AiboEnv, check_open, check_options

MAX_CYCLES = 900  # steps (camera frames at 30 fps): 30 s of play
BALL_PROGRESS_REWARD = 10.0  # per metre the ball moves towards the opposing goal, as ReachBall's progress
FALL_PENALTY = 1.0
KICKOFF_BALL = (0.0, 0.0)  # the centre spot
ATTACKS = {"red": 1.0, "blue": -1.0}  # the sign of the X axis each team attacks along (field.py: red defends -X)
# The third-person view of render(): the whole field from above its -Y side line.
FIELD_VIEW = {"lookat": (0.0, -0.1, 0.0), "distance": 4.9, "azimuth": 90.0, "elevation": -52.0}


def agent_name(spec: RobotSpec) -> str:
    """``red_2``: the agent of the robot ``spec``."""
    return f"{spec.team}_{spec.number}"


def match_robots(robots=None) -> tuple[RobotSpec, ...]:
    """The robots of a match, each pose resolved: ``None`` for 4 against 4 at the kickoff poses, a robots
    file (``team.load_robots``) or a sequence of ``RobotSpec``; every robot needs a team
    (``team.TeamError``, a ValueError of one line, otherwise)."""
    if robots is None:
        robots = [RobotSpec(team, number) for team in TEAMS for number in range(1, PLAYERS_PER_TEAM + 1)]
    robots = check_robots(robots, "robots")
    if any(robot.team is None for robot in robots):
        raise ValueError("robots: every robot of a match needs a team (red or blue)")
    return robots


class _Agent:
    """One robot of the match as a single-robot environment sees its own: the observation and
    the action mapping are ``AiboEnv``'s methods, borrowed, on this robot's ``sim`` (its view of
    the world: camera, sensors, servos)."""

    _observation = AiboEnv._observation
    _camera_image = AiboEnv._camera_image
    action_to_targets = AiboEnv.action_to_targets
    targets_to_action = AiboEnv.targets_to_action
    _per_joint = AiboEnv._per_joint
    image_position = AiboEnv.image_position

    def __init__(self, env: MatchEnv, sim: Simulation):
        self.sim, self.spec = sim, sim.spec
        self.camera, self.camera_layer, self.image_only = env.camera, env.camera_layer, env.image_only
        self.camera_message: openr_bridge.OFbkImageVectorData | None = None
        self._openr = OpenRCamera(sim) if env.camera == "openr" else None
        self.actuated_joints = env.actuated_joints
        self._actuated = np.array([JOINT_INDEX[name] for name in self.actuated_joints])
        self._target_low, target_high = sim.model.actuator_ctrlrange[sim.servos.ctrl][self._actuated].T
        self._target_span = target_high - self._target_low
        self.action_space = gym.spaces.Box(-1.0, 1.0, (len(self._actuated),), np.float32)
        spaces = {
            "joint_positions": gym.spaces.Box(-np.pi, np.pi, (len(JOINTS),), np.float32),
            "acceleration": gym.spaces.Box(-ACCEL_RANGE, ACCEL_RANGE, (3,), np.float32),
            "distance_mm": gym.spaces.Box(0.0, np.array([s.range_mm[1] for s in DISTANCE_SENSORS], np.float32)),
            "touch": gym.spaces.MultiBinary(len(TOUCH_SENSORS)),
        }
        if self.camera is not None:
            width, height = openr_bridge.LAYER_SIZE[LAYERS[self.camera_layer]]
            spaces["image"] = gym.spaces.Box(0, 255, (height, width, 3), np.uint8)
        self._image_shape = spaces["image"].shape if self.camera is not None else None
        self.observation_space = spaces["image"] if self.image_only else gym.spaces.Dict(spaces)
        self._distance_high = spaces["distance_mm"].high.tolist()

    def act(self, targets) -> None:
        """Give the servos ``targets`` (from ``action_to_targets``, which checks the action)."""
        self.sim.servos.set_target(self._actuated, targets)


# state()'s bounds, far beyond a field's (6.4 x 4.4 m) and a kicked ball's speed (1-2 m/s): finite,
# as PettingZoo's state_test asks, and never reached on a field.
STATE_DISTANCE_LIMIT, STATE_SPEED_LIMIT = 100.0, 20.0  # m, m/s on each axis


def _state_space(robots: int) -> gym.spaces.Box:
    """``state()``'s space: positions within STATE_DISTANCE_LIMIT, the ball's velocity within
    STATE_SPEED_LIMIT, yaw within +-pi, tilt within 0..pi."""
    robot = [STATE_DISTANCE_LIMIT] * 3 + [np.pi, np.pi]  # x, y, z, yaw, tilt
    high = np.array([STATE_DISTANCE_LIMIT] * 3 + [STATE_SPEED_LIMIT] * 3 + robot * robots, np.float32)
    low = -high
    low[10::5] = 0.0  # the tilts
    return gym.spaces.Box(low, high, dtype=np.float32)


class MatchEnv(pettingzoo.ParallelEnv):
    """``aibo_sim_match_v0``: red against blue on the RoboCup 2005 field, every robot an agent.

    ## Description

    A PettingZoo ``ParallelEnv``: all agents act at once, each step. Each robot observes
    through its own head camera and sensors and acts on its own 15 joints as ``ReachBall``'s
    robot does; the world (physics, ball, time) is shared, and the cameras see the other robots
    whole, with their team's uniform patches. A team is rewarded for moving the ball towards the
    goal it attacks. One step is one frame of the head cameras at 30 fps (4 or 5 joint frames of
    8 ms). ``pettingzoo.test.parallel_api_test`` passes.

    ## Agents

    One per robot that ``scripted`` does not drive, named ``{team}_{number}`` in the order of
    ``robots``: by default ``red_1`` .. ``red_4``, ``blue_1`` .. ``blue_4`` (1 the goalkeeper),
    at the kickoff poses (``team.kickoff_pose``): red in the -X half attacking +X (the sky-blue
    goal), blue the mirror image. ``possible_agents`` lists them; ``agents`` those still playing.

    ## Action Space

    Per agent (``action_space(agent)``) a ``Box(-1, 1, (15,), float32)``, as ``ReachBall``'s:
    each number mapped affinely onto the joint's range (-1 the lower limit, 1 the upper) and
    given to that robot's servos as its target. ``j1`` swings a leg forwards and backwards,
    ``j2`` lifts it sideways, ``j3`` is the knee.

    | Num   | Joints                                          | Min | Max | Target ranges, deg                 |
    |-------|-------------------------------------------------|-----|-----|------------------------------------|
    | 0-2   | left front leg ``lf_j1``, ``lf_j2``, ``lf_j3``  | -1  | 1   | -120 .. 135, -15 .. 93, -30 .. 127 |
    | 3-5   | left hind leg ``lh_j1``, ``lh_j2``, ``lh_j3``   | -1  | 1   | -135 .. 120, -15 .. 93, -30 .. 127 |
    | 6-8   | right front leg ``rf_j1``, ``rf_j2``, ``rf_j3`` | -1  | 1   | -120 .. 135, -15 .. 93, -30 .. 127 |
    | 9-11  | right hind leg ``rh_j1``, ``rh_j2``, ``rh_j3``  | -1  | 1   | -135 .. 120, -15 .. 93, -30 .. 127 |
    | 12-14 | ``neck_tilt``, ``head_pan``, ``head_tilt``      | -1  | 1   | -80 .. 3, -93 .. 93, -20 .. 50     |

    The targets go to the servos in rad (``ReachBallEnv``'s table lists them in rad). A live
    agent left out of ``actions`` holds its targets; NaN or infinity raises ValueError.

    ## Observation Space

    Per agent (``observation_space(agent)``) a ``Dict``, that of the single-robot environments
    (``AiboEnv``: the image by camera mode, the keys' details), from the agent's own robot:

    | Key                 | Shape         | Dtype   | Range               | Observation                             |
    |---------------------|---------------|---------|---------------------|-----------------------------------------|
    | ``image``           | (160, 208, 3) | uint8   | 0 .. 255            | its head camera at layer H (below)      |
    | ``joint_positions`` | (20,)         | float32 | -pi .. pi           | rad, every joint, ``ers7.JOINTS`` order |
    | ``acceleration``    | (3,)          | float32 | -19.61 .. 19.61     | m/s^2, body frame, clipped to +-2 g     |
    | ``distance_mm``     | (3,)          | float32 | 0 .. 500, 1500, 900 | mm: IR head near, head far, chest       |
    | ``touch``           | (9,)          | int8    | 0 or 1              | pressed, ``ers7.TOUCH_SENSORS`` order   |

    ``image`` is (80, 104, 3) at ``camera_layer="M"``, (40, 52, 3) at ``"L"``; absent with
    ``camera=None``; ``image_only=True`` makes it the whole observation. ``state()`` (for
    centralised critics, ``state_space``: a float32 ``Box`` of shape (6 + 5 * robots,), bounded
    where a field never reaches: ``_state_space``): the ball's position (m) and velocity (m/s),
    then each robot's body x, y, z (m), yaw and tilt (rad), in the order of ``robots``; zeros
    for the ball in a scene without one.

    ## Rewards

    Each step, every live agent of a team gets ``BALL_PROGRESS_REWARD`` (10) times the ball's
    progress towards the goal its team attacks, in metres along X since the previous step
    (red: +X, blue: -X; the two teams' rewards are opposite), minus ``FALL_PENALTY`` (1) on
    the step it falls.

    ## Starting State

    ``reset`` puts every robot in the keyframe ``stand``'s posture at its pose (``robots``'
    poses; the kickoff poses by default), its servo targets the keyframe's, and the ball at
    rest on the centre spot (``KICKOFF_BALL``), moved by up to r m in each horizontal
    direction with ``randomize={"ball_start": r}`` (drawn again where ``run`` would refuse that
    ball: ``placement.ball_start_problem``); ``reset(options={"ball": (x, y)})`` puts it at
    (x, y) instead. The same seed gives the same match, bit for bit.

    ## Episode End

    | Condition  | Agents | When                                                     |
    |------------|--------|----------------------------------------------------------|
    | terminated | one    | its robot fell (body over 60 degrees from upright)       |
    | truncated  | all    | ``max_cycles`` steps (default ``MAX_CYCLES``, 900: 30 s) |

    A terminated or truncated agent leaves ``agents``; a fallen robot then holds its targets.
    ``step`` with no agent left raises ``ResetNeeded``.

    ## Info

    Per agent: ``team``, ``number``, ``position`` (body centre, m), ``yaw`` (rad, about +Z from
    +X), ``tilt`` (rad from upright), ``fallen``, ``ball_position`` (m; None without a ball).

    ## Arguments

    | Argument           | Default    | Meaning                                                               |
    |--------------------|------------|-----------------------------------------------------------------------|
    | ``robots``         | ``None``   | the robots: ``None`` for 4 against 4, a robots file or ``RobotSpec``s |
    | ``camera``         | ``"rgb"``  | as ``AiboEnv``'s: ``"rgb"``, ``"ycrcb"``, ``"openr"`` or ``None``     |
    | ``camera_layer``   | ``"H"``    | as ``AiboEnv``'s: ``"H"``, ``"M"`` or ``"L"``                         |
    | ``render_mode``    | ``None``   | ``"rgb_array"``: the whole field from above a side line, 480x360      |
    | ``randomize``      | ``None``   | as ``AiboEnv``'s (below)                                              |
    | ``max_cycles``     | ``900``    | keyword-only: steps until every agent is truncated                    |
    | ``scene``          | ``None``   | keyword-only, as ``AiboEnv``'s                                        |
    | ``camera_profile`` | ``"ers7"`` | keyword-only, as ``AiboEnv``'s                                        |
    | ``camera_wb``      | ``"fl"``   | keyword-only, as ``AiboEnv``'s                                        |
    | ``camera_gain``    | ``"mid"``  | keyword-only, as ``AiboEnv``'s                                        |
    | ``camera_shutter`` | ``"mid"``  | keyword-only, as ``AiboEnv``'s                                        |
    | ``image_only``     | ``False``  | keyword-only, as ``AiboEnv``'s                                        |
    | ``scripted``       | ``None``   | keyword-only: robot name to a factory of a scripted policy (below)    |

    ``robots``: a sequence of ``team.RobotSpec`` (a pose of None is the kickoff pose) or a
    robots file (``team.load_robots``); every robot needs a team. The robots' ``controller``
    entries (of a robots file) are not run: agents and scripts drive the robots.
    ``randomize``: ``lighting``, ``ball_start`` (around the centre spot) and ``camera_robot``
    (one colour deviation drawn per robot; without it, each camera profile's own ``robot``).
    ``scripted``: robot name -> a factory called with
    that robot's ``Simulation`` view that returns a scripted policy (``BallChaser`` for one;
    ``scripted_team`` makes a whole set): those robots are no agents; before each step
    ``policy.plan(frames)`` gives their joint targets for each 8 ms frame of it (and
    ``policy.reset()`` starts it again at each ``reset``); a scripted robot that falls holds its
    targets from then on. A bad argument raises ValueError (or ``team.TeamError``, a ValueError,
    for bad robots) naming it.
    """

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": openr_bridge.FRAME_RATE_HZ,
        "name": "aibo_sim_match_v0",
        "is_parallelizable": True,
    }
    actuated_joints: tuple[str, ...] = LEG_JOINTS + HEAD_JOINTS

    def __init__(
        self,
        robots=None,
        camera: str | None = "rgb",
        camera_layer: str = "H",
        render_mode: str | None = None,
        randomize: dict[str, float] | None = None,
        *,
        max_cycles: int = MAX_CYCLES,
        scene=None,
        camera_profile: str = "ers7",
        camera_wb: str = "fl",
        camera_gain: str = "mid",
        camera_shutter: str = "mid",
        image_only: bool = False,
        scripted: Mapping[str, Callable[[Simulation], object]] | None = None,
    ):
        self.randomize = check_options(camera, camera_layer, render_mode, randomize, image_only)
        if isinstance(max_cycles, bool) or not isinstance(max_cycles, numbers.Integral) or max_cycles < 1:
            raise ValueError(f"max_cycles must be a whole number >= 1, not {max_cycles!r}")
        self.camera, self.camera_layer, self.render_mode, self.image_only = (
            camera,
            camera_layer,
            render_mode,
            image_only,
        )
        self.max_cycles = int(max_cycles)
        specs = match_robots(robots)
        names = [agent_name(spec) for spec in specs]
        if scripted is not None and not isinstance(scripted, Mapping):
            raise TypeError(f"scripted must be a dict of robot name to factory, not {short_repr(scripted)}")
        scripted = dict(scripted or {})
        unknown = [name for name in scripted if name not in names]
        if unknown:
            raise ValueError(f"scripted: no robot {unknown[0]!r} in this match (robots: {', '.join(names)})")
        for name, make in scripted.items():
            if not callable(make):
                raise TypeError(
                    f"scripted[{name!r}] is {short_repr(make)}, not a factory called with the robot's "
                    "Simulation (such as BallChaser)"
                )
        self.sim = Simulation(
            scene,
            robots=specs,
            camera=CameraConfig(camera_profile, settings=CameraSettings(camera_wb, camera_gain, camera_shutter)),
        )
        try:
            place_match(self.sim)  # no robot inside another, a wall or a goal, as run and dump refuse
        except BaseException:
            self.sim.close()
            raise
        self._kickoff = copy.copy(self.sim.data)  # where a ball's start is checked (ball_start_problem)
        overlap = ball_start_problem(self.sim, KICKOFF_BALL, self._kickoff) if self.sim.has_ball else None
        if overlap is not None:  # the ball's start when not randomised, and the randomised one's fallback
            self.sim.close()
            raise ValueError(f"the ball on the centre spot {overlap}: place the robots elsewhere")
        self._closed = False
        self.robots: dict[str, Simulation] = dict(zip(names, self.sim.world.robots))  # every robot, by name
        self.possible_agents = [name for name in names if name not in scripted]
        self.agents: list[str] = []
        self._agents = {name: _Agent(self, self.robots[name]) for name in self.possible_agents}
        self.observation_spaces = {name: agent.observation_space for name, agent in self._agents.items()}
        self.action_spaces = {name: agent.action_space for name, agent in self._agents.items()}
        self._scripts = {name: make(self.robots[name]) for name, make in scripted.items()}
        for name, script in self._scripts.items():
            if not (callable(getattr(script, "plan", None)) and callable(getattr(script, "reset", None))):
                self.sim.close()
                raise TypeError(
                    f"scripted[{name!r}] made {short_repr(script)}, not a scripted policy (with plan and reset, "
                    "as BallChaser)"
                )
        model = self.sim.model
        self.state_space = _state_space(len(names))
        self._nominal_lights = (
            model.light_diffuse.copy(),
            model.vis.headlight.diffuse.copy(),
            model.vis.headlight.ambient.copy(),
        )
        self.camera_robot = RobotColour()  # robot 1's camera colour deviation this episode
        self.camera_robots = dict.fromkeys(names, self.camera_robot)  # every robot's
        self.np_random: np.random.Generator | None = None
        self.np_random_seed: int | None = None
        self._renderer: Renderer | None = None
        self._cycles = 0
        self._ball_x = 0.0
        self._down: set[str] = set()  # scripted robots that fell: they hold their targets

    # ---------------------------------------------------------------- PettingZoo API

    def observation_space(self, agent: str) -> gym.Space:
        """``agent``'s observation space (the class docstring's table); ValueError for no agent."""
        return self._space(self.observation_spaces, agent)

    def action_space(self, agent: str) -> gym.Space:
        """``agent``'s action space, ``Box(-1, 1, (15,), float32)``; ValueError for no agent."""
        return self._space(self.action_spaces, agent)

    def _space(self, spaces: dict, agent: str) -> gym.Space:
        try:
            return spaces[agent]
        except (KeyError, TypeError):
            raise ValueError(f"no agent {agent!r} (agents: {', '.join(self.possible_agents)})") from None

    def ball_option(self, options: dict | None) -> tuple[float, float] | None:
        """``reset``'s ``options={"ball": (x, y)}``, checked: ValueError for a ball that is not two
        numbers, or that would start off the field or inside a wall, a goal or a robot;
        ClosedEnvironmentError after ``close``."""
        check_open(self, "reset")
        if options is not None and not isinstance(options, Mapping):
            raise TypeError(f'reset options must be a dict (such as {{"ball": (x, y)}}), not {short_repr(options)}')
        ball = (options or {}).get("ball")
        if ball is None:
            return None
        what = 'reset(options={"ball": (x, y)})'
        if isinstance(ball, (str, bytes, Mapping)) or not hasattr(ball, "__len__") or len(ball) != 2:
            raise ValueError(f"{what}: want two numbers (m), not {ball!r}")
        if not self.sim.has_ball:  # as run refuses --ball there (it was dropped without a word)
            raise ValueError(f"{what}: this scene has no body named 'ball' to place")
        ball = placement_values(what, x=ball[0], y=ball[1])
        problem = ball_start_problem(self.sim, ball, self._kickoff)
        if problem is not None:
            raise ValueError(f"{what}: the ball at {ball[0]:g}, {ball[1]:g} {problem}")
        return ball

    def reset(self, seed: int | None = None, options: dict | None = None):
        """Start a match: every robot at its pose in the keyframe's posture, the ball placed, the
        randomisations drawn, every possible agent playing again.

        :param seed: seeds the match's RNG (the noise streams, the randomisations); ``None`` goes
            on with the current one (seeded from the OS the first time).
        :param options: ``{"ball": (x, y)}`` puts the ball there (m, at rest) instead of on the
            centre spot.
        :returns: ``(observations, infos)``, dicts by agent.
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        ball = self.ball_option(options)  # checked before anything changes: a refused reset leaves the match as it was
        if seed is not None or self.np_random is None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        self.sim.reset(seed=int(self.np_random.integers(2**63)))
        self._randomize_scene()
        if self.sim.has_ball:
            self.sim.place_ball(*(self.drawn_ball_start(KICKOFF_BALL, state=self._kickoff) if ball is None else ball))
        mujoco.mj_forward(self.sim.model, self.sim.data)
        self._ball_x = self._ball_progress_x()
        for script in self._scripts.values():
            script.reset()
        self._down.clear()
        self._cycles = 0
        self.agents = list(self.possible_agents)
        self._make_frames()
        return (
            {name: self._agents[name]._observation() for name in self.agents},
            {name: self._info(name) for name in self.agents},
        )

    def step(self, actions: Mapping[str, object]):
        """Give each agent's action to its robot's servos (an agent left out holds its targets),
        run the scripts and the joint frames up to the cameras' next frame.

        :param actions: agent name to action, for live agents only.
        :returns: ``(observations, rewards, terminations, truncations, infos)``, dicts by the
            agents live before the step; the ones terminated or truncated then leave ``agents``.
        :raises ValueError: an action for a robot that is no live agent, or a bad action.
        :raises TypeError: ``actions`` not a dict, or an action of the wrong type.
        :raises gymnasium.error.ResetNeeded: no agent left (before ``reset``, or all done).
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        check_open(self, "step")
        if not self.agents:
            raise gym.error.ResetNeeded(
                f"{type(self).__name__}.step with no agent left (before reset, or every agent done): reset first"
            )
        if not isinstance(actions, Mapping):
            raise TypeError(f"actions must be a dict of agent name to action, not {type(actions).__name__}")
        extra = [name for name in actions if name not in self.agents]
        if extra:
            why = "is done" if extra[0] in self.possible_agents else "is no agent"
            raise ValueError(f"action for {extra[0]!r}, which {why} (agents: {', '.join(self.agents)})")
        targets = {}
        for name, action in actions.items():
            try:
                targets[name] = self._agents[name].action_to_targets(action)
            except (TypeError, ValueError) as exc:
                raise type(exc)(f"{name}'s {exc}") from None
        for name, joint_targets in targets.items():  # every action checked before any is given
            self._agents[name].act(joint_targets)
        self._advance(self.sim.frames_to_camera_frame())
        self._cycles += 1

        ball_x = self._ball_progress_x()
        progress, self._ball_x = ball_x - self._ball_x, ball_x
        truncated = self._cycles >= self.max_cycles
        observations, rewards, terminations, truncations, infos = {}, {}, {}, {}, {}
        self._make_frames()
        for name in self.agents:
            agent = self._agents[name]
            fallen = agent.sim.fallen()
            observations[name] = agent._observation()
            rewards[name] = ATTACKS[agent.spec.team] * BALL_PROGRESS_REWARD * progress - (
                FALL_PENALTY if fallen else 0.0
            )
            terminations[name], truncations[name] = fallen, truncated
            infos[name] = self._info(name)
        self._down.update(name for name in self._scripts if self.robots[name].fallen())
        self.agents = [name for name in self.agents if not (terminations[name] or truncations[name])]
        return observations, rewards, terminations, truncations, infos

    def _make_frames(self) -> None:
        """The live agents' camera frames, made together (in parallel: ``World.frames``)."""
        if self.camera is not None:
            self.sim.world.frames(self._agents[name].sim.camera for name in self.agents)

    def state(self) -> np.ndarray:
        """The ball (position, m, and velocity, m/s) and every robot's body (x, y, z, yaw, tilt), in
        the order of ``robots``; float32, zeros for the ball in a scene without one; within
        ``state_space`` (see ``_state_space``)."""
        check_open(self, "state")
        values = [0.0] * 6
        if self.sim.has_ball:
            position, velocity = self.sim.ball_state()
            values = [*position[:3], *velocity[:3]]
        for robot in self.robots.values():
            position, yaw, tilt = robot.body_pose()
            values += [*position, yaw, tilt]
        space = self.state_space
        return np.clip(np.array(values, np.float32), space.low, space.high)

    def render(self):
        """The whole field from above its -Y side line, a (360, 480, 3) uint8 RGB array, with
        ``render_mode="rgb_array"``; ``None`` otherwise (ClosedEnvironmentError after ``close``)."""
        check_open(self, "render")
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            self._renderer = Renderer(self.sim.model, *RENDER_SIZE, quality="high")
            self._view = mujoco.MjvCamera()
            self._view.type = mujoco.mjtCamera.mjCAMERA_FREE
            for key, value in FIELD_VIEW.items():
                setattr(self._view, key, value)
        return self._renderer.render(self.sim.data, self._view)

    def close(self):
        """Free the renderers; then ``reset``, ``step``, ``render`` and ``state`` raise
        ``gymnasium.error.ClosedEnvironmentError``. Closing again does nothing."""
        AiboEnv.close(self)
        self.robots = {}

    __reduce_ex__ = AiboEnv.__reduce_ex__  # a MuJoCo simulation and OpenGL renderers: no pickling

    # ---------------------------------------------------------------- per agent

    def robot(self, name: str) -> Simulation:
        """The ``Simulation`` view of robot ``name`` (an agent or a scripted robot)."""
        check_open(self, "robot")
        if not isinstance(name, str) or name not in self.robots:
            raise ValueError(f"no robot {name!r} (robots: {', '.join(self.robots)})")
        return self.robots[name]

    def action_to_targets(self, agent: str, action) -> np.ndarray:
        """Joint targets (rad) of ``agent``'s actuated joints for a normalised action."""
        self.action_space(agent)  # ValueError for an unknown agent
        return self._agents[agent].action_to_targets(action)

    def targets_to_action(self, agent: str, targets) -> np.ndarray:
        """The normalised action of ``agent`` that commands ``targets`` (rad)."""
        self.action_space(agent)
        return self._agents[agent].targets_to_action(targets)

    def image_position(self, agent: str, point) -> tuple[np.ndarray, bool]:
        """Where a world point lies in ``agent``'s current camera frame (``AiboEnv.image_position``)."""
        self.action_space(agent)
        return self._agents[agent].image_position(point)

    # ---------------------------------------------------------------- internals

    ball_start = AiboEnv.ball_start  # the ``ball_start`` randomisation about a nominal spot
    drawn_ball_start = AiboEnv.drawn_ball_start  # ... drawn again where the ball cannot start

    def _randomize_scene(self) -> None:
        AiboEnv._randomize_scene(self)  # the lights, and robot 1's camera colour deviation
        spread = self.randomize.get("camera_robot", 0.0)
        for name, robot in self.robots.items():
            colour = self.camera_robot
            if robot is not self.sim:
                colour = RobotColour.draw(self.np_random, spread) if spread else robot.camera.profile.robot
                robot.camera.set_robot(colour)
            self.camera_robots[name] = colour

    def _advance(self, frames: int) -> None:
        """Run the joint frames of one step: at once, or frame by frame while scripts command
        their robots' servos every 8 ms frame (the same trajectory for the agents' robots)."""
        plans = [
            (self.robots[name].servos, script.plan(frames))
            for name, script in self._scripts.items()
            if name not in self._down
        ]
        if not plans:
            self.sim.step_frames(frames)
            return
        for k in range(frames):
            for servos, plan in plans:
                servos.set_target(slice(None), plan[k])
            self.sim.step_frames(1, sensors=k == frames - 1)

    def _ball_progress_x(self) -> float:
        return float(self.sim.ball_position()[0]) if self.sim.has_ball else 0.0

    def _info(self, name: str) -> dict:
        robot = self.robots[name]
        position, yaw, tilt = robot.body_pose()
        return {
            "team": robot.spec.team,
            "number": robot.spec.number,
            "position": position,
            "yaw": yaw,
            "tilt": tilt,
            "fallen": robot.fallen(),
            "ball_position": self.sim.ball_position(),
        }


# ----------------------------------------------------------------------------- scripted robots

GAITS = {"walk": "WALKFWD.MTN", "left": "TURNL.MTN", "right": "TURNR.MTN"}  # in models/motions
TURN_BEARING = 0.35  # rad: turn instead of walking when the ball lies further aside (walk_to_ball's TURN_PAN)
TRACK_GAIN = 0.6  # controllers/ball_tracker.py: the fraction of the ball's angular offset corrected a step
HEAD_TILT_LOW = -0.26  # rad, ball_tracker.py: below this the neck tilts instead of the head


@functools.cache
def gait_frames(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Joint indices (``ers7.JOINTS``) and targets (rad, one row per 8 ms frame) of one period of
    a bundled gait file, as OPEN-R plays it in a loop (the closing keyframe, the first again,
    left out). Read-only arrays, shared."""
    motion = read_mtn(models_dir() / "motions" / name)
    player = MotionPlayer(motion, "openr")
    frames = np.array([player.frame(i) for i in range(player.num_frames - 1)]) / 1e6
    columns = np.array(joint_indices(motion.locators))
    frames.flags.writeable = columns.flags.writeable = False
    return columns, frames


class BallChaser:
    """A scripted robot: the head tracks the ball, the legs turn towards it and walk at it.

    Deterministic and without vision: it reads the ball's and its body's true pose. The head
    follows ``controllers/ball_tracker.py`` (each step pan and tilt move by ``TRACK_GAIN`` of
    the ball's angular offset from the camera's axis, the neck taking over below
    ``HEAD_TILT_LOW``). The legs play the bundled gaits (``models/motions``: WALKFWD, TURNL,
    TURNR) frame by frame as OPEN-R plays an MTN, choosing one whole 320 ms period at a time
    as ``controllers/walk_to_ball.py`` does: a turn while the ball lies more than
    ``TURN_BEARING`` aside, else a walk period (with ``walk=False``, the goalkeeper's way, it
    stands in the gait's stance instead). From the standing keyframe the legs first blend into
    the gait over ``motions.BLEND_MS``. A walk into the ball pushes it ahead.
    """

    def __init__(self, robot: Simulation, walk: bool = True):
        self.robot, self.walk = robot, walk
        self._head = [JOINT_INDEX[name] for name in ("neck_tilt", "head_pan", "head_tilt")]
        self._legs = gait_frames(GAITS["walk"])[0]
        self.reset()

    def reset(self) -> None:
        """Start again from standing: the next ``plan`` blends the legs into a gait."""
        self.motion: str | None = None  # the gait now playing (None: standing in its stance)
        self._path = np.empty((0, len(self._legs)))  # leg targets of the frames to come
        self._at = 0
        self._started = False

    def plan(self, frames: int) -> np.ndarray:
        """Joint targets (rad, ``ers7.JOINTS`` order) for each of the next ``frames`` 8 ms frames."""
        robot = self.robot
        targets = np.tile(robot.servos.target, (frames, 1))
        targets[:, self._head] = self._head_targets()
        for k in range(frames):
            if self._at == len(self._path):
                self._next_period()
            targets[k, self._legs] = self._path[self._at]
            self._at += 1
        return targets

    def _ball(self) -> tuple[float, float] | None:
        """The ball's bearing (rad, + to the left of the body's heading) and horizontal distance (m)."""
        ball = self.robot.ball_position()
        if ball is None:
            return None
        position, yaw, _ = self.robot.body_pose()
        dx, dy = ball[0] - position[0], ball[1] - position[1]
        return math.remainder(math.atan2(dy, dx) - yaw, 2 * math.pi), math.hypot(dx, dy)

    def _next_period(self) -> None:
        ball = self._ball()
        if ball is None:
            gait = None
        elif ball[0] > TURN_BEARING:
            gait = "left"
        elif ball[0] < -TURN_BEARING:
            gait = "right"
        else:
            gait = "walk" if self.walk else None
        _, frames = gait_frames(GAITS[gait or "walk"])
        path = frames if gait is not None else np.repeat(frames[:1], len(frames), axis=0)
        if not self._started:  # from the standing keyframe: blend in, as play_motion does
            self._started = True
            start = self.robot.servos.command[self._legs]
            n = BLEND_MS // FRAME_MS
            ease = (1 - np.cos(np.pi * np.arange(1, n + 1) / n))[:, None] / 2
            path = np.concatenate((start + ease * (path[0] - start), path))
        self.motion, self._path, self._at = gait, path, 0

    def _head_targets(self) -> np.ndarray:
        robot = self.robot
        neck, pan, tilt = robot.joint_positions()[self._head]
        ball = robot.ball_position()
        if ball is None:
            return np.array([neck, pan, tilt])
        camera = robot.camera.camera_id
        # The ball in the camera's axes (MuJoCo's: x right, y up, z backwards).
        x, y, z = robot.data.cam_xmat[camera].reshape(3, 3).T @ (ball - robot.data.cam_xpos[camera])
        left, up = math.atan2(-x, -z), math.atan2(y, math.hypot(x, z))
        pan, tilt = pan + TRACK_GAIN * left, tilt + TRACK_GAIN * up
        if tilt < HEAD_TILT_LOW:
            neck, tilt = neck + tilt - HEAD_TILT_LOW, HEAD_TILT_LOW
        return np.array([neck, pan, tilt])


def scripted_team(robots, learner: str) -> dict[str, Callable[[Simulation], BallChaser]]:
    """``MatchEnv``'s ``scripted`` for every robot of ``robots`` (``match_robots``) but ``learner``:
    ``BallChaser``s, the goalkeepers (number 1) turning on the spot without walking."""
    return {
        agent_name(spec): functools.partial(BallChaser, walk=spec.number != 1)
        for spec in robots
        if agent_name(spec) != learner
    }


class ScriptedOpponentsEnv(gym.Env):
    """``aibo_sim/MatchVsScripted-v0``: one robot of a match learns, every other robot is a
    scripted ``BallChaser``.

    ## Description

    The Gymnasium view of one robot, the ``learner``, of a ``MatchEnv`` (``self.match``): the
    other robots, teammates and opponents, are scripted ``BallChaser``s (``scripted_team``):
    they track the ball with the head and walk at it, the goalkeepers (number 1) turning on the
    spot without walking. Only the learner's camera is rendered. ``check_env`` passes.

    ## Action Space

    ``Box(-1, 1, (15,), float32)``: targets for the learner's 12 leg joints, then the 3 head
    joints, as ``ReachBallEnv``'s (whose table gives each joint's range):

    | Num   | Joints                                         | Min | Max | Unit of the target |
    |-------|------------------------------------------------|-----|-----|--------------------|
    | 0-11  | ``lf_j1`` .. ``lf_j3``, ``lh_j1`` .. ``rh_j3`` | -1  | 1   | rad                |
    | 12-14 | ``neck_tilt``, ``head_pan``, ``head_tilt``     | -1  | 1   | rad                |

    ## Observation Space

    The learner's in ``MatchEnv``: ``AiboEnv``'s ``Dict``:

    | Key                 | Shape         | Dtype   | Range               | Observation                             |
    |---------------------|---------------|---------|---------------------|-----------------------------------------|
    | ``image``           | (160, 208, 3) | uint8   | 0 .. 255            | its head camera at layer H (below)      |
    | ``joint_positions`` | (20,)         | float32 | -pi .. pi           | rad, every joint, ``ers7.JOINTS`` order |
    | ``acceleration``    | (3,)          | float32 | -19.61 .. 19.61     | m/s^2, body frame, clipped to +-2 g     |
    | ``distance_mm``     | (3,)          | float32 | 0 .. 500, 1500, 900 | mm: IR head near, head far, chest       |
    | ``touch``           | (9,)          | int8    | 0 or 1              | pressed, ``ers7.TOUCH_SENSORS`` order   |

    ``image`` is (80, 104, 3) at ``camera_layer="M"``, (40, 52, 3) at ``"L"``; absent with
    ``camera=None``; ``image_only=True`` makes it the whole observation.

    ## Rewards

    ``MatchEnv``'s for the learner: ``BALL_PROGRESS_REWARD`` (10) times the ball's progress (m
    along X since the previous step) towards the goal the learner's team attacks (red: +X,
    blue: -X), minus ``FALL_PENALTY`` (1) on the step the learner falls.

    ## Starting State

    ``MatchEnv``'s: every robot at its pose (the kickoff poses by default; the learner
    ``red_4`` just outside the centre circle, facing +X) in the keyframe ``stand``'s posture,
    the ball at rest on the centre spot (``randomize={"ball_start": r}`` moves it by up to r m
    in each horizontal direction; ``reset(options={"ball": (x, y)})`` puts it at (x, y)).

    ## Episode End

    - Termination: the learner fell (its body over 60 degrees from upright).
    - Truncation: after ``max_cycles`` steps (900, 30 s), and after 900 steps by the
      ``TimeLimit`` of ``gymnasium.make`` (``max_episode_steps`` of ``aibo_sim.envs.ENV_SPECS``):
      give ``gymnasium.make`` ``max_episode_steps`` too for longer episodes.

    ## Info

    ``MatchEnv``'s for the learner: ``team``, ``number``, ``position`` (body centre, m),
    ``yaw`` (rad), ``tilt`` (rad from upright), ``fallen``, ``ball_position`` (m).

    ## Arguments

    | Argument        | Default     | Meaning                                                             |
    |-----------------|-------------|---------------------------------------------------------------------|
    | ``learner``     | ``"red_4"`` | the learning robot, ``{team}_{number}`` (default red's striker)     |
    | ``robots``      | ``None``    | the match, as ``MatchEnv``'s (default 4 against 4 at kickoff poses) |
    | ``render_mode`` | ``None``    | ``"rgb_array"``: ``MatchEnv``'s view of the whole field             |
    | ``**options``   |             | ``MatchEnv``'s other keyword arguments but ``scripted``             |

    ``options``: ``camera``, ``camera_layer``, ``randomize``, ``max_cycles``, ``scene``,
    ``camera_profile``, ``camera_wb``, ``camera_gain``, ``camera_shutter``, ``image_only``. A
    ``learner`` that is no robot of the match raises ValueError.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": openr_bridge.FRAME_RATE_HZ}

    def __init__(self, learner: str = "red_4", robots=None, render_mode: str | None = None, **options):
        specs = match_robots(robots)
        names = [agent_name(spec) for spec in specs]
        if learner not in names:
            raise ValueError(f"learner {learner!r} is not a robot of this match (robots: {', '.join(names)})")
        self.learner, self.render_mode = learner, render_mode
        self.match = MatchEnv(specs, render_mode=render_mode, scripted=scripted_team(specs, learner), **options)
        self.observation_space = self.match.observation_space(learner)
        self.action_space = self.match.action_space(learner)

    @property
    def sim(self) -> Simulation:
        """The learner's robot."""
        return self.match.robot(self.learner)

    @property
    def camera_layer(self) -> str:
        """The learner's camera layer (``MatchEnv``'s)."""
        return self.match.camera_layer

    def check_reset_options(self, options: dict | None) -> None:
        """The error ``reset`` raises for ``options`` (a ball it cannot place), before anything changes."""
        self.match.ball_option(options)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start a match (``MatchEnv.reset``; ``options={"ball": (x, y)}`` places the ball).

        :returns: the learner's ``(observation, info)``.
        """
        self.check_reset_options(options)  # a refused ball changes nothing, the generator included
        super().reset(seed=seed)
        observations, infos = self.match.reset(seed=int(self.np_random.integers(2**63)), options=options)
        return observations[self.learner], infos[self.learner]

    def step(self, action):
        """Step the match with the learner's ``action``, the scripted robots playing too.

        :returns: the learner's ``(observation, reward, terminated, truncated, info)``.
        :raises ValueError: a bad action.
        :raises gymnasium.error.ResetNeeded: before ``reset``, or after the episode ended.
        """
        observations, rewards, terminations, truncations, infos = self.match.step({self.learner: action})
        name = self.learner
        return observations[name], rewards[name], terminations[name], truncations[name], infos[name]

    def render(self):
        """``MatchEnv.render``: the whole field, with ``render_mode="rgb_array"``."""
        return self.match.render()

    def close(self):
        """Close the match (``MatchEnv.close``)."""
        self.match.close()

    __reduce_ex__ = AiboEnv.__reduce_ex__
