"""cut-in's per-run braking criterion (issue 21, point 5): braking at the friction limit from
the moment the cutting car intrudes into the ego's lane (becomes its front object)."""

import pytest

from ego.runner import RunSpec, build

pytestmark = pytest.mark.sumo


def _run(**overrides):
    scenario = build(RunSpec("cut-in", "pid", 0, overrides, requirements=()))
    return scenario, scenario.run()


def test_the_margin_is_the_gap_less_the_closing_speeds_braking_distance():
    scenario, r = _run(cut_in_gap=15, cut_in_speed=14)
    t0, gap, v0, vc = scenario.reach.at
    assert r.metrics["reach_time"] == pytest.approx(t0, abs=1e-3)
    # its speed along the lane: the scripted 11 m/s, a little less while it moves across
    assert vc == pytest.approx(25.0 - 14.0, abs=0.5)
    p = scenario.ego.model.params
    decel = p.F_max / p.m + p.f * p.g
    # a car at constant speed: the smallest gap is the gap less (v0 - vc)^2 / (2 decel)
    assert scenario.braking_margin() == pytest.approx(gap - (v0 - vc) ** 2 / (2 * decel), abs=0.05)
    assert r.status == "collision"
    assert r.metrics["collision_avoidable"] is (scenario.braking_margin() > 0)


def test_no_collision_no_verdict_and_a_side_hit_is_physics():
    _, r = _run(cut_in_gap=25, cut_in_speed=5)
    assert r.status == "completed" and r.metrics["collision_avoidable"] is None
    assert r.metrics["reach_time"] is not None
    scenario, r = _run(cut_in_gap=5, cut_in_speed=12)  # hits the ego's side before intruding into its lane
    assert r.status == "collision" and scenario.reach.at is None
    assert r.metrics["collision_avoidable"] is False
