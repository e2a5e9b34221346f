"""Requirements in signal temporal logic (ego.requirements): parsing with units, rtamt's
robustness on hand-made traces, and real runs (issue 21, point 1)."""

import json
import math

import numpy as np
import pytest

from ego.cli import main
from ego.params import ConfigError
from ego.requirements import (
    DERIVED,
    RequirementError,
    evaluate,
    in_samples,
    parse,
    sample_stride,
    split,
    summary_lines,
)
from ego.scenarios.base import Event, RunResult

UNITS = {
    "t": "s",
    "speed": "m/s",
    "gap_front": "m",
    "ttc_front": "s",
    "lateral_clear": "bool",
    "aeb_active": "bool",
    "collision_avoidable": "bool",
    "collision": "bool",
}


def _result(t, events=(), status="completed", metrics=None, **columns):
    names = ("t", *columns)
    trace = np.column_stack([t, *columns.values()])
    return RunResult("x", "y", 0, status, dict(metrics or {}), list(events), names, trace)


@pytest.mark.parametrize(
    "formula",
    [
        "always (gap_front >= 2.0)",
        "always (ttc_front >= 1.0 or lateral_clear)",
        "always (aeb_active implies eventually[0:3] (speed <= 1.0))",
        "not collision_avoidable",
        "always (gap_front >= 2 m)",
        "eventually[0 s:2.5 s] (speed <= 0.5 m/s) -> always (abs(speed - 1 m/s) < 3 m/s)",
    ],
)
def test_the_issues_examples_parse(formula):
    assert parse(formula, UNITS).rtamt


@pytest.mark.parametrize(
    "formula, message",
    [
        (
            "always (gap_front >= 2 s)",
            "compares 'gap_front' in m with '2.0' in s (units differ)",
        ),
        ("always (gap_front >= ttc_front)", "in m with 'ttc_front' in s"),
        ("always (gap_front + speed >= 2)", "units differ"),
        ("always (gap_frnt >= 2)", "unknown signal 'gap_frnt'"),
        ("always (gap_front >= 2", "ends early"),
        ("always gap_front", "expected a comparison"),
        (
            "always (lateral_clear >= 1)",
            "lateral_clear is a boolean signal: use it alone",
        ),
        ("always (speed >= 1) $", "unexpected character '$'"),
        ("eventually[3:1] (speed >= 1)", "ends before it starts"),
        ("", "empty"),
        ("always (gap_front >= 1e999 m)", "1e999 is not a finite number"),
        ("always (speed >= 36 km/h)", "unknown unit 'km' after 36 (units: "),
        ("always (gap_front >= -1e999 m)", "1e999 is not a finite number"),
        ("eventually[0:1e999] (speed >= 1)", "1e999 is not a finite number"),
    ],
)
def test_bad_formulas_are_one_line_errors(formula, message):
    with pytest.raises(RequirementError, match=None) as err:
        parse(formula, UNITS)
    assert message in str(err.value) and "\n" not in str(err.value)
    assert isinstance(err.value, ConfigError)


def test_robustness_of_always_is_the_smallest_margin_and_the_first_violation_time():
    t = np.arange(0.0, 5.0, 0.01)
    gap = 10.0 - 2.0 * t  # 10 m down to 0.02 m
    r = _result(t, gap_front=gap)
    v = evaluate(parse("always (gap_front >= 2 m)", UNITS, "keep"), r, period=0)
    assert v.robustness == pytest.approx(gap[-1] - 2.0)
    assert v.violated_at == pytest.approx(4.01)  # the first sample with gap < 2 m (gap = 1.98 m)
    assert v.unit == "m"
    assert evaluate(parse("always (gap_front >= 2 m)", UNITS, "keep"), r) == v  # full rate: the default
    # on the 0.1 s grid, counted back from the last sample: the end is a sample
    v10 = evaluate(parse("always (gap_front >= 2 m)", UNITS, "keep"), r, period=0.1)
    assert v10.robustness == pytest.approx(v.robustness)
    assert v10.violated_at == pytest.approx(4.09)


