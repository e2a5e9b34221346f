"""The one summary formatter and the one progress display of compare, sweep and the docs."""

import io

from ego.results import summary
from ego.results.progress import Progress
from ego.results.trace import Metric


def test_mean_spread_by_hand():
    assert summary.mean_spread([1.0, 2.0, 3.0]) == "2 +- 1"  # sd with ddof=1
    assert summary.mean_spread([1.0, None, 3.0]) == "2 +- 1.4 (2/3)"
    assert summary.mean_spread([True, False, True]) == "2/3"  # yes/no: how many say yes
    assert summary.mean_spread([None, float("inf")]) == "-"
    assert summary.mean_spread([5.0, 5.0]) == "5 +- 0"


def test_percentiles_by_hand():
    assert summary.percentiles(list(range(1, 102))) == "51 [6, 96] (1 to 101), 101"
    assert summary.percentiles([None, "x", float("nan")]) == "-"


def test_comparison_table():
    declared = (Metric("gap", "m", "a gap", headline=True), Metric("hidden", "s", "not shown"))
    rows = [
        {"controller": "a", "seed": s, "status": "completed", "error": "", "metrics": {"gap": g, "hidden": 1}}
        for s, g in enumerate((1.0, 3.0))
    ]
    rows.append({"controller": "b", "seed": 0, "status": "error", "error": "Boom: x", "metrics": {}})
    text = summary.comparison("demo", rows, ["a", "b"], declared)
    assert text.splitlines()[:7] == [
        "# demo: 3 runs",
        "",
        "Mean +- standard deviation over seeds; (k/n) when only k of n runs have the value; "
        "k/n for a yes/no metric: k of n runs say yes.",
        "",
        "| controller | runs | gap [m] |",
        "|---|---|---|",
        "| a | 2 completed | 2 +- 1.4 |",
    ]
    assert "| b | 1 error | - |" in text and "- b seed 0: Boom: x" in text


def test_sweep_table():
    declared = (Metric("gap", "m", "a gap", headline=True),)
    rows = [
        {"controller": "a", "seed": 0, "status": s, "error": "", "gap": g}
        for s, g in (("completed", 1.0), ("collision", 2.0), ("completed", 3.0))
    ]
    text = summary.sweep("demo", "x.toml", ["v"], 1, rows, ["a"], declared)
    lines = text.splitlines()
    assert "| controller | runs | collision | completed |" in lines
    assert "| a | 3 | 1 | 2 |" in lines
    assert "| a | 2 [1.1, 2.9] (1 to 3), 3 |" in lines


def test_progress_writes_about_twenty_lines_and_the_last_off_a_terminal():
    out = io.StringIO()
    show = Progress(100, stream=out)
    for i in range(100):
        show(f"pid seed {i}", "completed")
    lines = out.getvalue().splitlines()
    assert len(lines) == 20 and lines[-1].startswith("[########################] 100/100 runs")
    assert lines[-1].endswith("pid seed 99: completed")
    small = io.StringIO()
    show = Progress(3, stream=small)
    for i in range(3):
        show(f"fuzzy seed {i}", "collision")
    assert [line.split("]")[1].split(",")[0] for line in small.getvalue().splitlines()] == [
        " 1/3 runs",
        " 2/3 runs",
        " 3/3 runs",
    ]


def test_progress_counts_another_unit_and_shows_a_count_set_by_its_caller():
    out = io.StringIO()
    show = Progress(10240, stream=out, unit="env steps")
    show.show("training", "sac on ego/CutIn-v0, seed 0", done=512)
    show.show("training", "sac on ego/CutIn-v0, seed 0", done=99999)  # past the total: the total
    first, last = out.getvalue().splitlines()
    assert first.startswith("[#.......................] 512/10240 env steps, ") and " env steps/s, " in first
    assert first.endswith("training: sac on ego/CutIn-v0, seed 0")
    assert last.startswith("[########################] 10240/10240 env steps")
