"""``evaluate(policy, env_id, episodes, seeds)``: a policy's success rate, collision rate and
mean return over evaluation episodes, each with a 95 % interval, as RL benchmarks report
them (from the outcome in the ``info`` of each episode's last step)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ego.gym.env import OUTCOME_KEYS
from ego.params import ConfigError

#: the two-sided normal quantile of the 95 % intervals
Z95 = 1.959963984540054


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson's score interval of a rate of ``successes`` in ``n`` trials (95 % by default)."""
    if n <= 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denom
    # exact at the ends (the arithmetic leaves a rounding error there)
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == n else min(1.0, centre + half)
    return (low, high)


def t_interval(values: Iterable[float], level: float = 0.95) -> tuple[float, float]:
    """Student's t interval of the mean of ``values`` (one value: the value itself)."""
    from scipy import stats

    x = np.asarray(list(values), dtype=np.float64)
    mean = float(x.mean())
    if len(x) < 2:
        return (mean, mean)
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * x.std(ddof=1) / math.sqrt(len(x)))
    return (mean - half, mean + half)


def _act(policy: Any, env) -> Callable[[Any], Any]:
    """``policy`` as observation -> action: an SB3 model (deterministic ``predict``), a
    controller name (:class:`ego.gym.ControllerPolicy` of the env) or a callable."""
    if hasattr(policy, "predict"):
        return lambda obs: policy.predict(obs, deterministic=True)[0]
    if isinstance(policy, str):
        from ego.gym.policy import ControllerPolicy

        return ControllerPolicy(policy, env)
    if callable(policy):
        return policy
    raise ConfigError(f"bad policy: {policy!r} (expected an SB3 model, a controller name or a callable)")


def evaluate(
    policy: Any,
    env_id: str,
    episodes: int | None = None,
    seeds: Iterable[int] | None = None,
    config: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Run ``policy`` on ``gym.make(env_id, config=config)`` for the episodes of ``seeds``
    (default ``0 .. episodes - 1``; with both, the first ``episodes`` seeds) and report
    ``episodes``, ``success_rate`` and ``collision_rate`` with Wilson's 95 % intervals
    (``success_interval``, ``collision_interval``), ``mean_return`` with Student's t 95 %
    interval (``return_interval``), and per episode its seed, return, length (env steps) and outcome
    (``per_episode``)."""
    seed_list = [int(s) for s in seeds] if seeds is not None else None
    if episodes is None:
        if seed_list is None:
            raise ConfigError("evaluate needs episodes or seeds")
        episodes = len(seed_list)
    if not isinstance(episodes, int) or isinstance(episodes, bool) or episodes < 1:
        raise ConfigError(f"bad value for episodes: {episodes!r} (expected a whole number from 1)")
    if seed_list is None:
        seed_list = list(range(episodes))
    elif len(seed_list) < episodes:
        raise ConfigError(f"bad value for seeds: {len(seed_list)} seeds for {episodes} episodes")
    seed_list = seed_list[:episodes]
    env = gym.make(env_id, config=dict(config or {}))
    rows = []
    try:
        act = _act(policy, env.unwrapped)
        for seed in seed_list:
            obs, _ = env.reset(seed=seed)
            total, steps = 0.0, 0
            while True:
                obs, reward, terminated, truncated, info = env.step(act(obs))
                total += float(reward)
                steps += 1
                if terminated or truncated:
                    break
            rows.append(
                {
                    "seed": seed,
                    "return": total,
                    "length": steps,
                    **{k: info.get(k) for k in OUTCOME_KEYS},
                }
            )
    finally:
        env.close()
    n = len(rows)
    successes = sum(bool(r["is_success"]) for r in rows)
    collisions = sum(bool(r["collision"]) for r in rows)
    returns = [r["return"] for r in rows]
    return {
        "env_id": env_id,
        "episodes": n,
        "success_rate": successes / n,
        "success_interval": wilson(successes, n),
        "collision_rate": collisions / n,
        "collision_interval": wilson(collisions, n),
        "mean_return": float(np.mean(returns)),
        "return_interval": t_interval(returns),
        "per_episode": rows,
    }