def test_a_number_minus_a_signal_is_a_difference_not_a_unit():
    """``-`` is also the dimensionless unit's name in the units table; after a number it is
    the minus sign (``100 - speed`` was refused as "100 in -" followed by a signal)."""
    t = np.arange(0.0, 2.0, 0.01)
    gap = 30.0 - 5.0 * t
    r = _result(t, gap_front=gap)
    for formula in (
        "always (40 - gap_front >= 0)",
        "always (40 m - gap_front >= 0 m)",
        "always (40 - 2*gap_front >= -30)",
    ):
        v = evaluate(parse(formula, UNITS, "diff"), r, period=0)
        assert v.unit == "m"
        assert v.robustness == pytest.approx(10.0)  # the gap starts at its largest, 30 m


def test_bounded_eventually_counts_seconds_not_samples():
    t = np.arange(0.0, 10.0, 0.01)
    events = [
        Event(1.0, "aeb", "AEB engages: ..."),
        Event(9.0, "aeb", "AEB releases (...)"),
    ]
    f = parse(
        "always (aeb_active implies eventually[0:3] (speed <= 1 m/s))",
        {**UNITS, "aeb_active": "bool"},
    )
    fast = _result(t, events, speed=np.where(t >= 3.5, 0.5, 10.0))  # slow 2.5 s after the AEB
    slow = _result(t, events, speed=np.where(t >= 4.5, 0.5, 10.0))  # 3.5 s after it
    assert evaluate(f, fast, period=0).robustness > 0
    v = evaluate(f, slow, period=0)
    assert v.robustness < 0 and v.violated_at == pytest.approx(1.0)


def test_a_boolean_proposition_is_plus_or_minus_one():
    t = np.arange(0.0, 2.0, 0.01)
    hit = [Event(1.5, "collision", "run ends: collision")]
    r = _result(
        t,
        hit,
        status="collision",
        metrics={"collision_avoidable": True},
        gap_front=np.ones_like(t),
        gap_rear=np.ones_like(t),
    )
    assert evaluate(parse("not collision_avoidable", UNITS), r).robustness == -1.0
    v = evaluate(parse("always (not collision)", UNITS), r, period=0)
    assert v.robustness == -1.0 and v.violated_at == pytest.approx(1.5)
    v = evaluate(parse("always (not collision)", UNITS), r, period=0.1)  # every 0.1 s: within one period
    assert v.robustness == -1.0 and 1.5 <= v.violated_at < 1.6
    clear = DERIVED["clearance"].fn(r, t)
    assert clear[0] == 1.0 and clear[-1] == -1.0


def test_split_and_summary():
    assert split("keep: always (gap_front >= 2 m)") == (
        "keep",
        "always (gap_front >= 2 m)",
    )
    with pytest.raises(RequirementError, match="expected NAME: FORMULA"):
        split("always (gap_front >= 2 m)")
    lines = summary_lines(
        {
            "pid": [{"requirements.keep": 1.0}, {"requirements.keep": -0.5}],
            "fuzzy": [{"requirements.keep": 2.0}],
        }
    )
    assert "| pid | 1/2 (-0.5) |" in lines and "| fuzzy | 1/1 (2) |" in lines


