"""ego sweep on the process engine: identical rows for any --jobs, resume after a kill, a
dead worker, the summary and the envelope plots."""

import os
import signal
import subprocess
import sys
import time

import pyarrow.parquet as pq
import pytest

from ego.parallel.executor import ProcessExecutor
from ego.sweep.pipeline import execute
from ego.sweep.runner import sweep, task_of
from ego.sweep.spec import parse

pytestmark = pytest.mark.sumo

SPEC = {
    "scenario": "emergency-brake",
    "controllers": ["pid", "fuzzy"],
    "seeds": 1,
    "set": {"duration": 8.0, "traffic_density": 5},
    "grid": {"ego_speed": [20, 30]},
    "sample": {"method": "lhs", "n": 3, "lead_decel": [3, 9]},
}
#: what differs between two runs of one spec besides the results
NOISE = ("wall_time", "host")


def _rows(table):
    rows = table.to_pylist()
    return {r["run_id"]: {k: v for k, v in r.items() if k not in NOISE} for r in rows}


def test_one_and_two_workers_give_identical_rows_and_write_everything(tmp_path, fuzzy_ready):
    spec = parse(SPEC, "spec.toml")
    a = sweep(spec, tmp_path / "a", jobs=1, record="none", plots=["ego_speed,lead_decel:min_gap_front"])
    b = sweep(spec, tmp_path / "b", jobs=2, record="none")
    assert a.ran == b.ran == spec.count() == 12 and not a.interrupted
    ta, tb = pq.read_table(tmp_path / "a" / "results.parquet"), pq.read_table(tmp_path / "b" / "results.parquet")
    assert _rows(ta) == _rows(tb)
    row = ta.to_pylist()[0]
    for column in (
        "run_id",
        "scenario",
        "controller",
        "seed",
        "ego_speed",
        "lead_decel",
        "duration",
        "traffic_density",
        "status",
        "min_gap_front",
        "wall_time",
        "host",
    ):
        assert column in row
    # a row is what ego run gives for the same run
    from ego.runner import RunSpec, run

    r = run(
        RunSpec(
            row["scenario"],
            row["controller"],
            row["seed"],
            {k: row[k] for k in ("duration", "traffic_density", "ego_speed", "lead_decel")},
        )
    )
    assert r.metrics["min_gap_front"] == row["min_gap_front"]
    summary = (tmp_path / "a" / "summary.md").read_text()
    assert "| pid | 6 |" in summary and "min_gap_front [m]" in summary
    assert (tmp_path / "a" / "envelope_ego_speed_lead_decel_min_gap_front.png").stat().st_size > 10_000
    # the same command again resumes: nothing left to run
    again = sweep(spec, tmp_path / "a", jobs=2, record="none")
    assert again.already == 12 and again.ran == 0


@pytest.mark.long  # a minute; the interrupted-and-resumed sweep of test_sweep_interrupt.py runs by default
def test_a_killed_sweep_resumes_with_no_duplicate_and_no_missing_row(tmp_path):
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(
        'scenario = "emergency-brake"\ncontrollers = ["pid", "fuzzy"]\nseeds = 3\n'
        "[set]\ntraffic_density = 10\n[grid]\nego_speed = [15, 20, 25, 30, 33]\n"
        "lead_gap = [20, 40, 60]\n"
    )
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "ego", "sweep", str(spec_file), "--out", str(out), "--record", "none"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    results = out / "results.parquet"
    deadline = time.time() + 120
    while time.time() < deadline and not results.exists():
        time.sleep(0.1)
    assert results.exists(), "no batch was written"
    import psutil

    children = psutil.Process(proc.pid).children(recursive=True)
    proc.send_signal(signal.SIGKILL)  # no chance to clean up
    proc.wait()
    first = pq.read_table(results).num_rows
    assert 0 < first < 90
    # the workers see their parent go and exit: nothing lives on
    gone, alive = psutil.wait_procs(children, timeout=15)
    assert not alive, [p.cmdline() for p in alive]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert f"{first} were already in" in p.stdout and f"{90 - first} ran now" in p.stdout
    ids = pq.read_table(results).column("run_id").to_pylist()
    assert len(ids) == 90 and len(set(ids)) == 90


