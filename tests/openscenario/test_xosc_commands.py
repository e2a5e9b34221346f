"""The commands on scenario files: ego run (recording, trace, --ego, --set), ego list
FILE.xosc, ego compare and ego sweep over a file's parameters; determinism."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from ego.cli import main

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
XOSC = ROOT / "scenarios" / "openscenario"


@pytest.fixture
def files(tmp_path):
    for name in ("emergency_brake.xosc", "cut_in.xosc", "straight3.xodr"):
        shutil.copy(XOSC / name, tmp_path / name)
    shutil.copytree(XOSC / "catalogs", tmp_path / "catalogs")
    return tmp_path


def test_run_records_and_traces(files, capsys):
    rrd, trace = files / "out" / "run.rrd", files / "out" / "trace.csv"
    rc = main(
        [
            "run",
            str(files / "cut_in.xosc"),
            "-c",
            "pid",
            "--record",
            str(rrd),
            "--trace",
            str(trace),
            "--set",
            "CutInSpeed=12",
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["status"] == "completed"
    assert out["trigger_time"] is not None  # the cut-in triggered ego's manoeuvre
    assert rrd.stat().st_size > 0 and trace.stat().st_size > 0
    header = trace.read_text().splitlines()[0]
    assert "ttc_front" in header and "gap_front" in header  # the surround sensor's columns
    from rerun.chunk import RrdReader  # noqa: F401  (the recording is a real Rerun file)


def test_run_is_deterministic(files):
    from ego.runner import RunSpec, run

    spec = RunSpec(str(files / "emergency_brake.xosc"), "fuzzy-pid", seed=4, overrides={"LeadDecel": 7.0})
    a, b = run(spec).metrics, run(spec).metrics
    a.pop("wall_time"), b.pop("wall_time")
    assert a == b


def test_set_reaches_the_storyboard(files, capsys):
    rc = main(
        [
            "run",
            str(files / "emergency_brake.xosc"),
            "-c",
            "pid",
            "--set",
            "LeadBrakeTime=4",
            "--set",
            "traffic_density=0",
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert any("t = 4.00 s: event 'LeadBrakeEvent' starts" in e["text"] for e in out["events"])


def test_ego_is_chosen(files, capsys):
    """--ego Lead: ego drives the lead car, whose braking becomes its speed reference."""
    rc = main(
        [
            "run",
            str(files / "emergency_brake.xosc"),
            "-c",
            "pid",
            "--ego",
            "lead",
            "--set",
            "traffic_density=0",
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert out["final_speed"] == pytest.approx(5.0, abs=0.3)  # it braked to LeadFinalSpeed


def test_list_file(files, capsys):
    assert main(["list", str(files / "emergency_brake.xosc")]) == 0
    text = capsys.readouterr().out
    assert "every element supported" in text
    assert "LeadGap                  double   default 30.0" in text
    assert "Ego                      Vehicle (car)" in text and "<- the ego" in text
    assert "traffic_density" in text and "(sets ego's parameter)" in text
    bad = files / "bad.xosc"
    bad.write_text(
        (files / "emergency_brake.xosc")
        .read_text()
        .replace("<Properties/>", "<Properties/><Trailer><Oops/></Trailer>", 1)
    )
    assert main(["list", str(bad), "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert listing["supported"] is False
    assert [e for e in listing["elements"] if not e["supported"]] == [
        {"element": "Oops", "line": 51, "supported": False}
    ]
    assert listing["ego"] == "Ego"
    # the ego's parameters as a run of the file starts them (its Init), not FileConfig's
    assert main(["list", str(files / "cut_in.xosc"), "--json"]) == 0
    own = {p["name"]: p["default"] for p in json.loads(capsys.readouterr().out)["ego_parameters"]}
    from ego.runner import RunSpec, resolve

    start = resolve(RunSpec(str(files / "cut_in.xosc"), "pid")).config
    assert (own["ego_speed"], own["ego_lane"], own["ego_start"]) == (start.ego_speed, start.ego_lane, start.ego_start)
    assert own["ego_start"] != 300.0  # FileConfig's default


@pytest.mark.long
def test_compare(files, capsys):
    out = files / "cmp"
    rc = main(
        [
            "compare",
            str(files / "emergency_brake.xosc"),
            "--controllers",
            "pid,fuzzy",
            "--out",
            str(out),
            "--set",
            "duration=8",
            "--jobs",
            "2",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    assert (out / "metrics.csv").is_file() and (out / "metrics.md").is_file()
    assert (out / "speed.png").is_file() and (out / "ttc.png").is_file()


def test_sweep_over_file_parameters(files, capsys):
    spec = files / "spec.toml"
    spec.write_text(
        'scenario = "emergency_brake.xosc"\ncontrollers = ["pid"]\nseeds = 1\n\n[set]\n'
        "duration = 6\ntraffic_density = 0\n\n[grid]\nLeadGap = [20, 40]\n"
    )
    out = files / "sweep"
    rc = main(["sweep", str(spec), "--out", str(out), "--jobs", "2", "--record", "none"])
    assert rc == 0, capsys.readouterr().err
    import pyarrow.parquet as pq

    table = pq.read_table(out / "results.parquet").to_pylist()
    assert sorted(r["LeadGap"] for r in table) == [20, 40]
    assert {r["status"] for r in table} <= {"completed", "timeout"}  # 6 s may end mid-manoeuvre
    assert len({r["trigger_time"] for r in table}) == 2  # the gap reached the storyboard


def test_sweep_refuses_undeclared_parameter(files, capsys):
    spec = files / "spec.toml"
    spec.write_text('scenario = "emergency_brake.xosc"\ncontrollers = ["pid"]\n\n[grid]\nLeadGapp = [20, 40]\n')
    assert main(["sweep", str(spec), "--out", str(files / "s")]) == 2
    err = capsys.readouterr().err
    assert "unknown parameter 'LeadGapp'" in err and err.count("\n") == 1
    assert not (files / "s").exists()


def test_sweep_refuses_a_value_the_file_constrains(files, capsys):
    """The shipped file bounds LeadGap as the built-in scenario does (5-300 m): a gap that puts
    the lead behind the ego is one line before anything runs, not a SUMO error row."""
    spec = files / "spec.toml"
    spec.write_text('scenario = "emergency_brake.xosc"\ncontrollers = ["pid"]\n\n[grid]\nLeadGap = [-40, 20]\n')
    assert main(["sweep", str(spec), "--out", str(files / "s")]) == 2
    err = capsys.readouterr().err
    assert "parameter 'LeadGap' = -40 breaks its value constraint: greaterOrEqual 5" in err and err.count("\n") == 1
    assert not (files / "s").exists()


@pytest.mark.parametrize("command", ["sweep", "falsify"])
def test_a_spec_whose_file_lacks_its_road_names_the_file_not_a_key(files, capsys, command):
    folder = files / "alone"
    folder.mkdir()
    shutil.copy(files / "emergency_brake.xosc", folder / "emergency_brake.xosc")  # no .xodr beside it
    spec = folder / "spec.toml"
    ranges = "[grid]" if command == "sweep" else 'requirement = "no_collision"\n[search]'
    spec.write_text(f'scenario = "emergency_brake.xosc"\ncontrollers = ["pid"]\n{ranges}\nLeadGap = [20, 40]\n')
    assert main([command, str(spec), "--out", str(files / f"o-{command}")]) == 2
    err = capsys.readouterr().err
    assert "road file 'straight3.xodr' not found" in err and "LeadGap" not in err and err.count("\n") == 1