@pytest.mark.sumo
def test_a_run_reports_each_requirement_and_its_violation(capsys):
    code = main(
        [
            "run",
            "emergency-brake",
            "-c",
            "pid",
            "--json",
            "--require",
            "far: always (gap_front >= 25 m)",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    req = out["requirements"]
    assert set(req) == {
        "no_avoidable_collision",
        "no_collision",
        "stays_in_lane",
        "gap_or_clear",
        "aeb_slows",
        "far",
    }
    assert req["no_collision"] == 1.0 and req["far"] < 0
    assert out["units"]["requirements.far"] == "m"
    events = [e for e in out["events"] if e["kind"] == "requirement"]
    assert len(events) == 1 and "far" in events[0]["text"] and events[0]["t"] > 0
    # the smallest gap, from the trace, is what the robustness says
    assert req["far"] == pytest.approx(out["min_gap_front"] - 25.0, abs=0.2)


@pytest.mark.parametrize(
    "req, what",
    [
        ("x: always (gap_front >= 2 s)", "units differ"),
        ("x: always (gap_frnt >= 2 m)", "unknown signal"),
        ("x: always (", "ends early"),
        ("always (gap_front >= 2 m)", "expected NAME: FORMULA"),
        ("x: always (gap_front >= 1e999 m)", "not a finite number"),
    ],
)
@pytest.mark.parametrize("command", ["run", "compare"])
def test_bad_requirements_exit_2_before_anything_runs(command, req, what, capsys, tmp_path):
    args = (
        ["run", "emergency-brake", "-c", "pid", "--record", str(tmp_path / "r.rrd")]
        if command == "run"
        else [
            "compare",
            "emergency-brake",
            "--controllers",
            "pid",
            "--out",
            str(tmp_path / "cmp"),
        ]
    )
    assert main(args + ["--require", req]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego: error:") and what in err and err.count("\n") == 1
    assert not list(tmp_path.iterdir())


def test_sweep_spec_requirements_are_checked(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[requirements]\nbad = "always (gap_front >= 2 s)"\n'
    )
    assert main(["sweep", str(spec), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "units differ" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()
    assert math.isfinite(1.0)


CROSS_CHECKED = [
    "always (gap_front >= 2 m or lateral_clear)",
    "always (aeb_active implies eventually[0:3] (speed <= 1 m/s or not aeb_active))",
    "always ((ttc_front <= 3 s) implies eventually[0:1.5] (accel <= -1 m/s^2))",
    "always (abs(speed - 1 m/s) < 3 m/s and 2 * gap_front - 3 m > 0.5 m / 2)",
    "always (speed > -1 m/s) or eventually (speed < 0.5 m/s)",
    "always[0.5:2] (speed > 0) and eventually[0.02:0.05] (speed > 0)",
    "historically[0.2:1] (speed > -1) and once[0:0.7] (gap_front > 1) and historically (speed < 5) and once (speed > 1)",
    "(speed > 0) until[0.3:1.2] (gap_front < 0)",
    "(speed > 0) until (gap_front < -2)",
    "(speed > 0) until[0:0.5] (gap_front < -2)",
    "eventually[1:2] (not (speed == 0.5)) -> always[0:0.1] (speed <= 0.5)",
    "always (-speed > -3 m/s)",
    "not collision",
    "true and not false",
]


@pytest.mark.parametrize("n, step", [(400, 0.01), (150, 0.1)])
@pytest.mark.parametrize("formula", CROSS_CHECKED)
def test_the_numpy_monitor_gives_rtamts_own_robustness_sample_by_sample(formula, n, step):
    """ego evaluates formulas with numpy (ego.stl: sliding-window min/max, no loop over
    samples): every sample's robustness is exactly rtamt's own (offline, discrete time, the
    interval bounds counted in samples) at the trace's full rate and on the 0.1 s grid."""
    import rtamt

    from ego.stl import robustness

    rng = np.random.default_rng(7)
    req = parse(formula, {**UNITS, "accel": "m/s^2"})
    signals = {}
    for name in req.signals:
        x = rng.normal(0.0, 3.0, n)
        x[::17] = 0.5  # exact ties
        signals[name] = np.sign(x) if UNITS.get(name) == "bool" else x
    plain = rtamt.StlDiscreteTimeOfflineSpecification()
    for name in req.signals or ("t",):
        plain.declare_var(name, "float")
    plain.set_sampling_period(1, "s", 0.1)
    plain.spec = in_samples(req.rtamt, step)
    plain.parse()
    data = {"time": [float(i) for i in range(n)], **{k: v.tolist() for k, v in signals.items()}}
    if not req.signals:
        data["t"] = [0.0] * n
    expected = np.array([v for _, v in plain.evaluate(data)])
    got = robustness(req.tree, signals, n, step)
    assert np.array_equal(got, expected)


def test_bounds_sit_on_samples_at_any_control_period():
    """The samples are the most control periods up to 0.1 s apart that every interval bound
    is a whole number of; where there are none, every control step, a bound at the nearest."""
    assert sample_stride((3.0,), 0.01) == 10
    assert sample_stride((3.0,), 0.03) == 2  # 0.09 s does not divide 3 s, 0.06 s does
    assert sample_stride((3.0,), 0.015) == 5
    assert sample_stride((0.05, 2.0), 0.01) == 5
    assert sample_stride((1.0,), 1 / 30) == 3  # 0.1 s, to a float's precision
    assert sample_stride((0.015,), 0.01) == 1
    assert sample_stride((), 0.03) == 3
    assert in_samples("eventually[0.0:3.0] (a > 0) and once[0.5:0.015] (b)", 0.01) == (
        "eventually[0:300] (a > 0) and once[50:2] (b)"
    )


def test_a_bound_between_control_steps_is_taken_at_the_nearest():
    t = np.round(np.arange(0.0, 2.0, 0.01), 2)
    r = _result(t, speed=np.where(t >= 1.02, 0.5, 10.0))
    assert evaluate(parse("eventually[0:1.016] (speed <= 1 m/s)", UNITS), r).robustness > 0  # 1.02
    assert evaluate(parse("eventually[0:1.014] (speed <= 1 m/s)", UNITS), r).robustness < 0  # 1.01


@pytest.mark.sumo
def test_a_run_at_a_control_period_that_does_not_divide_its_defaults_bounds_is_checked(capsys):
    """The scenario's default aeb_slows (eventually[0:1]) at dt = 0.03 s: no number of 0.03 s
    steps makes 1 s; the check samples every step, the bound at 0.99 s, instead of failing
    (rtamt refused a bound between samples, after the run)."""
    code = main(
        [
            "run",
            "emergency-brake",
            "-c",
            "pid",
            "--set",
            "dt=0.03",
            "--set",
            "sumo_step=0.09",
            "--set",
            "duration=2",
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["requirements"]["aeb_slows"] is not None


def test_aeb_slows_holds_for_a_stop_at_any_speed_and_fails_an_aeb_that_does_not_brake():
    """The default aeb_slows asks the AEB to decelerate (at least 4 m/s^2 within every second it
    is engaged, unless the car has stopped or the AEB released): a friction-limited stop from
    30 m/s takes 3.75 s at 8 m/s^2 and passes (a 'stopped within 3 s' form failed it); an
    engaged AEB under which the car keeps its speed fails from its engagement."""
    from ego.requirements import defaults, signal_units

    formula = defaults("emergency-brake")["aeb_slows"]
    units = signal_units({"t": "s", "speed": "m/s"})
    req = parse(formula, units, "aeb_slows")
    t = np.round(np.arange(0.0, 8.0, 0.01), 2)
    events = [Event(1.0, "aeb", "AEB engages: ..."), Event(4.8, "aeb", "AEB releases (...)")]
    stop = np.where(t < 1.0, 30.0, np.maximum(30.0 - 8.0 * (t - 1.0), 0.0))
    assert evaluate(req, _result(t, events, speed=stop)).passed
    coasting = np.full(len(t), 30.0)
    v = evaluate(req, _result(t, events, speed=coasting))
    assert not v.passed and 1.0 <= v.violated_at <= 1.1


def test_each_scenario_declares_its_default_requirements_and_a_subclass_inherits_them():
    from ego.requirements import defaults
    from ego.scenarios import SCENARIOS
    from ego.scenarios.emergency_brake import EmergencyBrake

    # the class attribute is the one place: defaults() by name reads it
    for name, cls in SCENARIOS.items():
        assert cls.requirements and defaults(name) == dict(cls.requirements)
    assert defaults("curve") == {
        "no_collision": "always (not collision)",
        "friction": "always (abs(lat_accel) <= 7 m/s^2)",
    }

    class MyBrake(EmergencyBrake):
        name = "my-brake"

    assert defaults("my-brake", MyBrake) == defaults("emergency-brake")
    assert defaults("no-such-scenario") == {}


def test_a_backend_lacking_a_capability_the_scenario_needs_is_refused_in_one_line():
    from ego.scenarios.base import check_backend
    from ego.scenarios.tracking import SineTracking

    class OffRoad(SineTracking):
        name = "off-road"
        backends = ("sumo", "highway-env")
        needs = ("any_network",)

    check_backend(OffRoad, "sumo")
    with pytest.raises(ConfigError) as e:
        check_backend(OffRoad, "highway-env")
    assert str(e.value) == (
        "bad value for --backend: 'highway-env' (scenario off-road needs any_network; backend highway-env lacks it)"
    )


@pytest.mark.sumo
def test_full_rate_by_default_the_grid_on_request_and_the_first_violation_stored(capsys):
    """Every 0.01 s sample by default; ``--requirement-period 0.1`` evaluates on the 0.1 s grid
    counted back from the run's end (a minimum over fewer samples: never below the full
    rate's); each requirement's first violation time is a metric (None: held)."""
    args = ["run", "emergency-brake", "-c", "pid", "--set", "duration=6", "--json"]
    args += ["--require", "ttc_brakes: always ((ttc_front <= 3 s) implies eventually[0:1.5] (accel <= -1 m/s^2))"]
    args += ["--require", "soft: always (accel >= -3 m/s^2)"]
    got = {}
    for period in ("0", "0.1"):
        assert main([*args, "--requirement-period", period]) in (0, 1)
        got[period] = json.loads(capsys.readouterr().out)
    full, grid = got["0"], got["0.1"]
    assert full["requirements"]["soft"] < grid["requirements"]["soft"] < 0  # a sample between grid points
    first, later = full["first_violation"], grid["first_violation"]
    assert first["no_collision"] is None and first["soft"] < later["soft"]
    assert 0 < first["ttc_brakes"] < later["ttc_brakes"] <= 6
    for name in ("soft", "ttc_brakes"):
        event = next(e for e in full["events"] if e["kind"] == "requirement" and f" {name} " in e["text"])
        assert event["t"] == pytest.approx(first[name])
    assert main([*args, "--requirement-period", "-0.1"]) == 2
    assert "bad --requirement-period '-0.1'" in capsys.readouterr().err


@pytest.mark.sumo
def test_a_sweep_spec_keeps_the_grid_with_requirement_period(tmp_path, capsys):
    """``requirement_period = 0.1`` in a sweep spec: the runs' requirements on the 0.1 s grid,
    as ``ego run --requirement-period 0.1`` gives them; a bad value is one line, exit 2."""
    import pyarrow.parquet as pq

    body = (
        'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[set]\nduration = 6\n'
        '[requirements]\nsoft = "always (accel >= -3 m/s^2)"\n'
    )
    got = {}
    for period in ("0", "0.1"):
        spec = tmp_path / f"s{period}.toml"
        spec.write_text(f"requirement_period = {period}\n" + body)
        assert main(["sweep", str(spec), "--out", str(tmp_path / period)]) == 0
        row = pq.read_table(tmp_path / period / "results.parquet").to_pylist()[0]
        got[period] = (row["requirements.soft"], row["first_violation.soft"])
    capsys.readouterr()
    main(
        ["run", "emergency-brake", "-c", "pid", "--set", "duration=6", "--json", "--requirement-period", "0.1"]
        + ["--require", "soft: always (accel >= -3 m/s^2)"]
    )
    run = json.loads(capsys.readouterr().out)
    assert got["0.1"] == (run["requirements"]["soft"], run["first_violation"]["soft"])
    assert got["0"][0] < got["0.1"][0] < 0 and got["0"][1] < got["0.1"][1]
    bad = tmp_path / "bad.toml"
    bad.write_text("requirement_period = -1\n" + body)
    assert main(["sweep", str(bad), "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err
    assert "requirement_period -1 (expected seconds from 0" in err and err.count("\n") == 1
    assert not (tmp_path / "bad").exists()


def test_the_sliding_window_is_the_min_and_max_of_each_window():
    from ego.stl import sliding

    rng = np.random.default_rng(0)
    for n in (1, 2, 5, 17, 100):
        for w in (1, 2, 3, 7, 16, 150):
            y = rng.normal(size=n)
            for low in (True, False):
                expected = [(min if low else max)(y[i : i + w]) for i in range(n)]
                assert sliding(y, w, low).tolist() == expected, (n, w, low)
