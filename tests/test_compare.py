"""ego compare: parallel runs, every file, failed runs as rows; what it shows comes from the
scenario's declarations (the point-mass scenario needs no SUMO)."""

import csv
import os
import subprocess
import sys

import pytest
from rerun.chunk import RrdReader

from ego.compare import compare, run_one
from ego.parallel.executor import InlineExecutor
from ego.params import ConfigError
from ego.plots import figure
from ego.results.trace import Plot
from ego.runner import RunSpec, declared_columns
from ego.scenarios import SCENARIOS

PNG = b"\x89PNG\r\n\x1a\n"


def test_compare_shows_what_the_scenario_declares_with_units(point_mass, tmp_path):
    out = tmp_path / "cmp"
    rows = compare("point-mass", ["pid", "fuzzy"], 2, {}, out, progress=None, executor=InlineExecutor())
    assert [(r.controller, r.seed, r.status) for r in rows] == [
        ("pid", 0, "completed"),
        ("pid", 1, "completed"),
        ("fuzzy", 0, "completed"),
        ("fuzzy", 1, "completed"),
    ]
    md = (out / "metrics.md").read_text().splitlines()
    # the scenario's headline metrics only, in declaration order, the prefix expanded, with units
    assert md[4] == (
        "| controller | runs | rms_speed_error [m/s] | settle_times.band5 [s] "
        "| settle_times.band1 [s] | reached_speed |"
    )
    assert md[6].startswith("| pid | 2 completed | 4 +- 0 | 0.79 +- 0 | - | 2/2 |")
    assert md[7].startswith("| fuzzy | 2 completed |")
    assert not any("final_position" in line for line in md)  # declared, not a headline
    # metrics.csv: the header is the first row; the sidecar gives a unit to each of its columns
    with open(out / "metrics.csv", newline="") as f:
        table = list(csv.reader(f))
    header = table[0]
    assert header[:4] == ["controller", "seed", "status", "error"]
    assert [r[:3] for r in table[1:]] == [
        ["pid", "0", "completed"],
        ["pid", "1", "completed"],
        ["fuzzy", "0", "completed"],
        ["fuzzy", "1", "completed"],
    ]
    with open(out / "metrics_units.csv", newline="") as f:
        units = list(csv.reader(f))
    assert units[0] == ["metric", "unit"]
    assert [u[0] for u in units[1:]] == header
    unit = dict(units[1:])
    assert unit["controller"] == "-" and unit["status"] == "-"
    assert unit["rms_speed_error"] == "m/s" and unit["final_position"] == "m"
    assert unit["settle_times.band5"] == unit["settle_times.band1"] == "s"
    assert unit["reached_speed"] == "-" and unit["sim_time"] == "s" and unit["steps"] == "-"
    # exactly the declared plots
    assert sorted(p.name for p in out.glob("*.png")) == ["lon_error.png", "speed.png"]
    for png in out.glob("*.png"):
        assert png.read_bytes()[:8] == PNG
    for r in rows:
        assert RrdReader(out / "runs" / f"{r.controller}-seed{r.seed}.rrd").recordings()


def test_a_run_row_keeps_the_plotted_columns_with_their_units(point_mass, tmp_path):
    row = run_one(RunSpec("point-mass", "pid", 0, {"duration": 1.0}))
    assert row.status == "completed"
    assert set(row.traces) == {"t", "speed", "e_lon"}  # only what the plots need
    assert row.units == {"t": "s", "speed": "m/s", "e_lon": "m"}
    assert len(row.traces["speed"]) == 100
    fig = figure("point-mass", point_mass.plots[1], [row], ["pid"])
    ax = fig.axes[0]
    assert ax.get_ylabel() == "position error [m]" and ax.get_xlabel() == "time [s]"
    assert fig._suptitle.get_text() == "point-mass: position error - seed 0"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["pid (1 completed)"]
    assert figure("point-mass", Plot("Fx", "fx.png", "force"), [row], ["pid"]) is None  # not kept


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_every_scenario_declares_what_compare_shows(name):
    # passes once every scenario declares its columns, metrics and plots (the kit's ports)
    cls = SCENARIOS[name]
    config = cls.default_config({})
    columns = {c.name: c.unit for c in declared_columns(cls, config)}
    plots = cls.compare_plots(config)
    for plot in plots:
        optional = getattr(plot, "gain_columns", ())  # controller signals, when there
        assert all(c in columns for c in plot.columns if c not in optional), plot
        assert plot.file.endswith(".png") and "[" not in getattr(plot, "label", ""), plot
    assert len({p.file for p in plots}) == len(plots)
    metrics = [m.name for m in cls.metrics_declared(config)]
    assert len(set(metrics)) == len(metrics)
    assert not {"units", "events", "record"} & set(metrics)  # keys ego run --json adds
    assert any(m.headline for m in cls.metrics_declared(config))


def test_unknown_scenario_stops_compare_before_anything_runs(tmp_path):
    with pytest.raises(ConfigError, match="unknown scenario 'point-mass'"):
        compare("point-mass", ["pid"], 1, {}, tmp_path / "x", progress=None)
    assert not (tmp_path / "x").exists()


