"""A lane change of DiscreteMetaAction's lane actions is a commanded lane change, as the
scenario planner's own is (issue 42, point 5: the run's lane-departure metric counted it as
a departure, so always LANE_LEFT ended 9 of the benchmark's 10 episodes without a collision
and none of them a success). The same motion without the command is still a departure."""

import gymnasium as gym
import numpy as np
import pytest

import ego.gym  # noqa: F401 - registers the ids
from ego.lane_frame import LANE_CHANGE_PHASE

#: one episode with nothing else on the road (the fast follower aside), the planner in lane
#: in both envs (the lane actions' env runs the scenario with evade false itself)
BASE = {"randomize": {}, "traffic_density": 0.0, "evade": False}


def _columns(env) -> dict[str, np.ndarray]:
    trace = env.unwrapped.scenario.trace
    array = trace.array()
    return {name: array[:, i] for i, name in enumerate(trace.names)}


@pytest.mark.sumo
def test_a_lane_action_is_a_commanded_lane_change_and_the_same_motion_uncommanded_is_a_departure():
    meta_env = gym.make(
        "ego/FastFollower-v0", config={**BASE, "action": {"type": "DiscreteMetaAction"}, "policy_frequency": 1}
    )
    replay = gym.make(
        "ego/FastFollower-v0",
        config={**BASE, "action": {"type": "EgoAction"}, "policy_frequency": 0},
        max_episode_steps=10**6,
    )
    try:
        meta_env.reset(seed=0)
        meta, road = meta_env.unwrapped.action_type, meta_env.unwrapped._view.road
        start, index = meta.lane, meta.actions_indexes
        for k in range(10**6):  # LANE_LEFT at the third decision (t = 2 s), IDLE otherwise
            _, _, terminated, truncated, info = meta_env.step(index["LANE_LEFT" if k == 2 else "IDLE"])
            if terminated or truncated:
                break
        assert info["termination_reason"] == "completed" and not info["collision"]
        assert info["lane_departure"] is False and info["metrics"]["max_lane_departure"] == 0.0
        assert info["is_success"]
        col = _columns(meta_env)
        changing = np.flatnonzero(col["phase"] == LANE_CHANGE_PHASE)
        # marked from the decision (t = 2 s) until the ego is within settle_band of the new lane
        assert col["t"][changing[0]] == pytest.approx(2.0) and np.all(np.diff(changing) == 1)
        assert np.all(col["target_lane"][: changing[0]] == start) and np.all(col["target_lane"][changing] == start + 1)
        settled = changing[-1] + 1
        assert abs(col["d"][settled]) < 0.2 <= abs(col["d"][changing[-1]])
        # ended in the left lane's centre: d measured from the lane the agent chose
        assert col["lane_offset"][-1] == pytest.approx(road.lane_offset[start + 1], abs=0.05)
        assert abs(col["d"][-1]) < 0.05

        # the ego's applied commands, replayed one control period each through EgoAction (no
        # lane change commanded): the same motion, now a departure of well over a metre
        replay.reset(seed=0)
        for fx, delta in zip(col["Fx"], col["delta"], strict=True):
            _, _, terminated, truncated, again = replay.step(np.array([fx, delta]))
            if terminated or truncated:
                break
        assert _columns(replay)["lane_offset"][-1] == col["lane_offset"][-1]  # the same motion, to the bit
        assert again["lane_departure"] is True and again["metrics"]["max_lane_departure"] > 1.0
        assert not again["is_success"]
    finally:
        meta_env.close()
        replay.close()


@pytest.mark.sumo
def test_the_lane_actions_leave_the_lane_to_the_agent_not_the_planner():
    # the scenario's planner would move the view's target lane itself: with the lane actions
    # it brakes (or speeds up) in lane instead; with the speed actions alone it evades as before
    lanes = gym.make("ego/EmergencyBrake-v0", config={"action": {"type": "DiscreteMetaAction"}})
    speeds = gym.make("ego/EmergencyBrake-v0", config={"action": {"type": "DiscreteMetaAction", "lateral": False}})
    try:
        lanes.reset(seed=0)  # a randomised episode: its scenario is made again at the reset
        assert lanes.unwrapped.scenario.config.evade is False and speeds.unwrapped.scenario.config.evade is True
    finally:
        lanes.close()
        speeds.close()
