"""``ego/Scenario-v0``: a built-in scenario or an OpenSCENARIO file as an env, with the same
spaces, the standard checkers silent, determinism per seed, randomisation over a file's
declared parameters, the outcome flags, and one-line errors for a bad scenario."""

import pickle
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ego.gym
from ego.params import ConfigError
from ego.runner import RunSpec, run

ROOT = Path(__file__).resolve().parents[2]
CCRB = str(ROOT / "scenarios/openscenario/ccrb.xosc")
#: the file's declared EgoSpeed (13.889 m/s) and LeadGap (12 m) drawn at every reset
CCRB_RANDOM = {"EgoSpeed": [8.0, 20.0], "LeadGap": [12.0, 40.0]}
CONFIGS = {
    "built-in": {"scenario": "cut-in", "policy_frequency": 10},
    "xosc": {"scenario": CCRB, "policy_frequency": 10, "randomize": CCRB_RANDOM},
}


def _episode(env, seed, steps=60):
    """Observations, rewards and the reset's info of ``steps`` env steps under actions drawn
    from a generator of their own (the same for every call)."""
    rng = np.random.default_rng(7)
    obs, info = env.reset(seed=seed)
    out = [obs.copy()]
    for _ in range(steps):
        action = rng.uniform(-0.3, 0.3, env.action_space.shape).astype(np.float32)
        obs, reward, terminated, truncated, _ = env.step(action)
        out.append((obs.copy(), reward))
        if terminated or truncated:
            break
    return out, info


@pytest.mark.sumo
@pytest.mark.parametrize("kind", CONFIGS)
def test_the_checkers_are_silent(kind):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("ego/Scenario-v0", config=CONFIGS[kind])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # any warning fails the test
            check_env(env.unwrapped, skip_render_check=True)
            sb3_check_env(env.unwrapped, warn=True)
    finally:
        env.close()


@pytest.mark.sumo
def test_the_same_spaces_as_the_scenarios_own_id_and_the_same_episodes():
    own = gym.make("ego/CutIn-v0", config={"policy_frequency": 10})
    env = gym.make("ego/Scenario-v0", config=CONFIGS["built-in"])
    try:
        assert env.observation_space == own.observation_space and env.action_space == own.action_space
        assert env.unwrapped.config["randomize"] == own.unwrapped.config["randomize"]
        mine, theirs = _episode(env, 4), _episode(own, 4)
    finally:
        env.close()
        own.close()
    assert mine[1] == theirs[1]  # the randomised parameters
    for a, b in zip(mine[0][1:], theirs[0][1:], strict=True):
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]


@pytest.mark.sumo
def test_a_file_env_is_deterministic_per_seed_and_randomises_its_declared_parameters():
    env = gym.make("ego/Scenario-v0", config=CONFIGS["xosc"])
    try:
        assert env.unwrapped.declared_parameters["EgoSpeed"] == 13.889
        first, info = _episode(env, 5)
        again, info_again = _episode(env, 5)
        other, info_other = _episode(env, 6)
    finally:
        env.close()
    assert set(info["randomized"]) == set(CCRB_RANDOM) and info == info_again
    assert 8.0 <= info["randomized"]["EgoSpeed"] <= 20.0 and 12.0 <= info["randomized"]["LeadGap"] <= 40.0
    assert info_other["randomized"] != info["randomized"]
    assert np.array_equal(first[0], again[0]) and not np.array_equal(first[0], other[0])
    for a, b in zip(first[1:], again[1:], strict=True):
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]


@pytest.mark.sumo
def test_a_file_env_driven_by_pid_is_ego_run_of_the_file_with_the_drawn_parameters():
    config = {"scenario": CCRB, "action": {"type": "EgoAction"}, "randomize": CCRB_RANDOM, "duration": 8.0}
    env = gym.make("ego/Scenario-v0", config=config)
    try:
        policy = ego.gym.ControllerPolicy("pid", env)
        obs, first = env.reset(seed=2)
        while True:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            if terminated or truncated:
                break
    finally:
        env.close()
    reference = run(RunSpec(CCRB, "pid", 2, {"duration": 8.0, **first["randomized"]})).metrics
    differ = {k: (v, reference.get(k)) for k, v in info["metrics"].items() if k not in ("wall_time", "controller")}
    assert {k: v for k, v in differ.items() if v[0] != v[1]} == {}
    outcome = {"is_success", "collision", "collision_avoidable", "lane_departure", "off_road", "completion"}
    assert outcome <= set(info) and info["termination_reason"] == info["status"]
    failed = info["collision"] or info["status"] in ("diverged", "error") or info["lane_departure"]
    assert info["is_success"] is (not failed) and info["metrics"]["steps"] > 100


@pytest.mark.sumo
def test_a_file_env_pickles_mid_episode():
    env = gym.make("ego/Scenario-v0", config=CONFIGS["xosc"])
    try:
        env.reset(seed=1)
        action = np.array([0.2, 0.0], np.float32)
        for _ in range(10):
            env.step(action)
        copy = pickle.loads(pickle.dumps(env))
        try:
            for _ in range(10):
                a, b = env.step(action), copy.step(action)
                assert np.array_equal(a[0], b[0]) and a[1] == b[1]
        finally:
            copy.close()
    finally:
        env.close()


