"""An AEB stop mid-lane-change weighs the follower in the target lane (issue 21's defect).

Before the fix, ``ego run emergency-brake -c fuzzy-pid --seed 13311774 --set lead_decel=6.35
--set ego_speed=17.39 --set lead_gap=22.15 --set traffic_density=20.67`` started a lane change
to the left, engaged the AEB 18 % across and stopped half in the new lane, where that lane's
follower bg2_24 (20 m/s) hit it from behind: an avoidable collision. bp-pid did the same.
"""

import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

CASE = {
    "lead_decel": 6.35,
    "ego_speed": 17.39,
    "lead_gap": 22.15,
    "traffic_density": 20.67,
}


@pytest.mark.parametrize("controller", ["fuzzy-pid", "bp-pid"])
def test_aborts_back_into_its_lane_instead_of_stopping_in_front_of_the_follower(
    controller,
):
    r = run(RunSpec("emergency-brake", controller, 13311774, CASE))
    m = r.metrics
    assert not m["collision"], m["status_detail"]
    assert m["status"] == "completed"
    aborted = [e for e in r.events if e.kind == "lane" and "aborted" in e.text]
    assert aborted and "bg2_24" in aborted[0].text  # the follower is why
    assert m["target_side"] is None  # it stayed in (went back to) its own lane
    assert m["requirements"]["no_avoidable_collision"] > 0


@pytest.mark.parametrize(
    "seed, case",
    [
        # found by ego falsify (scenarios/falsify/emergency-brake.toml, fuzzy): no AEB, the ego slowed
        # behind the lead it still overlapped, early in the change, and the new lane's follower hit it
        (
            99320,
            {
                "ego_speed": 18.0762,
                "lead_decel": 7.1856,
                "lead_gap": 10.6072,
                "traffic_density": 12.3334,
            },
        ),
        (
            91990,
            {
                "ego_speed": 14.6396,
                "lead_decel": 8.4011,
                "lead_gap": 10.0228,
                "traffic_density": 24.4863,
            },
        ),
    ],
)
def test_slowing_early_in_a_change_in_front_of_a_follower_goes_back(seed, case):
    r = run(RunSpec("emergency-brake", "fuzzy", seed, case))
    assert not r.metrics["collision"], r.metrics["status_detail"]
    assert any(e.kind == "lane" and "aborted" in e.text and "follower" in e.text for e in r.events)


def test_a_slow_down_further_across_finishes_the_change():
    # found by ego falsify with a first version that went back up to a quarter across without an
    # emergency stop: fuzzy's lateral lag carried the ego past the lead and swung it back into it
    case = {
        "ego_speed": 23.3631,
        "lead_decel": 4.7189,
        "lead_gap": 11.2988,
        "traffic_density": 14.3426,
        "block_right": True,
    }
    r = run(RunSpec("emergency-brake", "fuzzy", 10216, case))
    assert not r.metrics["collision"], r.metrics["status_detail"]


def test_a_lane_change_with_a_clear_new_lane_is_not_aborted():
    # the default case changes lane with nobody close behind in the new lane: finished, no abort
    r = run(RunSpec("emergency-brake", "pid", 0, {}))
    assert r.metrics["lane_change_completed"]
    assert not any(e.kind == "lane" and "aborted" in e.text for e in r.events)
