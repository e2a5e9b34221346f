"""Lane departure (issue 38, point 3): the measure by hand, the requirement's signal, and a
real file scenario on a curve whose run leaves its lane ending ``failed`` (exit 1)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from ego.cli import main
from ego.lane_frame import MARKING_WIDTH, lane_departure
from ego.requirements import DERIVED, defaults, evaluate, parse
from ego.scenarios.base import RunResult

CURVE = Path(__file__).resolve().parents[1] / "scenarios" / "openscenario" / "curve.xosc"


def test_departure_by_hand():
    # a 3.5 m lane, a 1.8 m car: the side reaches the marking's outer edge (1.75 + 0.075 m
    # from the centre) when its centre of gravity is 1.825 - 0.9 = 0.925 m off the centre
    d = np.array([0.0, 0.925, -1.025, 1.2, 1.2, 0.5, 1.2, 1.2])
    d_ref = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
    phase = np.array([0, 0, 2, 1, 3, 0, 0, 0])
    out = lane_departure(d, d_ref, phase, 3.5, 1.8)
    assert MARKING_WIDTH == 0.15
    # in the lane; on the edge; 0.1 m beyond on the right; a lane change; still settling into
    # the lane right after it (not yet back inside the marking); back inside; 0.275 m beyond,
    # now a departure; a reference off the centre (a commanded lateral motion)
    assert out == pytest.approx([0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.275, 0.0], abs=1e-12)
    signed = lane_departure(d, d_ref, phase, 3.5, 1.8, signed=True)
    assert signed[:3] == pytest.approx([-0.925, 0.0, 0.1], abs=1e-12)
    assert signed[5:7] == pytest.approx([-0.425, 0.275], abs=1e-12)
    assert signed[3] == signed[4] == signed[7] == -math.inf


def test_stays_in_lane_is_a_default_of_the_lane_scenarios_and_reads_the_margin():
    for name in ("emergency-brake", "cut-in", "fast-follower"):
        assert defaults(name)["stays_in_lane"] == "always (lane_departure <= 0 m)"
    t = np.arange(5) * 0.1
    columns = {"d": np.array([0.0, 0.3, 0.5, 0.2, 0.0]), "d_ref": np.zeros(5), "phase": np.zeros(5)}
    trace = np.column_stack([t, *columns.values()])
    result = RunResult("x", "y", 0, "completed", {}, [], ("t", *columns), trace, lanes=((3.5, ()),))
    assert DERIVED["lane_departure"].fn(result, t) == pytest.approx(np.array([-0.925, -0.625, -0.425, -0.725, -0.925]))
    req = parse("always (lane_departure <= 0 m)", {"lane_departure": "m", "t": "s"}, "stays_in_lane")
    assert evaluate(req, result).robustness == pytest.approx(0.425, abs=1e-9)


def test_a_run_that_leaves_its_lane_fails(capsys):
    """The shipped R 15 m curve with pid, its curvature feed-forward switched off: the tracking
    controller drifts out of its lane; cut at 12 s, before it leaves the road, the run is failed."""
    code = main(["run", str(CURVE), "-c", "pid", "--set", "duration=12", "--set", "feedforward=false", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["status"] == "failed"
    assert "left its lane" in out["status_detail"]
    assert out["max_lane_departure"] > 1.0
    assert out["requirements"]["stays_in_lane"] == pytest.approx(-out["max_lane_departure"], abs=1e-3)
    kinds = [e["kind"] for e in out["events"]]
    assert "lane_departure" in kinds and "requirement" in kinds


def test_a_straight_run_stays_in_its_lane(capsys):
    code = main(["run", "emergency-brake", "-c", "pid", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "completed"
    assert out["max_lane_departure"] == 0.0 and out["requirements"]["stays_in_lane"] > 0.5
