"""Lane changes on the ego (hand-written files on xosc_scenes' straight road, real SUMO): the
action lasts as long as its profile (an event waiting for its end starts then, not at once),
the next relative lane change counts from the lane the ego is commanded to, and a target lane
that does not exist when the action starts is a warning and a skipped action, not a refusal
mid-run (``ego list`` cannot know where the reference will be then)."""

from __future__ import annotations

import pytest
from xosc_scenes import event, run_scene, scene, sim_time, starts, trigger

#: the other cars out of the ego's way (lane -1, far ahead)
AWAY = {"A": (-1, 400.0, 25.0), "B": (-1, 450.0, 25.0), "C": (-1, 480.0, 25.0)}


def relative_change(dlane: int, seconds: float) -> str:
    return (
        '<LateralAction><LaneChangeAction><LaneChangeActionDynamics dynamicsShape="sinusoidal" '
        f'value="{seconds}" dynamicsDimension="time"/><LaneChangeTarget><RelativeTargetLane entityRef="Ego" '
        f'value="{dlane}"/></LaneChangeTarget></LaneChangeAction></LateralAction>'
    )


def after(name: str) -> str:
    return trigger(
        [
            '<Condition name="after" delay="0" conditionEdge="none"><ByValueCondition>'
            f'<StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="{name}" '
            'state="endTransition"/></ByValueCondition></Condition>'
        ]
    )


def _two_changes(tmp_path, second: int, duration: float):
    """The ego changes +1 lane over 2 s from t = 1 s, then ``second`` lanes when the first
    ends; the run and the ego's lane-frame d at its end."""
    path = scene(
        tmp_path,
        [
            event("First", "Ego", relative_change(1, 2.0), trigger([sim_time(1.0)])),
            event("Second", "Ego", relative_change(second, 2.0), after("First")),
        ],
        at=AWAY,
    )
    sc = run_scene(path, duration=duration)
    assert sc.status in ("completed", "timeout"), sc.status_detail
    e = sc.board.states[sc.ego_name]
    return sc, sc.road.project(e.x, e.y)[1]


def test_an_ego_lane_change_ends_with_its_profile_and_the_next_counts_from_its_target(tmp_path):
    # the ego in lane -3 (the rightmost of three): +1 over 2 s from t = 1 s, then +1 again when
    # the first ends: lanes -2 then -1 (were the first to end at once, the second would count
    # from lane -3 and stop in lane -2)
    sc, d = _two_changes(tmp_path, 1, 8.0)
    (first,) = starts(sc, "First")
    (second,) = starts(sc, "Second")
    assert first == pytest.approx(1.0, abs=0.11)
    assert second == pytest.approx(first + 2.0, abs=0.11)  # the first's profile lasts 2 s
    lanes = sc.lane_offset
    assert sc.target_lane == max(lanes, key=lambda i: lanes[i])  # the leftmost lane (-1)
    assert min(lanes, key=lambda i: abs(d - lanes[i])) == sc.target_lane  # in it (pid converges slowly)


def test_a_target_lane_missing_when_the_change_starts_is_skipped_with_a_warning(tmp_path, capsys):
    # +2 from lane -2 once the ego is there: no such lane on a three-lane road
    sc, d = _two_changes(tmp_path, 2, 6.0)
    err = capsys.readouterr().err
    assert "does not exist on the ego's road" in err and "the lane change is skipped" in err
    lanes = sc.lane_offset
    middle = sorted(lanes, key=lambda i: lanes[i])[1]
    assert sc.target_lane == middle and min(lanes, key=lambda i: abs(d - lanes[i])) == middle  # stays in -2
