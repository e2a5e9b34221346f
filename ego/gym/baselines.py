"""The RL baselines of docs/results/rl-baselines.md: trained PPO and SAC (stable-baselines3)
beside every ego controller of the task, on the same randomised evaluation episodes, and DQN
in the discrete setting (:data:`DISCRETE_CONFIG`) beside each meta action held all the time.

Every env runs in its benchmark configuration (:data:`BENCH_CONFIG`: the env's defaults,
randomised episodes included, at ``policy_frequency`` 10 Hz, with a shorter lane-centring
drive); a policy is scored by :func:`ego.gym.evaluate` on the episodes of :data:`EVAL_SEEDS`
(the env's seeds: the same traffic and the same randomised parameters for every policy). The
controllers drive through :class:`ego.gym.ControllerPolicy` (stepped at their own 100 Hz
inside each policy step); the agents act at 10 Hz (DQN at 1 Hz). Every training and
evaluation pins its computation (:func:`pin_numerics`), so a model is the same on any x86-64
processor with AVX2.

    python scenarios/rl/train_sb3.py --env ego/CutIn-v0 --algo ppo --seed 0 --steps 5000

stable-baselines3 is the ``rl`` extra (``pip install -e ".[rl]"``); it is imported only here.
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from ego.gym import BENCHMARK

#: env id -> config of the benchmark: gym.make(id)'s own defaults (ego.gym.BENCHMARK)
BENCH_CONFIG: dict[str, dict] = BENCHMARK
#: the evaluation episodes' seeds (never used in training: training seeds its episodes from 0)
EVAL_SEEDS = tuple(range(1000, 1010))
#: the training budget of the committed table, the same for every env and algorithm: env
#: steps (at 10 Hz: 1,024 simulated seconds; twenty rollouts of PPO's 512 steps); the 36 runs
#: take about 50 minutes on 2 idle cores (a SAC run ~4.5 minutes, a PPO run ~30 s)
BUDGET = 10240
#: how far (in mean return) a trained row retrained elsewhere may be from the committed one:
#: twice what another numerical code path moved the curve's PPO row (1.52: 43.07 pinned,
#: 44.59 with MKL's generic path and torch's default kernels), for a machine whose simulation
#: arithmetic (SUMO's build, libm) differs where the pin cannot reach;
#: docs/results/rl-baselines.md#reproducing-the-trained-rows-on-another-machine
REPRODUCE_TOLERANCE = 3.0
#: DQN's budget in the discrete setting (env steps at 1 Hz: 800 episodes of 25 s)
DQN_BUDGET = 20000
ALGOS = ("ppo", "sac")
#: the algorithms of discrete actions, trained and scored on :data:`DISCRETE_CONFIG`
DISCRETE_ALGOS = ("dqn",)
#: the discrete setting: highway-env's meta actions at its 1 Hz, seen through its
#: TimeToCollision observation (the EgoState of a motorway env has no other car in it: its
#: fields are the ego's and the references'), the agent choosing the speed and the scenario's
#: planner and controller steering. TimeToCollision shows, per lane and for the speed one step
#: slower, as now and one faster, in which second the ego would reach a car at that speed: the
#: choice SLOWER / IDLE / FASTER faces. With highway-env's Kinematics (the four nearest cars'
#: positions and speeds, normalised over +-200 m and +-80 m/s, sorted by distance) DQN's Q
#: values did not see a crash coming (docs/results/rl-baselines.md#dqn-on-discrete-meta-actions)
DISCRETE_CONFIG = {
    "action": {"type": "DiscreteMetaAction", "lateral": False},
    "observation": {"type": "TimeToCollision"},
    "policy_frequency": 1,
}
#: what each algorithm changes from stable-baselines3's defaults (the rest: SB3's own)
HYPERPARAMETERS: dict[str, dict] = {
    "ppo": {"n_steps": 512, "batch_size": 64},
    "sac": {"learning_starts": 500},
    # highway-env's published DQN settings (its README's SB3 example), and a longer exploration
    "dqn": {
        "policy_kwargs": {"net_arch": [256, 256]},
        "learning_rate": 5e-4,
        "buffer_size": 15000,
        "learning_starts": 200,
        "batch_size": 32,
        "gamma": 0.8,
        "train_freq": 1,
        "gradient_steps": 1,
        "target_update_interval": 50,
        "exploration_fraction": 0.7,
    },
}


#: what an algorithm's training env changes in the reward, over the setting it is scored in
#: (every row is scored on the env's default reward): DQN trains with a crash weighing ten
#: times the default (-10 for -1; with -1 a crash cost it less than the progress it gave up by
#: holding back, and it collided in 3 of 10 evaluation episodes)
TRAINING_REWARD: dict[str, dict] = {"dqn": {"collision_reward": -10.0}}


#: the numerical libraries' settings every training and evaluation here runs with, so that a
#: model is the same on any x86-64 processor with AVX2: MKL's conditional numerical
#: reproducibility on its AVX2 code path (left to itself MKL picks the path of the processor:
#: AVX-512 and AVX2 machines train different weights) and torch's own kernels on their AVX2
#: path. Set in the environment before torch starts (a value already there is kept).
PINNED_NUMERICS = {"MKL_CBWR": "AVX2", "ATEN_CPU_CAPABILITY": "avx2"}


def pin_numerics() -> None:
    """Pin the computation of a training or an evaluation: :data:`PINNED_NUMERICS`, one torch
    thread, torch's deterministic algorithms. Warns (once) if torch ran before with other
    settings: its models may then differ in the last bits from the page's."""
    if "torch" not in sys.modules:
        for key, value in PINNED_NUMERICS.items():
            os.environ.setdefault(key, value)
    import torch

    torch.set_num_threads(1)  # one core per run (the machine is shared) and one summation order
    torch.use_deterministic_algorithms(True)
    capability = torch.backends.cpu.get_cpu_capability()
    cbwr = os.environ.get("MKL_CBWR")
    if capability != "AVX2" or cbwr != PINNED_NUMERICS["MKL_CBWR"]:
        warnings.warn(
            f"torch runs with CPU capability {capability} and MKL_CBWR={cbwr} (the baselines pin AVX2 and "
            f"{PINNED_NUMERICS['MKL_CBWR']}): set them before torch is imported to reproduce the page's models",
            stacklevel=2,
        )


