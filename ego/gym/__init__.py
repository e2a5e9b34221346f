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

#: env id -> the benchmark's setting, which ``gym.make(id)`` makes by default and
#: docs/results/rl-baselines.md trains and scores in: ten env steps a simulated second (the
#: action held over ten 0.01 s control periods), the lane-centring drive cut to 30 s.
#: ``config={"policy_frequency": 0}`` gives one env step per control period (100 Hz; then
#: pass ``max_episode_steps`` to gym.make too, or the TimeLimit cuts the run short)
BENCHMARK: dict[str, dict] = {
    "ego/EmergencyBrake-v0": {"policy_frequency": 10},
    "ego/FastFollower-v0": {"policy_frequency": 10},
    "ego/CutIn-v0": {"policy_frequency": 10},
    "ego/Curve-v0": {"policy_frequency": 10},
    "ego/LaneCentering-v0": {"policy_frequency": 10, "duration": 30.0},
    "ego/Platoon-v0": {"policy_frequency": 10},
}

#: env id -> the mean return an agent must reach to count as solving it: the env's default
#: controller's mean return on the evaluation episodes of docs/results/rl-baselines.md in the
#: env as gym.make(id) makes it (its rl-thresholds table: the benchmark's setting), so
#: "solved" means "as good as the controller" in the registered env (tests/gym check it
#: against the page)
REWARD_THRESHOLDS: dict[str, float] = {
    "ego/EmergencyBrake-v0": 86.18,
    "ego/FastFollower-v0": 117.36,
    "ego/CutIn-v0": 152.25,
    "ego/Curve-v0": 48.46,
    "ego/LaneCentering-v0": 89.37,
    "ego/Platoon-v0": 210.26,
}


def _max_episode_steps(scenario: str, setting: dict | None = None) -> int:
    """Env steps of a default run in ``setting``: its duration over the env step (the control
    period dt where policy_frequency is 0)."""
    from ego.scenarios import scenario_class

    c = scenario_class(scenario).config_cls()
    setting = setting or {}
    duration = setting.get("duration", c.duration)
    frequency = setting.get("policy_frequency", 0)
    return round(duration * frequency) if frequency else round(duration / c.dt)


# EgoEnv refuses a step before reset itself, and passes gymnasium's checker (tests/gym): the
# per-step wrappers gym.make would add for both cost 10 % of a step. gym.make_vec(id, n) runs
# each env in its own process by default (ego.gym.vector: libsumo runs one SUMO per process).
for _id, _scenario in ENV_IDS.items():
    if _id not in gymnasium.registry:
        gymnasium.register(
            _id,
            entry_point="ego.gym.env:EgoEnv",
            kwargs={"scenario": _scenario, "defaults": BENCHMARK[_id]},
            vector_entry_point="ego.gym.vector:make_vector",
            max_episode_steps=_max_episode_steps(_scenario, BENCHMARK[_id]),
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
    "BENCHMARK",
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
