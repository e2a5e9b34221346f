"""The defects an RL user hit (issue 22), each reproduced and fixed: vectorisation by default
and several SUMO in one process, ControllerPolicy at policy_frequency > 0, NaN and badly
shaped actions, pickling, TimeLimit's metrics, randomised episodes and normalised
observations, render_fps and the agent's colour, and the status list of docs/gym.md."""

import pickle
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ego.gym
from ego.gym.env import DEFAULT_RANDOMIZE
from ego.params import ConfigError
from ego.requirements import METRIC_KEYS
from ego.runner import RunSpec, run
from ego.scenarios.base import STATUSES

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


@pytest.fixture
def make():
    made = []

    def _make(env_id, **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield _make
    for env in made:
        env.close()


# -- 1. vectorisation --------------------------------------------------------------------------
@pytest.mark.sumo
def test_sync_envs_in_one_process_with_multi_instance_false_name_the_cause():
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, vectorization_mode="sync", config={"multi_instance": False})
    try:
        envs.reset(seed=0)
        with pytest.raises(RuntimeError, match="multi_instance=False: libsumo runs one simulation per process"):
            envs.step(envs.action_space.sample())
    finally:
        envs.close()


@pytest.mark.sumo
def test_multi_instance_runs_a_second_sumo_through_traci_with_the_same_episode(make):
    config = {"multi_instance": True, "policy_frequency": 0}  # 150 steps: 1.5 s
    first = make("ego/CutIn-v0", config=config)
    second = make("ego/CutIn-v0", config=config)
    a, _ = first.reset(seed=5)
    b, _ = second.reset(seed=5)
    assert not first.unwrapped.scenario.bridge.via_traci and second.unwrapped.scenario.bridge.via_traci
    assert np.array_equal(a, b)
    actions = [np.array([0.2, 0.01 * (k % 5)], dtype=np.float32) for k in range(150)]
    for action in actions:  # interleaved: both simulations live in this process
        a, ra, *_ = first.step(action)
        b, rb, *_ = second.step(action)  # same reward too
    assert np.array_equal(a, b) and ra == rb


@pytest.mark.sumo
def test_an_env_made_with_multi_instance_false_does_not_end_one_made_with_it(make):
    """The multi_instance env chose to share the process: a later one-per-process env runs
    through TraCI, with a warning, instead of ending it."""
    shared = make("ego/CutIn-v0", config={"multi_instance": True})
    plain = make("ego/CutIn-v0", config={"multi_instance": False})
    a, _ = shared.reset(seed=5)
    with pytest.warns(UserWarning, match="multi_instance=True runs its SUMO through libsumo"):
        b, _ = plain.reset(seed=5)
    assert plain.unwrapped.scenario.bridge.via_traci and np.array_equal(a, b)
    action = np.array([0.2, 0.0], dtype=np.float32)
    a, *_ = shared.step(action)
    b, *_ = plain.step(action)
    assert np.array_equal(a, b)


# -- 2. ControllerPolicy at policy_frequency > 0 ----------------------------------------------
@pytest.mark.sumo
@pytest.mark.parametrize(
    "env_id, scenario, controller, config",
    [
        ("ego/LaneCentering-v0", "lane-centering", "cascade-pid", {"duration": 30.0}),
        ("ego/Curve-v0", "curve", "pid", {}),
        ("ego/Platoon-v0", "platoon", "pid", {"duration": 20.0}),
    ],
    ids=["lane-centering", "curve", "platoon"],
)
@pytest.mark.parametrize("policy_frequency", [0, 10])
def test_controller_policy_gives_the_controllers_metrics_at_any_policy_frequency(
    env_id, scenario, controller, config, policy_frequency, make
):
    # at 100 Hz the registered TimeLimit (the benchmark's 10 Hz steps) would cut the run
    limit = {} if policy_frequency else {"max_episode_steps": 10**6}
    env = make(env_id, config={**config, "policy_frequency": policy_frequency}, **limit)
    policy = ego.gym.ControllerPolicy(controller, env)
    obs, first = env.reset(seed=2)
    steps = 0
    while True:
        obs, _, terminated, truncated, info = env.step(policy(obs))
        steps += 1
        if terminated or truncated:
            break
    env.close()  # libsumo: one simulation per process
    reference = run(RunSpec(scenario, controller, 2, {**config, **first["randomized"]})).metrics
    for key, value in reference.items():
        if key in ("wall_time", "controller", *METRIC_KEYS):  # ego run evaluates requirements; an env does not
            continue
        if isinstance(value, float):
            assert info["metrics"][key] == pytest.approx(value, rel=1e-9, abs=1e-9), key
        else:
            assert info["metrics"][key] == value, key
    if policy_frequency:
        assert steps == pytest.approx(reference["steps"] / 10, abs=1)