def test_a_dead_worker_costs_one_retry_and_never_stops_the_sweep(tmp_path):
    spec = parse({**SPEC, "controllers": ["pid"], "set": {"duration": 25.0, "traffic_density": 0}})
    tasks = [task_of(r) for r in spec.runs()]
    victim = tasks[0].key.run_id
    with ProcessExecutor(2) as ex:
        outcomes = []
        for outcome in ex.run(execute, tasks):
            outcomes.append(outcome)
            if len(outcomes) == 1:  # kill a busy worker while the others keep going
                os.kill(ex.pids()[0], signal.SIGKILL)
    assert len(outcomes) == len(tasks)
    assert {o.task.key.run_id for o in outcomes} == {t.key.run_id for t in tasks}
    assert all(o.value is not None and o.value.status == "completed" for o in outcomes)
    assert max(o.attempts for o in outcomes) == 2  # the killed worker's run ran again
    assert victim in {o.task.key.run_id for o in outcomes}


def test_failed_runs_are_recorded_by_default_and_an_error_is_a_row(tmp_path):
    spec = parse(
        {
            "scenario": "emergency-brake",
            "controllers": ["none", "pid"],
            "seeds": 1,
            "set": {"duration": 10.0, "traffic_density": 0, "aeb": False},  # no controller, no AEB: a collision
        }
    )
    report = sweep(spec, tmp_path, jobs=2)
    assert report.by_status == {"collision": 1, "completed": 1}
    rrds = sorted(p.name for p in (tmp_path / "runs").glob("*.rrd"))
    assert len(rrds) == 1 and rrds[0].startswith("none-")


def test_an_envelope_metric_under_a_prefix_has_the_prefix_unit():
    from ego.sweep.report import _unit

    assert _unit("platoon", "settle_times.brake@10s") == "s"
    assert _unit("emergency-brake", "min_gap_front") == "m"


@pytest.mark.sumo
def test_no_more_workers_than_runs_to_do(tmp_path, monkeypatch):
    """--jobs 200 for a one-run spec started 200 worker processes (10.7 s against 1.6 s)."""
    import ego.sweep.runner as runner

    asked = []
    make = runner.make_executor

    def counting(engine, workers=None, address=None):
        asked.append(workers)
        return make(engine, workers, address)

    monkeypatch.setattr(runner, "make_executor", counting)
    spec = parse({"scenario": "emergency-brake", "controllers": ["pid"], "seeds": 1, "set": {"duration": 3.0}})
    report = sweep(spec, tmp_path / "out", jobs=200, record="none")
    assert asked == [1] and len(pq.read_table(tmp_path / "out" / "results.parquet")) == 1
    assert report is not None


@pytest.mark.sumo
def test_a_ctrl_c_while_the_summary_is_written_waits_for_it(tmp_path, monkeypatch):
    """A signal after the last run (every run done) lands while the summary is written: the
    summary is written whole, then the interruption is raised."""
    import ego.sweep.report as report

    write = report.write_summary

    def interrupted_while_writing(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return write(*args, **kwargs)

    monkeypatch.setattr(report, "write_summary", interrupted_while_writing)
    spec = parse({"scenario": "emergency-brake", "controllers": ["pid"], "seeds": 1, "set": {"duration": 3.0}})
    # Python's own Ctrl-C handler, whatever the test runner's worker put there
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            sweep(spec, tmp_path / "out", jobs=1, record="none")
    finally:
        signal.signal(signal.SIGINT, previous)
    assert "emergency-brake" in (tmp_path / "out" / "summary.md").read_text()
