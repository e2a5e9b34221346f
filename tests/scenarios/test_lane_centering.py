"""Report 003's lane centring in real SUMO: both plants, both speeds, the report's claims."""

import pytest

from ego.runner import RunSpec, run
from ego.scenarios.lane_centering import ROAD_LENGTH, LaneCenteringConfig, drive_time

pytestmark = pytest.mark.sumo
FIELDS = (
    "max_abs_lateral_error",
    "mean_abs_lateral_error",
    "std_lateral_error",
    "max_abs_heading_error",
    "max_abs_steer",
    "max_abs_lateral_accel",
    "status",
    "collision",
    "completed_road",
    "sim_time",
    "wall_time",
    "steps",
)


@pytest.mark.parametrize("plant", ["lateral-error", "dynamic-bicycle"])
@pytest.mark.parametrize("speed", [8.0, 25.0])
def test_the_shipped_preset_keeps_the_lane_within_half_a_metre(speed, plant):
    r = run(RunSpec("lane-centering", "cascade-pid", 0, {"speed": speed, "plant": plant}))
    m = r.metrics
    assert m["status"] == "completed", m["status_detail"]
    assert m["completed_road"] and not m["collision"]
    assert m["distance"] > 2850.0  # the whole road
    assert m["max_abs_lateral_error"] < 0.5
    assert m["max_abs_steer"] <= 0.4364  # 25 deg
    for key in FIELDS:
        assert key in m, key
    # one drive, one set of figures: where and when it ends, as ego list and the messages say
    assert m["sim_time"] == pytest.approx(drive_time(speed), abs=0.05)
    assert m["status_detail"] == "reached the end of the drive at s = 2920 m (15 m before the end of the road)"
    kinds = [e.kind for e in r.events]
    assert kinds.count("curve") == 2  # entering and leaving, from the SUMO lane's geometry


def test_the_reports_gains_swing_across_the_lane():
    m = run(RunSpec("lane-centering", "cascade-pid", 0, {"preset": "report"})).metrics
    # stable on the straight from rest, then a limit cycle of about +-2 m in the curve: into
    # the other lane (its traffic) or off the road
    assert m["max_abs_lateral_error"] > 1.0 or m["status"] != "completed"


def test_the_road_and_the_drive_are_one_set_of_figures():
    assert ROAD_LENGTH == pytest.approx(2935.4, abs=0.05)  # 2 x 1000 + 2 x 150 + (500 pi / 2 - 150)
    assert drive_time() == pytest.approx((2935.4 - 15 - (20 - 2.2)) / 8, abs=0.01)  # 362.8 s
    assert (
        "the end of the 2935 m road: 363 s at 8 m/s"
        in LaneCenteringConfig.__dataclass_fields__["duration"].metadata["doc"]
    )


def test_the_reports_fifty_seconds_are_exactly_zero():
    m = run(RunSpec("lane-centering", "cascade-pid", 0, {"duration": 50.0, "preset": "report"})).metrics
    assert m["status"] == "ended"  # 400 m of a 2920 m drive: the duration ended it, nothing failed
    assert m["status_detail"] == "the duration (50 s) ended the run at s = 418 m of the drive to s = 2920 m"
    assert m["max_abs_lateral_error"] == 0.0 and m["std_lateral_error"] == 0.0


def test_an_initial_offset_is_removed():
    r = run(RunSpec("lane-centering", "cascade-pid", 0, {"offset": 0.8, "duration": 30.0}))
    d = r.column("d")
    assert d[0] == pytest.approx(0.8, abs=1e-6)
    assert abs(d[-1]) < 0.05


def test_same_seed_same_metrics():
    a = run(RunSpec("lane-centering", "cascade-pid", 2, {"speed": 25.0, "plant": "dynamic-bicycle"})).metrics
    b = run(RunSpec("lane-centering", "cascade-pid", 2, {"speed": 25.0, "plant": "dynamic-bicycle"})).metrics
    a.pop("wall_time"), b.pop("wall_time")
    assert a == b


def test_without_a_controller_the_curve_throws_the_ego_off():
    m = run(RunSpec("lane-centering", "none", 0, {"speed": 25.0})).metrics
    assert m["status"] in ("diverged", "collision")
