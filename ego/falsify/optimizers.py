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

The dimensions have types (``kinds``: one :class:`Kind` per dimension, default every one
continuous): a boolean is a categorical dimension for optuna (``suggest_categorical``) and an
integer variable of CMA-ES (two levels), a whole number an integer dimension (optuna's
``IntDistribution``, CMA-ES's ``integer_variables``: the ``cma`` package's integer handling,
which keeps the step size of an integer variable from collapsing below one level and
centres it; the ``cmaes`` package's CMA-ES with margin is not used). Every optimiser still
proposes points of the unit cube: a dimension of L levels takes only the values k / (L - 1),
which the spec maps to the level's value.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np


class Kind(NamedTuple):
    """A dimension's type: ``float`` (continuous), ``int`` (``levels`` whole numbers) or
    ``bool`` (two categories)."""

    kind: str = "float"
    levels: int = 0

    @property
    def discrete(self) -> bool:
        return self.kind in ("int", "bool") and self.levels >= 2


def _kinds(kinds: Sequence[Kind] | None, d: int) -> tuple[Kind, ...]:
    return tuple(kinds) if kinds is not None else (Kind(),) * d


def on_levels(u: np.ndarray, kinds: Sequence[Kind]) -> np.ndarray:
    """Points of the unit cube with each discrete dimension on its nearest level k / (L - 1)."""
    u = np.array(u, dtype=float)
    for i, k in enumerate(kinds):
        if k.discrete:
            u[..., i] = np.round(np.clip(u[..., i], 0.0, 1.0) * (k.levels - 1)) / (k.levels - 1)
    return u + 0.0  # no -0.0


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
    def __init__(self, d: int, batch: int, seed: int, budget: int, kinds: Sequence[Kind] | None = None) -> None:
        self.d, self.batch, self.seed = d, batch, seed
        self.kinds = _kinds(kinds, d)
        # a discrete dimension of L levels is searched on 0..L-1 (its levels one apart, as
        # the cma package's integer handling asks), bounded half a level beyond its ends
        self.scale = np.array([k.levels - 1 if k.discrete else 1.0 for k in self.kinds])
        self.integer = [i for i, k in enumerate(self.kinds) if k.discrete]
        self.restarts = 0
        default = 4 + int(3 * math.log(d))
        self.popsize = batch * math.ceil(default / batch)
        self._new()

    def _new(self) -> None:
        import cma

        rng = np.random.default_rng([self.seed, self.restarts])
        x0 = rng.random(self.d) if self.restarts else np.full(self.d, 0.5)
        options = {
            "bounds": [0.0, 1.0],
            "popsize": self.popsize,
            "seed": int(rng.integers(1, 2**31 - 1)),
            "verbose": -9,
            "CMA_stds": None,
            "tolfun": 1e-6,
            "tolx": 1e-4,
        }
        if self.integer:
            margin = np.array([0.49 if i in self.integer else 0.0 for i in range(self.d)])
            options.update(
                bounds=[list(-margin), list(self.scale + margin)],
                CMA_stds=list(self.scale),
                integer_variables=list(self.integer),
            )
        self.es = cma.CMAEvolutionStrategy(x0 * self.scale, 0.3, options)

    def ask(self) -> np.ndarray:
        if self.es.stop():
            self.restarts += 1
            self.popsize *= 2
            self._new()
        self._asked = self.es.ask()
        x = np.array(self._asked)
        if self.integer:
            x[:, self.integer] = np.round(x[:, self.integer])
        return on_levels(np.clip(x / self.scale, 0.0, 1.0), self.kinds)

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        self.es.tell(self._asked, [float(s) for s in scores])


class Bayesian:
    def __init__(
        self, d: int, batch: int, seed: int, budget: int, tpe: bool = False, kinds: Sequence[Kind] | None = None
    ) -> None:
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
        self.kinds = _kinds(kinds, d)
        dists = optuna.distributions
        self.dist = {
            f"x{i}": (
                dists.CategoricalDistribution((False, True))
                if k.kind == "bool"
                else dists.IntDistribution(0, k.levels - 1)
                if k.discrete
                else dists.FloatDistribution(0.0, 1.0)
            )
            for i, k in enumerate(self.kinds)
        }
        self._trials: list = []

    def _unit(self, i: int, value) -> float:
        k = self.kinds[i]
        if k.kind == "bool":
            return 1.0 if value else 0.0
        return float(value) / (k.levels - 1) if k.discrete else float(value)

    def ask(self) -> np.ndarray:
        self._trials = [self.study.ask(self.dist) for _ in range(self.batch)]
        return np.array([[self._unit(i, t.params[f"x{i}"]) for i in range(self.d)] for t in self._trials])

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        for trial, s in zip(self._trials, scores):
            self.study.tell(trial, float(s))


def make(name: str, d: int, batch: int, seed: int, budget: int, kinds: Sequence[Kind] | None = None):
    """The optimiser ``name`` (:data:`NAMES`) for ``d`` dimensions of ``kinds`` (default all
    continuous), proposing ``batch`` points."""
    if name == "random":
        return RandomSearch(d, batch, seed, budget)
    if name == "lhs":
        return LatinHypercube(d, batch, seed, budget)
    if name == "cma":
        return CMAES(d, batch, seed, budget, kinds)
    if name in ("bo", "bo-tpe"):
        return Bayesian(d, batch, seed, budget, tpe=name == "bo-tpe", kinds=kinds)
    from ego.params import ConfigError

    raise ConfigError(f"unknown optimizer {name!r} (known: {', '.join(NAMES)})")
