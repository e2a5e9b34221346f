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
from ego.gym.baselines import ALGOS, BUDGET, EVAL_SEEDS, TrainedEval, evaluate, load, model_act, model_file, train

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
        (["--algo", "dqn"], "--algo"),
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


@pytest.mark.benchmark  # about a minute of training on a free core: run with -m benchmark
@pytest.mark.sumo
@pytest.mark.parametrize(("algo", "steps"), [("ppo", 512), ("sac", 600)])
def test_a_model_train_sb3_stores_is_the_one_the_page_trains_and_evaluates(algo, steps, tmp_path):
    env_id = "ego/CutIn-v0"
    p = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--env",
            env_id,
            "--algo",
            algo,
            "--seed",
            "0",
            "--steps",
            str(steps),
            "--models",
            str(tmp_path),
            "--no-score",
        ],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert p.returncode == 0, p.stderr
    path = tmp_path / model_file(env_id, algo, 0, steps)
    stored = load(algo, path)
    fresh = train(env_id, algo, 0, steps)  # here, in this process: the same model
    a, b = stored.policy.state_dict(), fresh.policy.state_dict()
    assert a.keys() == b.keys() and all(np.array_equal(a[k].numpy(), b[k].numpy()) for k in a)
    page = TrainedEval(env_id, algo, 0, steps, str(tmp_path))()  # reads the stored model: no training
    assert page == evaluate(env_id, model_act(fresh))
    assert len(page["returns"]) == len(EVAL_SEEDS) and all(np.isfinite(page["returns"]))
    assert sorted(f.name for f in tmp_path.iterdir()) == [path.name]  # nothing half-written left


@pytest.mark.benchmark  # three PPO trainings of the page's budget (minutes) unless runs/rl-baselines has them
@pytest.mark.sumo
def test_a_trained_row_of_the_committed_page_regenerates():
    from ego import docs

    table = next(t for t in docs.rl_baselines() if t.name == "rl-curve")
    row = table.row("PPO")
    line = docs.render_row(row, docs.run_jobs(row.jobs, workers=2, progress=False))
    assert line in docs.block(docs.page_path("rl-baselines").read_text(), table.name).splitlines()
