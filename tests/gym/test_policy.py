"""Controllers as policies: driving an env with a controller reproduces ``ego run``, and the
behaviour-cloning example runs end to end."""

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ego.gym
from ego.params import ConfigError
from ego.runner import RunSpec, run

ROOT = Path(__file__).resolve().parents[2]
#: what differs between two runs of one spec (``wall_time``) or names the driver
_VARYING = ("wall_time", "controller")


def drive(env_id, controller, seed, config):
    """The final info of one episode driven by ``controller``, with the episode's randomised
    parameters (``randomized``) beside the metrics."""
    env = gym.make(env_id, config=config)
    try:
        policy = ego.gym.ControllerPolicy(controller, env)
        obs, first = env.reset(seed=seed)
        while True:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            if terminated or truncated:
                return {**info, "randomized": first["randomized"]}
    finally:
        env.close()


def same_metrics(a, b):
    return {k: (a[k], b.get(k)) for k in a if k not in _VARYING and a[k] != b.get(k)}


@pytest.mark.sumo
def test_pid_policy_on_emergency_brake_gives_ego_runs_metrics():
    info = drive("ego/EmergencyBrake-v0", "pid", 0, {"action": {"type": "EgoAction"}})
    assert set(info["randomized"]) == set(ego.gym.env.DEFAULT_RANDOMIZE["emergency-brake"])
    # the same episode: the randomised parameters drawn from the seed, as --set values
    reference = run(RunSpec("emergency-brake", "pid", 0, info["randomized"])).metrics
    assert info["metrics"]["controller"] == "agent"
    assert same_metrics(info["metrics"], reference) == {}
    assert info["metrics"]["lane_change_completed"] is True  # the run did something


@pytest.mark.sumo
@pytest.mark.parametrize(
    "env_id, scenario, controller, config",
    [
        # the curve resets its controller when it engages: the policy follows
        ("ego/Curve-v0", "curve", "pid", {}),
        # the first follower is the agent; the others keep the env's pid
        ("ego/Platoon-v0", "platoon", "pid", {"duration": 15.0}),
        # one channel: the agent brakes and drives, the env's pid steers
        ("ego/CutIn-v0", "cut-in", "pid", {"duration": 10.0, "action_channels": "longitudinal"}),
    ],
    ids=["curve", "platoon", "cut-in-longitudinal-only"],
)
def test_policy_reproduces_ego_run(env_id, scenario, controller, config):
    config = dict(config)
    action = {"type": "EgoAction"}
    if config.pop("action_channels", None) == "longitudinal":
        action["lateral"] = False
    info = drive(env_id, controller, 3, {**config, "action": action})
    reference = run(RunSpec(scenario, controller, 3, {**config, **info["randomized"]})).metrics
    assert same_metrics(info["metrics"], reference) == {}


@pytest.mark.sumo
def test_continuous_action_round_trip_within_its_ranges():
    env = gym.make("ego/EmergencyBrake-v0")
    try:
        env.reset(seed=0)
        action_type = env.unwrapped.action_type
        p = env.unwrapped.scenario.ego.model.params
        a = action_type.from_native(p.m * 2.5 / p.Nw, 0.1)
        assert a == pytest.approx(np.array([0.5, 0.1 / (np.pi / 4)]), rel=1e-6)
        lon, lat = action_type.native(a)
        assert lon == pytest.approx(p.m * 2.5 / p.Nw, rel=1e-6) and lat == pytest.approx(0.1, rel=1e-6)
        # beyond the range: clipped to the box
        assert action_type.from_native(1e6, -5.0).tolist() == [1.0, -1.0]
    finally:
        env.close()


def test_policy_needs_the_ego_state_observation():
    env = ego.gym.EgoEnv("cut-in", config={"observation": {"type": "Kinematics"}})
    with pytest.raises(ConfigError, match="needs the EgoState observation"):
        ego.gym.ControllerPolicy("pid", env)
    with pytest.raises(ConfigError, match="unknown controller 'cascade-pid' for the tracking task"):
        ego.gym.ControllerPolicy("cascade-pid", ego.gym.EgoEnv("cut-in"))


@pytest.mark.sumo
@pytest.mark.long
def test_behaviour_cloning_example_runs(tmp_path):
    p = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scenarios" / "behaviour_cloning.py"),
            "--episodes",
            "2",
            "--duration",
            "3",
            "--epochs",
            "5",
        ],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    assert "600 demonstration steps from 2 cascade-pid runs" in p.stdout
    assert "rms_lateral_error" in p.stdout


@pytest.mark.parametrize(
    "task, longitudinal, lateral",
    [("tracking", True, True), ("tracking", True, False), ("tracking", False, True), ("car-following", True, False)],
)
def test_continuous_action_maps_each_channel_onto_its_range(task, longitudinal, lateral):
    from ego.gym.spaces import ContinuousAction

    at = ContinuousAction(
        task, (-1.0, 1.0, 0.5), longitudinal, lateral, acceleration_range=(-6.0, 2.0), steering_range=(-0.4, 0.2)
    )
    at.set_plant(100.0)  # N per m/s^2
    ranges = [r for r, on in zip(((-6.0, 2.0), (-0.4, 0.2)), (longitudinal, lateral)) if on]
    for x in (-3.0, -1.0, -0.25, 0.0, 0.7, 1.0, 2.5, float("nan")):
        action = np.full(at.size, x, dtype=np.float32)
        clipped = x if x != x else min(max(float(np.float32(x)), -1.0), 1.0)
        expect = [lo + (clipped + 1.0) / 2.0 * (hi - lo) for lo, hi in ranges]
        lon, lat = at.native(action)
        got = [v for v in (None if lon is None else lon / 100.0, lat) if v is not None]
        assert (lon is None) == (not longitudinal) and (lat is None) == (not lateral)
        if x != x:
            assert all(v != v for v in got)  # NaN passes through: the env ends the run on it
        else:
            assert got == pytest.approx(expect, abs=1e-12)
