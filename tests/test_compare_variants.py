"""ego compare with variants of one controller (``pid@kp_lon=2000``) and --traces: the label
as given in every table, plot and file name; bad variants refused before anything runs
(the point-mass scenario needs no SUMO)."""

import csv

import pandas as pd
import pytest
from rerun.chunk import RrdReader

from ego.cli import main
from ego.compare import compare, file_label, parse_variant, plan
from ego.parallel.executor import InlineExecutor
from ego.params import ConfigError
from ego.plots import figure

LABELS = ["pid", "pid@kp_lon=2000@kd_lon=500", "fuzzy"]


def test_variants_are_labelled_as_given_everywhere(point_mass, tmp_path):
    out = tmp_path / "cmp"
    rows = compare(
        "point-mass", LABELS, 1, {"duration": "2"}, out, progress=None, executor=InlineExecutor(), traces="csv"
    )
    assert [(r.controller, r.status) for r in rows] == [(label, "completed") for label in LABELS]
    # the variant's own gains made a different run
    assert rows[0].metrics["rms_speed_error"] != rows[1].metrics["rms_speed_error"]
    assert rows[1].metrics["controller"] == "pid@kp_lon=2000@kd_lon=500"
    with open(out / "metrics.csv", newline="") as f:
        assert [r["controller"] for r in csv.DictReader(f)] == LABELS
    md = (out / "metrics.md").read_text()
    assert "| pid@kp_lon=2000@kd_lon=500 | 1 completed |" in md
    fig = figure("point-mass", point_mass.plots[0], rows, LABELS)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert [next(t for t in legend if t.startswith(label + " ")) for label in LABELS]
    for label in LABELS:
        assert RrdReader(out / "runs" / f"{label}-seed0.rrd").recordings()
        trace = pd.read_csv(out / "traces" / f"{label}-seed0.csv")
        assert list(trace.columns[:3]) == ["t", "s", "speed"] and len(trace) == 200
        assert (out / "traces" / f"{label}-seed0.units.csv").exists()


def test_a_variant_overrides_the_common_set_for_its_runs(point_mass, tmp_path):
    specs = plan("point-mass", ["pid", "pid@kp_lon=2000"], 1, {"kp_lon": "900", "duration": "2"}, tmp_path)
    assert [(s.controller, s.name, s.overrides["kp_lon"]) for s in specs] == [
        ("pid", "pid", "900"),
        ("pid", "pid@kp_lon=2000", "2000"),
    ]
    assert all(s.overrides["duration"] == "2" for s in specs)


@pytest.mark.parametrize(
    "label, message",
    [
        ("pid@kp_lon=-1", "bad --controllers item 'pid@kp_lon=-1': bad value for kp_lon: -1 (expected a number"),
        ("pid@kp_lon=x", "bad value for kp_lon: 'x'"),
        ("pid@warp=1", "unknown parameter 'warp'"),
        ("pid@kp_lon", "'kp_lon' is not key=value (expected NAME@key=value@key=value...)"),
        ("pid@", "'' is not key=value"),
        ("pid@kp_lon=1@kp_lon=2", "kp_lon is given twice"),
        ("warp@kp_lon=1", "unknown controller 'warp'"),
    ],
    ids=["out-of-range", "not-a-number", "unknown-parameter", "no-value", "empty", "twice", "unknown-controller"],
)
def test_a_bad_variant_is_named(label, message):
    with pytest.raises(ConfigError) as err:
        parse_variant(label, "tracking")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_bad_variant_stops_compare_before_anything_is_written(point_mass, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "point-mass", "--controllers", "pid,pid@kp_lon=-1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad --controllers item 'pid@kp_lon=-1'" in err
    assert not out.exists()
    assert main(["compare", "point-mass", "--controllers", "pid,pid", "--out", str(out)]) == 2
    assert "'pid' is listed twice" in capsys.readouterr().err
    assert main(["compare", "point-mass", "--controllers", "pid", "--traces", "xlsx", "--out", str(out)]) == 2
    assert "bad --traces 'xlsx' (allowed: csv, parquet, mat)" in capsys.readouterr().err
    assert not out.exists()


def test_file_names_keep_the_label_but_not_a_path(point_mass, tmp_path):
    assert file_label("pid@kp_lat=0.02") == "pid@kp_lat=0.02"
    assert file_label("cascade-pid@gains_file=runs/a b.json") == "cascade-pid@gains_file=runs_a_b.json"
    with pytest.raises(ConfigError, match="would share the file name"):
        plan("point-mass", ["pid@kp_lon=1 ", "pid@kp_lon=1\t"], 1, {}, tmp_path)
