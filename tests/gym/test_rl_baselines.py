"""The RL baselines (issue 22, point 5): scenarios/rl/train_sb3.py writes a model that the
page docs/results/rl-baselines.md reads back and evaluates, training is deterministic (a
stored model is the one the page would train), and the page has trained PPO and SAC rows for
every env id at one fixed budget."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ego.gym
from ego.gym.baselines import ALGOS, BUDGET, EVAL_SEEDS, TrainedEval, evaluate, load, model_file, train

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scenarios" / "rl" / "train_sb3.py"
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


def test_every_env_table_has_ppo_and_sac_rows_from_the_stored_models_at_one_budget():
    from ego.docs import RL_MODELS, RL_SEEDS, RL_TABLES, rl_baselines

    tables = {t.name: t for t in rl_baselines()}
    assert set(RL_TABLES) == set(ego.gym.ENV_IDS)  # every env id, the multi-agent platoon aside
    for env_id, name in RL_TABLES.items():
        rows = {r.label: r for r in tables[name].rows}
        for algo in ALGOS:
            jobs = rows[algo.upper()].jobs
            assert jobs == tuple(TrainedEval(env_id, algo, seed, BUDGET, str(RL_MODELS)) for seed in RL_SEEDS)
        assert f"--steps {BUDGET} --models runs/rl-baselines" in tables[name].commands[0]
    assert len(RL_SEEDS) == 3 and model_file("ego/CutIn-v0", "sac", 2, BUDGET) == f"CutIn-v0-sac-seed2-{BUDGET}.zip"


def test_the_committed_page_has_trained_rows_for_every_env_at_the_budget():
    from ego.docs import RL_TABLES, block, page_path

    text = page_path("rl-baselines").read_text()
    for name in RL_TABLES.values():
        table = block(text, name)
        for algo in ALGOS:
            assert any(line.startswith(f"| {algo.upper()} | ") for line in table.splitlines()), (name, algo)
        assert f"PPO and SAC: {BUDGET} env steps each, training seeds 0-2" in table
        assert f"seeds {EVAL_SEEDS[0]}-{EVAL_SEEDS[-1]}" in table


@pytest.mark.parametrize(
    ("args", "bad"),
    [
        (["--env", "ego/Nope-v0"], "--env"),
        (["--algo", "a2c"], "--algo"),
        (["--steps", "0"], "--steps"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_train_sb3_refuses_a_bad_value_in_one_line_before_training(args, bad, tmp_path):
    p = subprocess.run(
        [sys.executable, str(SCRIPT), *args, "--models", str(tmp_path)], capture_output=True, text=True, timeout=60
    )
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "error: bad value for " + bad in p.stderr
    assert not any(tmp_path.iterdir())


def test_train_sb3_refuses_a_model_place_it_cannot_write_before_training(tmp_path):
    (tmp_path / "file").write_text("")
    for args, why in (
        (["--models", str(tmp_path / "file")], "bad --models"),
        (["--save", str(tmp_path)], "bad --save"),
    ):
        p = subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True, timeout=60)
        assert p.returncode == 2 and p.stderr.count("\n") == 1 and why in p.stderr, p.stderr
    assert [f.name for f in tmp_path.iterdir()] == ["file"]


@pytest.mark.sumo
def test_a_training_shows_its_progress_and_trains_the_same_model_without_it():
    import io

    out = io.StringIO()
    shown = train("ego/CutIn-v0", "ppo", 0, 512, progress=out)
    lines = out.getvalue().splitlines()
    # off a terminal: every 25 steps (512 // 20), a line each, and the last at the budget
    assert len(lines) == 21 and all(" env steps/s, " in line for line in lines)
    assert lines[0].startswith("[#.......................] 25/512 env steps")
    assert lines[-1].startswith("[########################] 512/512 env steps")
    assert lines[-1].endswith("training: ppo on ego/CutIn-v0, seed 0")
    quiet = train("ego/CutIn-v0", "ppo", 0, 512)
    a, b = shown.policy.state_dict(), quiet.policy.state_dict()
    assert a.keys() == b.keys() and all(np.array_equal(a[k].numpy(), b[k].numpy()) for k in a)


def _train_sb3(*args: str) -> None:
    """scenarios/rl/train_sb3.py in a process of its own (no scoring)."""
    p = subprocess.run([sys.executable, str(SCRIPT), *args, "--no-score"], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr


@pytest.mark.benchmark  # about a minute of training on a free core: run with -m benchmark
@pytest.mark.sumo
@pytest.mark.parametrize(("algo", "steps"), [("ppo", 512), ("sac", 600)])
def test_a_model_train_sb3_stores_is_the_one_the_page_trains_and_evaluates(algo, steps, tmp_path):
    env_id = "ego/CutIn-v0"
    _train_sb3("--env", env_id, "--algo", algo, "--seed", "0", "--steps", str(steps), "--models", str(tmp_path))
    path = tmp_path / model_file(env_id, algo, 0, steps)
    stored = load(algo, path)
    # trained again in a fresh process of its own (this one's torch may have started unpinned)
    again = tmp_path.parent / f"{tmp_path.name}-again.zip"
    _train_sb3("--env", env_id, "--algo", algo, "--steps", str(steps), "--save", str(again))
    fresh = load(algo, again)
    a, b = stored.policy.state_dict(), fresh.policy.state_dict()
    assert a.keys() == b.keys() and all(np.array_equal(a[k].numpy(), b[k].numpy()) for k in a)
    page = TrainedEval(env_id, algo, 0, steps, str(tmp_path))()  # reads the stored model: no training
    assert page == evaluate(env_id, fresh)
    assert len(page["returns"]) == len(EVAL_SEEDS) and all(np.isfinite(page["returns"]))
    assert sorted(f.name for f in tmp_path.iterdir()) == [path.name]  # nothing half-written left


@pytest.mark.long  # three PPO trainings of the page's budget from nothing: minutes (docs/results/rl-baselines.md)
@pytest.mark.sumo
def test_a_trained_row_of_the_committed_page_regenerates_within_its_tolerance(tmp_path):
    """The curve's PPO row trained again from nothing (three seeds, in fresh worker processes,
    the models into an empty folder) is the committed row: the mean return within
    REPRODUCE_TOLERANCE, the success and collision rates equal."""
    from ego import docs
    from ego.gym.baselines import REPRODUCE_TOLERANCE

    # in a process of its own, as a user runs it (this one's path has tests/gym, which SB3's
    # optional "import gym" would find in the workers)
    code = (
        "import dataclasses; from ego import docs; "
        "t = next(t for t in docs.rl_baselines() if t.name == 'rl-curve'); r = t.row('PPO'); "
        f"r = dataclasses.replace(r, jobs=tuple(dataclasses.replace(j, models={str(tmp_path)!r}) for j in r.jobs)); "
        "print(docs.render_row(r, docs.run_jobs(r.jobs, workers=2, progress=False)))"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=3600, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    again = _cells(p.stdout, "PPO")
    committed = _cells(docs.block(docs.page_path("rl-baselines").read_text(), "rl-curve"), "PPO")
    assert abs(float(again[1]) - float(committed[1])) <= REPRODUCE_TOLERANCE, (again, committed)
    assert again[3:5] == committed[3:5]  # success, collision
    assert len(list(tmp_path.iterdir())) == 3  # trained here, not read from runs/


def test_the_discrete_table_has_dqn_beside_each_meta_action_held_all_the_time():
    from ego.docs import RL_DISCRETE_TABLES, RL_MODELS, RL_SEEDS, rl_discrete
    from ego.gym.baselines import DISCRETE_CONFIG, DQN_BUDGET, HYPERPARAMETERS, ConstantEval, discrete_actions

    (table,) = rl_discrete()
    assert table.name == RL_DISCRETE_TABLES["ego/EmergencyBrake-v0"]
    rows = {r.label: r for r in table.rows}
    actions = discrete_actions("ego/EmergencyBrake-v0")
    assert {"SLOWER", "IDLE", "FASTER"} <= set(actions)
    for action in actions:
        assert rows[f"always {action}"].jobs == (ConstantEval("ego/EmergencyBrake-v0", action),)
    assert rows["DQN"].jobs == tuple(
        TrainedEval("ego/EmergencyBrake-v0", "dqn", seed, DQN_BUDGET, str(RL_MODELS)) for seed in RL_SEEDS
    )
    assert f"--algo dqn --seed $seed --steps {DQN_BUDGET}" in table.commands[0]
    assert DISCRETE_CONFIG["action"]["type"] == "DiscreteMetaAction" and HYPERPARAMETERS["dqn"]


def _cells(table: str, label: str) -> list[str]:
    line = next(x for x in table.splitlines() if x.startswith(f"| {label} | "))
    return [c.strip() for c in line.strip("|").split("|")]


def test_the_committed_dqn_row_beats_always_slower_on_the_return_and_collides_no_more():
    # what the page claims (issue 42, point 5): above always SLOWER (the crash-free floor) and
    # always FASTER on the return, and no collision where SLOWER has none
    from ego.docs import RL_DISCRETE_TABLES, block, page_path

    table = block(page_path("rl-baselines").read_text(), RL_DISCRETE_TABLES["ego/EmergencyBrake-v0"])
    dqn = _cells(table, "DQN")
    rate = lambda cell: float(cell.split(" %")[0])  # noqa: E731 - "90 % (60-98)" -> 90
    for action in ("SLOWER", "FASTER"):
        assert float(dqn[1]) > float(_cells(table, f"always {action}")[1]), action  # mean return
    assert rate(dqn[4]) <= rate(_cells(table, "always SLOWER")[4]) == 0.0  # collision
    assert dqn[4] == "0 % (0-11)"  # none of its 30 episodes


PIN_CHECK = (
    "import os, warnings; warnings.simplefilter('error'); from ego.gym.baselines import pin_numerics; "
    "pin_numerics(); import torch; "
    "print(torch.backends.cpu.get_cpu_capability(), os.environ['MKL_CBWR'], torch.get_num_threads(), "
    "torch.are_deterministic_algorithms_enabled())"
)


@pytest.mark.skipif("avx2" not in Path("/proc/cpuinfo").read_text(), reason="the pin is AVX2's code paths")
def test_a_training_process_pins_its_numerics_before_torch_starts():
    env = {k: v for k, v in __import__("os").environ.items() if k not in ("MKL_CBWR", "ATEN_CPU_CAPABILITY")}
    p = subprocess.run([sys.executable, "-c", PIN_CHECK], capture_output=True, text=True, timeout=120, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["AVX2", "AVX2", "1", "True"]
    # torch started first, unpinned: the pin says so instead of silently training other weights
    late = "import torch; torch.zeros(1) + 1; " + PIN_CHECK
    q = subprocess.run([sys.executable, "-c", late], capture_output=True, text=True, timeout=120, env=env)
    assert q.returncode != 0 and "set them before torch is imported" in q.stderr
