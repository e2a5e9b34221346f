"""FMUs as controllers: ego's pid re-implemented in C as FMI 2.0 co-simulation FMUs gives the
built-in pid's metrics exactly; units are converted, parameters set, mappings read; a faulty
FMU ends its run as ``error`` with its own message, every resource released."""

import json
import os
import subprocess
import sys
import tempfile

import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

DROP = ("wall_time", "controller", "real_time_factor")


def metrics(spec: RunSpec) -> dict:
    result = run(spec)
    return {k: v for k, v in result.metrics.items() if k not in DROP}


def same(a: dict, b: dict, rel: float = 1e-9) -> None:
    assert a.keys() == b.keys()
    for k in a:
        if isinstance(a[k], float) and isinstance(b[k], float):
            assert b[k] == pytest.approx(a[k], rel=rel, abs=1e-9), k
        else:
            assert a[k] == b[k], k


@pytest.mark.parametrize(
    "scenario,fmu", [("emergency-brake", "pid"), ("cut-in", "pid"), ("curve", "pid_curve"), ("emergency-brake", "pid3")]
)
def test_pid_as_an_fmu_gives_the_builtin_pids_metrics(fmus, scenario, fmu):
    builtin = metrics(RunSpec(scenario, "pid"))
    assert builtin["status"] in ("completed", "ended")
    same(builtin, metrics(RunSpec(scenario, fmus[fmu])))


def test_fmu_parameters_are_set_like_the_builtin_ones(fmus):
    over = {"duration": 8.0}
    builtin = metrics(RunSpec("emergency-brake", "pid", overrides={**over, "kp_lat": 0.02, "kd_lon": 1200.0}))
    fmu = metrics(RunSpec("emergency-brake", fmus["pid"], overrides={**over, "fmu.kp_lat": 0.02, "fmu.kd_lon": "1200"}))
    same(builtin, fmu)
    assert fmu != metrics(RunSpec("emergency-brake", fmus["pid"], overrides=over))


def test_units_km_h_kn_and_degrees_are_converted(fmus):
    same(metrics(RunSpec("cut-in", "pid")), metrics(RunSpec("cut-in", fmus["pid_units"])), rel=1e-7)


def test_a_unit_listed_by_name_only_is_read_as_the_common_unit(fmus, tmp_path):
    """km/h in the FMU's UnitDefinitions without a BaseUnit: read as ego's km/h, the same run
    as with the full definition."""
    import re
    import zipfile

    full = fmus["pid_units"]
    with zipfile.ZipFile(full) as z:
        md = z.read("modelDescription.xml").decode()
        named = re.sub(r'<Unit name="km/h"><BaseUnit[^/]*/></Unit>', '<Unit name="km/h"/>', md)
        assert named != md
        path = tmp_path / "pid_named_units.fmu"
        with zipfile.ZipFile(path, "w") as out:
            for name in z.namelist():
                out.writestr(name, named if name == "modelDescription.xml" else z.read(name))
    over = {"duration": 8.0}
    same(metrics(RunSpec("cut-in", full, overrides=over)), metrics(RunSpec("cut-in", str(path), overrides=over)))


def test_a_mapping_file_connects_other_names_and_units(fmus, tmp_path):
    mapping = tmp_path / "map.toml"
    mapping.write_text('[outputs]\nforce = "Fx"\nsteer = "delta"\n')
    over = {"duration": 4.0}
    renamed = metrics(
        RunSpec("emergency-brake", fmus["renamed"], overrides={**over, "fmu_map": str(mapping), "fmu.hold_fx": 0.25})
    )
    # the same command in N from the other FMU: 0.25 kN = 250 N
    plain = metrics(
        RunSpec("emergency-brake", fmus["error"], overrides={**over, "fmu.fail_step": 1e9, "fmu.hold_fx": 250.0})
    )
    same(plain, renamed)


