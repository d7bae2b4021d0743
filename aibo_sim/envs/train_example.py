"""Train PPO (Stable-Baselines3) on HeadTrackBall from the camera image and proprioception.

    pip install 'aibo-sim[train,plot]'
    python -m aibo_sim.envs.train_example [--steps 150000] [--plot learning_curve.png]

Trains on 2 environments in worker processes, saves the policy, then measures the trained
policy, a random one and one holding the head still (where each episode starts it) on the same
evaluation episodes (the same seeds, hence the same ball paths): mean episode reward, where an
episode is 300 steps (10 s) and a step earns ``1 - max(|x|, |y|)`` of the ball's offset from
the image centre, 0 when it is out of view. A policy that follows the ball beats the still one,
which earns while the ball passes through the view. The learning curve (episode rewards while
training, and the three policies' levels) is written as a PNG.
"""

from __future__ import annotations

import argparse
import io
import time

import gymnasium as gym
import numpy as np

from ..ers7 import JOINT_INDEX
from ..files import named_file, write_file_atomic

ENV_ID = "aibo_sim.envs:aibo_sim/HeadTrackBall-v0"  # names the module, so workers register it too
EVAL_SEED = 10_000  # evaluation episodes use seeds EVAL_SEED, EVAL_SEED + 1, ...


def evaluate(env, policy, episodes: int) -> list[float]:
    """Total reward of each of ``episodes`` episodes, seeded EVAL_SEED + k; ``policy(obs)``
    gives the action."""
    totals = []
    for k in range(episodes):
        obs, _ = env.reset(seed=EVAL_SEED + k)
        env.action_space.seed(EVAL_SEED + k)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, _ = env.step(policy(obs))
            total += float(reward)
            done = terminated or truncated
        totals.append(total)
    return totals


def hold_still(env):
    """The policy that holds the actuated joints at the targets an episode starts with (the
    keyframe's): the baseline that shows whether a policy follows the ball."""
    env.reset(seed=EVAL_SEED)
    unwrapped = env.unwrapped
    start = unwrapped.sim.servos.target[[JOINT_INDEX[name] for name in unwrapped.actuated_joints]]
    action = unwrapped.targets_to_action(start)
    return lambda obs: action


def plot_learning_curve(path: str, steps: np.ndarray, rewards: np.ndarray, levels: dict, size=(800, 480)) -> None:
    """Episode reward against training steps (points and a running mean), with the evaluation
    levels of ``levels`` (policy name: mean reward; up to three) as lines: a PNG of ``size``
    pixels drawn by matplotlib (Agg, headless), an ImportError naming
    ``pip install 'aibo-sim[plot]'`` without it."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.ticker import EngFormatter
    except ImportError:
        raise ImportError("plotting the learning curve needs matplotlib: pip install 'aibo-sim[plot]'") from None
    figure = Figure(figsize=(size[0] / 100, size[1] / 100), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.scatter(steps, rewards, s=6, color="tab:gray", label="episode")
    if len(rewards) >= 2:
        window = max(1, len(rewards) // 20)
        mean = np.convolve(rewards, np.ones(window) / window, mode="valid")
        axes.plot(steps[window - 1 :], mean, color="tab:blue", linewidth=2, label=f"running mean, {window} episodes")
    for (name, level), colour in zip(levels.items(), ("tab:red", "tab:orange", "tab:green"), strict=False):
        axes.axhline(level, color=colour, label=f"{name} policy: {level:.1f}")
    axes.set(
        xlabel="training steps",
        ylabel="episode reward (300 steps)",
        title="HeadTrackBall-v0, PPO: episode reward while training",
        ylim=(0, None),
    )
    axes.xaxis.set_major_formatter(EngFormatter())
    axes.grid(alpha=0.3)
    axes.legend(loc="lower right")
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    write_file_atomic(named_file(path), buffer.getvalue())


def at_least_one(text: str) -> int:
    """argparse type: a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return value


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description="Train PPO on aibo_sim/HeadTrackBall-v0 and compare it with a random policy and a still one."
    )
    parser.add_argument("--steps", type=at_least_one, default=150_000, help="environment steps to train for")
    parser.add_argument("--envs", type=at_least_one, default=2, help="environments stepped in parallel processes")
    parser.add_argument("--layer", default="L", choices=("H", "M", "L"), help="camera layer (L: 52x40)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=at_least_one, default=10, help="evaluation episodes for each policy")
    parser.add_argument("--save", default="head_track_ppo.zip", help="where to save the policy")
    parser.add_argument("--plot", default="learning_curve.png", help="where to write the learning curve")
    args = parser.parse_args(argv)
    try:
        import matplotlib  # noqa: F401  (checked before training: the plot comes last)
        from stable_baselines3 import PPO
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import SubprocVecEnv
    except ImportError:
        raise SystemExit(
            "this example needs stable-baselines3 and matplotlib: pip install 'aibo-sim[train,plot]'"
        ) from None

    class EpisodeRewards(BaseCallback):
        """(training step, episode reward) of each episode that ends (Monitor's ``episode`` info)."""

        def __init__(self):
            super().__init__()
            self.curve: list[tuple[int, float]] = []

        def _on_step(self) -> bool:
            self.curve += [
                (self.num_timesteps, info["episode"]["r"]) for info in self.locals["infos"] if "episode" in info
            ]
            return True

    options = {"camera_layer": args.layer}
    started = time.perf_counter()
    envs = make_vec_env(
        ENV_ID,
        n_envs=args.envs,
        seed=args.seed,
        env_kwargs=options,
        vec_env_cls=SubprocVecEnv,
        vec_env_kwargs={"start_method": "spawn"},
    )
    model = PPO("MultiInputPolicy", envs, n_steps=256, batch_size=128, gamma=0.95, seed=args.seed, verbose=0)
    episodes = EpisodeRewards()
    model.learn(total_timesteps=args.steps, callback=episodes)
    model.save(args.save)
    envs.close()
    train_s = time.perf_counter() - started

    env = gym.make(ENV_ID, **options)
    trained = evaluate(env, lambda obs: model.predict(obs, deterministic=True)[0], args.episodes)
    random = evaluate(env, lambda obs: env.action_space.sample(), args.episodes)
    still = evaluate(env, hold_still(env), args.episodes)
    env.close()
    steps, rewards = (
        (np.array(column, float) for column in zip(*episodes.curve)) if episodes.curve else (np.zeros(0), np.zeros(0))
    )
    levels = {"random": random, "holding still": still, "trained": trained}
    plot_learning_curve(args.plot, steps, rewards, {name: float(np.mean(v)) for name, v in levels.items()})
    # PPO trains whole rollouts of n_steps x envs: what it trained, not what was asked
    print(
        f"trained {model.num_timesteps} steps in {train_s / 60:.1f} min; saved {args.save}, learning curve {args.plot}"
    )
    print(
        f"mean episode reward over {args.episodes} episodes (seeds {EVAL_SEED}..{EVAL_SEED + args.episodes - 1}, "
        "300 steps, at most 300): "
        + ", ".join(f"{name} {np.mean(v):.1f} +- {np.std(v):.1f}" for name, v in reversed(levels.items()))
    )


if __name__ == "__main__":
    main()
