"""Scenario tests of a controller: each marked function runs its scenario once per seed and
fails on a violated requirement (the scenario's defaults plus ``require``)."""

import pytest


@pytest.mark.ego_scenario(
    scenario="emergency-brake",
    controller="pid",
    params={"traffic_density": 0},
    seeds=[0],
    require=["keep_2m: always (gap_front >= 2 m or lateral_clear)"],
)
def test_emergency_brake_keeps_its_distance(ego_result):
    # the body runs after the requirements passed, with the run to look at
    assert not ego_result.metrics["collision"]


@pytest.mark.ego_scenario(
    scenario="emergency-brake",
    controller="pid",
    params={"traffic_density": 0},
    seeds=[0],
    require=["keep_50m: always (gap_front >= 50 m)"],
)
def test_planted_failure_keeps_50_m():
    """Planted: the lead starts 30 m ahead, so a 50 m gap is violated at once."""
