"""The command line as a user runs it (a subprocess, real SUMO)."""

import json
import subprocess
import sys

import pytest

from ego.cli import main
from ego.scenarios.base import COMMON_METRICS, COMMON_TAIL_METRICS

EGO = [sys.executable, "-m", "ego"]
COMMON = {m.name for m in COMMON_METRICS + COMMON_TAIL_METRICS}


def ego(*args, env=None):
    return subprocess.run([*EGO, *args], capture_output=True, text=True, env=env, timeout=300)


def test_list_names_every_parameter_with_default_and_unit():
    out = ego("list", "--json")
    assert out.returncode == 0, out.stderr
    cat = json.loads(out.stdout)
    scenarios = {s["name"]: s for s in cat["scenarios"]}
    params = {p["name"]: p for p in scenarios["emergency-brake"]["parameters"]}
    for name in (
        "dt",
        "duration",
        "ego_speed",
        "lead_gap",
        "lead_brake_time",
        "lead_decel",
        "lead_final_speed",
        "ttc_threshold",
        "traffic_density",
    ):
        assert name in params and params[name]["unit"] and params[name]["default"] is not None
    assert params["lead_decel"]["unit"] == "m/s^2"
    assert {c["name"] for c in cat["controllers"]} >= {"fuzzy", "pid"}
    curve = {c["name"] for c in cat["controllers"] if c["task"] == "curve"}
    assert curve == {"pid", "fuzzy-curve", "narma-l2", "none"}
    assert scenarios["curve"]["task"] == "curve"
    curve_params = {p["name"]: p for p in scenarios["curve"]["parameters"]}
    assert curve_params["entry_speed"]["unit"] == "km/h" and curve_params["lead"]["default"] == 0.0
    text = ego("list")
    assert text.returncode == 0 and "lead_decel" in text.stdout and "m/s^2" in text.stdout
    following = {c["name"]: c for c in cat["controllers"] if c["task"] == "car-following"}
    assert set(following) == {"pid", "bp-pid-acc", "none"}
    gains = {p["name"]: p["default"] for p in following["pid"]["parameters"]}
    assert gains == {"kp": 0.85, "ki": 0.2, "kd": 0.3, "period": 0.1}
    bp = {p["name"]: p["default"] for p in following["bp-pid-acc"]["parameters"]}
    assert bp["learning_rate"] == 0.25 and bp["momentum"] == 0.01 and bp["init_range"] == 0.5
    platoon = {p["name"]: p for p in scenarios["platoon"]["parameters"]}
    assert platoon["followers"]["default"] == 3 and platoon["followers"]["allowed"] == "a whole number from 1 to 10"
    assert platoon["standstill_gap"]["default"] == 3.0 and platoon["headway"]["unit"] == "s"
    assert "scale-model" in platoon["variant"]["allowed"]


def test_list_json_gives_every_scenario_its_metrics_and_columns_with_units():
    # passes once every scenario declares its columns, metrics and plots (the kit's ports)
    out = ego("list", "--json")
    assert out.returncode == 0, out.stderr
    cat = json.loads(out.stdout)
    from ego.scenarios import SCENARIOS

    assert [s["name"] for s in cat["scenarios"]] == list(SCENARIOS)
    for s in cat["scenarios"]:
        names = [m["name"] for m in s["metrics"]]
        assert set(names) >= COMMON and set(names) - COMMON, f"{s['name']} declares no metric of its own"
        for m in s["metrics"]:
            assert m["unit"] and isinstance(m["headline"], bool) and isinstance(m["description"], str), m
        assert s["columns"][0] == {"name": "t", "unit": "s", "description": s["columns"][0]["description"]}
        assert all(c["unit"] for c in s["columns"]), s["name"]
    for c in cat["controllers"]:
        assert all(p["unit"] for p in c["parameters"]), c["name"]


