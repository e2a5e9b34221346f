"""The RL libraries' own checks on every env id and documented config: Gymnasium's and
stable-baselines3's env checkers, PettingZoo's parallel API test, and 1,000 steps of every
env through gym.make_vec's default, AsyncVectorEnv, SB3's SubprocVecEnv and DummyVecEnv(2)."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test
from stable_baselines3.common.env_checker import check_env as sb3_check_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

import ego.gym
from ego.gym.multi_agent import PlatoonParallelEnv
from ego.gym.vector import _Maker
from ego.params import ConfigError

pytestmark = [pytest.mark.sumo, pytest.mark.filterwarnings("ignore::UserWarning")]

#: the configurations docs/gym.md documents, beyond the defaults
CONFIGS = {
    "default": {},
    "kinematics": {"observation": {"type": "Kinematics"}},
    "ego-action-10hz": {"action": {"type": "EgoAction"}, "policy_frequency": 10},
    "raw-fixed": {"observation": {"type": "EgoState", "normalize": False}, "randomize": {}},
    "ttc": {"observation": {"type": "TimeToCollision"}, "policy_frequency": 10},
    "grid": {"observation": {"type": "OccupancyGrid"}},
}
MOTORWAY = ["ego/EmergencyBrake-v0", "ego/FastFollower-v0", "ego/CutIn-v0"]


@pytest.mark.parametrize("env_id", MOTORWAY)
def test_checkers_pass_with_discrete_meta_actions(env_id):
    env = gym.make(
        env_id,
        config={"action": {"type": "DiscreteMetaAction"}, "policy_frequency": 1, "observation": {"type": "Kinematics"}},
    )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_env(env.unwrapped)
            sb3_check_env(env, warn=False)
    finally:
        env.close()


@pytest.mark.parametrize("config", list(CONFIGS), ids=list(CONFIGS))
@pytest.mark.parametrize("env_id", list(ego.gym.ENV_IDS))
def test_gymnasium_and_sb3_env_checkers_pass(env_id, config):
    env = gym.make(env_id, config=CONFIGS[config])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_env(env.unwrapped)
            sb3_check_env(env, warn=False)
    finally:
        env.close()


@pytest.mark.parametrize(
    "config",
    [
        {},
        {"controlled_vehicles": 2, "policy_frequency": 10},
        {"variant": "scale-model", "action": {"type": "EgoAction"}},
        {"observation": {"type": "Kinematics"}, "policy_frequency": 10},
        {"observation": {"type": "OccupancyGrid"}, "policy_frequency": 10},
    ],
    ids=["default", "two-agents-10hz", "scale-model", "kinematics", "occupancy-grid"],
)
def test_pettingzoo_parallel_api_test_passes(config):
    env = PlatoonParallelEnv(config=config)
    try:
        parallel_api_test(env, num_cycles=200)
    finally:
        env.close()


def _step(envs, n_steps: int, sample) -> np.ndarray:
    """Step a vector env ``n_steps`` times; the last observations."""
    obs = None
    for _ in range(n_steps):
        out = envs.step(sample())
        obs = out[0]
    return obs


#: every vectoriser on the first env by default (``dummy``: two SUMOs in one process); the
#: other envs' pairs are minutes together (``-m long`` runs them)
_VECTOR_CASES = [
    pytest.param(
        env_id,
        kind,
        id=f"{env_id}-{kind}",
        marks=() if env_id == next(iter(ego.gym.ENV_IDS)) else pytest.mark.long,
    )
    for env_id in ego.gym.ENV_IDS
    for kind in ("make_vec", "async", "subproc", "dummy")
]


@pytest.mark.parametrize("env_id, kind", _VECTOR_CASES)
def test_vector_envs_step_1000_steps(env_id, kind):
    maker = _Maker(env_id, {"config": {"multi_instance": kind == "dummy"}})
    if kind == "make_vec":
        envs = gym.make_vec(env_id, num_envs=2)
    elif kind == "async":
        envs = gym.vector.AsyncVectorEnv([maker, maker])
    elif kind == "subproc":
        envs = SubprocVecEnv([maker, maker], start_method="fork")  # forkserver: +10 s per test
    else:
        envs = DummyVecEnv([maker, maker])  # one process: the second SUMO through TraCI
    try:
        space = envs.single_action_space if hasattr(envs, "single_action_space") else envs.action_space
        rng = np.random.default_rng(0)
        # a gentle random policy: some episodes end, the vector env resets them

        def sample():
            return 0.3 * rng.uniform(-1.0, 1.0, (2, *space.shape)).astype(space.dtype)

        if hasattr(envs, "single_action_space"):
            envs.reset(seed=0)
            obs = _step(envs, 1000, sample)
        else:
            envs.seed(0)
            envs.reset()
            obs = _step(envs, 1000, sample)
        assert obs.shape[0] == 2 and np.all(np.isfinite(obs))
    finally:
        envs.close()


def test_highway_envs_multi_agent_convention_as_one_gymnasium_env():
    env = gym.make(
        "ego/PlatoonMultiAgent-v0",
        config={
            "controlled_vehicles": 2,
            "policy_frequency": 10,
            "action": {"type": "MultiAgentAction", "action_config": {"type": "ContinuousAction", "lateral": False}},
            "observation": {"type": "MultiAgentObservation", "observation_config": {"type": "EgoState"}},
        },
    )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_env(env.unwrapped)
        obs, _ = env.reset(seed=0)
        assert len(obs) == 2 and env.unwrapped.controlled_vehicles == ("f1", "f2")
        obs, reward, *_, info = env.step(env.action_space.sample())
        assert reward == pytest.approx(np.mean(info["agents_rewards"])) and len(info["agents_rewards"]) == 2
        with pytest.raises(ValueError, match="expected a tuple of 2 actions"):
            env.step(np.zeros(1))
    finally:
        env.close()


def test_the_agents_observe_the_configured_type_each_from_its_own_car():
    env = PlatoonParallelEnv(config={"observation": {"type": "Kinematics", "vehicles_count": 4}})
    try:
        obs, _ = env.reset(seed=0)
        assert env.observation_space("f1").shape == (4, 5)
        assert all(o.shape == (4, 5) for o in obs.values())
        assert not np.array_equal(obs["f1"], obs["f2"])  # f2 has f1 ahead of it, f1 does not
    finally:
        env.close()


def test_a_reconfiguring_reset_rebuilds_the_agents_spaces_and_frame_rate():
    env = PlatoonParallelEnv()
    try:
        env.reset(seed=0, options={"config": {"followers": 2}})
        assert env.agents == env.possible_agents == ["f1", "f2"]
        env.reset(seed=0, options={"config": {"followers": 5, "controlled_vehicles": 3}})
        assert env.agents == ["f1", "f2", "f3"]
        env.reset(seed=0, options={"config": {"action": {"type": "EgoAction"}, "policy_frequency": 10}})
        assert env.action_space("f1") == env._env.action_space and env.action_space("f1").high[0] == 2.5
        assert env.metadata["render_fps"] == 10.0
        with pytest.raises(ConfigError, match="bad value for controlled_vehicles: 9"):
            env.reset(seed=0, options={"config": {"controlled_vehicles": 9}})
        env.reset(seed=0)
        assert env.agents == ["f1", "f2", "f3"]
    finally:
        env.close()
    multi = gym.make("ego/PlatoonMultiAgent-v0")
    try:
        obs, _ = multi.reset(seed=0, options={"config": {"followers": 2}})
        assert len(obs) == 2 and len(multi.unwrapped.action_space) == 2
    finally:
        multi.close()


def test_a_parallel_env_whose_run_another_env_ended_says_so():
    env = PlatoonParallelEnv(config={"multi_instance": False})
    other = gym.make("ego/CutIn-v0", config={"multi_instance": False})
    try:
        env.reset(seed=0)
        other.reset(seed=0)  # libsumo: one simulation per process
        with pytest.raises(RuntimeError, match="ended by the reset of another ego env"):
            env.step({a: np.zeros(1, np.float32) for a in env.agents})
    finally:
        other.close()
        env.close()
