"""ego compare under signals: Ctrl-C keeps the finished rows (in real processes, and in one
process with the in-process executor), SIGTERM and SIGKILL of the main process leave no
process of its group behind (workers, fork server, resource tracker), and the output folder
is held while it runs."""

import csv
import os
import signal
import subprocess
import sys

import pytest
from process_group import group, survivors, wait_for

from ego.compare import compare
from ego.control import CONTROLLERS, NoController, NoParams
from ego.control.base import ControllerSpec
from ego.parallel.executor import InlineExecutor


def _compare(out, *args, jobs=1):
    """Start ``ego compare emergency-brake`` in a session of its own (its pid is its group)."""
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "emergency-brake",
            *args,
            "--jobs",
            str(jobs),
            "--set",
            "duration=3600",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _rows(out):
    with open(out / "metrics.csv", newline="") as f:
        return [(r["controller"], r["seed"], r["status"]) for r in csv.DictReader(f)]


class CtrlCAt(NoController):
    """Presses Ctrl-C (SIGINT to this process) at its 10th control step."""

    def __init__(self, params, dt):
        self.steps = 0

    def step(self, obs):
        self.steps += 1
        if self.steps == 10:
            signal.raise_signal(signal.SIGINT)
        return 0.0, 0.0


def test_ctrl_c_in_an_in_process_comparison_stops_it_and_keeps_what_finished(point_mass, monkeypatch, tmp_path):
    monkeypatch.setitem(CONTROLLERS["tracking"], "ctrl-c", ControllerSpec("ctrl-c", "test", NoParams, CtrlCAt))
    out = tmp_path / "cmp"
    rows = compare(
        "point-mass", ["pid", "ctrl-c", "fuzzy"], 1, {"duration": 1.0}, out, progress=None, executor=InlineExecutor()
    )
    assert [(r.controller, r.status) for r in rows] == [
        ("pid", "completed"),
        ("ctrl-c", "interrupted"),
        ("fuzzy", "interrupted"),
    ]
    # the run that caught the Ctrl-C stopped at the next step, its metrics so far and its
    # recording closed; the one after it never ran
    assert rows[1].metrics["steps"] == 10 and rows[1].recording
    assert rows[2].metrics == {} and not rows[2].recording
    assert _rows(out) == [("pid", "0", "completed"), ("ctrl-c", "0", "interrupted"), ("fuzzy", "0", "interrupted")]
    assert "Interrupted: 2 of 3 runs did not finish" in (out / "metrics.md").read_text()
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["ctrl-c-seed0.rrd", "pid-seed0.rrd"]


@pytest.mark.sumo
def test_ctrl_c_keeps_the_finished_runs_and_marks_the_rest(tmp_path):
    out = tmp_path / "cmp"
    p = _compare(out, "--controllers", "none,pid", "--seeds", "2", "--set", "aeb=false")  # none collides
    first = out / "runs" / "none-seed0.rrd"  # a recording takes its name when its run ends
    wait_for(first.exists, p, "the first run finish")
    os.killpg(p.pid, signal.SIGINT)  # as a terminal does: the whole group
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stderr
    assert "Traceback" not in stderr and "did not finish" in stderr
    rows = _rows(out)
    assert rows[0] == ("none", "0", "collision")
    assert [r[:2] for r in rows] == [("none", "0"), ("none", "1"), ("pid", "0"), ("pid", "1")]
    unfinished = [r for r in rows if r[2] == "interrupted"]
    assert len(unfinished) >= 2  # the run under way and those never started
    # only finished runs have a recording, and no partial file is left
    finished = {f"{c}-seed{s}.rrd" for c, s, status in rows if status != "interrupted"}
    assert sorted(x.name for x in (out / "runs").iterdir()) == sorted(finished)
    md = (out / "metrics.md").read_text()
    assert f"Interrupted: {len(unfinished)} of 4 runs did not finish" in md
    assert f"{len(finished)} of 4 recordings" in stdout
    assert not survivors(p.pid)


@pytest.mark.sumo
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_a_killed_compare_leaves_no_process_behind(sig, tmp_path):
    out = tmp_path / "cmp"
    p = _compare(out, "--controllers", "pid,fuzzy", "--seeds", "3", jobs=2)
    # both workers are simulating: each has begun a recording
    wait_for(lambda: len(list((out / "runs").glob("*.partial"))) >= 2, p, "two runs under way")
    helpers = group(p.pid)
    assert len(helpers) >= 4  # ego, the fork server, the resource tracker, the workers
    p.send_signal(getattr(signal, sig))  # the main process only
    stdout, stderr = p.communicate(timeout=120)
    assert not survivors(p.pid)
    if sig == "SIGTERM":  # ends like Ctrl-C: every file written, no run claimed twice
        assert p.returncode == 130, stderr
        assert {r[2] for r in _rows(out)} <= {"completed", "interrupted"}
        assert not list((out / "runs").glob("*.partial"))
    else:
        assert p.returncode == -signal.SIGKILL
        assert not (out / "metrics.csv").exists()
        # the workers died mid-run: a worker that lived on would finish its run and put its
        # recording in place (renamed on close)
        assert not list((out / "runs").glob("*.rrd"))


@pytest.mark.sumo
@pytest.mark.long
def test_a_second_compare_into_a_busy_folder_is_refused(tmp_path):
    out = tmp_path / "cmp"
    p = _compare(out, "--controllers", "pid", "--seeds", "2")
    wait_for(lambda: list((out / "runs").glob("*.partial")), p, "a run under way")
    second = subprocess.run(
        [sys.executable, "-m", "ego", "compare", "emergency-brake", "--controllers", "fuzzy", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert second.returncode == 2
    assert second.stderr.count("\n") == 1 and "Traceback" not in second.stderr
    assert f"another ego process (pid {p.pid}) is writing into it" in second.stderr
    sweep_spec = tmp_path / "s.toml"
    sweep_spec.write_text('scenario = "emergency-brake"\ncontrollers = ["pid"]\n')
    third = subprocess.run(
        [sys.executable, "-m", "ego", "sweep", str(sweep_spec), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert third.returncode == 2 and f"(pid {p.pid})" in third.stderr
    p.kill()
    p.communicate()
    assert not survivors(p.pid)
    # the holder is gone: the folder is free again (a dead holder needs no cleaning up)
    again = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "emergency-brake",
            "--controllers",
            "none",
            "--set",
            "duration=2",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stderr
    assert _rows(out) == [("none", "0", "completed")]
    assert sorted(x.name for x in (out / "runs").iterdir()) == ["none-seed0.rrd"]