def test_list_shows_the_scenario_declarations(point_mass, capsys, monkeypatch):
    import ego.scenarios

    monkeypatch.setattr(ego.scenarios, "SCENARIOS", {point_mass.name: point_mass})  # alone, whatever the others
    assert main(["list", "--json"]) == 0
    cat = json.loads(capsys.readouterr().out)
    pm = {s["name"]: s for s in cat["scenarios"]}["point-mass"]
    assert pm["task"] == "tracking"
    assert {p["name"]: p["unit"] for p in pm["parameters"]} == {
        "dt": "s",
        "substeps": "-",
        "duration": "s",
        "ref_speed": "m/s",
        "mass": "kg",
    }
    own = [m for m in pm["metrics"] if m["name"] not in COMMON]
    assert own == [
        {"name": "rms_speed_error", "unit": "m/s", "description": "RMS of speed - reference speed", "headline": True},
        {"name": "final_position", "unit": "m", "description": "position at the end", "headline": False},
        {
            "name": "settle_times.",
            "unit": "s",
            "description": "time until |speed error| stays within each band",
            "headline": True,
        },
        {
            "name": "reached_speed",
            "unit": "-",
            "description": "the speed came within 1 m/s of the reference",
            "headline": True,
        },
    ]
    assert {"name": "sim_time", "unit": "s", "description": "simulated time", "headline": False} in pm["metrics"]
    assert [(c["name"], c["unit"]) for c in pm["columns"]] == [
        ("t", "s"),
        ("s", "m"),
        ("speed", "m/s"),
        ("e_lon", "m"),
        ("Fx", "N"),
    ]
    tracking = {c["name"]: c for c in cat["controllers"] if c["task"] == "tracking"}
    assert "kp_lat" in {p["name"] for p in tracking["pid"]["parameters"]}
    assert main(["list"]) == 0
    text = capsys.readouterr().out
    assert "rms_speed_error [m/s] *  RMS of speed - reference speed" in text
    assert "final_position [m]       position at the end" in text
    assert "settle_times.* [s] *" in text and "reached_speed *" in text and "sim_time [s]" in text


def test_run_text_gives_every_number_its_unit(point_mass, capsys):
    assert main(["run", "point-mass", "-c", "pid"]) == 0
    lines = {line.split()[0]: line.split()[1:] for line in capsys.readouterr().out.splitlines()[1:]}
    assert lines["rms_speed_error"] == ["3.999", "m/s"]
    assert lines["final_position"][1] == "m"
    assert lines["settle_times.band5"] == ["0.790", "s"] and lines["settle_times.band1"] == ["-"]
    assert lines["reached_speed"] == ["True"] and lines["steps"] == ["400"]
    assert lines["sim_time"] == ["4.000", "s"] and lines["collision"] == ["False"]


