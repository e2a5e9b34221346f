"""Time-to-collision and gap acceptance, checked on hand-made cases."""

import math

import pytest

from ego.scenarios.events import GapRule, check_lane, choose_lane, time_to_collision


@pytest.mark.parametrize(
    "gap, closing, expected",
    [
        (30.0, 10.0, 3.0),
        (30.0, 0.0, math.inf),  # not closing
        (30.0, -5.0, math.inf),  # opening
        (math.inf, 10.0, math.inf),  # nobody there
        (0.0, 10.0, 0.0),  # touching
        (-1.0, -3.0, 0.0),  # overlapping
    ],
    ids=["closing", "equal-speed", "opening", "no-vehicle", "touching", "overlap"],
)
def test_time_to_collision(gap, closing, expected):
    assert time_to_collision(gap, closing) == expected


RULE = GapRule(min_gap=5.0, time=1.5)


def test_required_gap_grows_with_closing_speed():
    assert RULE.required(-3.0) == 5.0
    assert RULE.required(4.0) == pytest.approx(11.0)


def test_lane_rejected_when_the_lag_vehicle_closes_fast():
    # follower 15 m behind at 25 m/s; the ego will drive 15 m/s: needs 5 + 1.5*10 = 20 m
    c = check_lane("left", True, 20.0, 15.0, math.inf, 0.0, 15.0, 25.0, RULE)
    assert not c.accepted and c.lag_required == pytest.approx(20.0)
    assert "lag gap 15.0 m < 20.0 m -> rejected" in c.explain()


def test_lane_rejected_when_a_car_is_alongside():
    c = check_lane("right", True, 20.0, 15.0, -4.0, 20.0, 41.0, 20.0, RULE)
    assert not c.accepted


def test_missing_lane_is_never_chosen():
    left = check_lane("left", False, 20.0, 15.0, math.inf, 0, math.inf, 0, RULE)
    right = check_lane("right", True, 20.0, 15.0, math.inf, 0, math.inf, 0, RULE)
    side, why = choose_lane(left, right)
    assert side == "right" and "left: no lane" in why


def test_larger_margin_wins_and_left_breaks_ties():
    tight = check_lane("left", True, 20.0, 15.0, 30.0, 20.0, 30.0, 20.0, RULE)
    roomy = check_lane("right", True, 20.0, 15.0, 80.0, 20.0, 90.0, 20.0, RULE)
    assert choose_lane(tight, roomy)[0] == "right"
    same_l = check_lane("left", True, 20.0, 15.0, math.inf, 0, math.inf, 0, RULE)
    same_r = check_lane("right", True, 20.0, 15.0, math.inf, 0, math.inf, 0, RULE)
    assert choose_lane(same_l, same_r)[0] == "left"


def test_no_acceptable_lane_means_brake_in_lane():
    bad = check_lane("left", True, 20.0, 15.0, 2.0, 5.0, 1.0, 20.0, RULE)
    side, why = choose_lane(bad, check_lane("right", False, 20, 15, 0, 0, 0, 0, RULE))
    assert side is None and why.endswith("brake in lane")


def test_boxes_overlap_by_separating_axes():
    from ego.scenarios.events import boxes_overlap

    car = (0.0, 0.0, 0.0, 4.0, 2.0)
    assert boxes_overlap(car, (3.9, 0.0, 0.0, 4.0, 2.0))  # nose to tail, 0.1 m overlap
    assert not boxes_overlap(car, (4.1, 0.0, 0.0, 4.0, 2.0))
    assert not boxes_overlap(car, (0.0, 2.05, 0.0, 4.0, 2.0))  # side by side, 5 cm apart
    # rotated 45 degrees: its corner reaches sqrt(2)/2 * (4 + 2) / 2 = 2.12 m sideways
    diag = math.pi / 4
    assert boxes_overlap(car, (0.0, 3.0, diag, 4.0, 2.0))
    assert not boxes_overlap(car, (0.0, 3.2, diag, 4.0, 2.0))
    # corner near corner, separated only along the rotated box's own axis
    assert not boxes_overlap(car, (3.6, 2.6, diag, 2.0, 2.0))
    assert boxes_overlap(car, (2.5, 1.5, diag, 2.0, 2.0))
    # symmetric
    b = (1.0, 2.0, 0.3, 4.5, 1.8)
    assert boxes_overlap(car, b) == boxes_overlap(b, car)
