"""The RL baselines of docs/results/rl-baselines.md: trained PPO and SAC (stable-baselines3)
beside every ego controller of the task, on the same randomised evaluation episodes.

Every env runs in its benchmark configuration (:data:`BENCH_CONFIG`: the env's defaults,
randomised episodes included, at ``policy_frequency`` 10 Hz, with a shorter lane-centring
drive); a policy is scored on the episodes of :data:`EVAL_SEEDS` (the env's seeds: the
same traffic and the same randomised parameters for every policy). The controllers drive
through :class:`ego.gym.ControllerPolicy` (stepped at their own 100 Hz inside each policy
step); the agents act at 10 Hz.

    python scenarios/rl/train_sb3.py --env ego/CutIn-v0 --algo ppo --seed 0 --steps 5000

stable-baselines3 is the ``rl`` extra (``pip install -e ".[rl]"``); it is imported only here.
"""

from __future__ import annotations

import math
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
ALGOS = ("ppo", "sac")


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
    from stable_baselines3 import PPO, SAC

    return {"ppo": PPO, "sac": SAC}[algo].load(path, device="cpu")


def make_env(env_id: str, config: dict | None = None):
    """``gym.make(env_id)``: its registered defaults are the benchmark's setting
    (:data:`ego.gym.BENCHMARK`), ``config`` overrides them key by key."""
    import gymnasium as gym

    import ego.gym  # noqa: F401 - registers the ids

    return gym.make(env_id, config=config or {})


def evaluate(env_id: str, act, config: dict | None = None) -> dict:
    """``act(env, obs) -> action`` on every episode of :data:`EVAL_SEEDS`: the returns, the
    statuses and the episode lengths (env steps); the env as :func:`make_env` makes it."""
    env = make_env(env_id, config)
    returns, statuses, lengths = [], [], []
    try:
        for seed in EVAL_SEEDS:
            obs, _ = env.reset(seed=seed)
            total, steps = 0.0, 0
            while True:
                obs, reward, terminated, truncated, info = env.step(act(env, obs))
                total += float(reward)
                steps += 1
                if terminated or truncated:
                    break
            returns.append(total)
            statuses.append(info["status"])
            lengths.append(steps)
    finally:
        env.close()
    return {"returns": returns, "statuses": statuses, "lengths": lengths}


def controller_policy_act(controller: str):
    """``act`` of an ego controller through :class:`ego.gym.ControllerPolicy` (one per env)."""
    from ego.gym import ControllerPolicy

    policies: dict = {}

    def act(env, obs):
        policy = policies.get(id(env))
        if policy is None:
            policy = policies[id(env)] = ControllerPolicy(controller, env)
        return policy(obs)

    return act


def train(env_id: str, algo: str, seed: int, steps: int, progress=None):
    """A stable-baselines3 ``algo`` (ppo, sac) trained ``steps`` env steps on ``env_id`` (one
    env; its episodes drawn from ``seed``); SB3's default hyper-parameters, MLP policy.
    ``progress``: a text stream (e.g. ``sys.stderr``) that gets ego's progress line as the
    training goes (:class:`ego.results.progress.Progress`, counting env steps); the model is
    the same with or without it."""
    import torch
    from stable_baselines3 import PPO, SAC

    torch.set_num_threads(1)  # the machine is shared: one core per run
    env = make_env(env_id)
    try:
        env.reset(seed=seed)
        cls = {"ppo": PPO, "sac": SAC}[algo]
        kwargs = {"n_steps": 512, "batch_size": 64} if algo == "ppo" else {"learning_starts": 500}
        model = cls("MlpPolicy", env, seed=seed, verbose=0, device="cpu", **kwargs)
        model.set_logger(quiet_logger())  # SB3's own would leave an empty /tmp/SB3-* folder per run
        callback = None if progress is None else _progress_callback(steps, progress, f"{algo} on {env_id}, seed {seed}")
        model.learn(total_timesteps=steps, callback=callback)
        return model
    finally:
        env.close()


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


def model_act(model):
    def act(env, obs):
        action, _ = model.predict(obs, deterministic=True)
        return action

    return act


@dataclass(frozen=True)
class ControllerEval:
    """A docs job: an ego controller on the evaluation episodes of ``env_id``."""

    env_id: str
    controller: str

    def __call__(self) -> dict:
        return evaluate(self.env_id, controller_policy_act(self.controller))


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
        return evaluate(self.env_id, controller_policy_act(controller), config={})


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
        return evaluate(self.env_id, model_act(model))


def summary(results: list[dict]) -> tuple[float, float, float]:
    """(mean return, its standard deviation over the runs' means, share of episodes that did
    not crash): the runs are the training seeds (one run for a controller)."""
    means = [float(np.mean(r["returns"])) for r in results]
    crashed = sum(s in ("collision", "diverged") for r in results for s in r["statuses"])
    episodes = sum(len(r["statuses"]) for r in results)
    sd = float(np.std(means, ddof=1)) if len(means) > 1 else math.nan
    return float(np.mean(means)), sd, 1.0 - crashed / episodes
