"""Euro NCAP-style car-to-car rear (AEB) tests on emergency-brake: evade=false, a stopped or
slow lead (lead_speed), the impact speed; and the sweep spec files in scenarios/sweeps."""

import itertools
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from ego.control import CONTROLLERS
from ego.models import NonlinearBicycleParams
from ego.params import ConfigError, apply_overrides, describe
from ego.runner import RunSpec, resolve, run
from ego.scenarios import EmergencyBrakeConfig, scenario_class

P = NonlinearBicycleParams()
#: the ego's braking limit: the friction circle plus rolling resistance (m/s^2)
DECEL_LIMIT = P.F_max / P.m + P.f * P.g
CONTROLLER_NAMES = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
SWEEPS = Path(__file__).resolve().parents[2] / "scenarios" / "sweeps"
#: CCRs as aeb-ccr-s.toml sets it
CCRS = dict(evade=False, lead_speed=0, lead_final_speed=0, lead_gap=100, traffic_density=0)


def _run(controller, seed=0, **overrides):
    return run(RunSpec("emergency-brake", controller, seed, {k: str(v).lower() for k, v in overrides.items()}))


# -- parameters (no SUMO) ------------------------------------------------------------------------


def test_lead_speed_defaults_to_the_ego_speed_and_rejects_other_negatives():
    c, _ = apply_overrides(EmergencyBrakeConfig(), {"ego_speed": 25.0})
    assert c.lead_speed == -1 and c.lead_cruise_speed == 25.0
    c, _ = apply_overrides(EmergencyBrakeConfig(), {"lead_speed": 0})
    assert c.lead_cruise_speed == 0.0
    with pytest.raises(ConfigError, match="lead_speed"):
        apply_overrides(EmergencyBrakeConfig(), {"lead_speed": -0.5})


def test_too_dense_background_is_a_config_error():
    with pytest.raises(ConfigError, match=r"traffic_density.*at most 20\.2 veh/km"):
        apply_overrides(EmergencyBrakeConfig(), {"traffic_speed": 30.0, "traffic_density": 25.0})
    apply_overrides(EmergencyBrakeConfig(), {"traffic_speed": 20.0, "traffic_density": 25.0})


# -- in SUMO -----------------------------------------------------------------------------------


@pytest.mark.sumo
@pytest.mark.parametrize("controller", ["fuzzy", "pid"])
def test_evade_false_brakes_in_lane_although_a_lane_is_free(controller, fuzzy_ready):
    free = _run(controller, traffic_density=0).metrics
    assert free["target_side"] == "left"  # the default would change lane
    r = _run(controller, traffic_density=0, evade=False)
    m = r.metrics
    assert m["target_side"] is None and m["target_lane"] == 1
    assert m["lane_choice"] == "evade=false: no lane change, brake in lane"
    assert any(e.kind == "lane" and "stay in the middle lane (brake)" in e.text for e in r.events)
    assert np.max(np.abs(r.column("lane_offset"))) < 0.2
    assert m["status"] == "completed" and not m["collision"]
    assert m["impact_speed"] is None and m["impact_relative_speed"] is None


@pytest.mark.sumo
def test_a_stopped_lead_stays_put_and_the_sensor_sees_it_from_the_start():
    from ego.runner import build

    sc = build(
        RunSpec(
            "emergency-brake",
            "none",
            0,
            {**{k: str(v).lower() for k, v in CCRS.items()}, "ego_speed": "5", "duration": "3"},
        )
    )
    try:
        sc.reset()
        veh = sc.bridge.libsumo.vehicle
        x0 = veh.getLanePosition("lead")
        assert sc.view.sensor.front.id == "lead" and sc.view.sensor.front.speed == 0.0
        assert sc.view.gap_front == pytest.approx(100.0, abs=0.05)
        while not sc.done:
            sc.step((0.0, 0.0))
        assert "lead" in veh.getIDList() and veh.getSpeed("lead") == 0.0
        assert veh.getLanePosition("lead") == x0
    finally:
        sc.close()