def model_file(env_id: str, algo: str, seed: int, steps: int) -> str:
    """The file name of a trained model in a models folder (``train_sb3.py --models``, the
    page's ``runs/rl-baselines/``): ``CutIn-v0-ppo-seed0-2048.zip``."""
    return f"{env_id.removeprefix('ego/')}-{algo}-seed{seed}-{steps}.zip"


def save(model, path) -> None:
    """Write ``model`` to ``path`` atomically (all of it or, if this process dies, nothing)."""
    import io

    from ego.outputs import atomic_path

    buffer = io.BytesIO()
    model.save(buffer)
    with atomic_path(path) as tmp:
        tmp.write_bytes(buffer.getvalue())


def load(algo: str, path):
    """A model that :func:`save` wrote (on the CPU)."""
    pin_numerics()
    return algo_class(algo).load(path, device="cpu")


def make_env(env_id: str, config: dict | None = None):
    """``gym.make(env_id)``: its registered defaults are the benchmark's setting
    (:data:`ego.gym.BENCHMARK`), ``config`` overrides them key by key."""
    import gymnasium as gym

    import ego.gym  # noqa: F401 - registers the ids

    return gym.make(env_id, config=config or {})


def evaluate(env_id: str, policy, config: dict | None = None) -> dict:
    """``policy`` (an SB3 model, a controller name or a callable, as :func:`ego.gym.evaluate`
    takes it) on every episode of :data:`EVAL_SEEDS` in the env as :func:`make_env` makes
    it: per episode the return, the termination reason, the length (env steps) and the
    outcome flags ``is_success`` and ``collision``."""
    import ego.gym  # noqa: F401 - registers the ids
    from ego.gym.evaluate import evaluate as run

    rows = run(policy, env_id, seeds=EVAL_SEEDS, config=config or {})["per_episode"]
    return {
        "returns": [r["return"] for r in rows],
        "statuses": [r["termination_reason"] for r in rows],
        "lengths": [r["length"] for r in rows],
        "success": [bool(r["is_success"]) for r in rows],
        "collision": [bool(r["collision"]) for r in rows],
    }


def train(env_id: str, algo: str, seed: int, steps: int, progress=None):
    """A stable-baselines3 ``algo`` (ppo, sac, dqn) trained ``steps`` env steps on ``env_id`` (one
    env; its episodes drawn from ``seed``) in the algorithm's setting (:func:`algo_config`),
    with the hyper-parameters of :data:`HYPERPARAMETERS` (SB3's defaults otherwise), MLP
    policy, the computation pinned (:func:`pin_numerics`). ``progress``: a text stream (e.g.
    ``sys.stderr``) that gets ego's progress line as the training goes
    (:class:`ego.results.progress.Progress`, counting env steps); the model is the same with
    or without it."""
    pin_numerics()
    env = make_env(env_id, {**algo_config(algo), **TRAINING_REWARD.get(algo, {})})
    try:
        env.reset(seed=seed)
        model = algo_class(algo)("MlpPolicy", env, seed=seed, verbose=0, device="cpu", **HYPERPARAMETERS[algo])
        model.set_logger(quiet_logger())  # SB3's own would leave an empty /tmp/SB3-* folder per run
        callback = None if progress is None else _progress_callback(steps, progress, f"{algo} on {env_id}, seed {seed}")
        model.learn(total_timesteps=steps, callback=callback)
        return model
    finally:
        env.close()


def algo_class(algo: str):
    """stable-baselines3's class of ``algo``."""
    from stable_baselines3 import DQN, PPO, SAC

    return {"ppo": PPO, "sac": SAC, "dqn": DQN}[algo]


