"""Controllers named by reference - a Python file's class and an FMU - in ego run, ego compare
--jobs 2 and ego sweep on the process and Ray engines: the workers load them themselves; a
faulty FMU's runs end as ``error`` with its message while the sweep goes on; no process or
temporary folder is left behind."""

import csv
import json
import subprocess
import sys

import pyarrow.parquet as pq
import pytest
from fmu_zoo import fmu_folders, fmu_folders_left
from process_group import survivors

from ego.params import ConfigError
from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

USER_CONTROLLER = '''
"""A user's controller in a file of their own: ego's pid under another name."""
from ego.control.pid import PIDController, PIDParams


class MyPID(PIDController):
    """ego's tracking pid, from a user's file."""

    Params = PIDParams
    task = "tracking"


class Broken:
    """Not a controller."""
'''

DROP = ("wall_time", "controller", "real_time_factor")


@pytest.fixture
def user_file(tmp_path):
    path = tmp_path / "my_controllers.py"
    path.write_text(USER_CONTROLLER)
    return path


def metrics(spec):
    return {k: v for k, v in run(spec).metrics.items() if k not in DROP}


def test_a_files_class_and_a_modules_class_are_controllers(user_file, monkeypatch):
    over = {"duration": 5.0, "kp_lat": 0.02}
    builtin = metrics(RunSpec("emergency-brake", "pid", overrides=over))
    assert metrics(RunSpec("emergency-brake", f"{user_file}:MyPID", overrides=over)) == builtin
    monkeypatch.syspath_prepend(str(user_file.parent))
    assert metrics(RunSpec("emergency-brake", "my_controllers:MyPID", overrides=over)) == builtin


@pytest.mark.parametrize(
    "ref,expected",
    [
        ("{f}:Broken", "class Broken has no reset, step, signals"),
        ("{f}:Nope", "has no 'Nope'"),
        ("nowhere/file.py:X", "no file 'nowhere/file.py'"),
        ("no_such_module_xyz:X", "cannot import 'no_such_module_xyz'"),
    ],
)
def test_bad_references_are_config_errors(user_file, ref, expected):
    with pytest.raises(ConfigError, match=expected):
        run(RunSpec("emergency-brake", ref.format(f=user_file)))


def test_a_class_for_another_task_is_refused(user_file):
    with pytest.raises(ConfigError, match="drives the tracking task, not curve"):
        run(RunSpec("curve", f"{user_file}:MyPID"))


def ego(*args, cwd=None, timeout=600):
    """An ego command in a session of its own; (completed process, leftover processes)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "ego", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        cwd=cwd,
    )
    out, err = proc.communicate(timeout=timeout)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), survivors(proc.pid)


def test_compare_jobs_2_with_a_file_class_and_fmus(user_file, fmus, tmp_path):
    before = fmu_folders()
    controllers = ",".join(["pid", f"{user_file}:MyPID", fmus["pid"], f"{fmus['pid']}@fmu.kp_lat=0.02", fmus["error"]])
    proc, left = ego(
        "compare",
        "emergency-brake",
        "--controllers",
        controllers,
        "--jobs",
        "2",
        "--set",
        "duration=4",
        "--set",
        "fmu.fail_step=20",
        "--out",
        str(tmp_path / "cmp"),
    )
    assert proc.returncode == 1, proc.stderr  # one controller's runs ended in error
    assert not left
    rows = {r["controller"]: r for r in csv.DictReader(open(tmp_path / "cmp" / "metrics.csv"))}
    keep = [k for k in rows["pid"] if k not in DROP]
    assert {k: rows[f"{user_file}:MyPID"][k] for k in keep} == {k: rows["pid"][k] for k in keep}
    assert {k: rows[fmus["pid"]][k] for k in keep} == {k: rows["pid"][k] for k in keep}
    assert {k: rows[f"{fmus['pid']}@fmu.kp_lat=0.02"][k] for k in keep} != {k: rows["pid"][k] for k in keep}
    bad = rows[fmus["error"]]
    assert bad["status"] == "error" and "actuator model diverged at t = 0.20 s" in bad["error"]
    assert not fmu_folders_left(before)


@pytest.mark.parametrize("engine", ["process", pytest.param("ray", marks=pytest.mark.long)])
def test_sweep_with_a_file_class_and_fmus(user_file, fmus, tmp_path, engine):
    before = fmu_folders()
    spec = tmp_path / "sweep.toml"
    names = ["pid", f"{user_file}:MyPID", fmus["pid"], fmus["error"]]
    spec.write_text(
        f'scenario = "emergency-brake"\ncontrollers = {json.dumps(names)}\nseeds = 1\n'
        "[set]\nduration = 3\n[grid]\nego_speed = [20, 25]\n"
    )
    proc, left = ego(
        "sweep", str(spec), "--engine", engine, "--jobs", "2", "--record", "none", "--out", str(tmp_path / "sw")
    )
    assert proc.returncode == 1, proc.stderr  # the faulty FMU's runs are errors; the sweep went on
    assert not left
    by = {}
    for row in pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist():
        by.setdefault(row["controller"], []).append(row)
    assert {c: len(rs) for c, rs in by.items()} == {c: 2 for c in names}
    errors = by[fmus["error"]]
    assert all(r["status"] == "error" and "actuator model diverged at t = 0.50 s" in r["error"] for r in errors)
    pid = {r["ego_speed"]: r["max_abs_lateral_accel"] for r in by["pid"]}
    for name in names[1:3]:  # the same runs as the built-in pid
        assert {r["ego_speed"]: r["max_abs_lateral_accel"] for r in by[name]} == pid
        assert all(r["status"] in ("completed", "ended") for r in by[name])
    assert not fmu_folders_left(before)


def test_an_fmu_parameter_is_swept_like_any_other(fmus, tmp_path):
    spec = tmp_path / "sweep.toml"
    spec.write_text(
        f'scenario = "emergency-brake"\ncontrollers = ["{fmus["pid"]}"]\nseeds = 1\n'
        '[set]\nduration = 5\n[grid]\n"fmu.kp_lat" = [0.01, 0.02]\n'
    )
    proc, left = ego("sweep", str(spec), "--jobs", "2", "--record", "none", "--out", str(tmp_path / "sw"))
    assert proc.returncode == 0, proc.stderr
    rows = {r["fmu.kp_lat"]: r for r in pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist()}
    over = {"duration": 5.0}
    for gain, row in rows.items():
        builtin = run(RunSpec("emergency-brake", "pid", overrides={**over, "kp_lat": gain})).metrics
        assert row["max_abs_lateral_accel"] == builtin["max_abs_lateral_accel"]