# -- 3. NaN and badly shaped actions -----------------------------------------------------------
@pytest.mark.sumo
@pytest.mark.parametrize("env_id", ["ego/CutIn-v0", "ego/Platoon-v0"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_nan_action_ends_the_episode_diverged_with_a_finite_reward(env_id, value, make):
    """NaN and infinities alike (the default ContinuousAction clips only finite values)."""
    env = make(env_id)
    env.reset(seed=0)
    nan = np.full(env.action_space.shape, value, dtype=np.float32)
    obs, reward, terminated, truncated, info = env.step(nan)
    assert np.isfinite(reward) and reward < 0.0 and np.all(np.isfinite(obs))
    assert terminated and not truncated and info["status"] == "diverged"
    assert "not finite" in info["status_detail"] and info["metrics"]["status"] == "diverged"


@pytest.mark.sumo
@pytest.mark.parametrize(
    "action",
    [np.zeros((1, 1)), 0.5, [0.1, 0.2, 0.3], "left", None, np.array([1 + 2j, 0.0])],
    ids=["(1,1)", "scalar", "three", "string", "none", "complex"],
)
@pytest.mark.parametrize("action_type", ["ContinuousAction", "EgoAction"])
def test_a_badly_shaped_action_names_the_expected_shape(action, action_type, make):
    """The action as given (None is not shown as the nan it converts to) and what the space
    takes; complex numbers are refused (they reached the model's comparisons: a TypeError)."""
    env = make("ego/CutIn-v0", config={"action": {"type": action_type}})
    env.reset(seed=0)
    with pytest.raises(ValueError) as err:
        env.step(action)
    text = str(err.value)
    assert text.startswith(f"bad action {action!r}"[:40])
    assert f"expected real numbers in an array of shape (2,) ({action_type}: [longitudinal, steering])" in text


# -- 4. pickling --------------------------------------------------------------------------------
@pytest.mark.sumo
def test_pickle_before_and_after_reset_continues_the_same_episode(make):
    env = make("ego/CutIn-v0", config={"policy_frequency": 10})
    fresh = pickle.loads(pickle.dumps(env))  # before reset
    assert fresh.unwrapped.config == env.unwrapped.config
    env.reset(seed=3)
    actions = [np.array([0.3, -0.02], dtype=np.float32)] * 8
    for a in actions[:4]:
        env.step(a)
    blob = pickle.dumps(env)  # mid-episode
    tail = [env.step(a) for a in actions[4:]]
    copy = pickle.loads(blob)  # replays the episode's commands in a new SUMO (this one ends)
    try:
        again = [copy.step(a) for a in actions[4:]]
        assert all(np.array_equal(x[0], y[0]) and x[1] == y[1] for x, y in zip(tail, again))
    finally:
        copy.close()
        fresh.close()


# -- 5. TimeLimit keeps the metrics --------------------------------------------------------------
@pytest.mark.sumo
def test_time_limit_truncation_carries_the_runs_metrics(make):
    # a run longer than the registered max_episode_steps (900 at 10 Hz): gym.make's TimeLimit
    # ends it, after 9000 control steps
    env = make("ego/Platoon-v0", config={"duration": 200.0, "randomize": {}, "manoeuvres": "none"})
    assert env.spec.max_episode_steps == 900
    env.reset(seed=0)
    hold = np.zeros(1, dtype=np.float32)
    for _ in range(900):
        _, _, terminated, truncated, info = env.step(hold)
        if terminated or truncated:
            break
    assert truncated and not terminated and info["status"] == "running"
    assert info["metrics"]["steps"] == 9000 and "max_episode_steps (900)" in info["status_detail"]
    assert env.unwrapped.metrics()["steps"] == 9000


def test_every_spec_has_max_episode_steps_and_a_vector_entry_point():
    """max_episode_steps is the benchmark's whole run: its duration at 10 env steps a second."""
    from ego.scenarios import scenario_class

    for env_id, name in ego.gym.ENV_IDS.items():
        spec = gym.spec(env_id)
        duration = ego.gym.BENCHMARK[env_id].get("duration", scenario_class(name).config_cls().duration)
        assert spec.max_episode_steps == round(10 * duration) >= 200
        assert spec.vector_entry_point == "ego.gym.vector:make_vector"


# -- 6. randomised episodes, normalised observations ---------------------------------------------
@pytest.mark.sumo
@pytest.mark.parametrize("env_id", list(ego.gym.ENV_IDS))
def test_each_env_is_a_distribution_reproducible_per_seed(env_id, make):
    env = make(env_id)
    drawn = [env.reset(seed=s)[1]["randomized"] for s in (0, 1, 0)]
    assert drawn[0] == drawn[2] != drawn[1]
    scenario = ego.gym.ENV_IDS[env_id]
    for name, (lo, hi) in DEFAULT_RANDOMIZE[scenario].items():
        assert lo <= drawn[1][name] <= hi
        assert getattr(env.unwrapped.scenario.config, name) == drawn[0][name]


@pytest.mark.sumo
def test_seeds_beyond_2_31_are_folded_into_a_run_seed_and_reproducible(make):
    """Gymnasium takes any non-negative seed and SB3's VecEnv.seed() draws below 2^32; the
    run's seed is the seed itself up to 2^31 - 1 (ego run --seed), a larger one folded."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from ego.gym.env import run_seed_of

    assert run_seed_of(7) == 7 and run_seed_of(np.int64(2**31 - 1)) == 2**31 - 1
    assert 0 <= run_seed_of(2**31) <= 2**31 - 1 and run_seed_of(2**31) != run_seed_of(2**32 - 1)
    env = make("ego/CutIn-v0")
    a, _ = env.reset(seed=2**40)
    seed = env.unwrapped.scenario.seed
    b, _ = env.reset(seed=2**40)
    assert np.array_equal(a, b) and seed == env.unwrapped.scenario.seed == run_seed_of(2**40)
    vec = DummyVecEnv([lambda: make("ego/Platoon-v0")])
    vec.seed(2**32 - 5)
    assert vec.reset().shape == (1, 10)


@pytest.mark.sumo
def test_the_seed_changes_the_controllers_return(make):
    env = make("ego/CutIn-v0", config={"duration": 8.0, "policy_frequency": 10})
    policy = ego.gym.ControllerPolicy("pid", env)
    returns = []
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        total = 0.0
        while True:
            obs, reward, terminated, truncated, _ = env.step(policy(obs))
            total += reward
            if terminated or truncated:
                break
        returns.append(total)
    assert len(set(returns)) == 3


@pytest.mark.parametrize(
    "randomize, message",
    [
        ({"ego_speed": [20, 100]}, "bad value for ego_speed: 100"),
        ({"ego_sped": [20, 30]}, "unknown parameter 'ego_sped'"),
        ({"ego_speed": [30, 20]}, r"randomize\[ego_speed\].*low <= high"),
        ({"cut_in_side": [0, 1]}, r"randomize\[cut_in_side\]: cut_in_side is not a number"),
        ("wide", "bad value for randomize: 'wide'"),
        ({"dt": [0.01, 0.02]}, r"randomize\[dt\]: the control period and SUMO's step cannot vary"),
    ],
    ids=["range", "unknown", "order", "not-a-number", "not-a-dict", "dt"],
)
def test_bad_randomize_is_one_line_config_error(randomize, message):
    with pytest.raises(ConfigError, match=message) as err:
        ego.gym.EgoEnv("cut-in", config={"randomize": randomize})
    assert "\n" not in str(err.value)


@pytest.mark.sumo
@pytest.mark.parametrize("env_id, tracks", [("ego/LaneCentering-v0", False), ("ego/CutIn-v0", True)])
def test_ego_state_is_normalised_by_default_and_raw_on_request(env_id, tracks, make):
    env = make(env_id, config={"randomize": {}, "policy_frequency": 0})  # 100 steps: 1 s
    raw = make(
        env_id,
        config={
            "randomize": {},
            "policy_frequency": 0,
            "multi_instance": True,
            "observation": {"type": "EgoState", "normalize": False},
        },
    )
    a, _ = env.reset(seed=0)
    b0, _ = raw.reset(seed=0)
    names = env.unwrapped.observation_type.names
    t, s, s_ref = names.index("t"), names.index("s"), names.index("s_ref")
    duration = env.unwrapped.scenario.config.duration
    for _ in range(100):
        a, *_ = env.step(np.zeros(2, dtype=np.float32))
        b, *_ = raw.step(np.zeros(2, dtype=np.float32))
    assert a[t] == pytest.approx(b[t] / duration) == pytest.approx(1.0 / duration)
    if tracks:  # the station error and the reference's progress
        assert b[s] > 300.0 and a[s] == pytest.approx(b[s] - b[s_ref])
        assert a[s_ref] == pytest.approx((b[s_ref] - b0[s_ref]) / (b0[names.index("ds_ref")] * duration))
    else:  # the ego's progress
        assert a[s] == pytest.approx((b[s] - b0[s]) / (b0[names.index("ds")] * duration))
    assert 0.0 < a[s] < 0.01 or abs(a[s]) < 1.0
    others = [i for i in range(len(names)) if i not in (t, s, s_ref)]
    assert np.array_equal(a[others], b[others])


# -- 7. rendering --------------------------------------------------------------------------------
def test_render_fps_is_the_env_step_rate():
    assert ego.gym.EgoEnv("cut-in").metadata["render_fps"] == 100.0
    assert ego.gym.EgoEnv("cut-in", config={"policy_frequency": 10}).metadata["render_fps"] == 10.0
    assert ego.gym.EgoEnv("cut-in", config={"policy_frequency": 20, "dt": 0.005}).metadata["render_fps"] == 20.0


@pytest.mark.sumo
def test_the_platoon_frame_shows_the_agents_car_in_its_own_colour(make):
    env = make("ego/Platoon-v0", render_mode="rgb_array", config={"randomize": {}})
    env.reset(seed=0)
    frame = env.render()
    colours = {tuple(c) for c in frame.reshape(-1, 3)}
    green = (int(0.1 * 255), int(0.85 * 255), int(0.3 * 255))
    assert any(max(abs(int(x) - y) for x, y in zip(c, green)) <= 2 for c in colours)  # the agent
    assert (220, 40, 40) in colours  # the other followers


@pytest.mark.sumo
def test_record_video_writes_an_mp4_without_a_system_ffmpeg(tmp_path, monkeypatch):
    import imageio_ffmpeg

    monkeypatch.setenv("PATH", "/nonexistent")
    env = gym.wrappers.RecordVideo(
        gym.make(
            "ego/CutIn-v0",
            render_mode="rgb_array",
            config={"policy_frequency": 10, "duration": 2.0, "screen_width": 160, "screen_height": 64},
        ),
        str(tmp_path),
        disable_logger=True,
    )
    try:
        env.reset(seed=0)
        while True:
            *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    (video,) = tmp_path.glob("*.mp4")
    reader = imageio_ffmpeg.read_frames(str(video))
    meta = next(reader)
    assert meta["fps"] == 10.0 and len(list(reader)) == 21  # t = 0 and 20 steps of 0.1 s


def test_docs_status_list_names_every_status():
    text = (ROOT / "docs" / "gym.md").read_text()
    line = next(x for x in text.splitlines() if "`info`: `status`" in x)
    for status in ("running", *STATUSES):
        assert f"`{status}`" in line or f"`{status}`" in text.split("`info`: `status`")[1][:600], status


# -- highway-env's action and observation types ---------------------------------------------------
@pytest.mark.sumo
def test_discrete_meta_actions_change_lane_and_speed_through_the_controller(make):
    env = make(
        "ego/FastFollower-v0",
        config={
            "action": {"type": "DiscreteMetaAction"},
            "randomize": {},
            "policy_frequency": 1,
            "traffic_density": 0.0,
        },
    )
    env.reset(seed=0)
    u = env.unwrapped
    meta, road = u.action_type, u._view.road  # the composed scenario's road state (its view)
    assert meta.actions == {0: "LANE_LEFT", 1: "IDLE", 2: "LANE_RIGHT", 3: "FASTER", 4: "SLOWER"}
    start_lane, offsets = meta.lane, road.lane_offset
    env.step(meta.actions_indexes["LANE_LEFT"])
    for _ in range(7):
        env.step(meta.actions_indexes["IDLE"])
    assert meta.lane == start_lane + 1
    assert road.d_road == pytest.approx(offsets[start_lane + 1], abs=0.3)  # the pid steered across
    env.step(meta.actions_indexes["FASTER"])
    for _ in range(4):
        env.step(meta.actions_indexes["IDLE"])
    assert u._view.obs.ds == pytest.approx(meta.target_speeds[meta.speed_index], abs=1.0)
    with pytest.raises(ValueError, match=r"expected an integer from 0 to 4 \(DiscreteMetaAction: 0 LANE_LEFT"):
        env.step(7)


def test_discrete_meta_action_needs_lanes():
    with pytest.raises(ConfigError, match="DiscreteMetaAction needs lanes"):
        ego.gym.EgoEnv("curve", config={"action": {"type": "DiscreteMetaAction"}})


@pytest.mark.sumo
def test_time_to_collision_and_occupancy_grid_see_the_lead_car(make):
    env = make(
        "ego/EmergencyBrake-v0",
        config={
            "randomize": {},
            "traffic_density": 0.0,
            "policy_frequency": 0,
            "observation": {"type": "TimeToCollision"},
        },
    )
    env.reset(seed=0)
    for _ in range(300):  # the lead brakes at 2 s: closing in the ego's own lane
        obs, *_ = env.step(np.zeros(2, dtype=np.float32))
    assert obs.shape == (3, 3, 10) and obs[:, 1, :].sum() >= 1.0  # own lane: a predicted collision
    faster, now = obs[2, 1].argmax(), obs[1, 1].argmax()
    assert faster <= now  # faster: sooner
    grid = make(
        "ego/EmergencyBrake-v0",
        config={
            "randomize": {},
            "traffic_density": 0.0,
            "multi_instance": True,
            "lead_gap": 12.0,
            "observation": {"type": "OccupancyGrid"},
        },
    )
    g, _ = grid.reset(seed=0)
    presence = g[0]
    assert g.shape == (4, 11, 11) and presence.sum() >= 1.0
    ix, iy = np.argwhere(presence == 1.0)[0]
    assert ix > 5 and iy == 5  # ahead, in the ego's own lane (the centre column)


def test_reward_threshold_is_the_default_controllers_mean_return_in_the_registered_env():
    """The threshold is of returns in the env gym.make(id) makes, which is the benchmark's
    setting (10 Hz, the lane-centring drive cut to 30 s): the rl-thresholds table of the
    baselines page, and the default controller's row of the env's own table."""
    from ego.docs import RL_TABLES, block, page_path
    from ego.scenarios import scenario_class

    page = page_path("rl-baselines").read_text()
    text = block(page, "rl-thresholds")
    for env_id, table in RL_TABLES.items():
        controller = scenario_class(ego.gym.ENV_IDS[env_id]).reference_controller()
        row = next(line for line in text.splitlines() if line.startswith(f"| {env_id} ({controller}) |"))
        assert gym.spec(env_id).reward_threshold == float(row.split(" | ")[1]), env_id
        own = next(line for line in block(page, table).splitlines() if line.startswith(f"| {controller} |"))
        assert float(own.split(" | ")[1]) == gym.spec(env_id).reward_threshold, env_id
        env = gym.make(env_id)
        assert env.unwrapped.config["policy_frequency"] == 10  # the env the tables ran
        assert env.unwrapped.config["duration"] == ego.gym.BENCHMARK[env_id].get(
            "duration", env.unwrapped.config["duration"]
        )
        env.close()


@pytest.mark.sumo
def test_the_100_hz_form_is_one_key_away_and_a_short_time_limit_is_named(make):
    """config={"policy_frequency": 0} steps every control period; the registered TimeLimit
    (the benchmark's 250 steps) then ends the run at 2.5 s, and the last info says so and
    which max_episode_steps keeps the whole run; given that, the env runs on past 250 steps
    (the env reads the TimeLimit gym.make put around it)."""
    hold = np.zeros(2, dtype=np.float32)
    env = make("ego/EmergencyBrake-v0", config={"policy_frequency": 0, "randomize": {}})
    assert env.unwrapped.config["policy_frequency"] == 0
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(hold)
        steps += 1
        if terminated or truncated:
            break
    assert truncated and steps == 250 and info["metrics"]["steps"] == 250
    assert "at 2.5 s of the run's 25 s" in info["status_detail"]
    assert "max_episode_steps=2500) keeps the whole run" in info["status_detail"]
    env = make(
        "ego/EmergencyBrake-v0",
        config={"policy_frequency": 0, "randomize": {}, "multi_instance": True},
        max_episode_steps=2500,
    )
    env.reset(seed=0)
    for k in range(1, 301):
        _, _, terminated, truncated, info = env.step(hold)
        assert not (terminated or truncated) and "status_detail" not in info, k
    assert env.unwrapped.scenario.t == pytest.approx(3.0) and env.unwrapped._fast_step is not None


@pytest.mark.sumo
def test_a_parameter_set_to_its_own_value_is_left_out_of_the_default_randomisation(make):
    env = make("ego/EmergencyBrake-v0", config={"ego_speed": 30.0})
    _, info = env.reset(seed=0)
    assert "ego_speed" not in info["randomized"] and "lead_gap" in info["randomized"]
    assert env.unwrapped.scenario.config.ego_speed == 30.0
    env.reset(seed=0, options={"config": {"lead_gap": 33.0}})
    assert env.unwrapped.scenario.config.lead_gap == 33.0 and "lead_gap" not in env.unwrapped.randomized
    # a randomize given in the config draws what it names, over a plain value
    env.reset(seed=0, options={"config": {"randomize": {"ego_speed": [20, 22]}}})
    assert set(env.unwrapped.randomized) == {"ego_speed"} and 20 <= env.unwrapped.scenario.config.ego_speed <= 22


@pytest.mark.sumo
def test_the_lanes_that_exist_follow_the_ego_and_the_road(make):
    """TimeToCollision marks a lane that is not there as 1 throughout, seen from where the
    ego is now (after a change into the leftmost lane its left is off the road), on any road
    (the curve: no lane to its right, the oncoming lane to its left); OccupancyGrid's on_road
    covers every lane (the curve's oncoming one too)."""
    env = make(
        "ego/FastFollower-v0",
        config={
            "action": {"type": "DiscreteMetaAction"},
            "observation": {"type": "TimeToCollision"},
            "randomize": {},
            "policy_frequency": 1,
            "traffic_density": 0.0,
        },
    )
    obs, _ = env.reset(seed=0)
    meta = env.unwrapped.action_type
    assert meta.lane == 1 and not obs[:, 2, :].all() and not obs[:, 0, :].all()  # the middle lane
    env.step(meta.actions_indexes["LANE_LEFT"])
    for _ in range(7):
        obs, *_ = env.step(meta.actions_indexes["IDLE"])
    assert meta.lane == 2 and obs[:, 2, :].all() and not obs[:, 0, :].all()  # the leftmost
    curve = make("ego/Curve-v0", config={"multi_instance": True, "observation": {"type": "TimeToCollision"}})
    obs, _ = curve.reset(seed=0)
    assert obs[:, 0, :].all() and not obs[:, 2, :].all()  # no lane to the right; the oncoming one
    grid = make("ego/Curve-v0", config={"multi_instance": True, "observation": {"type": "OccupancyGrid"}})
    g, _ = grid.reset(seed=0)
    on_road = g[grid.unwrapped.observation_type.features.index("on_road"), 0]
    assert on_road[5] == 1.0 and on_road[6] == 1.0 and on_road[4] == 0.0  # own, oncoming, right of it