@pytest.mark.sumo
@pytest.mark.parametrize("controller", CONTROLLER_NAMES)
def test_stopped_lead_at_20_kmh_is_avoided(controller, fuzzy_ready):
    r = _run(controller, ego_speed=5.556, duration=40, **CCRS)
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"], m["status_detail"]
    assert m["lane_choice"].startswith("evade=false") and m["target_side"] is None
    assert m["impact_speed"] is None and m["impact_relative_speed"] is None
    assert m["min_gap_front"] > 0.5 and abs(m["final_speed"]) < 0.3
    # stopped, it stays stopped: no backing up after the stop (it did, by brake_max_lag = 2 m,
    # when the braking reference stayed behind the car at standstill)
    s = r.column("s")
    assert s.max() - s[-1] < 0.1


@pytest.mark.sumo
@pytest.mark.parametrize("controller", ["pid", "fuzzy"])
def test_a_stopped_lead_found_too_late_is_hit_at_the_speed_physics_leaves(controller, fuzzy_ready):
    # 80 km/h, trigger at TTC 1 s (~22 m): stopping takes 22.2^2 / (2 x 6.96) = 35 m
    r = _run(controller, ego_speed=22.222, ttc_threshold=1.0, **CCRS)
    m = r.metrics
    assert m["status"] == "collision" and m["collision_with"] == "lead"
    i = int(np.searchsorted(r.column("t"), m["trigger_time"]))
    v0, gap0 = float(r.column("ds")[i]), float(r.column("gap_front")[i])
    assert gap0 < v0**2 / (2.0 * DECEL_LIMIT)  # braking cannot stop in time: it must collide
    # no car brakes harder than its friction limit: the impact speed is at least what braking
    # at the limit from the trigger leaves; the AEB brakes at that limit at once, so not
    # much more (one SUMO step, 0.1 s, of reaction at most)
    floor = math.sqrt(v0**2 - 2.0 * DECEL_LIMIT * gap0)
    late = math.sqrt(v0**2 - 2.0 * DECEL_LIMIT * (gap0 - 0.1 * v0))
    assert floor - 0.1 <= m["impact_speed"] <= late
    assert m["aeb_time"] == m["trigger_time"]
    assert m["impact_relative_speed"] == m["impact_speed"]  # the lead stands still


@pytest.mark.sumo
def test_a_slow_lead_is_hit_at_the_relative_speed():
    # CCRm-like, no controller: the ego at 50 km/h runs into a lead at 20 km/h
    m = _run(
        "none",
        ego_speed=13.889,
        lead_speed=5.556,
        lead_final_speed=5.556,
        lead_gap=20,
        traffic_density=0,
        evade=False,
        aeb=False,
    ).metrics
    assert m["status"] == "collision" and m["collision_with"] == "lead"
    assert m["impact_relative_speed"] == pytest.approx(m["impact_speed"] - 5.556, abs=1e-3)
    assert 10.0 < m["impact_speed"] <= 13.889


# -- the sweep spec files ----------------------------------------------------------------------

SPEC_FILES = sorted(SWEEPS.glob("*.toml"))


def test_the_spec_files_are_there():
    names = {p.name for p in SPEC_FILES}
    assert {"aeb-ccr-s.toml", "aeb-ccr-m.toml", "aeb-ccr-b.toml", "envelope.toml", "cut-in.toml"} <= names


