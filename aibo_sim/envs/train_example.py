"""Train PPO (stable-baselines3) on HeadTrackBall from the camera image and proprioception.

    pip install 'aibo-sim[train]'
    python -m aibo_sim.envs.train_example --steps 200000

Saves the policy, then prints its mean reward per step over one episode (1 = ball always
centred; a random policy scores about 0.15, a proportional controller about 0.88).
"""

from __future__ import annotations

import argparse

import gymnasium as gym

ENV_ID = "aibo_sim.envs:aibo_sim/HeadTrackBall-v0"  # names the module, so workers register it too


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Train PPO on aibo_sim/HeadTrackBall-v0.")
    parser.add_argument("--steps", type=int, default=200_000, help="environment steps to train for")
    parser.add_argument("--envs", type=int, default=2, help="environments stepped in parallel processes")
    parser.add_argument("--layer", default="M", choices=("H", "M", "L"), help="camera layer (M: 104x80)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--save", default="head_track_ppo.zip", help="where to save the policy")
    args = parser.parse_args(argv)
    try:
        from stable_baselines3 import PPO
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import SubprocVecEnv
    except ImportError:
        raise SystemExit("this example needs stable-baselines3: pip install 'aibo-sim[train]'") from None

    options = {"camera_layer": args.layer}
    envs = make_vec_env(ENV_ID, n_envs=args.envs, seed=args.seed, env_kwargs=options, vec_env_cls=SubprocVecEnv,
                        vec_env_kwargs={"start_method": "spawn"})
    model = PPO("MultiInputPolicy", envs, n_steps=128, batch_size=64, seed=args.seed, verbose=1)
    model.learn(total_timesteps=args.steps)
    model.save(args.save)
    envs.close()

    env = gym.make(ENV_ID, **options)
    obs, _ = env.reset(seed=args.seed + 1000)
    rewards, done = [], False
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, _ = env.step(action)
        rewards.append(reward)
        done = terminated or truncated
    env.close()
    print(f"saved {args.save}; mean reward per step over one episode: {sum(rewards) / len(rewards):.3f}")


if __name__ == "__main__":
    main()
