"""ego compare's PNGs from real (short) SUMO runs: every declared file is written, every seed is
drawn, the references, bands and event markers are there, labels never reach file names."""

import dataclasses

import numpy as np
import pytest

from ego.compare import compare, run_one
from ego.parallel.executor import InlineExecutor
from ego.plots import figure, measured_gains, write_all
from ego.runner import RunSpec
from ego.scenarios import scenario_class

PNG = b"\x89PNG\r\n\x1a\n"
EVASIVE_FILES = [
    "fx.png",
    "gap_front.png",
    "lateral_error.png",
    "speed.png",
    "steering.png",
    "trajectory.png",
    "ttc.png",
]


def _pngs(out):
    files = sorted(p.name for p in out.glob("*.png"))
    for name in files:
        assert (out / name).read_bytes()[:8] == PNG, name
    return files


def _declared(scenario, overrides):
    cls = scenario_class(scenario)
    return sorted(p.file for p in cls.compare_plots(cls.config_cls(**overrides)))


@pytest.mark.sumo
def test_an_evasive_comparison_writes_every_plot_with_every_seed(tmp_path):
    out = tmp_path / "eb"
    rows = compare(
        "emergency-brake", ["fuzzy", "pid"], 2, {"duration": 7.0}, out, progress=None, executor=InlineExecutor()
    )
    assert _pngs(out) == EVASIVE_FILES == _declared("emergency-brake", {})
    assert all(r.traffic is not None and "lead" in r.traffic.ids for r in rows)
    fig = figure(
        "emergency-brake",
        scenario_class("emergency-brake").compare_plots(scenario_class("emergency-brake").config_cls(duration=7.0))[0],
        rows,
        ["fuzzy", "pid"],
    )
    ax = fig.axes[0]
    assert "all 2 seeds" in fig._suptitle.get_text()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:3] == ["settle band +-0.2 m", "fuzzy (2 timeout)", "pid (2 timeout)"]
    assert {"lateral reference", "trigger (TTC below the threshold)", "lane chosen (or stay)"} <= set(labels)
    solid = [line for line in ax.lines if line.get_linestyle() == "-" and len(line.get_xdata()) > 100]
    assert len(solid) == 4  # one line per run
    trajectory = figure(
        "emergency-brake",
        scenario_class("emergency-brake").compare_plots(scenario_class("emergency-brake").config_cls())[-1],
        rows,
        ["fuzzy", "pid"],
    )
    assert len(trajectory.axes) == 4  # a panel per run
    texts = [t.get_text() for t in trajectory.axes[0].texts]
    assert "lead" in texts and any(t.startswith("gap ") for t in texts)


@pytest.mark.sumo
def test_a_label_with_signs_never_reaches_a_file_name(tmp_path):
    row = run_one(RunSpec("cut-in", "fuzzy", 0, {"duration": 3.0}))
    odd = dataclasses.replace(row, controller="pid@kp_lat=0.02,kd=1/2")
    plots = scenario_class("cut-in").compare_plots(scenario_class("cut-in").config_cls())
    written = write_all("cut-in", plots, [row, odd], ["fuzzy", odd.controller], tmp_path)
    assert sorted(p.name for p in written) == _pngs(tmp_path) == sorted(EVASIVE_FILES)


@pytest.mark.sumo
def test_a_platoon_comparison_writes_its_plots_and_string_stability(tmp_path):
    out = tmp_path / "platoon"
    overrides = {"duration": 20.0, "followers": 2}
    rows = compare("platoon", ["pid", "bp-pid-acc"], 1, overrides, out, progress=None, executor=InlineExecutor())
    files = ["accel.png", "gap.png", "spacing_error.png", "speed.png", "string_stability.png"]
    assert _pngs(out) == files == _declared("platoon", overrides)
    plots = scenario_class("platoon").compare_plots(scenario_class("platoon").config_cls(**overrides))
    spacing = figure("platoon", plots[1], rows, ["pid", "bp-pid-acc"])
    assert len(spacing.axes) == 2  # a panel per controller, a line per follower
    assert [t.get_text() for t in spacing.axes[0].get_legend().get_texts()] == [
        "settle band +-0.2 m",
        "f1",
        "f2",
        "the leader's manoeuvre starts",
    ]  # braking at 10 s
    bode = figure("platoon", plots[-1], rows, ["pid", "bp-pid-acc"], {"pid": _pid_params()})
    labels = [t.get_text() for t in bode.axes[0].get_legend().get_texts()]
    assert labels[0].startswith("pid: theory (kp 0.85, ki 0.2, kd 0.3)")
    assert any(label.startswith("bp-pid-acc: theory") for label in labels)  # its mean adapted gains


def _pid_params():
    from ego.control import controller_spec

    return controller_spec("pid", "car-following").params()


@pytest.mark.sumo
def test_lane_centring_shows_report_003s_criterion(tmp_path):
    out = tmp_path / "lc"
    compare(
        "lane-centering",
        ["cascade-pid"],
        1,
        {"duration": 5.0, "offset": 1.0},
        out,
        progress=None,
        executor=InlineExecutor(),
    )
    assert _pngs(out) == ["a_x.png", "lateral_error.png", "speed.png", "steering.png"]
    header = (out / "metrics.md").read_text().splitlines()[4]
    assert "max_abs_lateral_error [m]" in header


def test_the_measured_gain_of_a_pure_gain_is_that_gain():
    t = np.arange(0.0, 60.0, 0.01)
    up = np.sin(0.5 * t) + 0.3 * np.sin(2.0 * t)
    w, g = measured_gains(t, up, 0.7 * up)
    assert len(w) >= 2 and np.allclose(g, 0.7)


@pytest.mark.sumo
@pytest.mark.parametrize(
    "scenario, controller",
    [
        ("fast-follower", "pid"),
        ("curve", "pid"),
        ("sine-tracking", "fuzzy"),
        ("report-000", "pid"),
    ],
    ids=["fast-follower", "curve", "sine-tracking", "report-000"],
)
def test_every_declared_plot_of_the_other_scenarios_is_written(scenario, controller, tmp_path):
    row = run_one(RunSpec(scenario, controller, 0, {"duration": 2.0}))
    assert row.status != "error", row.error
    cls = scenario_class(scenario)
    plots = cls.compare_plots(cls.config_cls(duration=2.0))
    write_all(scenario, plots, [row], [controller], tmp_path)
    assert _pngs(tmp_path) == sorted(p.file for p in plots)