def algo_config(algo: str) -> dict:
    """The env config an algorithm trains and is scored in, over gym.make(id)'s defaults: DQN
    acts on :data:`DISCRETE_CONFIG`, PPO and SAC on the env's default continuous actions."""
    return dict(DISCRETE_CONFIG) if algo in DISCRETE_ALGOS else {}


def quiet_logger():
    """An SB3 logger that writes nowhere: SB3's default makes a ``SB3-<date>`` folder in the
    temp dir on every ``learn`` and never removes it."""
    from stable_baselines3.common.logger import Logger

    return Logger(folder=None, output_formats=[])


def _progress_callback(steps: int, stream, what: str):
    """An SB3 callback showing ego's progress line on ``stream``: on a terminal every 1 % of
    ``steps`` (rewritten in place), elsewhere every 5 % (a line each), and at the budget (one
    env: the count passes every number). It only reads the step count: the training is the
    same without it."""
    from stable_baselines3.common.callbacks import BaseCallback

    from ego.results.progress import Progress

    shown = Progress(steps, stream, unit="env steps")
    every = max(1, steps // (100 if stream.isatty() else 20))

    class ShowProgress(BaseCallback):
        def _on_step(self) -> bool:
            n = self.num_timesteps
            if n <= steps and (n % every == 0 or n == steps):  # PPO may step past the budget
                shown.show("training", what, done=n)
            return True

    return ShowProgress()


@dataclass(frozen=True)
class ControllerEval:
    """A docs job: an ego controller on the evaluation episodes of ``env_id``."""

    env_id: str
    controller: str

    def __call__(self) -> dict:
        return evaluate(self.env_id, self.controller)


@dataclass(frozen=True)
class ThresholdEval:
    """A docs job: the env's default controller on its evaluation episodes in the env as
    ``gym.make(env_id)`` makes it (the registered defaults: the benchmark's setting): its mean
    return is the spec's ``reward_threshold``."""

    env_id: str

    def __call__(self) -> dict:
        import ego.gym
        from ego.scenarios import scenario_class

        controller = scenario_class(ego.gym.ENV_IDS[self.env_id]).reference_controller()
        return evaluate(self.env_id, controller, config={})


@dataclass(frozen=True)
class TrainedEval:
    """A docs job: ``algo`` trained ``steps`` env steps with ``seed``, then evaluated. With a
    ``models`` folder the model is read from there if ``train_sb3.py --models`` (or an earlier
    run of this job) wrote it, else trained and written there; training is deterministic, so
    a stored model is the one this job would train."""

    env_id: str
    algo: str
    seed: int
    steps: int = BUDGET
    models: str | None = None

    def __call__(self) -> dict:
        from pathlib import Path

        path = (
            None
            if self.models is None
            else Path(self.models) / model_file(self.env_id, self.algo, self.seed, self.steps)
        )
        if path is not None and path.is_file():
            model = load(self.algo, path)
        else:
            model = train(self.env_id, self.algo, self.seed, self.steps)
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                save(model, path)
        return evaluate(self.env_id, model, algo_config(self.algo))


@dataclass(frozen=True)
class ConstantEval:
    """A docs job: one meta action all the time (``action``, e.g. ``SLOWER``) on the
    evaluation episodes of ``env_id`` in the discrete setting (:data:`DISCRETE_CONFIG`): the
    floor a discrete agent must beat."""

    env_id: str
    action: str

    def __call__(self) -> dict:
        index = discrete_actions(self.env_id)[self.action]
        return evaluate(self.env_id, lambda obs: index, DISCRETE_CONFIG)


def discrete_actions(env_id: str) -> dict[str, int]:
    """Meta action name -> index in the discrete setting of ``env_id``."""
    import ego.gym

    env = ego.gym.EgoEnv(ego.gym.ENV_IDS[env_id], DISCRETE_CONFIG)
    try:
        return dict(env.action_type.actions_indexes)
    finally:
        env.close()


def summary(results: list[dict]) -> dict:
    """The row's figures over its runs (the training seeds; one run for a controller):
    ``mean`` return (the mean of the runs' means), ``sd`` of the runs' means (nan for one
    run), and over all their episodes ``success``, ``collision`` (rates) with Wilson's 95 %
    intervals (``success_interval``, ``collision_interval``), ``no_crash`` (the share of
    episodes that ended neither in a collision nor diverged) and ``length`` (mean env steps)."""
    from ego.gym.evaluate import wilson

    means = [float(np.mean(r["returns"])) for r in results]
    n = sum(len(r["statuses"]) for r in results)
    successes = sum(sum(r["success"]) for r in results)
    collisions = sum(sum(r["collision"]) for r in results)
    crashed = sum(s in ("collision", "diverged") for r in results for s in r["statuses"])
    return {
        "mean": float(np.mean(means)),
        "sd": float(np.std(means, ddof=1)) if len(means) > 1 else math.nan,
        "success": successes / n,
        "success_interval": wilson(successes, n),
        "collision": collisions / n,
        "collision_interval": wilson(collisions, n),
        "no_crash": 1.0 - crashed / n,
        "length": float(np.mean([k for r in results for k in r["lengths"]])),
    }
