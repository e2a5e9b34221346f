"""FMU plants: ego's own bicycles exported with ego export-fmu and run as the ego's plant
(--set plant=vehicle.fmu) give the metrics of the built-in plant; a plant FMU is checked
before anything runs."""

import subprocess
import sys

import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo
DROP = ("wall_time", "controller", "real_time_factor")


def export(tmp_path, model, *sets):
    out = tmp_path / f"{model}.fmu"
    args = [a for s in sets for a in ("--set", s)]
    subprocess.run(
        [sys.executable, "-m", "ego", "export-fmu", model, "--out", str(out), *args], check=True, capture_output=True
    )
    return str(out)


def metrics(spec):
    return {k: v for k, v in run(spec).metrics.items() if k not in DROP}


def test_the_exported_nonlinear_bicycle_as_the_plant_of_emergency_brake(tmp_path):
    # the motorway scenarios run report 000's model with ABS and a 1 m/s slip-speed floor
    fmu = export(tmp_path, "nonlinear-bicycle", "abs=1", "slip_speed_floor=1")
    builtin = metrics(RunSpec("emergency-brake", "pid"))
    assert builtin["status"] == "completed"
    assert metrics(RunSpec("emergency-brake", "pid", overrides={"plant": fmu})) == builtin


def test_the_exported_linear_bicycle_as_the_plant_of_the_curve(tmp_path):
    fmu = export(tmp_path, "linear-bicycle", "slip_speed_floor=1")
    builtin = metrics(RunSpec("curve", "fuzzy-curve", overrides={"substeps": 2}))
    assert metrics(RunSpec("curve", "fuzzy-curve", overrides={"substeps": 2, "plant": fmu})) == builtin


def test_a_plant_fmu_and_a_controller_fmu_together(tmp_path, fmus):
    fmu = export(tmp_path, "nonlinear-bicycle", "abs=1", "slip_speed_floor=1")
    over = {"duration": 6.0}
    builtin = metrics(RunSpec("cut-in", "pid", overrides=over))
    assert metrics(RunSpec("cut-in", fmus["pid"], overrides={**over, "plant": fmu})) == builtin


def ego_error(*args):
    proc = subprocess.run([sys.executable, "-m", "ego", "run", *args], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    return proc.stderr


def test_plant_fmus_are_checked_before_anything_runs(tmp_path, fmus):
    # a controller FMU is no plant: its inputs are not the plant's commands
    assert "input 's_ref' is connected to no observation signal (known: Fx, a_x, delta)" in ego_error(
        "emergency-brake", "-c", "pid", "--set", f"plant={fmus['pid']}"
    )
    # outputs named otherwise need a mapping: plant_map (fmu_map is a controller FMU's)
    unmapped = ego_error("emergency-brake", "-c", "pid", "--set", f"plant={fmus['error']}")
    assert "no output for the plant output 'X'" in unmapped and "(--set plant_map=map.toml)" in unmapped
    assert "bad value for plant_map: no file 'nowhere.toml'" in ego_error(
        "emergency-brake", "-c", "pid", "--set", f"plant={fmus['error']}", "--set", "plant_map=nowhere.toml"
    )
    assert "plant_map needs plant" in ego_error("emergency-brake", "-c", "pid", "--set", "plant_map=m.toml")
    # lane centring has a plant parameter of its own (its model)
    assert "bad value for plant" in ego_error("lane-centering", "-c", "cascade-pid", "--set", f"plant={fmus['pid']}")
