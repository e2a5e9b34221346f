"""Faults inside ego compare's runs: a controller that raises mid-run and a SUMO that fails to
start are rows with status ``error`` and the reason, the worker that ran them goes on to run
the next ones, and a comparison where every run failed says so (exit 1, no recording
claimed)."""

import csv
import os
import subprocess
import sys

import pytest
from engine_tasks import compare_run_with_fault

from ego.compare import run_one
from ego.parallel.executor import ProcessExecutor
from ego.runner import RunSpec

pytestmark = pytest.mark.sumo


@pytest.fixture
def broken_nets(tmp_path):
    """A networks folder whose highway network passes ego's checks (the file is there) but
    that SUMO refuses."""
    folder = tmp_path / "nets" / "highway"
    folder.mkdir(parents=True)
    (folder / "highway.net.xml").write_text('<net version="1.20"><edge id="x" from="nowhere"/></net>\n')
    return folder.parent


def test_faulty_runs_are_error_rows_and_the_same_worker_runs_the_next(broken_nets, tmp_path):
    def spec(controller, seed):
        return RunSpec(
            "emergency-brake",
            controller,
            seed,
            {"duration": 3.0, "traffic_density": 0},
            record=str(tmp_path / f"{controller}-{seed}.rrd"),
            background_recording=False,
        )

    jobs = [
        ("none", spec("pid", 0), None),
        ("controller", spec("raises", 1), 40),
        ("sumo", spec("pid", 2), broken_nets),
        ("none", spec("pid", 3), None),
        ("controller", spec("raises", 4), 1),
        ("none", spec("fuzzy", 5), None),
    ]
    with ProcessExecutor(1) as ex:
        outcomes = list(ex.run(compare_run_with_fault, jobs))
        worker = ex.pids()
        assert len(outcomes) == len(jobs)
        assert ex.pids() == worker  # one worker did it all: never replaced
    assert all(o.attempts == 1 and not o.error for o in outcomes)  # no worker died
    rows = {r.seed: r for r in (o.value for o in outcomes)}
    assert [rows[s].status for s in range(6)] == ["completed", "error", "error", "completed", "error", "completed"]
    assert rows[1].error == "RuntimeError: controller fault injected at step 40"
    assert rows[4].error == "RuntimeError: controller fault injected at step 1"
    assert rows[2].error.startswith("SumoError: SUMO could not start on ") and "highway.net.xml" in rows[2].error
    assert rows[1].metrics == {} and rows[3].metrics["status"] == "completed"
    # a run that raised mid-run still closed its recording; one that never started has none
    assert (tmp_path / "raises-1.rrd").exists() and not (tmp_path / "pid-2.rrd").exists()
    # and the run after the faults is the run a fresh process gives
    fresh = run_one(RunSpec("emergency-brake", "pid", 3, {"duration": 3.0, "traffic_density": 0}))
    assert {**rows[3].metrics, "wall_time": 0} == {**fresh.metrics, "wall_time": 0}


def test_a_compare_where_every_run_fails_exits_1_and_claims_no_recording(broken_nets, tmp_path):
    out = tmp_path / "cmp"
    env = dict(os.environ, EGO_SUMO_NETS=str(broken_nets))
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "emergency-brake",
            "--controllers",
            "pid,fuzzy",
            "--seeds",
            "2",
            "--jobs",
            "1",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert p.returncode == 1, p.stderr
    assert "ego: 4 of 4 runs ended in an error" in p.stderr and "Traceback" not in p.stderr
    assert "0 of 4 recordings" in p.stdout
    rows = list(csv.DictReader(open(out / "metrics.csv", newline="")))
    assert [r["status"] for r in rows] == ["error"] * 4
    assert all(r["error"].startswith("SumoError: SUMO could not start on") for r in rows)
    assert list((out / "runs").iterdir()) == []
    assert "| pid | 2 error |" in (out / "metrics.md").read_text()
