"""``ego run`` / ``ego compare`` with ``--backend``, and the SUMO path without highway-env."""

import csv
import json
import subprocess
import sys

import pytest

from ego.cli import main


@pytest.mark.highway_env
def test_ego_run_on_highway_env_prints_the_backend_and_writes_the_video(tmp_path, capsys):
    video = tmp_path / "eb.gif"
    code = main(
        [
            "run",
            "emergency-brake",
            "-c",
            "pid",
            "--backend",
            "highway-env",
            "--json",
            "--video",
            str(video),
            "--set",
            "duration=10",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["backend"] == "highway-env" and out["video"] == str(video)
    assert out["units"]["backend"] == "-"
    assert video.stat().st_size > 0


@pytest.mark.highway_env
def test_ego_compare_on_highway_env(tmp_path, capsys):
    out = tmp_path / "cmp"
    code = main(
        [
            "compare",
            "fast-follower",
            "--controllers",
            "pid,fuzzy",
            "--backend",
            "highway-env",
            "--out",
            str(out),
            "--set",
            "duration=8",
            "--jobs",
            "2",
        ]
    )
    assert code == 0
    with open(out / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["controller"], r["backend"]) for r in rows] == [("pid", "highway-env"), ("fuzzy", "highway-env")]
    assert all(r["status"] in ("completed", "timeout") and r["error"] == "" for r in rows)
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["fuzzy-seed0.rrd", "pid-seed0.rrd"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["run", "curve", "-c", "pid", "--backend", "highway-env"],
            "bad value for --backend: 'highway-env' (scenario curve needs any_network; backend highway-env lacks it)",
        ),
        (
            ["compare", "platoon", "--controllers", "pid", "--backend", "highway-env", "--out", "{tmp}/x"],
            "bad value for --backend: 'highway-env' (scenario platoon needs any_network, several_egos; backend highway-env lacks them)",
        ),
        (["run", "cut-in", "-c", "pid", "--backend", "carla"], "invalid choice: 'carla'"),
        (["run", "cut-in", "-c", "pid", "--video", "{tmp}/v.gif"], "--video needs --backend highway-env"),
    ],
    ids=["unsupported-scenario", "compare-unsupported", "unknown-backend", "video-on-sumo"],
)
def test_bad_backend_use_is_one_line_and_exit_2(argv, message, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.sumo
def test_the_sumo_path_never_imports_highway_env():
    code = (
        "import sys\n"
        "from ego.cli import main\n"
        "main(['run', 'emergency-brake', '-c', 'pid', '--set', 'duration=2', '--json'])\n"
        "print('highway_env' in sys.modules, 'pygame' in sys.modules, file=sys.stderr)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stderr.strip().splitlines()[-1] == "False False"
