"""ego's SUMO scenarios as Gymnasium environments, registered on import.

    import gymnasium as gym
    import ego.gym

    env = gym.make("ego/EmergencyBrake-v0", config={"observation": {"type": "Kinematics"}})
    obs, info = env.reset(seed=0)

One environment class (:class:`EgoEnv`) over every scenario, configured as highway-env's
environments are (``default_config()``, ``configure()``, ``gym.make(id, config=...)``,
``reset(options={"config": ...})``). Only this package imports gymnasium; install it with
``pip install ego[gym]``. See docs/gym.md.
"""

from __future__ import annotations

import gymnasium

from ego.gym.env import ENV_KEYS, EgoEnv, EgoView, EnvConfig, Reward
from ego.gym.evaluate import evaluate
from ego.gym.policy import ControllerPolicy
from ego.gym.scenario_env import ScenarioEnv
from ego.gym.spaces import (
    ContinuousAction,
    DiscreteMetaAction,
    EgoAction,
    EgoStateObservation,
    KinematicsObservation,
    OccupancyGridObservation,
    TimeToCollisionObservation,
)

#: env id -> scenario name
ENV_IDS = {
    "ego/EmergencyBrake-v0": "emergency-brake",
    "ego/FastFollower-v0": "fast-follower",
    "ego/CutIn-v0": "cut-in",
    "ego/Curve-v0": "curve",
    "ego/LaneCentering-v0": "lane-centering",
    "ego/Platoon-v0": "platoon",
}

#: env id -> the mean return an agent must reach to count as solving it: the env's default
#: controller's mean return on the evaluation episodes of docs/results/rl-baselines.md in the
#: env as gym.make(id) makes it (its rl-thresholds table: every control step an env step, the
#: full duration), so "solved" means "as good as the controller" in the registered env
#: (tests/gym check it against the page)
REWARD_THRESHOLDS: dict[str, float] = {
    "ego/EmergencyBrake-v0": 862.26,
    "ego/FastFollower-v0": 1173.12,
    "ego/CutIn-v0": 1522.96,
    "ego/Curve-v0": 485.04,
    "ego/LaneCentering-v0": 17943.61,
    "ego/Platoon-v0": 2102.58,
}


def _max_episode_steps(scenario: str) -> int:
    """Env steps of a default run: its duration over the control period (policy_frequency 0)."""
    from ego.scenarios import scenario_class

    c = scenario_class(scenario).config_cls()
    return round(c.duration / c.dt)


# EgoEnv refuses a step before reset itself, and passes gymnasium's checker (tests/gym): the
# per-step wrappers gym.make would add for both cost 10 % of a step. gym.make_vec(id, n) runs
# each env in its own process by default (ego.gym.vector: libsumo runs one SUMO per process).
for _id, _scenario in ENV_IDS.items():
    if _id not in gymnasium.registry:
        gymnasium.register(
            _id,
            entry_point="ego.gym.env:EgoEnv",
            kwargs={"scenario": _scenario},
            vector_entry_point="ego.gym.vector:make_vector",
            max_episode_steps=_max_episode_steps(_scenario),
            reward_threshold=REWARD_THRESHOLDS.get(_id),
            order_enforce=False,
            disable_env_checker=True,
        )

#: the id of the env over any scenario: gym.make(SCENARIO_ENV_ID, config={"scenario": NAME_OR_FILE})
SCENARIO_ENV_ID = "ego/Scenario-v0"

# no max_episode_steps nor reward_threshold: they belong to a scenario (its duration truncates)
if SCENARIO_ENV_ID not in gymnasium.registry:
    gymnasium.register(
        SCENARIO_ENV_ID,
        entry_point="ego.gym.scenario_env:ScenarioEnv",
        kwargs={"scenario": None},
        vector_entry_point="ego.gym.vector:make_vector",
        order_enforce=False,
        disable_env_checker=True,
    )

if "ego/PlatoonMultiAgent-v0" not in gymnasium.registry:
    gymnasium.register(
        "ego/PlatoonMultiAgent-v0",
        entry_point="ego.gym.multi_agent:PlatoonMultiAgentEnv",
        max_episode_steps=_max_episode_steps("platoon"),
        order_enforce=False,
        disable_env_checker=True,
    )

__all__ = [
    "ENV_IDS",
    "ENV_KEYS",
    "SCENARIO_ENV_ID",
    "ContinuousAction",
    "ControllerPolicy",
    "DiscreteMetaAction",
    "EgoAction",
    "EgoEnv",
    "EgoStateObservation",
    "EgoView",
    "EnvConfig",
    "KinematicsObservation",
    "OccupancyGridObservation",
    "Reward",
    "ScenarioEnv",
    "TimeToCollisionObservation",
    "evaluate",
]
