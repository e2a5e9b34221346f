"""Sine tracking in SUMO and report 000's bare-model experiments."""

import pytest

from ego.runner import RunSpec, run


@pytest.mark.sumo
@pytest.mark.parametrize("controller, bound", [("rbf-smc", 0.05), ("fuzzy", 1.0)])
def test_sine_at_0_5_rad_s_converges(controller, bound, fuzzy_ready):
    m = run(RunSpec("sine-tracking", controller, 0, {"omega": "0.5"})).metrics
    assert m["status"] == "completed"
    assert m["max_abs_lateral_error_after_10s"] < bound
    assert m["rms_lateral_error_after_10s"] <= m["max_abs_lateral_error_after_10s"]
    for key in ("rms_lateral_error", "max_abs_lateral_error", "rms_lateral_error_after_10s", "rms_speed_error"):
        assert m[key] is not None


@pytest.mark.sumo
def test_sine_reference_is_the_reports(fuzzy_ready):
    r = run(RunSpec("sine-tracking", "rbf-smc", 0, {"omega": "0.5", "duration": "20"}))
    import numpy as np

    t, d_ref = r.column("t"), r.column("d_ref")
    np.testing.assert_allclose(d_ref, 4.0 * np.sin(0.5 * t), atol=1e-12)
    assert np.all(r.column("speed_ref") == 25.0)


@pytest.mark.parametrize("ref_speed", ["25", "15"], ids=["accelerate", "decelerate"])
def test_report_000_lane_change_with_rbf_has_no_overshoot(ref_speed):
    m = run(RunSpec("report-000", "rbf-smc", 0, {"ref_speed": ref_speed})).metrics
    assert m["status"] == "completed" and m["lane_change_completed"]
    assert m["lane_change_duration"] < 10.0 and m["max_overshoot"] < 0.1
    assert m["x_settling_time"] is not None


def test_report_000_bp_pid_as_published_diverges():
    m = run(RunSpec("report-000", "bp-pid", 0, {"variant": "report"})).metrics
    assert m["status"] == "diverged"


def test_report_000_sine_case_has_tracking_metrics(fuzzy_ready):
    m = run(RunSpec("report-000", "fuzzy", 0, {"case": "sine", "omega": "0.2"})).metrics
    assert m["status"] == "completed" and m["rms_lateral_error"] < 1.0
    assert "lane_change_duration" not in m
