"""The benchmarks as pytest items: ``pytest benchmarks -m benchmark -s`` prints the figures.

They assert nothing about time (CI machines are noisy); only that they ran and that the
fast paths still agree with their references.
"""

import pytest

pytestmark = pytest.mark.benchmark


def test_fuzzy_speedup():
    from bench_fuzzy import main

    figures = main(["--points", "200"])
    assert figures["max_abs_difference"] < 1e-9


def test_controller_steps_with_and_without_their_c_twins():
    from bench_controllers import main

    figures = main(["--steps", "300", "--repeat", "1"])
    assert figures["bp-pid"]["identical"] and figures["rbf-smc"]["identical"] and figures["bp-pid-acc"]["identical"]
    assert figures["compile_s"]["rules"] > 0.0 and figures["compile_s"]["system"] > 0.0


def test_loop_against_bare_sumo(tmp_path, monkeypatch):
    from bench_loop import main

    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    figures = main(["--repeat", "5"])
    assert figures["control_steps"] == 2500
    figures = main(["--repeat", "3", "--scenario", "platoon", "--controller", "bp-pid-acc", "--set", "followers=10"])
    assert figures["control_steps"] == 9000


def test_loop_parts():
    from bench_loop_parts import main

    figures = main(["--runs", "1"])
    # every part was met in the run, the plan in each state through C and through Python
    for part in ("controller", "simulationStep", "moveToXY", "period, between", "plan Python, lane change"):
        assert figures[part] > 0.0
    assert figures["plan as bound, lane change"] > 0.0


def test_run_parts():
    from bench_run_parts import main

    figures = main(["--every", "40"])  # 5 runs of the 200-run envelope, one per controller
    assert figures["runs"] == 5
    # SUMO's step is timed inside the loop: a part of it, and what a worker of the sweep
    # spends in it is scaled from the same runs
    assert 0.0 < figures["ms_sumo_step"] < figures["ms_loop"]
    assert figures["sweep_sumo_s"] == pytest.approx(2500 / 2 * figures["ms_sumo_step"] / 1e3)
    assert figures["ms_bare_sumo"] > 0.0


def test_tuning_batch_against_the_per_member_loop():
    from bench_tune import main

    figures = main(["--members", "40", "--loop-members", "4", "--no-full"])
    assert figures["batch_generation_s"] > 0 and figures["drive_steps"] > 40000


def test_highway_env_against_sumo():
    from bench_highway_env import main

    figures = main(["--repeat", "2"])
    assert figures["sumo"]["control_steps"] == figures["highway-env"]["control_steps"] == 2500
    figures = main(["--repeat", "2", "--scenario", "fast-follower"])
    assert figures["highway-env"]["traffic_steps"] > 0


def test_gym_wrapper_against_the_raw_step(tmp_path, monkeypatch):
    from bench_gym import main

    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path))
    figures = main(["--repeat", "3"])
    round_trip = figures.pop("round_trip_us")
    assert round_trip["EgoVectorEnv"] > 0.0 and round_trip["AsyncVectorEnv"] > 0.0
    assert all(row["steps"] > 0 and row["overhead"] >= 0.0 for row in figures.values())


def test_scenario_file_against_builtin():
    from bench_xosc import main

    figures = main(["--repeat", "2"])
    assert figures["ratio"] > 0 and figures["convert_ms"] > 0


def test_falsify_runs_to_first_violation():
    """Issue 21's benchmark on real runs (20 repetitions x 4 optimisers, 300 runs each; it
    resumes from runs/bench-falsify/): every repetition made, LHS's median the reference."""
    from bench_falsify import main

    figures = main(["--reps", "20", "--budget", "300"])
    assert figures and all(len(f["runs"]) == 20 for f in figures.values())
    assert all(figures[(req, "lhs")]["ratio_to_lhs"] == 1.0 for req, _ in figures)


def test_falsify_rate_at_a_fixed_budget():
    """Issue 40's table: 10 repetitions of 150 runs per optimiser, psy-taliro's two included,
    on three requirements (one violating 0.144 % of the box); it resumes from runs/bench-falsify/."""
    from bench_falsify import main

    figures = main(["--rate"])
    assert {o for _, o in figures} >= {"cma", "bo", "random", "lhs", "psytaliro-uniform", "psytaliro-annealing"}
    assert all(len(f["runs"]) == 10 for f in figures.values())


def test_requirements_cost_at_full_rate_and_on_the_grid():
    """Issue 40's requirement check: its CPU share of a run at full rate and on the 0.1 s
    grid, alternating (printed; no time asserted), and the full rate's robustness never above
    the grid's on the cut-in formula."""
    from bench_requirements import main

    figures = main(["--seeds", "1", "--rounds", "1"])
    assert figures[0.0]["runs"] == figures[0.1]["runs"] == 3
    assert figures[0.0]["robustness"] <= figures[0.1]["robustness"]


def test_thread_pools_beside_an_env(tmp_path, monkeypatch):
    from bench_pool_threads import main

    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path))
    figures = main(["--ids", "ego/LaneCentering-v0", "ego/EmergencyBrake-v0", "--rounds", "2", "--steps", "50"])
    assert set(figures) == {"ego/LaneCentering-v0", "ego/EmergencyBrake-v0"}
    assert all(len(f["cpu_s"]) == 2 and min(f["wall_s"]) > 0.0 for f in figures.values())


def test_gym_wrapper_parts(tmp_path, monkeypatch):
    from bench_gym_parts import main

    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path))
    figures = main(["--rounds", "1", "--duration", "5"])
    assert set(figures) == {"ego/CutIn-v0", "ego/Platoon-v0"}
    assert all(
        row["env_us"] > 0.0
        and row["raw_us"] > 0.0
        and row["python_step_us"] > 0.0
        and set(row["saves_us"]) == {"reward", "observation", "action"}
        for row in figures.values()
    )
