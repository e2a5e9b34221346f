"""Issue 42: every standard RL client works with the default config - no negative speed
reaches SUMO on either interface, several envs in one process, PettingZoo's parallel tests,
SB3's vec envs, finite observation bounds and the outcome of every episode."""

import gymnasium as gym
import numpy as np
import pytest

import ego.gym

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

#: the ego stopped by full braking, then steered at a crawl: its speed along the lane goes a
#: hair below 0 (the failing situation of issue 42, defect 1: TraCI's "Previous speed must
#: not be negative" at PPO's step 868 on EmergencyBrake with multi_instance)
STANDSTILL = {"policy_frequency": 10, "randomize": {}, "lead_gap": 45, "lead_decel": 3}


def _standstill_steering(env, steer):
    sc = env.unwrapped.scenario
    lowest, trace, speeds = np.inf, [], []
    for _ in range(300):
        action = [-1.0, 0.0] if sc.ego.state[1] > 0.2 else [-0.05, steer]
        obs, reward, terminated, truncated, info = env.step(np.array(action, dtype=np.float32))
        lowest = min(lowest, sc.view.ds)
        trace.append((obs.copy(), reward))
        if not (terminated or truncated):
            speeds.append(sc.bridge.libsumo.vehicle.getSpeed("ego"))
        if terminated or truncated:
            break
    return lowest, trace, speeds, info["status"]


@pytest.mark.sumo
@pytest.mark.parametrize("steer", [1.0, 0.05])
def test_a_standstill_while_steering_reaches_sumo_as_speed_0_on_libsumo_and_traci(steer):
    first = gym.make("ego/EmergencyBrake-v0", config={**STANDSTILL, "multi_instance": True})
    second = gym.make("ego/EmergencyBrake-v0", config={**STANDSTILL, "multi_instance": True})
    try:
        first.reset(seed=0)
        second.reset(seed=0)
        assert not first.unwrapped.scenario.bridge.via_traci and second.unwrapped.scenario.bridge.via_traci
        lib = _standstill_steering(first, steer)
        traci = _standstill_steering(second, steer)
    finally:
        first.close()
        second.close()
    for lowest, _, speeds, status in (lib, traci):
        assert lowest < 0.0  # the failing situation: a negative speed along the lane
        assert min(speeds) >= 0.0 and status != "error"
    assert lib[3] == traci[3]
    for (a, ra), (b, rb) in zip(lib[1], traci[1], strict=True):  # the same episode either way
        assert np.array_equal(a, b) and ra == rb


