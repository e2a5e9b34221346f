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
* ``psytaliro-uniform`` and ``psytaliro-annealing``: psy-taliro's ``UniformRandom`` and
  ``DualAnnealing`` (scipy's generalised simulated annealing without local search), run by
  psy-taliro's own test loop (``staliro.staliro`` with a cost function) in a helper thread
  whose cost function hands each sample to :meth:`PsyTaliro.ask` and waits for the run's
  robustness from :meth:`PsyTaliro.tell`: one point at a time, as psy-taliro proposes them.
  psy-taliro is not a dependency of ego (``pip install psy-taliro``; ego's ``test`` extra).

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


NAMES = ("cma", "bo", "bo-tpe", "random", "lhs", "psytaliro-uniform", "psytaliro-annealing")
#: psy-taliro's optimisers by ego's name for them
PSYTALIRO = {"psytaliro-uniform": "UniformRandom", "psytaliro-annealing": "DualAnnealing"}


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


def unsquash(s: float) -> float:
    """The robustness a :func:`squash` score stands for (a clipped infinity: +-1e9)."""
    return math.copysign(math.expm1(abs(s)), s)


class _Stop(Exception):
    """Raised in psy-taliro's thread by its cost function once the search no longer asks."""


class PsyTaliro:
    """psy-taliro's optimiser ``kind`` (:data:`PSYTALIRO`) over the unit cube, driven by
    ``staliro.staliro`` (one optimisation of ``budget`` samples, seeded with ``seed``) in a
    helper thread. Its cost function puts each sample on a queue for :meth:`ask` and returns
    the robustness :meth:`tell` gives back (unsquashed: psy-taliro sees the requirement's
    robustness, as its users give it). When psy-taliro's optimisation ends before the search
    does, a new one starts with the next seed. Deterministic given ``seed``."""

    def __init__(self, d: int, seed: int, budget: int, kind: str, kinds: Sequence[Kind] | None = None) -> None:
        try:
            import staliro  # noqa: F401
        except ImportError:
            from ego.params import ConfigError

            raise ConfigError(
                f"optimizer {kind!r} needs psy-taliro, which is not installed (pip install psy-taliro)"
            ) from None
        import queue

        self.d, self.seed, self.budget, self.kind = d, seed, budget, kind
        self.kinds = _kinds(kinds, d)
        self.restarts = 0
        self._samples: queue.Queue = queue.Queue(maxsize=1)
        self._costs: queue.Queue = queue.Queue()
        self._start()

    def _start(self) -> None:
        import threading

        import staliro
        from staliro import optimizers

        optimizer = getattr(optimizers, PSYTALIRO[self.kind])()
        options = staliro.TestOptions(
            static_inputs={f"x{i}": (0.0, 1.0) for i in range(self.d)},
            iterations=self.budget,
            runs=1,
            seed=1 + self.seed + 1_000_003 * self.restarts,  # psy-taliro takes seeds > 0
        )

        @staliro.costfunc
        def cost(inputs) -> float:
            self._samples.put(np.array([inputs.static[f"x{i}"] for i in range(self.d)], dtype=float))
            value = self._costs.get()
            if value is None:
                raise _Stop
            return value

        def optimise() -> None:
            try:
                staliro.staliro(cost, optimizer, options)
                self._samples.put(None)  # its budget is spent: the next ask starts another
            except _Stop:
                pass
            except BaseException as exc:  # noqa: BLE001 - psy-taliro's error, raised by the next ask
                self._samples.put(exc)

        self._thread = threading.Thread(target=optimise, name=f"ego-{self.kind}", daemon=True)
        self._thread.start()

    def ask(self) -> np.ndarray:
        x = self._samples.get()
        if isinstance(x, BaseException):
            raise x
        if x is None:
            self.restarts += 1
            self._start()
            return self.ask()
        return on_levels(np.clip(x, 0.0, 1.0)[None, :], self.kinds)

    def tell(self, points: np.ndarray, scores: np.ndarray) -> None:
        self._costs.put(unsquash(float(scores[0])))

    def close(self) -> None:
        """End psy-taliro's thread (it waits for a cost once it has proposed a point)."""
        if self._thread.is_alive():
            self._costs.put(None)


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
    if name in PSYTALIRO:
        return PsyTaliro(d, seed, budget, name, kinds)
    from ego.params import ConfigError

    raise ConfigError(f"unknown optimizer {name!r} (known: {', '.join(NAMES)})")
