"""Gymnasium environments of the ERS-7, registered under the ``aibo_sim/`` namespace.

``register_envs()`` registers them (``import aibo_sim`` calls it); registration imports no
simulation code. Then::

    env = gymnasium.make("aibo_sim/HeadTrackBall-v0", camera="rgb", camera_layer="H")

Without importing anything first, name the module in the id (Gymnasium 1.x has no plugin
loading): ``gymnasium.make("aibo_sim.envs:aibo_sim/HeadTrackBall-v0")``.
The classes live in ``aibo_sim.envs.head_track`` and ``aibo_sim.envs.reach_ball``; the options
and observations are described in ``aibo_sim.envs.base``.
A match (several robots, red against blue): ``aibo_sim.envs.match.MatchEnv``, a PettingZoo
``ParallelEnv`` (every robot an agent), and ``aibo_sim/MatchVsScripted-v0``
(``ScriptedOpponentsEnv``: one learning robot, the others scripted ball chasers).
``aibo_sim.envs.vector.BusyWaitWorker`` is a worker for ``make_vec(..., "async")`` that keeps
its process awake between steps. ``make_vec(id, num_envs)`` without a mode (or with
``vectorization_mode="vector_entry_point"``) makes a ``HybridVectorEnv`` (``aibo_sim.envs.vector``,
the fastest here): the first environment stepped in the calling process, the others in such
workers (spawned: guard a script's top level with ``if __name__ == "__main__":``); ``"sync"`` and
``"async"`` are Gymnasium's. ``aibo_sim.envs.threaded.ThreadedVectorEnv(id, num_envs, **kwargs)``
steps them in threads of this process instead.
"""

from functools import partial

import gymnasium

HEAD_TRACK_BALL, REACH_BALL, MATCH_VS_SCRIPTED = (
    "aibo_sim/HeadTrackBall-v0",
    "aibo_sim/ReachBall-v0",
    "aibo_sim/MatchVsScripted-v0",
)
ENV_SPECS = {  # id: (entry point, max_episode_steps, vector entry point)
    HEAD_TRACK_BALL: ("aibo_sim.envs.head_track:HeadTrackBallEnv", 300, "aibo_sim.envs:head_track_ball_vector"),
    REACH_BALL: ("aibo_sim.envs.reach_ball:ReachBallEnv", 450, "aibo_sim.envs:reach_ball_vector"),
    MATCH_VS_SCRIPTED: ("aibo_sim.envs.match:ScriptedOpponentsEnv", 900, "aibo_sim.envs:match_vs_scripted_vector"),
}


def _hybrid_vector_env(env_id: str, num_envs: int, **kwargs):
    from .vector import HybridVectorEnv

    return HybridVectorEnv(env_id, num_envs, **kwargs)


# make_vec's vector entry points, named as "module:function" strings so that a spec serialises
# (EnvSpec.to_json, as datasets record it) where a callable would not.
head_track_ball_vector = partial(_hybrid_vector_env, HEAD_TRACK_BALL)
reach_ball_vector = partial(_hybrid_vector_env, REACH_BALL)
match_vs_scripted_vector = partial(_hybrid_vector_env, MATCH_VS_SCRIPTED)


def register_envs() -> None:
    """Register the environments with Gymnasium; calling it again changes nothing."""
    for env_id, (entry_point, max_episode_steps, vector_entry_point) in ENV_SPECS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(
                env_id,
                entry_point=entry_point,
                max_episode_steps=max_episode_steps,
                vector_entry_point=vector_entry_point,
            )


register_envs()