@pytest.mark.sumo
def test_compare_two_controllers_two_seeds_writes_everything(tmp_path):
    out = tmp_path / "cmp"
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
            "--out",
            str(out),
            "--set",
            "duration=16",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    rows = list(csv.DictReader(open(out / "metrics.csv")))
    assert [(r["controller"], r["seed"]) for r in rows] == [("pid", "0"), ("pid", "1"), ("fuzzy", "0"), ("fuzzy", "1")]
    assert all(r["status"] == "completed" for r in rows)
    md = (out / "metrics.md").read_text()
    assert "| pid | 2 completed |" in md and "| fuzzy | 2 completed |" in md
    assert "min_ttc_front [s]" in md and "min_gap_front [m]" in md
    units = dict(csv.reader(open(out / "metrics_units.csv")))
    assert units["min_gap_front"] == "m" and units["status"] == "-"
    assert "metrics_units.csv" in p.stdout
    for png in ("lateral_error.png", "speed.png", "steering.png", "fx.png"):
        data = (out / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    for r in rows:
        rrd = out / "runs" / f"{r['controller']}-seed{r['seed']}.rrd"
        assert RrdReader(rrd).recordings()
    assert "4/4 runs" in p.stderr  # the progress bar
    assert not (out / "e_d.png").exists()  # the curve's plots only where there is a curve


@pytest.mark.sumo
def test_compare_the_curve_controllers(tmp_path):
    out = tmp_path / "curve"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "curve",
            "--controllers",
            "pid,fuzzy-curve,narma-l2",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    rows = {r["controller"]: r for r in csv.DictReader(open(out / "metrics.csv"))}
    assert set(rows) == {"pid", "fuzzy-curve", "narma-l2"}
    for r in rows.values():
        assert r["status"] == "completed" and r["completed_arc"] == "True"
        assert float(r["max_abs_ed"]) < 0.5
    md = (out / "metrics.md").read_text()
    assert "max_abs_ed [m]" in md and "time_in_arc [s]" in md and "| narma-l2 | 1 completed |" in md
    for png in ("e_d.png", "e_a.png", "speed.png", "steering.png", "a_x.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png
    assert not (out / "fx.png").exists() and not (out / "lateral_error.png").exists()
    assert "e_d.png" in p.stdout


@pytest.mark.sumo
def test_a_diverging_controller_is_a_row_not_a_crash(tmp_path):
    out = tmp_path / "cmp"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "report-000",
            "--controllers",
            "rbf-smc,bp-pid",
            "--set",
            "variant=report",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    status = {r["controller"]: r["status"] for r in csv.DictReader(open(out / "metrics.csv"))}
    assert status == {"rbf-smc": "completed", "bp-pid": "diverged"}


@pytest.mark.sumo
def test_a_run_that_raises_becomes_an_error_row(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    row = run_one(RunSpec("report-000", "pid", 0, {}, record=str(blocker / "x.rrd")))
    assert row.status == "error" and "Error" in row.error


@pytest.mark.sumo
def test_bad_input_is_rejected_before_anything_runs(tmp_path):
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "emergency-brake",
            "--controllers",
            "pid,warp",
            "--out",
            str(tmp_path / "x"),
        ],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and "unknown controller 'warp'" in p.stderr
    assert not (tmp_path / "x").exists()
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "emergency-brake",
            "--controllers",
            "pid",
            "--set",
            "kp_lat=x",
            "--out",
            str(tmp_path / "y"),
        ],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and "bad value for kp_lat" in p.stderr


@pytest.mark.sumo
@pytest.mark.long  # tens of seconds; the docs' envelope and platoon tables run the same code
def test_compare_the_platoon_controllers(tmp_path):
    out = tmp_path / "platoon"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "platoon",
            "--controllers",
            "pid,bp-pid-acc",
            "--seeds",
            "2",
            "--set",
            "duration=40",
            "--set",
            "period=0.2",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    rows = list(csv.DictReader(open(out / "metrics.csv")))
    assert [(r["controller"], r["seed"], r["status"]) for r in rows] == [
        ("pid", "0", "completed"),
        ("pid", "1", "completed"),
        ("bp-pid-acc", "0", "completed"),
        ("bp-pid-acc", "1", "completed"),
    ]
    # nested metrics become dotted columns
    assert {"followers.f3.min_gap", "settle_times.brake@10s", "amplification.f2->f3.l2_spacing_error"} <= set(rows[0])
    md = (out / "metrics.md").read_text()
    assert "settle_times.brake@10s [s]" in md and "string_stable" in md and "| pid | 2 completed |" in md
    for png in ("speed.png", "spacing_error.png", "gap.png", "accel.png", "string_stability.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png
    assert not (out / "lateral_error.png").exists()


@pytest.mark.sumo
def test_compare_checks_the_control_period_before_starting(tmp_path):
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "ego",
            "compare",
            "platoon",
            "--controllers",
            "pid",
            "--set",
            "period=0.015",
            "--out",
            str(tmp_path / "x"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 2 and "bad value for period: 0.015" in p.stderr
    assert not (tmp_path / "x").exists()


def test_the_plots_listed_are_the_ones_this_comparison_wrote(tmp_path, capsys):
    """An earlier comparison's plots in the same --out are not listed as written now."""
    from ego.cli import main

    out = tmp_path / "out"
    out.mkdir()
    (out / "e_d.png").write_bytes(b"an earlier comparison's plot")
    os.utime(out / "e_d.png", (0, 0))
    assert (
        main(
            [
                "compare",
                "emergency-brake",
                "--controllers",
                "pid",
                "--seeds",
                "1",
                "--set",
                "duration=3",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    written = capsys.readouterr().out.rsplit("wrote into", 1)[1]
    assert "e_d.png" not in written and "gap_front.png" in written
