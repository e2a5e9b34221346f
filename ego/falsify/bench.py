"""Runs-to-first-violation of each optimiser: the jobs behind ``benchmarks/bench_falsify.py``
and ``docs/results/falsify.md`` (its tables: :mod:`ego.docs.falsify`).

* :class:`BenchJob`: one repetition on real ego runs - ``ego falsify`` (in this process, one
  run after another: a docs job already has a worker process of its own) with
  ``--until first`` over the benchmark spec ``benchmarks/falsify/bench.toml`` for one
  requirement, one optimiser and one optimiser seed, within a budget.
* :class:`SurrogateJob`: the same search against an analytic stand-in (no SUMO, clearly
  labelled as such): a violating ball in the unit cube, robustness = distance to it.
* :class:`SweepJob`: one run of the dense sweep that measures how small each violating
  region is (the requirements of ``benchmarks/falsify/dense.toml`` evaluated on it).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BENCH_SPEC = ROOT / "benchmarks" / "falsify" / "bench.toml"
DENSE_SPEC = ROOT / "benchmarks" / "falsify" / "dense.toml"
OPTIMIZERS = ("cma", "bo", "random", "lhs")


def bench_spec(requirement: str):
    """The benchmark spec with ``requirement`` as the target."""
    import dataclasses

    from ego.falsify.spec import load

    spec = load(BENCH_SPEC)
    if requirement not in spec.requirements:
        from ego.params import ConfigError

        raise ConfigError(f"unknown benchmark requirement {requirement!r} (known: {', '.join(spec.requirements)})")
    return dataclasses.replace(
        spec,
        requirement=requirement,
        requirements={requirement: spec.requirements[requirement]},
    )


@dataclass(frozen=True)
class BenchJob:
    """One repetition on real runs: runs to the first violation (None: none within the budget)
    and the best robustness after each run."""

    requirement: str
    optimizer: str
    seed: int
    budget: int
    batch: int = 2  #: points per proposal (the workers of an ``ego falsify --jobs 2``)

    def __call__(self) -> dict:
        from ego.falsify.search import falsify
        from ego.parallel.executor import InlineExecutor

        class Batched(InlineExecutor):
            workers = self.batch

        with tempfile.TemporaryDirectory(prefix="ego-bench-falsify-") as tmp:
            report = falsify(
                bench_spec(self.requirement),
                Path(tmp),
                optimizer=self.optimizer,
                budget=self.budget,
                until="first",
                optimizer_seed=self.seed,
                verify=False,
                executor=Batched(),
            )
        search = report.searches[0]
        return {
            "runs": search.first_violation,
            "curve": [float(x) for x in search.best_so_far()],
        }


#: the surrogate: a violating ball of this radius in the unit cube of DIMS dimensions
SURROGATE_CENTRE = (0.83, 0.17, 0.71, 0.36)
SURROGATE_RADIUS = 0.08


@dataclass(frozen=True)
class SurrogateJob:
    """One repetition against the analytic stand-in (NOT ego runs): a ball of radius
    :data:`SURROGATE_RADIUS` around :data:`SURROGATE_CENTRE` in [0, 1]^4 violates (0.04 % of
    the cube); the robustness is the distance to it."""

    optimizer: str
    seed: int
    budget: int = 2000
    batch: int = 2

    def __call__(self) -> dict:
        from ego.falsify.optimizers import make, squash

        centre = np.array(SURROGATE_CENTRE)
        opt = make(self.optimizer, len(centre), self.batch, self.seed, self.budget)
        n, best, curve = 0, np.inf, []
        while n < self.budget:
            x = opt.ask()
            rob = np.linalg.norm(x - centre, axis=1) - SURROGATE_RADIUS
            for r in rob:
                n += 1
                best = min(best, float(r))
                curve.append(best)
                if r < 0:
                    return {"runs": n, "curve": curve}
            opt.tell(x, np.array([squash(float(r)) for r in rob]))
        return {"runs": None, "curve": curve}


@dataclass(frozen=True)
class SweepJob:
    """One run of the dense sweep with its requirements: their robustness by name."""

    seed: int
    overrides: tuple[tuple[str, Any], ...]
    controller: str = "pid"

    def __call__(self) -> dict:
        from ego.runner import RunSpec, run
        from ego.sweep.spec import load

        spec = load(DENSE_SPEC)
        result = run(
            RunSpec(
                spec.scenario,
                self.controller,
                self.seed,
                dict(self.overrides),
                requirements=spec.requirements,
            )
        )
        return dict(result.metrics.get("requirements", {}))


def dense_jobs() -> list[SweepJob]:
    from ego.sweep.spec import load

    spec = load(DENSE_SPEC)
    return [SweepJob(r.seed, tuple(r.overrides.items()), r.controller) for r in spec.runs()]


def quartiles(runs: list, budget: int) -> tuple[float, float, float, int]:
    """(25th, 50th, 75th percentile, found) of runs-to-first; a repetition that found
    nothing counts as more than ``budget`` (the statistics are then lower bounds: ">")."""
    values = np.array([r if r is not None else np.inf for r in runs], dtype=float)
    q = np.percentile(np.where(np.isinf(values), budget + 1, values), [25, 50, 75], method="lower")
    found = int(np.isfinite(values).sum())
    return float(q[0]), float(q[1]), float(q[2]), found


def fmt_runs(x: float, budget: int) -> str:
    return f">{budget}" if x > budget else f"{x:.0f}"
