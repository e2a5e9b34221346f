"""ego tune lane-centering --cost sumo: each member's cost from SUMO runs through an engine."""

import json

import numpy as np
import pytest

from ego.control.cascade import REPORT_GAINS
from ego.runner import RunSpec, run
from ego.train.lane_centering import TuneSpec, cost, sumo_cost, tune

pytestmark = pytest.mark.sumo


def test_a_members_sumo_cost_is_the_reports_cost_of_that_run():
    got = sumo_cost((REPORT_GAINS, 8.0, 0.5, 10.0))
    r = run(
        RunSpec(
            "lane-centering",
            "cascade-pid",
            0,
            {"preset": "report", "plant": "dynamic-bicycle", "speed": 8.0, "offset": 0.5, "duration": 10.0},
        )
    )
    e = np.abs(r.column("d"))
    want = float(cost(np.array([e.max()]), np.array([e.mean()]), np.array([e.std()]))[0])
    assert got == pytest.approx(want, rel=1e-12) and 0.0 < got < 1e4


def test_differential_evolution_runs_its_generations_on_the_process_engine(tmp_path):
    out = tmp_path / "preset.json"
    spec = TuneSpec(popsize=1, maxiter=2, seed=0, workers=2, drives=((8.0, 0.5),), cost="sumo", duration=8.0)
    preset = tune(spec, out, log=lambda *_: None)
    saved = json.loads(out.read_text())
    assert saved["differential_evolution"]["cost"] == "sumo"
    assert saved["simulated_members"] >= 24  # the initial population and at least one generation
    assert 0.0 < preset["cost"] < 1e4
    # the best member's cost is what its own SUMO run gives
    gains = [preset["gains"][k] for k in preset["gains"]]
    assert sumo_cost((gains, 8.0, 0.5, 8.0)) == pytest.approx(preset["cost"], rel=1e-9)
