"""ego.gym: the env ids against Gymnasium's checker, determinism, vector envs, configuration,
actions, episode ends, the Kinematics observation and rendering - all on real SUMO."""

import copy
import functools
import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import ego.gym
from ego.gym.vector import EgoVectorEnv
from ego.params import ConfigError

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")  # the checker's unbounded-Box notes


@pytest.fixture
def make():
    """gym.make, every env closed at the end (one SUMO per process)."""
    made = []

    def _make(env_id, **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield _make
    for env in made:
        env.close()


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", list(ego.gym.ENV_IDS))
def test_check_env_passes(env_id, make):
    env = make(env_id)
    check_env(env.unwrapped)


@pytest.mark.sumo
@pytest.mark.parametrize("observation", ["EgoState", "Kinematics"])
@pytest.mark.parametrize("env_id", ["ego/CutIn-v0", "ego/Curve-v0", "ego/Platoon-v0"])
def test_same_seed_same_episode_and_fresh_arrays(env_id, observation, make):
    env = make(env_id, config={"observation": {"type": observation}, "policy_frequency": 10})
    actions = [env.action_space.sample() for _ in range(30)]

    def episode(seed):
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for a in actions:
            obs, reward, terminated, truncated, _ = env.step(a)
            out += [obs, np.array([reward])]
            if terminated or truncated:
                break
        return out

    first, second = episode(7), episode(7)
    assert len(first) == len(second)
    assert all(np.array_equal(a, b) for a, b in zip(first, second))
    # no two observations share memory: the env never hands out its buffers
    assert not any(np.shares_memory(a, b) for a, b in zip(first[:-2:2], first[2::2]))
    obs0, _ = env.reset(seed=7)
    assert np.array_equal(obs0, first[0]) and obs0 is not first[0]


@pytest.mark.sumo
def test_make_vec_by_default_runs_one_sumo_per_subprocess():
    envs = gym.make_vec("ego/EmergencyBrake-v0", num_envs=2, config={"policy_frequency": 10})
    assert isinstance(envs, EgoVectorEnv)
    try:
        obs, info = envs.reset(seed=[0, 1])
        assert obs.shape == (2, 16) and list(info["status"]) == ["running", "running"]
        for _ in range(5):
            obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
        assert obs.shape == (2, 16) and reward.shape == (2,)
        # t after 5 x 0.1 s, over the 25 s duration (normalised)
        assert obs[0, 0] == pytest.approx(0.5 / 25) and obs[1, 0] == pytest.approx(0.5 / 25)
    finally:
        envs.close()
    # the parent never started SUMO: a single env still runs here
    env = gym.make("ego/EmergencyBrake-v0")
    try:
        env.reset(seed=0)
    finally:
        env.close()


def test_default_config_and_configure():
    cfg = ego.gym.EgoEnv.default_config("platoon")
    assert cfg["observation"] == {"type": "EgoState"} and cfg["controller"] == "pid"
    assert cfg["action"]["lateral"] is False and cfg["followers"] == 3 and cfg["dt"] == 0.01
    assert set(ego.gym.ENV_KEYS) <= set(cfg)
    env = ego.gym.EgoEnv("platoon", config={"variant": "scale-model"})
    assert env.default_config() == cfg  # an env lists its own scenario's keys
    assert env.scenario.config.followers == 2  # the preset wins over the listed defaults
    assert env.observation_space.shape == (10,) and env.action_space.shape == (1,)
    assert env.observation_type.names[:3] == ("t", "gap", "speed")
    env.close()


@pytest.mark.parametrize(
    "config, message",
    [
        ({"ego_speed": 100}, "bad value for ego_speed: 100"),
        ({"ego_speed": "fast"}, "bad value for ego_speed: 'fast'"),
        ({"bogus": 1}, "unknown parameter 'bogus'"),
        ({"observation": {"type": "Pixels"}}, "bad value for observation"),
        ({"observation": {"type": "Kinematics", "features": ["z"]}}, "unknown Kinematics feature 'z'"),
        ({"action": {"type": "EgoAction", "steer": True}}, "unknown action option 'steer'"),
        ({"action": {"type": "ContinuousAction", "lateral": False, "longitudinal": False}}, "both false"),
        ({"controller": "narma-l2"}, "bad value for controller: 'narma-l2'"),
        ({"policy_frequency": 3}, "bad value for policy_frequency: 3"),
        ({"collision_reward": "x"}, "bad value for collision_reward"),
        ({"reward_speed_range": [30, 10]}, "bad value for reward_speed_range"),
        ({"observation": {"type": "Kinematics", "features": []}}, "bad value for features: []"),
        ({"observation": {"type": "Kinematics", "features": "presence"}}, "bad value for features: 'presence'"),
        ({"observation": {"type": "OccupancyGrid", "features": []}}, "non-empty list of OccupancyGrid features"),
        ({"observation": {"type": "Kinematics", "features": ["x", "x"]}}, "each Kinematics feature once"),
    ],
    ids=[
        "range",
        "type",
        "unknown",
        "observation",
        "feature",
        "action-option",
        "no-channel",
        "controller",
        "frequency",
        "reward",
        "speed-range",
        "no-features",
        "features-as-text",
        "grid-no-features",
        "repeated-feature",
    ],
)
def test_bad_config_is_one_line_config_error(config, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")) as err:
        ego.gym.EgoEnv("emergency-brake", config=config)
    assert "\n" not in str(err.value)


def test_platoon_does_not_steer():
    with pytest.raises(ConfigError, match="does not steer"):
        ego.gym.EgoEnv("platoon", config={"action": {"type": "ContinuousAction", "lateral": True}})


@pytest.mark.sumo
def test_reset_options_reconfigure_and_rebuild_the_spaces(make):
    env = make("ego/EmergencyBrake-v0")
    assert env.observation_space.shape == (16,)
    obs, _ = env.reset(
        seed=0,
        options={
            "config": {"observation": {"type": "Kinematics", "vehicles_count": 7}, "ego_speed": 25.0, "randomize": {}}
        },
    )
    assert obs.shape == (7, 5) and env.unwrapped.observation_space.shape == (7, 5)
    assert env.unwrapped.scenario.config.ego_speed == 25.0


@pytest.mark.sumo
def test_configure_or_an_edit_of_config_takes_effect_at_the_next_reset(make):
    """highway-env's idiom: env.unwrapped.configure(...) (or editing env.unwrapped.config),
    then reset(); the config never disagrees with the env that runs."""
    env = make("ego/EmergencyBrake-v0")
    u = env.unwrapped
    u.configure({"observation": {"type": "Kinematics"}, "policy_frequency": 10})
    obs, _ = env.reset(seed=0)
    assert obs.shape == (5, 5) and u._every == 10 and u.metadata["render_fps"] == 10.0
    u.config["observation"] = {"type": "EgoState"}
    obs, _ = env.reset(seed=0)
    assert obs.shape == (16,) and env.observation_space.shape == (16,)


@pytest.mark.sumo
def test_a_rejected_configuration_is_taken_back(make):
    env = make("ego/EmergencyBrake-v0")
    u = env.unwrapped
    env.reset(seed=0)
    before = copy.deepcopy(u.config)
    with pytest.raises(ConfigError, match="bad value for policy_frequency: 3"):
        env.reset(options={"config": {"policy_frequency": 3}})
    assert u.config == before
    env.reset(seed=0)
    pickle.loads(pickle.dumps(u)).close()
    env.reset(options={"config": {"policy_frequency": 10}})
    assert u._every == 10


@pytest.mark.sumo
def test_a_copy_replays_the_built_configuration_and_keeps_a_pending_one(make):
    env = make("ego/EmergencyBrake-v0")
    u = env.unwrapped
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(2, np.float32))
    u.configure({"observation": {"type": "Kinematics"}})  # pending until the next reset
    twin = pickle.loads(pickle.dumps(u))
    try:
        assert twin.observation_space.shape == (16,) and twin.scenario.k == u.scenario.k
        assert twin.config == u.config
        obs, _ = twin.reset(seed=0)
        assert obs.shape == (5, 5)
    finally:
        twin.close()


@pytest.mark.sumo
def test_continuous_action_becomes_report_000s_fx(make):
    env = make("ego/EmergencyBrake-v0")
    env.reset(seed=0)
    env.step(np.array([0.4, 0.0], dtype=np.float32))  # 0.4 of +-5 m/s^2
    ego_plant = env.unwrapped.scenario.ego
    p = ego_plant.model.params
    assert ego_plant.applied[0] == pytest.approx(p.m * 2.0 / p.Nw)
    assert ego_plant.applied[1] == 0.0


@pytest.mark.sumo
def test_collision_terminates_and_reports_metrics(make):
    env = make("ego/EmergencyBrake-v0", config={"aeb": False, "action": {"type": "EgoAction"}})
    env.reset(seed=0)
    coast = np.zeros(2)
    for _ in range(3000):
        obs, reward, terminated, truncated, info = env.step(coast)
        if terminated or truncated:
            break
    assert terminated and not truncated and info["status"] == "collision"
    assert info["rewards"]["crashed"] == 1.0 and reward < 0.0
    assert info["metrics"]["collision_with"] == "lead" and info["metrics"]["controller"] == "agent"


@pytest.mark.sumo
def test_duration_truncates(make):
    env = make("ego/Platoon-v0", config={"duration": 2.0, "policy_frequency": 10})
    env.reset(seed=0)
    steps = 0
    while True:
        steps += 1
        _, _, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
        if terminated or truncated:
            break
    assert steps == 20 and truncated and not terminated
    assert info["status"] == "completed" and info["metrics"]["steps"] == 200
    assert "completion" not in info["rewards"]  # the duration reached: nothing left to count


@pytest.mark.sumo
def test_completing_the_task_early_earns_the_steps_left_at_that_steps_reward(make):
    """The curve's arc driven before duration: the last step's reward is its own terms plus
    the env steps left to duration times that reward; completion_reward 0 leaves it out."""
    ends = {}
    for weight in (1.0, 0.0):
        env = make("ego/Curve-v0", config={"policy_frequency": 10, "randomize": {}, "completion_reward": weight})
        obs, _ = env.reset(seed=3)
        policy = ego.gym.ControllerPolicy("pid", env)
        steps, total = 0, 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            steps += 1
            total += reward
            if terminated or truncated:
                break
        ends[weight] = (steps, total, reward, info["rewards"])
        env.close()
    (steps, total, reward, terms), (steps0, total0, reward0, terms0) = ends[1.0], ends[0.0]
    assert steps == steps0 < 200  # 20 s at 10 Hz: completed well before
    own = -1.0 * terms["crashed"] + 0.4 * terms["progress"] + 0.2 * terms["centring"] - 0.1 * terms["discomfort"]
    assert own > 0.0 and reward0 == pytest.approx(own, rel=1e-12) and "completion" not in terms0
    assert terms["completion"] == pytest.approx((200 - steps) * own, rel=1e-12)
    assert reward == pytest.approx(own + terms["completion"], rel=1e-12)
    assert total - total0 == pytest.approx(terms["completion"], rel=1e-9)


@pytest.mark.sumo
def test_kinematics_rows_in_the_lane_frame(make):
    env = make(
        "ego/EmergencyBrake-v0",
        config={
            "randomize": {},
            "observation": {
                "type": "Kinematics",
                "normalize": False,
                "see_behind": True,
                "vehicles_count": 6,
                "features": ["presence", "x", "y", "vx", "vy", "heading"],
            },
        },
    )
    obs, _ = env.reset(seed=0)
    sc = env.unwrapped.scenario
    assert obs[0, 0] == 1.0 and obs[0, 1] == pytest.approx(sc.view.s) and obs[0, 3] == pytest.approx(sc.view.ds)
    present = obs[1:][obs[1:, 0] == 1.0]
    distance = np.hypot(present[:, 1], present[:, 2])
    assert len(present) >= 1 and np.all(np.diff(distance) >= 0.0)  # nearest first
    # the lead car: ahead in the ego's lane, lead_gap (30 m) plus half of both cars
    lead = present[(np.abs(present[:, 2]) < 0.5) & (present[:, 1] > 0)][0]
    assert lead[1] == pytest.approx(30.0 + 2.25 + sc.geometry.cg_to_front, abs=0.05)


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", ["ego/CutIn-v0", "ego/Curve-v0", "ego/Platoon-v0"])
def test_render_rgb_array(env_id, make):
    env = make(env_id, render_mode="rgb_array", config={"screen_width": 200, "screen_height": 80})
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (80, 200, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 3  # road, vehicles, background


def test_only_ego_gym_imports_gymnasium():
    code = (
        "import sys, ego, ego.cli, ego.runner, ego.compare, ego.sweep, ego.scenarios, ego.control; "
        "assert 'gymnasium' not in sys.modules, 'gymnasium imported'"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr


def test_env_ids_are_registered():
    for env_id, scenario in ego.gym.ENV_IDS.items():
        spec = gym.spec(env_id)
        assert spec.kwargs["scenario"] == scenario


def test_step_before_reset_is_refused():
    env = gym.make("ego/CutIn-v0")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(env.action_space.sample())
    env.close()


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", ["ego/CutIn-v0", "ego/Curve-v0", "ego/Platoon-v0"])
def test_the_steps_bound_reward_and_observation_are_the_references_bit_for_bit(env_id, make):
    """env.step's reward (EgoView.bind_reward: the scenario's signals reader, the rate and the
    terms in one call) and observation (EgoStateObservation.bind: one call into C) against the
    reference chains Reward(view, crashed) -> reward_signals -> agent_signals and
    observe(view), over the same episode (the curve's reward reads the rate of the speed)."""

    env = make(env_id, config={"policy_frequency": 10})
    actions = [env.action_space.sample() for _ in range(60)]

    def episode(reference):
        env.reset(seed=5)
        u = env.unwrapped
        if reference:
            u._fast_step = None  # the whole step in Python (policy_frequency 10 has none anyway)
            u._step_reward = functools.partial(u.reward, u._view)
            u._observe = functools.partial(u.observation_type.observe, u._view)
        out = []
        for a in actions:
            obs, reward, terminated, truncated, info = env.step(a)
            out.append((obs.tolist(), reward, info["rewards"]))
            if terminated or truncated:
                break
        return out

    fast, reference = episode(False), episode(True)
    assert len(fast) > 10 and fast == reference


def _bits(step_return) -> str:
    """An env step's return to the bit (every float as Python prints it, NaN included), the
    run's wall time aside."""
    obs, reward, terminated, truncated, info = step_return
    if "metrics" in info:
        info = {**info, "metrics": {k: v for k, v in info["metrics"].items() if k != "wall_time"}}
    return repr((obs.dtype, obs.tolist(), reward, terminated, truncated, info))


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", list(ego.gym.ENV_IDS))
def test_the_step_in_c_gives_the_python_steps_every_return(env_id, make, monkeypatch):
    """EgoEnv.step through ego._native.env_step against EgoEnv._step alone, over whole episodes
    of random actions: every observation, reward, flag and info (the metrics at the end) the
    same to the bit. Three episodes each: one to the run's end, one cut by a registered
    TimeLimit of 40 steps (the step that reaches it runs in Python) and one with a NaN action at
    step 25 (the run ends diverged, through Python)."""
    from ego.gym.env import EgoEnv

    short = "ego-test/" + env_id.split("/")[1]  # the env id registered with 40 steps
    spec = gym.spec(env_id)
    gym.register(short, entry_point=spec.entry_point, kwargs=spec.kwargs, max_episode_steps=40)
    try:
        _compare_steps(env_id, short, make, monkeypatch, EgoEnv)
    finally:
        gym.registry.pop(short, None)


def _compare_steps(env_id, short, make, monkeypatch, EgoEnv):
    cases = [(env_id, None), (short, None), (env_id, 25)]
    bind = EgoEnv._bind_step
    for made, nan_at in cases:
        env = make(made, config={"duration": 3.0, "policy_frequency": 0})  # the C step's rate
        env.action_space.seed(3)
        actions = [env.action_space.sample() for _ in range(400)]
        if nan_at is not None:
            actions[nan_at] = np.full_like(actions[nan_at], np.nan)
        out = {}
        for fast in (True, False):
            monkeypatch.setattr(EgoEnv, "_bind_step", bind if fast else lambda self: None)
            obs, _ = env.reset(seed=11)
            assert (env.unwrapped._fast_step is not None) == fast
            returns = [repr(obs.tolist())]
            for a in actions:
                step = env.step(a)
                returns.append(_bits(step))
                if step[2] or step[3]:
                    break
            out[fast] = returns
        assert len(out[True]) > 20 and out[True] == out[False], (made, nan_at)
        last = out[True][-1]
        assert "'metrics'" in last
        if nan_at is not None:
            assert "'diverged'" in last and len(out[True]) == nan_at + 2
        if made == short:
            assert "max_episode_steps (40) reached" in last and len(out[True]) == 41
        env.close()


def test_a_scenario_that_overrides_only_agent_signals_keeps_its_own():
    from ego.gym.env import _signals_reader
    from ego.scenarios.base import Scenario

    class Own(Scenario):
        def agent_signals(self, vid):
            return (1.0, 2.0, 3.0, 4.0)

    class Both(Own):
        def agent_signals(self, vid):
            return (5.0, 6.0, 7.0, 8.0)

        def agent_signals_reader(self, vid):
            return lambda: (5.0, 6.0, 7.0, 8.0)

    own, both = Own.__new__(Own), Both.__new__(Both)
    assert isinstance(_signals_reader(own, "ego"), functools.partial) and _signals_reader(own, "ego")() == (
        1.0,
        2.0,
        3.0,
        4.0,
    )
    assert not isinstance(_signals_reader(both, "ego"), functools.partial) and _signals_reader(both, "ego")() == (
        5.0,
        6.0,
        7.0,
        8.0,
    )
