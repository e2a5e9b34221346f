"""Sweep specs: every name and value checked before anything runs; runs expanded lazily."""

import itertools
import subprocess
import sys

import pytest

from ego.params import ConfigError
from ego.sweep.spec import parse, run_id

BASE = {"scenario": "emergency-brake", "controllers": ["pid", "fuzzy"], "seeds": 2}


def spec(**parts):
    return parse({**BASE, **parts}, "test.toml")


def test_grid_and_sample_expand_to_every_point_controller_and_seed():
    s = spec(
        set={"traffic_density": 5},
        grid={"ego_speed": [20, 25, 30], "lead_decel": [4, 6, 8]},
        sample={"method": "sobol", "n": 4, "lead_gap": [20, 60]},
    )
    runs = list(s.runs())
    assert s.count() == len(runs) == 3 * 3 * 4 * 2 * 2
    assert len({r.run_id for r in runs}) == len(runs)
    gaps = {r.overrides["lead_gap"] for r in runs}
    assert len(gaps) == 4 and all(20 <= g <= 60 for g in gaps)
    assert all(r.overrides["traffic_density"] == 5 for r in runs)
    assert {(r.overrides["ego_speed"], r.overrides["lead_decel"]) for r in runs} == set(
        itertools.product([20, 25, 30], [4, 6, 8])
    )


def test_sampling_is_deterministic_and_respects_integer_parameters():
    a = [r.overrides for r in spec(sample={"method": "lhs", "n": 16, "ego_speed": [15, 33]}).runs()]
    b = [r.overrides for r in spec(sample={"method": "lhs", "n": 16, "ego_speed": [15, 33]}).runs()]
    assert a == b
    followers = [
        r.overrides["followers"]
        for r in parse(
            {
                "scenario": "platoon",
                "controllers": ["pid"],
                "sample": {"method": "random", "n": 20, "seed": 3, "followers": [1, 10]},
            }
        ).runs()
    ]
    assert all(isinstance(f, int) and 1 <= f <= 10 for f in followers) and len(set(followers)) > 3


def test_whole_numbers_alone_are_each_run_once():
    # an LHS of 8 points over followers 2..4 draws 2, 3 and 4 again and again: each point
    # is one run (the same run twice counted twice in the summary), and the count says so
    for method in ("lhs", "random", "sobol"):
        s = parse(
            {
                "scenario": "platoon",
                "controllers": ["pid", "bp-pid-acc"],
                "seeds": 2,
                "grid": {"headway": [1.0, 2.0]},
                "sample": {"method": method, "n": 8, "followers": [2, 4]},
            }
        )
        runs = list(s.runs())
        assert len({r.run_id for r in runs}) == len(runs) == s.count() == 2 * 3 * 2 * 2
        assert {r.overrides["followers"] for r in runs} == {2, 3, 4}


def test_a_whole_number_takes_each_value_of_its_range_alike():
    # beside a real-valued parameter (no repeats to leave out), an LHS of 30 points gives each
    # of 2, 3 and 4 exactly ten times; rounding the range [2, 4] gave its ends half a share
    s = parse(
        {
            "scenario": "platoon",
            "controllers": ["pid"],
            "sample": {"method": "lhs", "n": 30, "followers": [2, 4], "headway": [1.0, 3.0]},
        }
    )
    followers = [r.overrides["followers"] for r in s.runs()]
    assert s.count() == len(followers) == 30
    assert sorted(followers) == [2] * 10 + [3] * 10 + [4] * 10


def test_run_ids_are_stable_and_depend_on_everything():
    a = run_id("emergency-brake", "pid", 0, {"ego_speed": 20.0, "lead_gap": 30.0})
    assert a == run_id("emergency-brake", "pid", 0, {"lead_gap": 30.0, "ego_speed": 20.0})
    assert len(a) == 16
    others = {
        run_id("emergency-brake", "fuzzy", 0, {"ego_speed": 20.0, "lead_gap": 30.0}),
        run_id("emergency-brake", "pid", 1, {"ego_speed": 20.0, "lead_gap": 30.0}),
        run_id("emergency-brake", "pid", 0, {"ego_speed": 21.0, "lead_gap": 30.0}),
        run_id("fast-follower", "pid", 0, {"ego_speed": 20.0, "lead_gap": 30.0}),
    }
    assert a not in others and len(others) == 4