# -- 2. the default config with the standard clients ---------------------------------------------
def _trajectory(envs, steps, seed):
    """Observations and rewards of a vec env (SB3's or Gymnasium's) under fixed actions."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        actions = rng.uniform(-0.3, 0.3, (envs.num_envs, 2)).astype(np.float32)
        result = envs.step(actions)
        out.append((np.array(result[0]), np.array(result[1])))
    return out


@pytest.mark.sumo
def test_two_default_envs_in_one_process_give_the_trajectories_of_one_each():
    config = {"policy_frequency": 10}
    pair = gym.make_vec("ego/CutIn-v0", num_envs=2, vectorization_mode="sync", config=config)
    try:
        obs, _ = pair.reset(seed=[3, 4])
        both = [(obs, np.zeros(2))] + _trajectory(pair, 40, 0)
        assert pair.unwrapped.envs[1].unwrapped.scenario.bridge.via_traci  # chosen by itself
    finally:
        pair.close()
    for i, seed in enumerate((3, 4)):
        single = gym.make("ego/CutIn-v0", config=config)
        try:
            obs, _ = single.reset(seed=seed)
            rng = np.random.default_rng(0)
            alone = [obs]
            for _ in range(40):
                action = rng.uniform(-0.3, 0.3, (2, 2)).astype(np.float32)[i]
                obs, reward, terminated, truncated, _ = single.step(action)
                alone.append((obs, reward))
                if terminated or truncated:
                    break
        finally:
            single.close()
        assert np.array_equal(both[0][0][i], alone[0])
        for (o, r), (a, ra) in zip([b for b in both[1:]][: len(alone) - 1], alone[1:], strict=True):
            assert np.array_equal(o[i], a) and r[i] == ra


@pytest.mark.sumo
def test_pettingzoo_parallel_tests_pass_on_the_default_platoon():
    from pettingzoo.test import parallel_api_test, parallel_seed_test

    from ego.gym.multi_agent import PlatoonParallelEnv

    env = PlatoonParallelEnv()
    try:
        parallel_api_test(env, num_cycles=50)
    finally:
        env.close()
    parallel_seed_test(PlatoonParallelEnv, num_cycles=50)


@pytest.mark.sumo
def test_sb3_ppo_learns_on_two_default_envs_in_one_process():
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    envs = make_vec_env("ego/EmergencyBrake-v0", n_envs=2, seed=0)  # DummyVecEnv, the default config
    try:
        PPO("MlpPolicy", envs, n_steps=128, batch_size=64, n_epochs=1, seed=0, device="cpu").learn(256)
    finally:
        envs.close()


@pytest.mark.sumo
@pytest.mark.parametrize("mode", ["sync", "async", None])
def test_make_vec_in_every_mode_with_the_default_config(mode):
    kwargs = {} if mode is None else {"vectorization_mode": mode}
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, **kwargs)
    try:
        envs.reset(seed=0)
        for _ in range(5):
            envs.step(envs.action_space.sample())
    finally:
        envs.close()


@pytest.mark.sumo
@pytest.mark.parametrize("kind", ["dummy", "subproc"])
def test_sb3_vec_envs_with_the_default_config(kind):
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    cls = DummyVecEnv if kind == "dummy" else SubprocVecEnv
    envs = make_vec_env("ego.gym:ego/CutIn-v0", n_envs=2, seed=0, vec_env_cls=cls)  # module: id, for forkserver
    try:
        envs.reset()
        for _ in range(5):
            envs.step(np.zeros((2, 2), np.float32))
    finally:
        envs.close()


# -- 3. finite, physical observation bounds ------------------------------------------------------
IDS = [
    "ego/EmergencyBrake-v0",
    "ego/FastFollower-v0",
    "ego/CutIn-v0",
    "ego/Curve-v0",
    "ego/LaneCentering-v0",
    "ego/Platoon-v0",
]


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", IDS)
def test_the_checkers_are_silent_on_the_default_config(env_id):
    import warnings

    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    for config, sb3 in (({}, True), ({"observation": {"type": "Kinematics"}}, False)):
        env = gym.make(env_id, config=config)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # any warning fails the test
                check_env(env.unwrapped, skip_render_check=True)
                if sb3:  # SB3's also advises a 1-D shape for the (rows, features) table
                    sb3_check_env(env.unwrapped, warn=True)
            assert np.isfinite(env.observation_space.low).all() and np.isfinite(env.observation_space.high).all()
        finally:
            env.close()


@pytest.mark.sumo
@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("normalize", [True, False])
def test_every_observation_of_a_whole_episode_lies_in_the_bounds(env_id, normalize):
    config = {"policy_frequency": 10, "observation": {"type": "EgoState", "normalize": normalize}}
    if env_id == "ego/LaneCentering-v0":
        config["duration"] = 20.0
    env = gym.make(env_id, config=config)
    try:
        obs, _ = env.reset(seed=1)
        assert env.observation_space.contains(obs)
        zero = np.zeros(env.action_space.shape, np.float32)
        while True:
            obs, _, terminated, truncated, info = env.step(zero)
            if info["status"] != "diverged":
                assert env.observation_space.contains(obs), (obs, info["status"])
            if terminated or truncated:
                break
    finally:
        env.close()


# -- 4. the outcome of every episode, and evaluate ---------------------------------------------
OUTCOME = {
    "is_success",
    "collision",
    "collision_avoidable",
    "lane_departure",
    "off_road",
    "completion",
    "termination_reason",
}


def _last_info(env, action, seed=0):
    env.reset(seed=seed)
    while True:
        _, _, terminated, truncated, info = env.step(np.array(action, np.float32))
        if terminated or truncated:
            return info


@pytest.mark.sumo
def test_the_last_info_carries_the_outcome():
    env = gym.make("ego/CutIn-v0", config={"policy_frequency": 10})
    try:
        info = _last_info(env, [0.0, 0.3])  # steered off the road
        assert OUTCOME <= set(info)
        assert info["termination_reason"] == "diverged" and info["off_road"] and not info["is_success"]
        assert not info["collision"] and 0.0 < info["completion"] < 1.0
    finally:
        env.close()
    env = gym.make("ego/EmergencyBrake-v0", config={"policy_frequency": 10, "randomize": {}})
    try:
        info = _last_info(env, [1.0, 0.0])  # full throttle into the braking lead
        assert info["termination_reason"] == "collision" and info["collision"] and not info["is_success"]
        assert info["collision_avoidable"] == info["metrics"]["collision_avoidable"] and not info["off_road"]
        # stopped short of the lead through the whole run: a success, completion 1
        info = _last_info(env, [-1.0, 0.0])  # full braking from the start: stopped, no collision
        assert info["termination_reason"] == "completed" and info["is_success"] and info["completion"] == 1.0
    finally:
        env.close()


@pytest.mark.sumo
def test_a_lane_departure_is_flagged_and_is_no_success():
    # a 0.5 s steer pulse of 0.02 rad and back: the ego's side crosses its lane's marking
    # (max_lane_departure > 0, status failed in the run's result) but stays on the road
    config = {"policy_frequency": 10, "randomize": {}, "lead_decel": 0.5, "lead_final_speed": 19}
    env = gym.make("ego/EmergencyBrake-v0", config=config)
    try:
        for steer, departed in ((0.04, True), (0.0, False)):
            env.reset(seed=0)
            for k in range(1000):
                action = [0.0, steer if k < 5 else (-steer if k < 10 else 0.0)]
                _, _, terminated, truncated, info = env.step(np.array(action, np.float32))
                if terminated or truncated:
                    break
            assert info["lane_departure"] is departed and (info["metrics"]["max_lane_departure"] > 0) is departed
            assert info["is_success"] is not departed and not info["off_road"] and not info["collision"]
            assert info["termination_reason"] == "completed"
    finally:
        env.close()


@pytest.mark.sumo
def test_the_benchmarks_lane_centring_drive_to_its_duration_is_a_success():
    # the benchmark cuts the drive to 30 s, before the road's end, at the scenario's own speed:
    # driven in lane to the duration it ends "ended", a success; steered off, no success
    from ego.gym import evaluate

    report = evaluate("cascade-pid", "ego/LaneCentering-v0", seeds=[1000])
    (row,) = report["per_episode"]
    assert row["termination_reason"] == "ended" and row["is_success"] and row["completion"] == 1.0
    assert report["success_rate"] == 1.0
    off = evaluate(lambda obs: np.array([0.0, 1.0], np.float32), "ego/LaneCentering-v0", seeds=[1000])
    assert off["per_episode"][0]["termination_reason"] != "ended" and off["success_rate"] == 0.0


def test_wilson_and_t_intervals_against_hand_numbers():
    from ego.gym.evaluate import t_interval, wilson

    low, high = wilson(0, 3)  # upper z^2 / (n + z^2)
    assert low == 0.0 and high == pytest.approx(1.959963984540054**2 / (3 + 1.959963984540054**2))
    low, high = wilson(5, 10)  # symmetric about 1/2: 0.5 -+ z sqrt(0.025 + z^2/400) / (1 + z^2/10)
    z = 1.959963984540054
    half = z * np.sqrt(0.025 + z * z / 400) / (1 + z * z / 10)
    assert (low, high) == pytest.approx((0.5 - half, 0.5 + half))
    low, high = t_interval([1.0, 2.0, 3.0])  # t(0.975, 2) = 4.302653, sd 1
    assert (low, high) == pytest.approx((2 - 4.302653 / np.sqrt(3), 2 + 4.302653 / np.sqrt(3)), rel=1e-6)


@pytest.mark.sumo
def test_evaluate_reports_the_rates_and_the_mean_return_with_intervals():
    config = {"policy_frequency": 10}
    report = ego.gym.evaluate("pid", "ego/EmergencyBrake-v0", episodes=3, seeds=[0, 1, 2], config=config)
    rows = report["per_episode"]
    assert report["episodes"] == 3 and [r["seed"] for r in rows] == [0, 1, 2]
    assert report["success_rate"] == sum(r["is_success"] for r in rows) / 3
    assert report["collision_rate"] == sum(r["collision"] for r in rows) / 3
    assert report["mean_return"] == pytest.approx(np.mean([r["return"] for r in rows]))
    for key, value in (("success_interval", "success_rate"), ("collision_interval", "collision_rate")):
        low, high = report[key]
        assert 0.0 <= low <= report[value] <= high <= 1.0
    low, high = report["return_interval"]
    assert low <= report["mean_return"] <= high
    # the same episodes by hand: the returns agree
    env = gym.make("ego/EmergencyBrake-v0", config=config)
    try:
        policy = ego.gym.ControllerPolicy("pid", env.unwrapped)
        obs, _ = env.reset(seed=1)
        total = 0.0
        while True:
            obs, reward, terminated, truncated, _ = env.step(policy(obs))
            total += reward
            if terminated or truncated:
                break
    finally:
        env.close()
    assert rows[1]["return"] == total


def test_evaluate_refuses_bad_episodes():
    from ego.params import ConfigError

    with pytest.raises(ConfigError, match="bad value for episodes: 0"):
        ego.gym.evaluate("pid", "ego/EmergencyBrake-v0", episodes=0)
