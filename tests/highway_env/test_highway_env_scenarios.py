"""The motorway scenarios on the highway-env backend, end to end (real highway-env)."""

import pytest

from ego.results.metrics import flatten
from ego.runner import RunSpec, resolve, run

pytestmark = pytest.mark.highway_env

SCENARIOS = ("emergency-brake", "fast-follower", "cut-in")


def _run(scenario, controller="pid", seed=0, backend="highway-env", **overrides):
    return run(RunSpec(scenario, controller, seed, {k: str(v) for k, v in overrides.items()}, backend=backend))


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_each_scenario_runs_its_manoeuvre_on_highway_env(scenario):
    r = _run(scenario)
    m = r.metrics
    assert m["backend"] == "highway-env"
    assert m["status"] == "completed" and not m["collision"], m["status_detail"]
    assert m["trigger_time"] is not None  # the scripted actor came, the sensor saw it
    assert 0.0 < m["min_gap_front"] < 20.0
    # the same metrics, in the same order, as the scenario declares (and SUMO reports)
    assert list(flatten(m)) == [x.name for x in resolve(RunSpec(scenario, "pid")).metrics_declared()]


@pytest.mark.parametrize("side", ["left", "right"])
def test_the_cutting_car_settles_in_the_egos_lane_as_on_sumo(side, tmp_path):
    """The cutter steers by its front bumper's offset, which on highway-env moves as asked (it
    swung from side to side and ended half in the far lane: the bumper's y carried the body's
    turn); it ends on the ego's lane centre on both simulators, with about the same gaps."""
    import pandas as pd

    ends, gaps = {}, {}
    for backend in ("sumo", "highway-env"):
        trace = tmp_path / f"{backend}.csv"
        spec = RunSpec("cut-in", "pid", 0, {"duration": "14", "cut_in_side": side}, backend=backend, trace=str(trace))
        gaps[backend] = run(spec).metrics["min_gap_front"]
        traffic = pd.read_csv(tmp_path / f"{backend}.traffic.csv")
        cutter = traffic[traffic.vehicle == "cutter"]
        ends[backend] = cutter[cutter.t >= 13.0][["y", "heading"]].abs().max()
    for backend, end in ends.items():
        assert end["y"] < 0.15 and end["heading"] < 0.01, (backend, end)
    assert abs(gaps["highway-env"] - gaps["sumo"]) < 0.5


def test_the_same_seed_gives_the_same_metrics():
    a, b = (_run("cut-in", seed=3, duration=12).metrics for _ in range(2))
    a.pop("wall_time"), b.pop("wall_time")
    assert a == b


@pytest.mark.sumo
def test_a_crash_into_the_braking_lead_matches_sumos():
    """highway-env's crashed flag (box overlap) becomes the run's collision: same status,
    other party and impact as SUMO, the lead being scripted identically on both."""
    setting = dict(aeb=False, evade=False, traffic_density=0, duration=10)
    he = _run("emergency-brake", "none", **setting).metrics
    sumo = _run("emergency-brake", "none", backend="sumo", **setting).metrics
    assert he["status"] == "collision" and he["collision_with"] == "lead"
    assert "highway-env" in he["status_detail"]
    for key in ("status", "collision_with", "impact_speed", "impact_relative_speed", "sim_time"):
        assert he[key] == sumo[key], key


def test_a_follower_hitting_the_ego_is_a_collision_with_the_follower():
    m = _run("fast-follower", evade=False, ttc_threshold=0.5, duration=10).metrics
    assert m["status"] == "collision" and m["collision_with"] == "follower"


@pytest.mark.sumo
def test_the_recording_has_the_same_layout_on_both_backends(tmp_path):
    from rerun.chunk import RrdReader

    paths = {}
    for backend in ("sumo", "highway-env"):
        rrd = tmp_path / f"{backend}.rrd"
        run(
            RunSpec("cut-in", "pid", 0, {"duration": "3"}, record=str(rrd), background_recording=False, backend=backend)
        )
        paths[backend] = {c.entity_path for c in RrdReader(rrd).stream()}
    assert paths["sumo"] == paths["highway-env"]
    assert "/plots/ttc/front" in paths["highway-env"] and "/events" in paths["highway-env"]


@pytest.mark.sumo
def test_sine_tracking_runs_on_highway_env_as_its_needs_allow_and_tracks_as_on_sumo():
    """sine-tracking needs nothing highway-env lacks, so it runs there without being listed
    anywhere; the ego alone on the road is ego's own model on either simulator: the same
    tracking metrics (the backend is only the road then)."""
    on = {
        b: _run("sine-tracking", backend=b, traffic_density=0.0, duration=10.0).metrics for b in ("sumo", "highway-env")
    }
    assert on["highway-env"]["backend"] == "highway-env" and on["sumo"]["backend"] == "sumo"
    for name in ("status", "rms_lateral_error", "max_abs_lateral_error", "rms_speed_error", "steps"):
        assert on["highway-env"][name] == on["sumo"][name], name
