"""Vector envs of the ego ids: what ``gym.make_vec(id, n)`` builds by default.

libsumo runs one SUMO simulation per process, so ``n > 1`` envs in one process cannot all
run through it. The ids' ``vector_entry_point`` (:func:`make_vector`) therefore gives an
:class:`gymnasium.vector.AsyncVectorEnv`: each env in its own worker process (one libsumo
each, the cores used in parallel). ``n == 1`` stays in this process
(:class:`gymnasium.vector.SyncVectorEnv`).

Several envs in one process (SB3's ``DummyVecEnv``, ``vectorization_mode="sync"``) need
``config={"multi_instance": True}``: the second and later run SUMO through TraCI (see
docs/gym.md for its cost).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
from gymnasium.vector import AsyncVectorEnv, SyncVectorEnv

from ego.params import ConfigError
from ego.sim import exclusive_running


def env_id_of(scenario: str) -> str:
    from ego.gym import ENV_IDS

    for env_id, name in ENV_IDS.items():
        if name == scenario:
            return env_id
    raise ConfigError(f"bad value for scenario: {scenario!r} (expected one of {', '.join(ENV_IDS.values())})")


class _Maker:
    """A picklable ``gym.make(env_id, **kwargs)`` (the spec's TimeLimit included)."""

    def __init__(self, env_id: str, kwargs: dict) -> None:
        self.env_id, self.kwargs = env_id, kwargs

    def __call__(self):
        import ego.gym  # noqa: F401 - registers the ids in a fresh worker

        return gym.make(self.env_id, **self.kwargs)


def make_vector(
    num_envs: int = 1,
    scenario: str = "emergency-brake",
    config: Mapping[str, Any] | None = None,
    render_mode: str | None = None,
    **kwargs: Any,
):
    """``num_envs`` envs of ``scenario``'s id, each in its own process when more than one.

    Workers start by ``fork`` when no SUMO runs in this process, else by ``forkserver``
    (a fork of a process whose libsumo runs would inherit its simulation)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ConfigError(f"bad value for num_envs: {num_envs!r} (expected a whole number >= 1)")
    make = _Maker(env_id_of(scenario), {"config": dict(config or {}), "render_mode": render_mode, **kwargs})
    if num_envs == 1:
        return SyncVectorEnv([make])
    context = "forkserver" if exclusive_running() else "fork"
    return AsyncVectorEnv([make] * num_envs, context=context)