@pytest.mark.parametrize(
    "parts, message",
    [
        ({"scenario": "nowhere"}, "unknown scenario"),
        ({"controllers": ["pid", "narma-l2"]}, "unknown controller 'narma-l2'"),
        ({"controllers": ["pid", "pid"]}, "listed twice"),
        ({"controllers": []}, "non-empty list"),
        ({"seeds": -1}, "seeds = -1"),
        ({"seeds": [0, 2**31]}, "seed 2147483648"),
        ({"seeds": [1, 1]}, "listed twice"),
        ({"set": {"lead_decel": 50}}, "[set] lead_decel: bad value for lead_decel: 50"),
        ({"set": {"nonsense": 1}}, "[set] unknown parameter 'nonsense'"),
        ({"grid": {"ego_speed": [20, "fast"]}}, "bad value for ego_speed: 'fast'"),
        ({"grid": {"ego_speed": []}}, "non-empty list"),
        ({"grid": {"block_left": [True, 3]}}, "bad value for block_left"),
        ({"sample": {"method": "halton", "n": 4, "lead_gap": [20, 60]}}, "method 'halton'"),
        ({"sample": {"n": 0, "lead_gap": [20, 60]}}, "n must be"),
        ({"sample": {"n": 4, "lead_gap": [60, 20]}}, "low < high"),
        ({"sample": {"n": 4, "lead_gap": [20, 900]}}, "bad value for lead_gap: 900"),
        (
            {"grid": {"duration": [3, 30]}, "sample": {"n": 4, "lead_brake_time": [0.5, 5]}},
            "[sample] lead_brake_time with [grid] duration = 3: bad value for lead_brake_time: 5",
        ),
        ({"sample": {"n": 4, "block_left": [0, 1]}}, "not a number to sample"),
        ({"sample": {"method": "sobol", "n": 100, "lead_gap": [20, 60]}}, "power of 2"),
        ({"set": {"ego_speed": 20}, "grid": {"ego_speed": [20, 25]}}, "both fixed"),
        ({"bogus": 1}, "unknown key 'bogus'"),
    ],
    ids=lambda v: str(v)[:40],
)
def test_bad_specs_are_one_line_errors_naming_the_problem(parts, message):
    with pytest.raises(ConfigError) as err:
        spec(**parts)
    text = str(err.value)
    assert message in text and "\n" not in text and text.startswith("test.toml: ")


def test_a_huge_spec_fails_by_counting_without_listing_its_runs(monkeypatch):
    from ego.sweep import spec as spec_module

    def no_listing(self):
        raise AssertionError("the runs were listed")

    monkeypatch.setattr(spec_module.SweepSpec, "runs", no_listing)
    grid = {
        "ego_speed": list(range(10, 40)),
        "lead_decel": [1, 2, 3, 4, 5, 6, 7, 8, 9],
        "lead_gap": list(range(10, 300, 2)),
        "traffic_density": list(range(0, 25)),
    }
    with pytest.raises(ConfigError, match="expands to 1,957,500,000 runs; the limit is 10,000,000"):
        spec(seeds=1000, grid=grid)


def test_the_cli_reports_a_bad_spec_in_one_line_and_writes_nothing(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('scenario = "emergency-brake"\ncontrollers = ["pid"]\n[grid]\nlead_decel = [3, 99]\n')
    out = tmp_path / "out"
    p = subprocess.run(
        [sys.executable, "-m", "ego", "sweep", str(bad), "--out", str(out)], capture_output=True, text=True
    )
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "lead_decel" in p.stderr
    assert not out.exists()
    broken = tmp_path / "broken.toml"
    broken.write_text("scenario = \n")
    p = subprocess.run(
        [sys.executable, "-m", "ego", "sweep", str(broken), "--out", str(out)], capture_output=True, text=True
    )
    assert p.returncode == 2 and "not valid TOML" in p.stderr and p.stderr.count("\n") == 1