def test_run_json_carries_a_units_map_beside_the_metrics(point_mass, capsys):
    assert main(["run", "point-mass", "-c", "fuzzy", "--json", "--set", "duration=2"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["status"] == "completed" and m["steps"] == 200 and set(m["settle_times"]) == {"band5", "band1"}
    assert m["units"] == {
        "scenario": "-",
        "controller": "-",
        "seed": "-",
        "status": "-",
        "status_detail": "-",
        "collision": "-",
        "collision_with": "-",
        "rms_speed_error": "m/s",
        "final_position": "m",
        "settle_times.band5": "s",
        "settle_times.band1": "s",
        "reached_speed": "-",
        "sim_time": "s",
        "wall_time": "s",
        "steps": "-",
    }


def test_bad_input_to_a_declared_scenario_is_one_line(point_mass, capsys):
    assert main(["run", "point-mass", "-c", "pid", "--set", "ref_speed=fast"]) == 2
    out = capsys.readouterr()
    assert out.out == "" and out.err == (
        "ego: error: bad value for ref_speed: 'fast' (expected a number from 0 to 40 (m/s))\n"
    )


@pytest.mark.sumo
def test_platoon_run_prints_per_follower_metrics_and_json(tmp_path):
    text = ego("run", "platoon", "-c", "pid", "--set", "duration=20")
    assert text.returncode == 0, text.stderr
    for line in (
        "followers.f3.max_abs_jerk",
        "settle_times.brake@10s",
        "amplification.f1->f2.l2_accel",
        "string_stable",
    ):
        assert line in text.stdout
    out = ego("run", "platoon", "-c", "bp-pid-acc", "--json", "--set", "followers=2", "--set", "duration=20")
    assert out.returncode == 0, out.stderr
    m = json.loads(out.stdout)
    assert set(m["followers"]) == {"f1", "f2"}
    assert set(m["followers"]["f1"]) == {
        "rms_spacing_error",
        "max_abs_spacing_error",
        "min_gap",
        "min_ttc",
        "max_abs_accel",
        "max_abs_jerk",
        "settle_times",
    }
    assert m["collision"] is False and isinstance(m["string_stable"], bool)
    assert set(m["amplification"]) == {"leader->f1", "f1->f2"}


@pytest.mark.sumo
def test_run_json_is_one_object_with_the_documented_fields(tmp_path):
    rec = tmp_path / "runs" / "eb.rrd"
    out = ego("run", "emergency-brake", "--controller", "pid", "--json", "--record", str(rec), "--set", "duration=15")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert len(lines) == 1
    m = json.loads(lines[0])
    for key in (
        "status",
        "collision",
        "lane_change_completed",
        "target_lane",
        "trigger_time",
        "lane_change_duration",
        "max_overshoot",
        "min_ttc_front",
        "min_ttc_rear",
        "max_abs_lateral_accel",
        "sim_time",
        "wall_time",
        "steps",
    ):
        assert key in m, key
    assert m["status"] == "completed" and m["sim_time"] == 15.0 and m["steps"] == 1500
    assert m["units"]["min_ttc_front"] == "s" and m["units"]["max_abs_lateral_accel"] == "m/s^2"
    assert rec.exists() and rec.stat().st_size > 0


@pytest.mark.sumo
def test_a_collision_is_reported_with_exit_status_1():
    out = ego("run", "emergency-brake", "-c", "none", "--set", "aeb=false", "--json")  # no controller, no AEB
    assert out.returncode == 1
    assert json.loads(out.stdout)["status"] == "collision"


@pytest.mark.parametrize(
    "args, message",
    [
        (["run", "nowhere", "-c", "fuzzy"], "unknown scenario 'nowhere' (known: emergency-brake"),
        (
            ["run", "emergency-brake", "-c", "magic"],
            "unknown controller 'magic' for the tracking task (known: fuzzy, pid",
        ),
        (["run", "emergency-brake", "-c", "fuzzy", "--set", "warp=9"], "unknown parameter 'warp'"),
        (
            ["run", "emergency-brake", "-c", "fuzzy", "--set", "lead_decel=fast"],
            "bad value for lead_decel: 'fast' (expected a number from 0.5 to 12 (m/s^2))",
        ),
        (["run", "emergency-brake", "-c", "fuzzy", "--set", "ttc_threshold=-1"], "bad value for ttc_threshold"),
        (["run", "emergency-brake", "-c", "fuzzy", "--set", "dt=0.03"], "bad value for sumo_step"),
        (["run", "emergency-brake", "-c", "pid", "--set", "kp_lat=x"], "bad value for kp_lat"),
        (["run", "emergency-brake", "-c", "fuzzy", "--record", "x.txt"], "expected a file ending in .rrd"),
        (["run", "emergency-brake"], "--controller"),
        (
            ["run", "curve", "-c", "fuzzy"],
            "unknown controller 'fuzzy' for the curve task (known: pid, "
            "fuzzy-curve, narma-l2, none); 'fuzzy' is a tracking controller",
        ),
        (["run", "curve", "-c", "pid", "--set", "preview=30"], "bad value for preview: 30.0 (expected at most"),
        (["run", "curve", "-c", "narma-l2", "--set", "model=/nowhere/m.npz"], "no trained NARMA-L2 model"),
        (["run", "curve", "-c", "narma-l2", "--set", "dt=0.02"], "dt must divide"),
        (["train", "narma-l2", "--speeds", "30"], "bad value for --speeds: '30' (expected LO,HI"),
        (["train", "narma-l2", "--samples", "5"], "bad value for --samples: 5"),
        (["train", "narma-l2", "--out", "x.pt"], "expected a file ending in .npz"),
        (["train", "anything"], "invalid choice: 'anything'"),
    ],
    ids=[
        "scenario",
        "controller",
        "parameter",
        "value",
        "range",
        "timing",
        "controller-param",
        "record",
        "missing",
        "task",
        "preview",
        "model",
        "sample-period",
        "train-range",
        "train-samples",
        "train-out",
        "train-what",
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message):
    out = ego(*args)
    assert out.returncode == 2
    assert out.stdout == ""
    err = out.stderr.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith("ego: error: ") and message in err


def test_help_explains_the_run_command():
    out = ego("run", "--help")
    assert out.returncode == 0
    for word in ("--controller", "--record", "--seed", "--set", "--json", "Exit status", "130 interrupted"):
        assert word in out.stdout


def _help(*args, capsys) -> str:
    with pytest.raises(SystemExit) as stop:
        main([*args, "--help"])
    assert stop.value.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps lines


def test_help_says_where_train_and_tune_write_and_how_their_output_is_used(capsys):
    train, tune, top = _help("train", capsys=capsys), _help("tune", capsys=capsys), _help(capsys=capsys)
    assert "rewrites" not in train + tune
    assert "(writes runs/narma_l2.npz; use it with --set model=runs/narma_l2.npz" in train and "--install)" in train
    assert "writes runs/cascade_pid_tuned.json, --install replaces the shipped preset" in tune
    assert "loads by default." not in tune  # only the --install one is
    # the model a command line trains is the one the next one runs
    trained = "ego train narma-l2 --seed 1 --out runs/narma_s1.npz"
    assert f"{trained} ego run curve --controller narma-l2 --set model=runs/narma_s1.npz" in top


@pytest.mark.slow
def test_train_writes_weights_and_metadata(tmp_path):
    out = tmp_path / "m.npz"
    res = ego("train", "narma-l2", "--samples", "400", "--epochs", "2", "--seed", "3", "--out", str(out))
    assert res.returncode == 0, res.stderr
    assert "held-out RMS" in res.stdout and out.exists()
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["seed"] == 3 and meta["samples"] >= 400 and meta["train"]["epochs"] == 2


@pytest.mark.slow
@pytest.mark.sumo
def test_curve_run_uses_a_model_trained_elsewhere(tmp_path):
    out = tmp_path / "m.npz"
    assert ego("train", "narma-l2", "--samples", "400", "--epochs", "2", "--out", str(out)).returncode == 0
    res = ego("run", "curve", "-c", "narma-l2", "--set", f"model={out}", "--json")
    assert res.returncode in (0, 1), res.stderr  # a two-epoch model may well fail the curve
    m = json.loads(res.stdout)
    assert m["scenario"] == "curve" and m["controller"] == "narma-l2"


@pytest.mark.parametrize(
    "args, message",
    [
        (["run", "emergency-brake", "-c", "pid", "--seed", "-1"], "bad value for --seed: -1"),
        (["run", "emergency-brake", "-c", "pid", "--seed", "2147483648"], "bad value for --seed: 2147483648"),
        (["run", "emergency-brake", "-c", "pid", "--record", ""], "bad --record path ''"),
        (["run", "emergency-brake", "-c", "pid", "--record", "/proc/x.rrd"], "not a place for files"),
        (["run", "emergency-brake", "-c", "pid", "--record", "{tmp}/file.txt/x.rrd"], "is a file, not a folder"),
        (["run", "emergency-brake", "-c", "pid", "--record", "{tmp}/dir.rrd"], "it is a folder"),
        (["compare", "emergency-brake", "--controllers", "pid", "--out", "{tmp}/file.txt"], "it is a file"),
        (["compare", "emergency-brake", "--controllers", "pid,pid", "--out", "{tmp}/c"], "'pid' is listed twice"),
        (
            ["compare", "emergency-brake", "--controllers", "pid", "--seeds", "1000000000", "--out", "{tmp}/c"],
            "bad value for --seeds: 1000000000",
        ),
        (["compare", "emergency-brake", "--controllers", "pid", "--out", ""], "bad --out ''"),
        (["train", "narma-l2", "--seed", "-1"], "bad value for --seed: -1"),
        (["train", "narma-l2", "--out", "{tmp}/a.npz", "--install"], "not both"),
        (["tune", "lane-centering", "--seed", "-1"], "bad value for --seed: -1"),
        (["tune", "lane-centering", "--drives", "8:nan"], "bad value for --drives: '8:nan'"),
        (["tune", "lane-centering", "--drives", "8:1:2"], "bad value for --drives: '8:1:2'"),
        (["sweep", "{tmp}/none.toml", "--out", "{tmp}/s"], "cannot read the sweep spec"),
    ],
    ids=lambda a: " ".join(a)[:60] if isinstance(a, list) else None,
)
def test_bad_seeds_and_output_places_fail_at_once_writing_nothing(args, message, tmp_path):
    (tmp_path / "file.txt").write_text("x")
    (tmp_path / "dir.rrd").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    res = ego(*[a.replace("{tmp}", str(tmp_path)) for a in args])
    assert res.returncode == 2, res.stderr
    assert message in res.stderr and res.stderr.count("\n") == 1 and "Traceback" not in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_the_python_api_refuses_a_seed_it_would_truncate():
    from ego.params import ConfigError
    from ego.runner import RunSpec, resolve

    for seed in (1.7, "1", True, -1, 2**31):
        with pytest.raises(ConfigError, match="bad value for seed"):
            resolve(RunSpec("emergency-brake", "pid", seed))


@pytest.mark.slow
def test_train_and_tune_write_into_the_working_folder_unless_told_to_install(tmp_path):
    import subprocess
    import sys

    from ego.control.cascade import TUNED_PRESET

    shipped = TUNED_PRESET.read_bytes()
    p = subprocess.run(
        [sys.executable, "-m", "ego", "tune", "lane-centering", "--quick"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "runs" / "cascade_pid_tuned.json").is_file()
    assert TUNED_PRESET.read_bytes() == shipped  # the shipped preset is untouched


def test_list_gives_numbers_readably_and_angles_in_degrees_too(capsys):
    assert main(["list"]) == 0
    text = capsys.readouterr().out
    assert "0.4363323129985824" not in text and "25.0 s" not in text
    lane = text[text.index("lane-centering [lane-centering task; needs any_network]") :]
    assert "max_steer           0.436332 rad (25 deg)  front steer limit" in lane
    assert "the end of the 2935 m road: 363 s at 8 m/s" in lane


@pytest.mark.sumo
def test_the_duration_that_ends_a_run_is_named_and_a_shortened_drive_is_no_failure(capsys):
    # lane centring's end is the road's, at the configured speed: a shorter duration is a choice
    assert main(["run", "lane-centering", "-c", "cascade-pid", "--set", "duration=20"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (
        "lane-centering with cascade-pid (seed 0): ENDED - the duration (20 s) ended the run "
        "at s = 178 m of the drive to s = 2920 m"
    )
    # the duration cut the emergency brake's lane change short: the manoeuvre did not finish
    assert main(["run", "emergency-brake", "-c", "pid", "--set", "duration=5"]) == 1
    first = capsys.readouterr().out.splitlines()[0]
    assert first.endswith("TIMEOUT - the duration (5 s) ended the run before the manoeuvre (lane change) finished")


def test_list_of_a_name_shows_each_tasks_controller_and_parameters(capsys):
    assert main(["list", "pid"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("pid: a controller of its own in each task\n")
    tracking = text[text.index("in the tracking task (emergency-brake") : text.index("in the curve task (curve)")]
    following = text[text.index("in the car-following task (platoon)") :]
    assert "kp_lat" in tracking and "kp_lat" not in following
    assert "\n      kp " in following and "\n      kp " not in tracking
    assert main(["list", "pid", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert "parameters" not in listed and list(listed["per_task"]) == ["tracking", "curve", "car-following"]
    assert main(["list", "fuzzy"]) == 0  # one task: one list, as before
    text = capsys.readouterr().out
    assert text.startswith("fuzzy: report 000's") and "\n  parameters (--set key=value):\n    fx_gain" in text


def test_list_of_a_class_that_fits_no_task_says_why_and_exits_0(tmp_path, capsys):
    (tmp_path / "other.py").write_text(
        "class X:\n    'Drives a task ego has not.'\n    task = 'flying'\n"
        "    def reset(self): pass\n    def step(self, obs): pass\n    def signals(self): return {}\n"
    )
    assert main(["list", f"{tmp_path / 'other.py'}:X"]) == 0
    text = capsys.readouterr().out
    assert "connects to no task as it is:" in text and "drives the flying task, not tracking" in text
