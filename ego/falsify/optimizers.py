"""Optimisers that propose points of the unit cube in batches and learn from their scores.

Every optimiser has ``ask() -> array (n, d)`` (a batch: its size follows the executor's
workers) and ``tell(points, scores)`` (lower is better: a requirement's robustness, squashed
by :func:`squash`). They are deterministic given their seed, so a search can be replayed
point for point (how ``ego falsify`` resumes).

* ``random``: independent uniform points (the baseline).
* ``lhs``: a Latin hypercube over the whole budget (scipy.stats.qmc), in batches.
* ``cma``: CMA-ES (the ``cma`` package) in the cube (bounded), its population a multiple of
  the batch, restarted with a doubled population when it converges (IPOP).
* ``bo``: Bayesian optimisation with optuna's Gaussian-process sampler (it accounts for
  the trials of a batch still running), or its TPE sampler (``bo-tpe``) where a GP does not fit.
"""

from __future__ import annotations

import math

import numpy as np

NAMES = ("cma", "bo", "bo-tpe", "random", "lhs")


def squash(y: float) -> float:
    """A robustness as an optimiser's score: sign(y) log(1 + |y|) (a clipped infinity of
    1e9 or a run with no result (NaN: the worst seen) must not swamp a GP's fit)."""
    if not math.isfinite(y):
        return math.copysign(math.log1p(1e9), y) if not math.isnan(y) else math.log1p(1e9)
    return math.copysign(math.log1p(abs(y)), y)


class RandomSearch:
    def __init__(self, d: int, batch: int, seed: int, budget: int) -> None:
        self.d, self.batch = d, batch
        self.rng = np.random.default_rng(seed)

    def ask(self) -> np.ndarray:
        return self.rng.random((self.batch, self.d))

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        pass


class LatinHypercube:
    def __init__(self, d: int, batch: int, seed: int, budget: int) -> None:
        from scipy.stats import qmc

        self.batch = batch
        self.points = qmc.LatinHypercube(d=d, seed=seed).random(budget)
        self.i = 0

    def ask(self) -> np.ndarray:
        out = self.points[self.i : self.i + self.batch]
        self.i += len(out)
        if not len(out):  # the budget is spent; more points are a fresh hypercube's
            from scipy.stats import qmc

            out = qmc.LatinHypercube(d=self.points.shape[1], seed=self.i).random(self.batch)
        return out

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        pass


class CMAES:
    def __init__(self, d: int, batch: int, seed: int, budget: int) -> None:
        self.d, self.batch, self.seed = d, batch, seed
        self.restarts = 0
        default = 4 + int(3 * math.log(d))
        self.popsize = batch * math.ceil(default / batch)
        self._new()

    def _new(self) -> None:
        import cma

        rng = np.random.default_rng([self.seed, self.restarts])
        x0 = rng.random(self.d) if self.restarts else np.full(self.d, 0.5)
        self.es = cma.CMAEvolutionStrategy(
            x0,
            0.3,
            {
                "bounds": [0.0, 1.0],
                "popsize": self.popsize,
                "seed": int(rng.integers(1, 2**31 - 1)),
                "verbose": -9,
                "CMA_stds": None,
                "tolfun": 1e-6,
                "tolx": 1e-4,
            },
        )

    def ask(self) -> np.ndarray:
        if self.es.stop():
            self.restarts += 1
            self.popsize *= 2
            self._new()
        self._asked = self.es.ask()
        return np.clip(np.array(self._asked), 0.0, 1.0)

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        self.es.tell(self._asked, [float(s) for s in scores])


class Bayesian:
    def __init__(self, d: int, batch: int, seed: int, budget: int, tpe: bool = False) -> None:
        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        self.d, self.batch = d, batch
        # the random initial design: two points per dimension (at least a batch) before the
        # model proposes; optuna's default of 10 spends a third of a small budget blindly
        startup = max(2 * d, batch, 4)
        if tpe:
            sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=startup, constant_liar=True)
        else:
            import warnings

            warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
            sampler = optuna.samplers.GPSampler(seed=seed, n_startup_trials=startup, deterministic_objective=True)
        self.study = optuna.create_study(direction="minimize", sampler=sampler)
        self.dist = {f"x{i}": optuna.distributions.FloatDistribution(0.0, 1.0) for i in range(d)}
        self._trials: list = []

    def ask(self) -> np.ndarray:
        self._trials = [self.study.ask(self.dist) for _ in range(self.batch)]
        return np.array([[t.params[f"x{i}"] for i in range(self.d)] for t in self._trials])

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        for trial, s in zip(self._trials, scores):
            self.study.tell(trial, float(s))


def make(name: str, d: int, batch: int, seed: int, budget: int):
    """The optimiser ``name`` (:data:`NAMES`) for ``d`` dimensions, proposing ``batch`` points."""
    if name == "random":
        return RandomSearch(d, batch, seed, budget)
    if name == "lhs":
        return LatinHypercube(d, batch, seed, budget)
    if name == "cma":
        return CMAES(d, batch, seed, budget)
    if name in ("bo", "bo-tpe"):
        return Bayesian(d, batch, seed, budget, tpe=name == "bo-tpe")
    from ego.params import ConfigError

    raise ConfigError(f"unknown optimizer {name!r} (known: {', '.join(NAMES)})")