@pytest.mark.parametrize(
    "fmu,detail",
    [
        ("error", "FMU error_at_step (doStep at t = 0.300 s): error: actuator model diverged at t = 0.30 s (step 30)"),
        ("nan", "FMU nan_output: output 'delta' (delta) is nan at t = 0.300 s (step 30)"),
        (
            "error3",
            "FMU error_at_step3 (doStep at t = 0.300 s): error: actuator model diverged at t = 0.30 s (step 30)",
        ),
    ],
)
def test_a_faulty_fmu_ends_the_run_as_error_with_its_message(fmus, fmu, detail, tmp_path):
    before = set(os.listdir(tempfile.gettempdir()))
    result = run(
        RunSpec(
            "emergency-brake",
            fmus[fmu],
            overrides={"fmu.fail_step": 30},
            record=str(tmp_path / "r.rrd"),
            background_recording=False,
        )
    )
    assert (result.status, result.metrics["status_detail"]) == ("error", detail)
    assert result.metrics["steps"] == 30 if fmu != "nan" else 31
    fmu_events = [e for e in result.events if e.kind == "fmu"]
    assert fmu_events[0].text.endswith("faulty controller initialised (logEvents)")
    if fmu != "nan":  # the FMU's log message is an event of the run and the recording
        assert fmu_events[-1].level == "ERROR" and "actuator model diverged" in fmu_events[-1].text
    assert (tmp_path / "r.rrd").stat().st_size > 0
    # this process's own folders (a test beside it under pytest -n has its own)
    left = {n for n in set(os.listdir(tempfile.gettempdir())) - before if n.startswith(f"ego-fmu-{os.getpid()}-")}
    assert not left


def test_the_cli_reports_an_fmu_error_as_status_error(fmus, tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "run",
            "emergency-brake",
            "-c",
            fmus["error"],
            "--set",
            "fmu.fail_step=10",
            "--json",
        ],
        capture_output=True,
        text=True,
    )
    out = json.loads(proc.stdout)
    assert proc.returncode == 1 and out["status"] == "error"
    assert "actuator model diverged at t = 0.10 s" in out["status_detail"]


def test_reset_between_runs_gives_the_same_run(fmus):
    from ego.control import controller_spec
    from ego.scenarios import scenario_class

    cls = scenario_class("emergency-brake")
    config = cls.default_config({"duration": 3.0})
    spec = controller_spec(fmus["pid"], "tracking")
    scenario = cls(config, cls.build_controller(spec, spec.params(), config), controller_name="fmu")
    first = scenario.run().metrics
    second = scenario.run().metrics  # closed after the first run: instantiated afresh
    scenario.reset()
    scenario.controller.reset()  # a live instance: fmi2Reset
    while not scenario.done:
        scenario.step(scenario.controller.step(scenario.obs))
    third = scenario.result().metrics
    scenario.close()
    for m in (second, third):
        same({k: v for k, v in first.items() if k not in DROP}, {k: v for k, v in m.items() if k not in DROP})


def test_ctrl_c_ends_the_run_and_frees_the_fmu(fmus, tmp_path):
    """SIGINT mid-run: the run ends as interrupted, the FMU instance is terminated and freed
    and its extracted folder removed, with or without a second Ctrl-C."""
    import signal
    import time

    env = dict(os.environ, TMPDIR=str(tmp_path))
    for presses in (1, 2):
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "ego",
                "run",
                "sine-tracking",
                "-c",
                fmus["pid"],
                "--set",
                "duration=3600",
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        deadline = time.monotonic() + 120
        while not any(p.name.startswith("ego-fmu-") for p in tmp_path.iterdir()):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.05)
        time.sleep(1.0)  # running
        for _ in range(presses):
            proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
        if presses == 1:
            assert proc.returncode == 130, err
            assert json.loads(out)["status"] == "interrupted"
        else:  # the second press interrupts at once (or, landing late, the exit itself)
            assert proc.returncode in (130, -signal.SIGINT), err
        assert not [p.name for p in tmp_path.iterdir() if p.name.startswith("ego-fmu-")]
