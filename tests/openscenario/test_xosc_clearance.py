"""The RelativeClearanceCondition (OpenSCENARIO 1.2) in real SUMO runs, against gaps computed
by hand from the cars' recorded positions: hand-written files on a hand-written two-way road
(lane +1, the other direction, beside lanes -1 and -2; every car 4.5 m long, its reference
point its box centre). T drives lane -2 at 20 m/s; B drives ahead of it at 10 m/s."""

from __future__ import annotations

import pytest
from test_xosc_against_lane import ROAD
from xosc_scenes import entity, event, run_scene, speed, starts, trigger, write_file

from ego.openscenario.runtime import Storyboard


def _clearance(free: bool, lanes: str = "", refs: str = "", opposite: bool = False, fwd=45, back=20) -> str:
    return (
        f'<RelativeClearanceCondition distanceForward="{fwd}" distanceBackward="{back}" '
        f'freeSpace="{str(free).lower()}" oppositeLanes="{str(opposite).lower()}">{lanes}'
        + "".join(f'<EntityRef entityRef="{r}"/>' for r in refs.split(",") if r)
        + "</RelativeClearanceCondition>"
    )


def _run(tmp, monkeypatch, condition: str, b_lane=-1, b_s=200.0, b_speed=10.0, edge="falling"):
    """Run with an event on T starting when ``condition`` stops holding (a falling edge; or
    ``edge``):
    the event's start time and T's and B's s at each storyboard time."""
    (tmp / "twoway.xodr").write_text(ROAD)
    rows = [
        ("Ego", "1", -1, 20.0, 20.0, ""),
        ("T", "1", -2, 100.0, 20.0, ""),
        ("B", "1", b_lane, b_s, b_speed, '<Orientation type="relative" h="0"/>'),
    ]
    ev = event("E", "T", speed(20.0), trigger([entity("T", condition, edge=edge)]))
    path = write_file(tmp / "clear.xosc", "twoway.xodr", rows, [ev])
    seen: dict[float, tuple[float, float]] = {}
    step = Storyboard.step

    def recording(self, t):
        seen[round(t, 6)] = (self.states["T"].s, self.states["B"].s)
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    sc = run_scene(path, 8.0)
    return starts(sc, "E"), seen


def _first(seen, inside) -> float:
    return min(t for t, (ts, bs) in seen.items() if inside(ts, bs))


LEFT = '<RelativeLaneRange from="1" to="1"/>'


def test_free_space_ahead_in_the_lane_to_the_left(tmp_path, monkeypatch):
    """B enters the area when the free space from T's front to B's rear, gap - 4.5 m, falls
    to distanceForward = 45 m: about t = (100 - 4.5 - 45) / 10 = 5.05 s."""
    times, seen = _run(tmp_path, monkeypatch, _clearance(True, LEFT))
    expect = _first(seen, lambda ts, bs: bs - ts - 4.5 <= 45.0)
    assert times == [pytest.approx(expect)]
    assert 5.05 - 1e-9 <= expect <= 5.25


def test_reference_points_ahead_in_the_lane_to_the_left(tmp_path, monkeypatch):
    """Without freeSpace the reference points count: B.s - T.s falls to 45 m, about t = 5.5 s."""
    times, seen = _run(tmp_path, monkeypatch, _clearance(False, LEFT))
    expect = _first(seen, lambda ts, bs: bs - ts <= 45.0 + 1e-9)
    assert times == [pytest.approx(expect)]
    assert 5.5 - 1e-9 <= expect <= 5.7


def test_every_lane_without_a_range_and_none_to_the_right(tmp_path, monkeypatch):
    """No RelativeLaneRange: every lane of T's direction (B counts); the lane to T's right
    (relative -1) does not exist on this road: the condition never holds (no clearance to
    have), though the lane to the left is clear at the start (an event on it starts at once)."""
    times, seen = _run(tmp_path, monkeypatch, _clearance(True))
    assert times == [pytest.approx(_first(seen, lambda ts, bs: bs - ts - 4.5 <= 45.0))]
    times, _ = _run(tmp_path, monkeypatch, _clearance(True, '<RelativeLaneRange from="-1" to="-1"/>'), edge="none")
    assert times == []
    times, _ = _run(tmp_path, monkeypatch, _clearance(True, LEFT), edge="none")
    assert times == [0.0]


def test_only_the_entities_referred_to_count(tmp_path, monkeypatch):
    times, _ = _run(tmp_path, monkeypatch, _clearance(True, LEFT, refs="Ego"))
    assert times == []


def test_behind_counts_backwards_from_the_rear(tmp_path, monkeypatch):
    """B starts 60 m behind T in lane -1 at 30 m/s: its front reaches distanceBackward = 20 m
    behind T's rear when 60 - 4.5 - 10 t = 20, about t = 3.55 s."""
    times, seen = _run(tmp_path, monkeypatch, _clearance(True, LEFT), b_s=40.0, b_speed=30.0)
    expect = _first(seen, lambda ts, bs: ts - bs - 4.5 <= 20.0)
    assert times == [pytest.approx(expect)]
    assert 3.55 - 1e-9 <= expect <= 3.75


@pytest.mark.parametrize("opposite", [False, True])
def test_the_other_directions_lanes_only_with_opposite_lanes(tmp_path, monkeypatch, opposite):
    """B in lane +1 (the other direction, relative +2 from T) coming towards T at 10 m/s from
    s = 300: the gap closes at 30 m/s; it counts only with oppositeLanes."""
    cond = _clearance(True, '<RelativeLaneRange from="1" to="2"/>', opposite=opposite)
    times, seen = _run(tmp_path, monkeypatch, cond, b_lane=1, b_s=300.0)
    if not opposite:
        assert times == []
        return
    expect = _first(seen, lambda ts, bs: bs - ts - 4.5 <= 45.0)
    assert times == [pytest.approx(expect)]
    assert (200 - 4.5 - 45) / 30 - 1e-9 <= expect <= (200 - 4.5 - 45) / 30 + 0.2