@pytest.mark.parametrize("path", SPEC_FILES, ids=[p.name for p in SPEC_FILES])
def test_spec_file_names_real_parameters_and_allowed_values(path):
    spec = tomllib.loads(path.read_text())
    assert set(spec) <= {"scenario", "controllers", "seeds", "set", "grid", "sample"}
    cls = scenario_class(spec["scenario"])
    assert cls.task == "tracking"
    assert spec["controllers"] and set(spec["controllers"]) <= set(CONTROLLERS["tracking"])
    seeds = spec.get("seeds", 1)
    assert (isinstance(seeds, int) and seeds >= 1) or (isinstance(seeds, list) and seeds)
    known = {i.name for i in describe(cls.config_cls)}
    fixed, grid = spec.get("set", {}), spec.get("grid", {})
    sample = dict(spec.get("sample", {}))
    method, n = sample.pop("method", None), sample.pop("n", None)
    if sample or method is not None:
        assert method in ("random", "lhs", "sobol") and isinstance(n, int) and n > 0
    for section in (fixed, grid, sample):
        unknown = set(section) - known
        assert not unknown, f"{path.name}: unknown parameters {unknown}"
    assert all(isinstance(v, list) and v for v in grid.values())
    assert all(isinstance(v, list) and len(v) == 2 and v[0] < v[1] for v in sample.values())
    # every grid point, at each corner of the sampled ranges, is a valid configuration
    corners = [dict(zip(sample, c)) for c in itertools.product(*sample.values())] or [{}]
    for values in itertools.product(*grid.values()):
        for corner in corners:
            overrides = {**fixed, **dict(zip(grid, values)), **corner}
            for controller in spec["controllers"]:
                resolve(RunSpec(spec["scenario"], controller, 0, overrides))


def test_ccr_files_hold_the_euro_ncap_matrices():
    load = lambda name: tomllib.loads((SWEEPS / name).read_text())  # noqa: E731
    kmh = lambda speeds: [round(v * 3.6) for v in speeds]  # noqa: E731
    s, m_, b = load("aeb-ccr-s.toml"), load("aeb-ccr-m.toml"), load("aeb-ccr-b.toml")
    assert kmh(s["grid"]["ego_speed"]) == list(range(10, 90, 10))
    assert s["set"]["lead_speed"] == 0 and s["set"]["evade"] is False
    assert kmh(m_["grid"]["ego_speed"]) == list(range(30, 90, 10))
    assert round(m_["set"]["lead_speed"] * 3.6) == 20
    assert round(b["set"]["ego_speed"] * 3.6) == 50 and b["set"]["lead_speed"] == -1
    assert b["grid"] == {"lead_decel": [2, 6], "lead_gap": [12, 40]}
    for spec in (s, m_, b):
        assert spec["controllers"] == list(CONTROLLER_NAMES)


def test_the_envelope_classifier_knows_a_stopped_lead():
    from ego.scenarios.envelope import avoidable

    # a stopped lead 30 m ahead of the ego at 22.2 m/s: braking at 6.96 m/s^2 needs 35.5 m
    stopped, _ = apply_overrides(EmergencyBrakeConfig(), {"lead_speed": 0, "lead_final_speed": 0})
    assert not avoidable({"trigger_time": 0.0}, 30.0, 22.222, stopped, DECEL_LIMIT)
    assert avoidable({"trigger_time": 0.0}, 40.0, 22.222, stopped, DECEL_LIMIT)
    # the same gap to a lead at the ego's speed is no danger at all
    assert avoidable(
        {"trigger_time": 0.0}, 30.0, 22.222, EmergencyBrakeConfig(ego_speed=22.222, lead_brake_time=25.0), DECEL_LIMIT
    )


@pytest.mark.sumo
def test_stopped_by_the_aeb_behind_a_car_that_then_stops_does_not_roll_away(fuzzy_ready):
    # CCRb 12 m, 2 m/s^2, a late trigger: the AEB stops the ego while the lead still rolls,
    # then the lead stops too. The braking reference used to stay behind the resting ego, so
    # the controller never held it and it rolled backwards until the run diverged
    r = _run(
        "fuzzy-pid",
        ego_speed=13.889,
        lead_final_speed=0,
        lead_gap=12,
        lead_decel=2,
        ttc_threshold=1.0,
        traffic_density=0,
        evade=False,
    )
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"], m["status_detail"]
    s = r.column("s")
    assert s.max() - s[-1] < 1.0 and r.column("ds").min() > -0.5  # was: -1 m/s, diverged
