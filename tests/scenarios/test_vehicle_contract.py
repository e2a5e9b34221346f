"""One contract for every task: the controlled vehicles by id. A front-end driving one vehicle
(ego.gym) reads the same methods of a single-ego scenario and of the platoon."""

import pytest

from ego.runner import RunSpec, build


@pytest.mark.sumo
@pytest.mark.parametrize("scenario, controller", [("emergency-brake", "pid"), ("platoon", "pid")])
def test_the_agent_s_vehicle_through_one_contract(scenario, controller):
    sc = build(RunSpec(scenario, controller, 0, {"duration": "2"}))
    try:
        sc.reset()
        vid = sc.agent_id
        assert vid == sc.controlled_ids[0]
        obs, plant = sc.observation(vid), sc.plant(vid)
        speed, error, _, _ = sc.agent_signals(vid)
        assert speed == pytest.approx(obs.ds if scenario != "platoon" else obs.speed)
        assert plant.speed == pytest.approx(speed, abs=0.5)
        ego, rows, length = sc.lane_rows(vid)
        assert len(ego) == 5 and length > 3.0 and all(len(r) == 5 for r in rows)
        own = sc.controller.step(sc.obs)
        steer = own[1] if scenario != "platoon" else None
        joint = sc.joint_action(own, vid, -1.0, None)
        if scenario == "platoon":  # one action per follower: the agent's first is replaced
            assert joint[0] == (-1.0, 0.0) and len(joint) == len(sc.controlled_ids)
        else:
            assert joint == (-1.0, steer)
        sc.step(joint)
        assert sc.status == "running"
    finally:
        sc.close()