@pytest.mark.parametrize(
    "config, message",
    [
        ({}, "missing config key scenario (expected a scenario of ego list with traffic (emergency-brake"),
        ({"scenario": "cut_in"}, "bad value for scenario: 'cut_in' (expected a scenario of ego list with traffic"),
        ({"scenario": "report-000"}, "bad value for scenario: 'report-000' runs no traffic simulator"),
        (
            {"scenario": "missing.xosc"},
            "bad value for scenario: 'missing.xosc' is not a file (expected a scenario of ego list with traffic",
        ),
        ({"scenario": 3}, "bad value for scenario: 3 (expected a scenario of ego list"),
        ({"scenario": CCRB, "randomize": {"evade": [0, 1]}}, "bad value for randomize[evade]: evade is not a number"),
        ({"scenario": CCRB, "randomize": {"EgoSpeed": [-5.0, 2.0]}}, "bad value for randomize: its low corner"),
    ],
    ids=["missing", "unknown", "no-traffic", "no-file", "not-a-name", "not-a-number", "bad-corner"],
)
def test_a_bad_scenario_is_a_one_line_error(config, message):
    with pytest.raises(ConfigError) as exc:
        gym.make("ego/Scenario-v0", config=config)
    text = str(exc.value)
    assert text.startswith(message) and "\n" not in text
    if config.get("scenario") == "cut_in":
        assert text.endswith("did you mean 'cut-in'?")


def test_the_scenario_is_fixed_when_the_env_is_made():
    env = gym.make("ego/Scenario-v0", config={"scenario": "curve"})
    with pytest.raises(ConfigError, match="the scenario is fixed when the env is made, here 'curve'"):
        env.reset(options={"config": {"scenario": "cut-in"}})
    assert env.unwrapped.config["scenario"] == "curve"  # taken back
    assert ego.gym.ScenarioEnv.default_config(CCRB)["randomize"] == {}  # a file as written


@pytest.mark.sumo
def test_make_vec_of_a_file_env():
    envs = gym.make_vec("ego/Scenario-v0", num_envs=2, config={"scenario": CCRB, "policy_frequency": 10})
    try:
        obs, _ = envs.reset(seed=0)
        assert obs.shape == (2, *envs.single_observation_space.shape)
        obs, reward, *_ = envs.step(np.zeros((2, 2), np.float32))
        assert np.isfinite(reward).all()
    finally:
        envs.close()


# -- an OpenSCENARIO ParameterValueDistribution file ---------------------------------------------
def _distribution(tmp_path, body: str, target: str | None = None) -> str:
    """A ParameterValueDistribution file in ``tmp_path`` over ``target`` (default: ccrb.xosc,
    named relative to the distribution file) with ``body`` after the ScenarioFile."""
    import os

    target = os.path.relpath(CCRB, tmp_path) if target is None else target
    path = tmp_path / "distribution.xosc"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenSCENARIO>\n'
        '  <FileHeader revMajor="1" revMinor="2" date="2026-11-28T00:00:00" description="d" author="ego"/>\n'
        f'  <ParameterValueDistribution>\n    <ScenarioFile filepath="{target}"/>\n{body}\n'
        "  </ParameterValueDistribution>\n</OpenSCENARIO>\n"
    )
    return str(path)


def _uniform(name: str, low: str, high: str) -> str:
    return (
        f'      <StochasticDistribution parameterName="{name}">\n'
        f'        <UniformDistribution><Range lowerLimit="{low}" upperLimit="{high}"/></UniformDistribution>\n'
        "      </StochasticDistribution>"
    )


@pytest.mark.sumo
def test_a_distribution_file_is_its_scenario_randomised_over_its_uniform_ranges(tmp_path):
    body = f'    <Stochastic numberOfTestRuns="5" randomSeed="1">\n{_uniform("EgoSpeed", "8", "20")}\n{_uniform("LeadGap", "12", "40")}\n    </Stochastic>'
    path = _distribution(tmp_path, body)
    env = gym.make("ego/Scenario-v0", config={"scenario": path, "policy_frequency": 10})
    plain = gym.make("ego/Scenario-v0", config=CONFIGS["xosc"])  # the same ranges in the config
    try:
        u = env.unwrapped
        assert u.scenario_name == str(Path(CCRB)) and u.source == path and u.config["scenario"] == path
        assert u.config["randomize"] == u.default_config()["randomize"] == CCRB_RANDOM
        mine, theirs = _episode(env, 5, steps=20), _episode(plain, 5, steps=20)
        copy = pickle.loads(pickle.dumps(env))  # mid-episode: rebuilt from the distribution file
        copy.close()
    finally:
        env.close()
        plain.close()
    assert mine[1]["randomized"] == theirs[1]["randomized"]
    for a, b in zip(mine[0][1:], theirs[0][1:], strict=True):
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]


@pytest.mark.parametrize(
    "body, message",
    [
        (
            "    <Deterministic/>",
            ":6: <Deterministic> is not supported by ego's environments (a <Stochastic> one is)",
        ),
        (
            '    <Stochastic numberOfTestRuns="5" randomSeed="1">\n      <StochasticDistribution parameterName="EgoSpeed">\n'
            '        <NormalDistribution expectedValue="10" variance="1"/>\n      </StochasticDistribution>\n    </Stochastic>',
            ":7: <NormalDistribution> of 'EgoSpeed' is not supported by ego's environments",
        ),
        (
            f'    <Stochastic numberOfTestRuns="5" randomSeed="1">\n{_uniform("Speed", "8", "20")}\n    </Stochastic>',
            ":7: parameter 'Speed' is not one of",
        ),
    ],
    ids=["deterministic", "normal", "unknown-parameter"],
)
def test_a_distribution_ego_cannot_draw_is_one_line_with_its_line(tmp_path, body, message):
    path = _distribution(tmp_path, body)
    with pytest.raises(ConfigError) as exc:
        gym.make("ego/Scenario-v0", config={"scenario": path})
    text = str(exc.value)
    assert text.startswith(path + message) and "\n" not in text
